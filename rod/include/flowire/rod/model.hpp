#pragma once
/// @file model.hpp
/// @brief What a guidewire is made of: `WireSpec` (the user's description) and `RodModel`
/// (the constant per-segment data derived from it, built once).
///
/// **Material coordinate.** Properties are functions of u, the distance from the distal
/// tip along the wire (u = 0 at the tip, u = length at the proximal end). The rod is
/// discretized on a fixed grid u_k = k·h anchored at the tip, so a vertex keeps its
/// material (stiffness, mass, rest curvature) for its whole life while the wire is fed in
/// and pulled back; the simulated vertices are the grid points from the tip to within a
/// segment and a half of the entry, then the material point at the entry and one a segment
/// behind it (the clamp stub, feeder.hpp). Beyond the proximal end the shaft material is
/// continued (the holder is virtual).
///
/// **Inextensibility.** Stretching uses the wire's physical axial stiffness EA as a stiff
/// penalty (no constraint): the strain is N/(EA) for an axial force N. For the stiffest
/// wires (steel core, 200 GPa, EA ≈ 1.2·10⁵ N at r = 0.445 mm) the drift is below 10⁻⁵ at
/// newton-level loads; the softest listed (5 GPa, r = 0.2 mm, EA ≈ 630 N) stays below
/// 0.1% up to 0.6 N of axial load. A penalty keeps the step an unconstrained minimization
/// with a banded symmetric Hessian (solved in O(n)); the implicit integrator makes its
/// stiffness harmless for stability. `stretch_stiffness` can raise EA if a test needs a
/// stricter length.
///
/// Tip shapes (the pre-shaped, softer distal part):
/// - straight: no rest curvature;
/// - angled: an arc of radius `bend_radius` turning by `angle`, starting `bend_offset` from
///   the tip (default 2 mm);
/// - j: as angled with default angle 180° and offset 0 (the arc reaches the tip; it starts
///   half a segment in, since the distal half segment has no vertex to bend).
///
/// Curvature is integrated over each vertex's cell, κ̄ = 2 tan(Φ/2) with Φ the turning
/// angle of the cell, so the discrete rest shape turns by exactly `angle`.
#include <Eigen/Core>
#include <string_view>
#include <vector>

namespace flowire::rod {

enum class TipShape { Straight, Angled, J };

/// @brief "straight" | "angled" | "j" (scene files). @throws flowire::Error (usage) otherwise.
[[nodiscard]] TipShape parse_tip_shape(std::string_view name);
[[nodiscard]] const char* to_string(TipShape shape);

/// @brief The distal part of the wire: softer, optionally thinner, optionally pre-shaped.
struct TipSpec {
  double length = 0.03;            ///< [m] softer part length (0: no tip)
  double youngs_modulus = 0.0;     ///< [Pa] 0: same as the shaft
  double radius = 0.0;             ///< [m] 0: same as the shaft
  double transition_length = 0.0;  ///< [m] linear blend of E and r across the tip/shaft joint
  TipShape shape = TipShape::Straight;
  double angle = -1.0;         ///< [rad] bend angle; < 0: default (45° angled, 180° j)
  double bend_radius = 0.005;  ///< [m] radius of the pre-shaped arc
  double bend_offset = -1.0;   ///< [m] distance from the tip to the arc; < 0: default
};

/// @brief Curvature-adaptive resampling of the free part of the wire (off by default).
///
/// Edges live on a dyadic hierarchy anchored at the tip: an edge of rest length ℓ spans
/// [i·ℓ, (i+1)·ℓ] in the material coordinate, ℓ = h·2^m with h the feeding grid
/// (`segment_length`). An edge is split at its material midpoint where the turning angle
/// at one of its end vertices (the larger of the current and the rest turning) exceeds
/// `split_angle`; two sibling edges are merged where the turning at the three vertices
/// involved is below `merge_angle` and lumping the middle vertex's mass onto its neighbours
/// changes the kinetic energy by less than 10⁻⁴ of theirs. Neighbouring rest lengths never differ by more than a
/// factor 2. The state is transferred so that positions lie on the smooth curve through
/// the old vertices, momentum is conserved and the twist density is kept (see
/// RodSimulator::adapt).
struct AdaptSpec {
  bool enabled = false;
  double min_segment_length = 0.0;  ///< [m] finest edge; 0: h/4
  double max_segment_length = 0.0;  ///< [m] coarsest edge; 0: h (coarsening only undoes refinement)
  double split_angle = 0.1;         ///< [rad] turning angle above which edges are split
  double merge_angle = -1.0;        ///< [rad] below which siblings merge; < 0: split_angle/4
};

/// @brief The most segments a rod may have (a 2 m wire at 2 µm): beyond it the arrays alone
/// would take gigabytes, so a larger count is refused as an input error, not attempted.
inline constexpr double kMaxRodSegments = 1e6;

/// @brief A guidewire and where it enters (the clamp/introducer).
struct WireSpec {
  double length = 1.7;           ///< [m] total wire length
  double radius = 4.45e-4;       ///< [m] shaft radius (0.035")
  double youngs_modulus = 67e9;  ///< [Pa] flexural modulus of the shaft
  double shear_modulus = 0.0;    ///< [Pa] 0: E / (2(1 + ν))
  double poisson_ratio = 0.3;
  double density = 6450.0;       ///< [kg/m³]
  int segments = 0;              ///< > 0: segment length = length / segments
  double segment_length = 1e-3;  ///< [m] used when segments == 0
  TipSpec tip;
  Eigen::Vector3d base_position = Eigen::Vector3d::Zero();    ///< entry point [m]
  Eigen::Vector3d base_direction = Eigen::Vector3d::UnitX();  ///< insertion direction
  /// Direction ⊥ base_direction fixing the material frame at zero rotation (the plane of
  /// a pre-shaped tip); zero: any perpendicular.
  Eigen::Vector3d base_normal = Eigen::Vector3d::Zero();
  double inserted_length = -1.0;  ///< [m] initially inserted; < 0: the whole length
  double damping = 0.0;           ///< [N s/m²] viscous damping per unit length
  /// [1/s] mass-proportional damping ζ: each vertex feels −ζ m v (each mode's amplitude then
  /// decays as e^(−ζt/2)); adds to `damping`
  double mass_damping = 0.0;
  // Overrides (0: derived from E, r, G, ρ) for benchmark cases given in stiffnesses.
  double bending_stiffness = 0.0;  ///< EI [N m²]
  double twist_stiffness = 0.0;    ///< GJ [N m²]
  double stretch_stiffness = 0.0;  ///< EA [N]
  double mass_per_length = 0.0;    ///< ρA [kg/m]
  AdaptSpec adapt;
};

/// @brief Cross-section constants at one material coordinate.
struct Section {
  double stretch_stiffness = 0.0;  ///< EA [N]
  double bend_stiffness = 0.0;     ///< EI [N m²]
  double twist_stiffness = 0.0;    ///< GJ [N m²]
  double rho_a = 0.0;              ///< mass per length [kg/m]
  double radius = 0.0;             ///< [m]
};

/// @brief Discrete constants of a polyline whose vertices sit at material coordinates u_k
/// (vertex k, edge j joins vertices j and j+1). Edge constants are taken at the edge's
/// midpoint; vertex constants are length-weighted averages over the vertex's cell
/// [u_k − ℓ̄_{k−1}/2, u_k + ℓ̄_k/2]; rest curvature is integrated over that cell,
/// κ̄ = 2 tan(Φ/2) with Φ the rest turning angle of the cell.
struct Discretization {
  // per edge j
  std::vector<double> rest_length;        ///< ℓ̄ [m]
  std::vector<double> stretch_stiffness;  ///< EA [N]
  std::vector<double> rho_a;              ///< mass per length [kg/m]
  std::vector<double> twist_inertia;      ///< ρ J ℓ̄: rotational inertia of the edge [kg m²]
  std::vector<double> edge_radius;        ///< [m]
  // per vertex k (bending/twisting quantities live on interior vertices)
  std::vector<double> mass;             ///< lumped mass [kg] (the vertex's cell)
  std::vector<double> cell_length;      ///< (ℓ̄_{k−1} + ℓ̄_k)/2, one-sided at the ends [m]
  std::vector<double> bend_stiffness;   ///< EI [N m²]
  std::vector<double> twist_stiffness;  ///< GJ [N m²]
  std::vector<double> rest_kappa1;      ///< integrated rest curvature (material frame)
  std::vector<double> rest_kappa2;
  /// @brief Reserve room for @p vertices vertices (no allocation in later `discretize`).
  void reserve(int vertices);
};

/// @brief The wire's material as functions of the material coordinate u, and its
/// discretization on the uniform feeding grid u_k = k·h (grid index k from the distal tip;
/// the Discretization arrays are sized for the grid capacity `grid_vertices`).
struct RodModel : Discretization {
  double h = 1e-3;        ///< segment (rest) length [m]
  double length = 0.0;    ///< total wire length [m]
  int grid_vertices = 0;  ///< capacity: grid points that may ever be simulated
  Eigen::Vector3d base_position, base_direction, base_normal;
  double damping = 0.0;       ///< [N s/m²] per unit length
  double mass_damping = 0.0;  ///< [1/s]
  AdaptSpec adapt;            ///< with defaults resolved (min/max lengths, merge angle)

  /// @brief Build from a spec. @throws flowire::Error (usage) on invalid values.
  static RodModel from_spec(const WireSpec& spec);
  /// @brief Material coordinate (distance from the tip) of grid point k.
  [[nodiscard]] double u(int k) const { return h * k; }
  /// @brief Cross-section at material coordinate @p u (shaft material continued past the
  /// proximal end).
  [[nodiscard]] Section section(double u) const;
  /// @brief Rest turning angle ∫κ̄ du over [a, b] (in the plane of the pre-shaped tip) [rad].
  [[nodiscard]] double rest_turning(double a, double b) const;
  /// @brief Constants of the polyline with vertices at material coordinates @p u
  /// (increasing); @p out must have room (Discretization::reserve) to stay allocation-free.
  void discretize(const std::vector<double>& u, Discretization& out) const;

 private:
  // Material description (from the spec).
  double E_shaft_ = 0.0, E_tip_ = 0.0, r_shaft_ = 0.0, r_tip_ = 0.0, nu_ = 0.3;
  double G_shaft_ = 0.0;
  double tip_length_ = 0.0, transition_ = 0.0;
  double ei_override_ = 0.0, gj_override_ = 0.0, ea_override_ = 0.0, rho_a_override_ = 0.0;
  double density_ = 0.0;
  double arc_begin_ = 0.0, arc_end_ = 0.0, arc_radius_ = 1.0;  ///< pre-shaped arc [m]
};

}  // namespace flowire::rod
