#pragma once
/// @file catheter.hpp
/// @brief A hollow catheter over the guidewire: its rod and the contact inside its lumen.
///
/// **Model.** The catheter is a second discrete elastic rod (rod::RodSimulator) with the
/// stiffnesses of a thick-walled tube, EI = E π (r_o⁴ − r_i⁴)/4, GJ = G π (r_o⁴ − r_i⁴)/2,
/// EA = E π (r_o² − r_i²), ρA = ρ π (r_o² − r_i²). Where the two overlap they bend as one
/// composite because the wire is held inside the lumen by contact: each wire vertex whose
/// axis is farther than the clearance c = r_i − r_w from the catheter's axis (its distance to
/// the nearest catheter edge) is pushed back by the penalty E = k φ(d − c), φ(g) = ½ g² with
/// its onset smoothed to C² over |g| < δ/2 (onset_quadratic; δ = lumen_onset_fraction c).
/// With the wire kept coaxial, both rods take the same curvature and their bending moments add:
/// EI_pair = EI_wire + EI_catheter exactly (the composite tube in contact), not the
/// Halpin–Tsai estimate of a homogenized composite (composite catheter paper, 2006).
///
/// **Coupling.** Dynamic implicit Euler steps: one Newton over both rods (step_pair_newton), the
/// contact's coupling blocks in the joint matrix. Statics and the midpoint rule: partitioned
/// (block Gauss–Seidel sweeps): the wire is solved against the
/// catheter held, then the catheter against the wire just computed; each rod keeps its own
/// side of the penalty implicit (force and Jacobian in its Newton), so stiff lumen contact is
/// stable in each solve. Within a time step the sweeps repeat from the step's start, with the
/// held catheter updated by IQN-ILS, until the pair balances (step_pair; solve_static_pair
/// for statics; docs/catheter.md). The reaction on the catheter is
/// the gradient of the same energy with respect to the catheter's vertices (the force at the
/// nearest point, split between the edge's ends by the projection parameter).
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "flowire/coupling/interaction.hpp"
#include "flowire/rod/external.hpp"
#include "flowire/rod/model.hpp"
#include "flowire/rod/simulator.hpp"

namespace flowire::coupling {

/// @brief The `catheter:` section of a scene.
struct CatheterSpec {
  double length = 1.0;            ///< [m]
  double outer_radius = 1e-3;     ///< [m]
  double inner_radius = 0.55e-3;  ///< [m]
  double youngs_modulus = 2e9;    ///< [Pa]
  double poisson_ratio = 0.4;
  double density = 1200.0;       ///< [kg/m³]
  double initial_length = 0.02;  ///< [m] inside at t = 0
  double stiffness = 3e4;        ///< [N/m] lumen penalty per wire vertex
  double inner_friction = 0.0;   ///< Coulomb coefficient between wire and lumen
  double speed = 0.0;            ///< [m/s] insertion speed
  double rotation_speed = 0.0;   ///< [rad/s]
};

/// @brief The rod of a tube with the catheter's section, on the wire's feeding grid and at
/// its entry (same base position and direction, same segment length).
[[nodiscard]] rod::WireSpec catheter_rod_spec(const CatheterSpec& cat, const rod::WireSpec& wire);

/// @brief The mean rest length of the edges at each vertex of @p rod over its grid's segment length
/// (RodView::cell_weight, for every vertex).
[[nodiscard]] std::vector<double> cell_weights(const rod::RodSimulator& rod);

/// @brief Width of the lumen penalty's smoothed onset as a fraction of the clearance: δ = 0.3 c
/// (a wire vertex starts to feel the lumen 0.15 c inside the clearance and feels ½ k (d − c)₊²'s
/// force from 0.15 c beyond it). With the plain ½ k (d − c)₊² (δ = 0), whose stiffness jumps
/// from 0 to k at d = c, the catheter's Newton stalled in examples/catheter_arch: the set of wire
/// vertices pressing on it changed at every iterate and the largest residual walked along it a
/// vertex or two per iteration (192 subdivided steps and 4 unconverged ones at dt 5 ms). The
/// jump's Newton basin grows with δ: 0.05 c left 89 subdivided steps, 0.1 c 47, 0.3 c none
/// (docs/catheter.md).
inline constexpr double lumen_onset_fraction = 0.3;

/// @brief Energy, gradients and diagonal Hessian blocks of the lumen penalty
/// E = k φ(d − c) (onset_quadratic) for one point x and one edge [a, b] (d: distance from x to
/// the edge).
struct LumenPenalty {
  double energy = 0.0;
  double distance = 0.0;
  double alpha = 0.0;                         ///< nearest point a + α (b − a)
  double weight = 1.0;                        ///< w(α) at the open tip end, else 1
  Eigen::Vector3d grad_x, grad_a, grad_b;     ///< ∂E/∂x, ∂E/∂a, ∂E/∂b
  Eigen::Matrix3d hess_xx, hess_aa, hess_bb;  ///< ∂²E/∂x², ∂²E/∂a², ∂²E/∂b²
  Eigen::Matrix3d hess_ab;                    ///< ∂²E/∂a∂b
  Eigen::Matrix3d hess_xa, hess_xb;           ///< ∂²E/∂x∂a, ∂²E/∂x∂b (rows x)
};
/// @brief The penalty of x against edge [a, b] with clearance @p c, stiffness @p k and onset
/// width @p onset (δ of onset_quadratic; zero when d ≤ c − δ/2). Exact derivatives of the
/// distance to the segment (interior or end).
/// @p open_before_a: [a, b] is the catheter's tip edge, a its open end. Before a the distance
/// is to the edge's line (a wire vertex level with the tip is held by its lateral distance
/// only), and the penalty is weighted by tip_weight(α), the vertex's share of its cell inside
/// the lumen: full half an edge inside the tip, none half an edge beyond it, where the vertex
/// leaves the lumen (LumenContact::nearest_edge). The wire's exit is then C² in the weight and
/// the energy at least C¹ as a whole, with no force switched off.
[[nodiscard]] LumenPenalty lumen_penalty(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                         double c, double k, bool open_before_a = false, double onset = 0.0);

/// @brief The weight of the lumen penalty at the catheter's open tip end for a wire vertex at
/// α along the tip edge (α = 0 at the tip end, < 0 beyond it): the quintic smoothstep of
/// α + ½ over [0, 1] (1 for α ≥ ½, 0 for α ≤ −½). @p dw, @p d2w: its first two derivatives.
[[nodiscard]] double tip_weight(double alpha, double* dw = nullptr, double* d2w = nullptr);

/// @brief The wire–catheter contact, one object shared by two ExternalForce views: the wire
/// side (catheter held at `catheter_snapshot`) and the catheter side (wire held at
/// `wire_snapshot`). The coupling loop refreshes the snapshots between the two solves.
class LumenContact {
 public:
  /// @param onset_fraction the penalty's onset width over the clearance (lumen_onset_fraction)
  LumenContact(double clearance, double stiffness, double onset_fraction = lumen_onset_fraction)
      : clearance_(clearance), stiffness_(stiffness), onset_(onset_fraction * clearance) {}
  /// @brief Held catheter: its vertices (tip first) and arc lengths from the entry.
  std::vector<Eigen::Vector3d> catheter_snapshot;
  std::vector<double> catheter_arc;
  /// @brief Held wire: its vertices (tip first) and arc lengths from the entry.
  std::vector<Eigen::Vector3d> wire_snapshot;
  std::vector<double> wire_arc;

  /// @brief The nearest catheter edge to wire point @p x with arc length @p s, or −1 when it
  /// is out of the catheter (beyond its tip, or not inserted).
  [[nodiscard]] int nearest_edge(const Eigen::Vector3d& x, double s, const std::vector<Eigen::Vector3d>& cath,
                                 const std::vector<double>& arc) const;
  /// @brief The penalty on the wire at @p rod (catheter held).
  void evaluate_wire(const rod::RodView& rod, rod::ForceAccumulator& out) const;
  /// @brief The reaction on the catheter at @p rod (wire held).
  void evaluate_catheter(const rod::RodView& rod, rod::ForceAccumulator& out) const;
  /// @brief Total penalty energy of the held configurations [J].
  [[nodiscard]] double energy() const;
  /// @brief The catheter edge each wire vertex is measured against, chosen (nearest) when a
  /// rod is held and kept through the other rod's solve, so that the penalty is a smooth
  /// function of the unknowns within a solve; −1: out of the lumen.
  std::vector<int> wire_edge;
  /// @brief Choose wire_edge from the held configurations.
  void assign_edges();
  /// @brief Per held wire vertex: inside the catheter (assigned an edge and behind the plane of
  /// its tip), where the blood does not reach it.
  [[nodiscard]] std::vector<char> inside() const;
  /// @brief Hold the catheter / the wire at the rod's current state, velocities included (and
  /// assign_edges()).
  void hold_catheter(const rod::RodSimulator& catheter);
  void hold_wire(const rod::RodSimulator& wire);
  /// @brief Held velocities of the catheter's and the wire's vertices (hold_catheter, hold_wire).
  std::vector<Eigen::Vector3d> catheter_velocity;
  std::vector<Eigen::Vector3d> wire_velocity;
  /// @brief The held wire's cell weights (RodView::cell_weight): the penalty of wire vertex i is
  /// stiffness × weight(i) on both sides.
  std::vector<double> wire_weight;
  [[nodiscard]] double weight(size_t i) const { return i < wire_weight.size() ? wire_weight[i] : 1.0; }

  /// @brief Coulomb friction between the wire and the lumen (catheter.inner_friction): on each
  /// wire vertex pressed on the lumen, f = −μ N v_t/√(|v_t|² + ε²) (coulomb_friction) of the
  /// velocity relative to the catheter's at the same point, v = v_w − ((1 − α) v_j + α v_{j+1}),
  /// and −f on the catheter's edge j split as (1 − α, α). The normal
  /// force N, the normal, the edge and α are those of the step's start (lag_friction), as on the
  /// walls: friction is then the gradient of Δt·D(v) in either rod's positions, an exact
  /// incremental potential with an exact Jacobian, and the two sides are equal and opposite to
  /// round-off. Static solves have none. μ = 0: frictionless (the default).
  void set_friction(double mu, double slip_speed) { friction_ = mu, slip_speed_ = slip_speed; }
  [[nodiscard]] double friction() const { return friction_; }
  /// @brief Record N, the normal, the edge and α of every wire vertex from the held states (the
  /// step's start); step_pair calls it before its sweeps.
  void lag_friction();
  /// @brief A wire vertex's friction contact of the step's start (lag_friction): against the
  /// point α along a catheter edge.
  struct FrictionContact {
    int edge = -1;                                        ///< the catheter edge (−1: none)
    double alpha = 0.0;                                   ///< the point (1 − α) x_edge + α x_edge+1
    double normal = 0.0;                                  ///< N [N]
    Eigen::Vector3d direction = Eigen::Vector3d::Zero();  ///< unit normal between the two
  };
  /// @brief Per wire vertex, against the catheter's edges.
  std::vector<FrictionContact> friction_contact;
  /// @brief The friction on the wire vertex of contact @p fc at its velocity @p vp and the
  /// catheter edge's vertex velocities @p va, @p vb (zero force without a contact).
  [[nodiscard]] FrictionResult friction_at(const FrictionContact& fc, const Eigen::Vector3d& vp,
                                           const Eigen::Vector3d& va, const Eigen::Vector3d& vb) const;
  /// @brief One Newton iteration over both rods (step_pair_newton): the catheter's side adds its
  /// forces without their energy, which the wire's side reports whole (the penalty and the
  /// friction's Δt·D as functions of both rods), so that the two rods' potentials add up to the
  /// pair's once.
  bool catheter_reports_energy = true;
  /// @brief Copy both rods' positions and velocities into the held states, keeping the edges
  /// each wire vertex is measured against (assigned at the step's start) and wire_weight.
  void sync(const rod::RodSimulator& wire, const rod::RodSimulator& catheter);
  /// @brief The coupling blocks of the pair's Newton matrix, ∂²(E + Δt·D)/∂x_w∂x_c, as the
  /// lower-triangle entries (catheter rows at @p catheter_offset + 4 c, wire columns at 4 i) at
  /// the held states, for the vertices free in each rod (@p wire_free, @p catheter_free: nonzero
  /// where free); Δt = @p dt.
  void cross_matrix(std::vector<Eigen::Triplet<double>>& out, const std::vector<char>& wire_free,
                    const std::vector<char>& catheter_free, int catheter_offset, double dt) const;
  [[nodiscard]] double clearance() const { return clearance_; }
  [[nodiscard]] double stiffness() const { return stiffness_; }
  /// @brief Width δ of the penalty's smoothed onset [m].
  [[nodiscard]] double onset() const { return onset_; }

 private:
  double clearance_;
  double stiffness_;
  double onset_;
  double friction_ = 0.0;
  double slip_speed_ = 1e-4;
};

/// @brief Outcome of a coupled static solve.
struct PairStaticReport {
  bool converged = false;
  int sweeps = 0;           ///< wire + catheter solves
  double correction = 0.0;  ///< last max |catheter change| [m]
  double imbalance = 0.0;   ///< the wire's residual against the final catheter over its tolerance (≤ 1: balanced)
};
/// @brief Static equilibrium of wire and catheter together: block Gauss–Seidel sweeps (wire
/// against the held catheter, then catheter against the held wire), accelerated by the
/// interface quasi-Newton least-squares update on the held catheter (IQN-ILS, Degroote,
/// Bruggeman, Haelterman & Vierendeels 2009), until the catheter moves less than @p tol [m]
/// in a sweep and the wire balances against the catheter as it then is (the pair in
/// equilibrium together, RodSimulator::static_imbalance). Plain sweeps would contract only by 1 − EI/(k L³) per sweep
/// under a stiff lumen penalty; the least-squares update removes those slow modes.
PairStaticReport solve_static_pair(rod::RodSimulator& wire, rod::RodSimulator& catheter, LumenContact& contact,
                                   int max_sweeps = 200, double tol = 1e-9);

/// @brief How well a coupled step balances the pair: the wire's step residual against the
/// catheter's end of step, relative to the wire's force scale (the rod's own Newton converges
/// each body to 1e-8 of it; the pair is held to 1e-5, where the interface force is right to a
/// thousandth of a percent of the load and a step takes a few sweeps, not tens).
inline constexpr double kPairForceTolerance = 1e-5;

/// @brief Outcome of one coupled time step of wire and catheter.
struct PairStepReport {
  int sweeps = 0;            ///< wire + catheter steps taken for this step
  bool converged = false;    ///< the wire's step holds against the catheter's end of step
  double imbalance = 0.0;    ///< the wire's step residual against it over its tolerance
  rod::StepReport wire;      ///< the last wire step
  rod::StepReport catheter;  ///< the last catheter step
};
/// @brief One time step of wire and catheter solved together (implicit in the lumen contact):
/// the wire steps against the catheter's end of step as last estimated, the catheter against
/// that wire; until the wire's step still holds against the catheter as it then is
/// (RodSimulator::step_imbalance within kPairForceTolerance), both are taken again from the
/// step's start (each from its last solution) with the catheter's estimate updated by IQN-ILS
/// as in solve_static_pair, each vertex's correction held within the clearance. At most
/// @p max_sweeps, and no more once three sweeps have not halved the imbalance (a contact set
/// that changes between sweeps leaves no smooth fixed point): such a step is reported
/// unbalanced. With the catheter of the last step held (one sweep, the former staggered
/// scheme) a pair pressed together crept towards its shape by about the penalty's band per
/// step. Implicit Euler only (step_imbalance); with the midpoint rule one sweep per step.
PairStepReport step_pair(rod::RodSimulator& wire, rod::RodSimulator& catheter, LumenContact& contact, double dt,
                         int max_sweeps = 8);

/// @brief One implicit Euler step of wire and catheter as one system: Newton's method on both
/// rods' unknowns at once, the lumen contact's coupling blocks in the matrix (cross_matrix), the
/// unknowns interleaved by arc length so that the joint matrix is a band (factorized by the
/// rods' banded LDLᵀ; a band wider than @p max_band by a sparse LDLᵀ), and a backtracking line
/// search on the sum of the two rods' merits; a step that does not converge is taken again as
/// two halves (the rods' own max_subdivisions). The pair balances to each rod's own tolerance in
/// every converged step, where the block sweeps (step_pair) stopped at 1e-5 of the force scale
/// or not at all.
PairStepReport step_pair_newton(rod::RodSimulator& wire, rod::RodSimulator& catheter, LumenContact& contact, double dt,
                                int max_band = 96);

/// @brief ExternalForce adaptor: one side of a LumenContact.
class LumenContactSide : public rod::ExternalForce {
 public:
  enum class Side { Wire, Catheter };
  LumenContactSide(std::shared_ptr<LumenContact> contact, Side side) : contact_(std::move(contact)), side_(side) {}
  void evaluate(const rod::RodView& rod, rod::ForceAccumulator& out) override {
    if (side_ == Side::Wire)
      contact_->evaluate_wire(rod, out);
    else
      contact_->evaluate_catheter(rod, out);
  }

 private:
  std::shared_ptr<LumenContact> contact_;
  Side side_;
};

}  // namespace flowire::coupling
