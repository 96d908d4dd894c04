#pragma once
/// @file spec.hpp
/// @brief What a flow computation is asked to do: model, solver, blood properties and
/// boundary conditions (the `flow:` section of a scene), in SI units.
///
/// Boundary conditions are attached to network nodes. Inlets prescribe a pressure or a
/// flow into the network; outlets prescribe a pressure, a resistance to a distal pressure,
/// or a three-element (RCR) windkessel (proximal resistance, compliance, distal resistance:
/// Westerhof, Lankhaar & Westerhof 2009, "The arterial Windkessel", Med. Biol. Eng. Comput.
/// 47, 131–141). An RCR outlet has state, so it is only dynamic
/// in `Model::Rlc`; the quasi-steady Poiseuille model replaces it by its total
/// resistance Rp + Rd to Pd and reports that with a warning.
#include <array>
#include <cmath>
#include <complex>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "flowire/flow/junction.hpp"
#include "flowire/vessels/network.hpp"

namespace flowire::config {
class Config;
class Schema;
}  // namespace flowire::config

namespace flowire::flow {

using vessels::Network;
using vessels::Vec3;

/// @brief A scalar function of time: constant, the published sine, or a periodic table.
///
/// Sine: \f$ p(t) = \frac{P_1 - P_2}{2}\sin(2\pi t / T) + \frac{P_1 + P_2}{2} \f$ with
/// P1 = `systolic`, P2 = `diastolic`, T = `period` (eq. 5 of the published method).
/// Table: piecewise-linear in `times`/`values`, repeated with period
/// `times.back() - times.front()` when `periodic` (the default), held constant otherwise.
struct Waveform {
  enum class Kind { Constant, Sine, Table };
  Kind kind = Kind::Constant;
  double value = 0.0;                 ///< Constant
  double systolic = 0.0;              ///< Sine: P1
  double diastolic = 0.0;             ///< Sine: P2
  double period = 0.8;                ///< Sine: T (s)
  std::vector<double> times, values;  ///< Table
  bool periodic = true;               ///< Table

  static Waveform constant(double v);
  static Waveform sine(double systolic, double diastolic, double period);
  static Waveform table(std::vector<double> times, std::vector<double> values, bool periodic = true);

  /// @brief Value at time t (allocation-free).
  [[nodiscard]] double operator()(double t) const;
  /// @brief Time average over one period (the value itself for a constant).
  [[nodiscard]] double mean() const;
  /// @brief Period in s, or 0 when the waveform is not periodic.
  [[nodiscard]] double cycle() const;
  [[nodiscard]] bool is_constant() const { return kind == Kind::Constant; }
};

/// @brief Read a table waveform from a CSV file with columns `time,<value>` (one header line).
/// @throws flowire::Error (input) naming the file and line.
Waveform read_waveform_csv(const std::string& path);

struct InletBC {
  enum class Type { Pressure, Flow };
  int node = -1;  ///< network node (default: Network::widest_end())
  Type type = Type::Pressure;
  Waveform waveform;  ///< Pa or m³/s into the network
};

/// @brief Open-loop coronary outlet (Kim et al. 2010, "Patient-specific modeling of blood flow
/// and pressure in human coronary arteries", Ann. Biomed. Eng. 38, 3195–3209): Ra, then Ca to
/// ground, Ram, then Cim against the intramyocardial pressure Pim(t), then Rv to Pv.
struct CoronaryValues {
  double ra = 0.0, ca = 0.0, ram = 0.0, cim = 0.0, rv = 0.0;  ///< Pa·s/m³ and m³/Pa
  Waveform pim;                                               ///< intramyocardial pressure (Pa)
  double pv = 0.0;                                            ///< venous pressure (Pa)
};

/// @brief One outlet's condition: the catalogue every solver reads (boundary.cpp).
///
/// Each kind is the svZeroDSolver boundary block of that name (svzerod/blocks.hpp), where its
/// equations live: `to_svzerod` writes it as such a block (the compliant `rlc` model simulates
/// its windkessels and coronary beds with those very blocks) and `from_svzerod` reads one back.
/// The quasi-steady models see the steady law `steady_resistance()` to `steady_pressure()`;
/// the frequency domain sees `impedance(ω)`. Adding a kind: a Type here, its block class.
struct OutletBC {
  enum class Type { Pressure, Resistance, Rcr, Coronary, Flow };
  int node = -1;
  Type type = Type::Pressure;
  Waveform pressure;                   ///< Pressure: Pa (constant, sine or table)
  Waveform flow;                       ///< Flow: m³/s leaving the network
  double resistance = 0.0;             ///< Resistance: Pa·s/m³
  double distal_pressure = 0.0;        ///< Resistance and Rcr: Pa
  double rp = 0.0, c = 0.0, rd = 0.0;  ///< Rcr: proximal resistance, compliance (m³/Pa), distal resistance
  CoronaryValues coronary;             ///< Coronary
  bool defaulted = false;              ///< expanded from the template for the ends not named (resolve_nodes)

  static OutletBC at_pressure(double p);
  static OutletBC with_resistance(double r, double pd = 0.0);
  static OutletBC rcr(double rp, double c, double rd, double pd = 0.0);

  /// @brief svZeroDSolver's name of the kind: PRESSURE, RESISTANCE, RCR, CORONARY, FLOW.
  [[nodiscard]] std::string_view kind() const;
  /// @brief Whether the outlet has state of its own (a capacitor): RCR with C > 0, CORONARY.
  [[nodiscard]] bool dynamic() const;
  /// @brief The steady law P = R Q + P₀ it obeys at constant flow: R = resistance, Rp + Rd,
  /// Ra + Ram + Rv (Pressure and Flow: 0). @see steady_pressure.
  [[nodiscard]] double steady_resistance() const;
  /// @brief P₀ of the steady law: Pd, Pv (coronary), the pressure's mean (Pressure).
  [[nodiscard]] double steady_pressure() const;
  /// @brief Input impedance P̂/Q̂ at angular frequency ω ≥ 0 (Resistance, Rcr, Coronary; the
  /// distal and intramyocardial pressures held constant): R; Rp + Rd/(1 + iωRdC);
  /// Ra + 1/(iωCa + 1/(Ram + 1/(iωCim + 1/Rv))).
  /// @throws flowire::Error (usage) for Pressure and Flow, which have none.
  [[nodiscard]] std::complex<double> impedance(double omega) const;
  /// @brief The svZeroDSolver boundary condition `{bc_name, bc_type, bc_values}` (SI; a
  /// waveform that is a table or a sine is written over `t`, the sine sampled 128 times a period).
  [[nodiscard]] nlohmann::json to_svzerod(const std::string& name) const;
  /// @brief Read an svZeroDSolver boundary condition (its `bc_type` and `bc_values`, SI as that
  /// JSON is). @throws flowire::Error (input) naming @p where: an unknown or inlet-only type,
  /// a missing or negative value, a value table over time where the catalogue keeps a constant.
  static OutletBC from_svzerod(const nlohmann::json& bc, const std::string& where);
  /// @brief Refuse values no outlet can have: a negative or non-finite resistance, compliance
  /// or pressure, Rp + Rd = 0, a coronary bed without resistance. @throws flowire::Error
  /// (input) naming @p where.
  void check(const std::string& where) const;
};

/// @brief A branch's own vessel wall (`flow.wall.NAME`), in place of the network-wide one.
struct BranchWall {
  int branch = -1;
  double youngs_modulus = 0.0;   ///< Pa
  double thickness = 0.0;        ///< m; > 0: an absolute thickness
  double thickness_ratio = 0.0;  ///< h / r where thickness is 0
};

/// @brief White's ratio of a curved pipe's laminar resistance to the straight pipe's at Dean number
/// @p de (losses.hpp): 1 up to De = 11.6, \f$ [1 - (1 - (11.6/De)^{0.45})^{2.2}]^{-1} \f$ above.
[[nodiscard]] double dean_resistance_ratio(double de);
/// @brief d(dean_resistance_ratio)/dDe.
[[nodiscard]] double dean_resistance_ratio_slope(double de);

/// @brief Shah's incremental pressure drop number K(x⁺) of laminar flow developing from a uniform
/// profile in a circular tube (losses.hpp): the drop from the entrance to x beyond Poiseuille's,
/// over ½ρū², at x⁺ = x/(D Re); 0 at the entrance, 1.25 far downstream.
[[nodiscard]] double shah_incremental_drop(double x_plus);
/// @brief dK/dx⁺ of shah_incremental_drop.
[[nodiscard]] double shah_incremental_drop_slope(double x_plus);

/// @brief A segment's pressure–flow law where it departs from Poiseuille's (a calibration to the
/// 3D solution, calibration.hpp; the losses of losses.hpp):
/// \f$ \Delta p = f R_P Q\,\phi(c|Q|) + K |Q| Q + E(Q) \f$ with R_P the segment's Poiseuille (frustum)
/// resistance, f its `resistance_factor`, K its `quadratic` coefficient (Pa·s²/m⁶: the losses that
/// grow with the square of the flow, a stenosis's expansion, a calibration's junctions and
/// developing flow, in the form of svZeroDSolver's stenosis coefficient), φ White's ratio for a
/// curved segment at the Dean number De = c|Q| (`dean` = c; 0: a straight segment, φ = 1) and E
/// the excess drop of flow still developing after an entrance (Shah's correlation):
/// \f$ E(Q) = \mathrm{sign}(Q)\, k Q^2 [K(c_{far}/|Q|) - K(c_{near}/|Q|)] \f$, k = `entry` = ρ/(2A²)
/// and c = x μπ/(4ρ) at the segment's two ends, x their distances from the entrance (so that
/// c/|Q| = x/(D Re) whatever the radius), taken from `entry_forward` for Q > 0 and from
/// `entry_backward` for Q < 0 (far = 0: no entrance that way).
struct SegmentLaw {
  double resistance_factor = 1.0;          ///< > 0
  double quadratic = 0.0;                  ///< ≥ 0, Pa·s²/m⁶
  double dean = 0.0;                       ///< ≥ 0, s/m³: the Dean number per unit |Q|
  double entry = 0.0;                      ///< ≥ 0, Pa·s²/m⁶: ρ/(2A²) where flow develops after an entrance
  std::array<double, 2> entry_forward{};   ///< m³/s: c at the near and far end for Q > 0
  std::array<double, 2> entry_backward{};  ///< m³/s: the same for Q < 0
  /// @brief Anything beyond the linear law f R_P Q.
  [[nodiscard]] bool nonlinear() const { return quadratic > 0.0 || dean > 0.0 || developing(); }
  /// @brief Flow develops in this segment in some direction.
  [[nodiscard]] bool developing() const { return entry > 0.0 && (entry_forward[1] > 0.0 || entry_backward[1] > 0.0); }
  /// @brief Δp at the flow @p q with the linear resistance @p r (f R_P, times an occlusion's factor).
  [[nodiscard]] double pressure_drop(double q, double r) const {
    const double aq = std::abs(q);
    return r * q * (dean > 0.0 ? dean_resistance_ratio(dean * aq) : 1.0) + quadratic * aq * q +
           (developing() ? entrance_drop(q) : 0.0);
  }
  /// @brief dΔp/dQ at @p q (> 0: the law is increasing).
  [[nodiscard]] double slope(double q, double r) const {
    const double aq = std::abs(q);
    const double phi =
        dean > 0.0 ? dean_resistance_ratio(dean * aq) + dean * aq * dean_resistance_ratio_slope(dean * aq) : 1.0;
    return r * phi + 2.0 * quadratic * aq + (developing() ? entrance_slope(q) : 0.0);
  }
  /// @brief The flow through the segment under the pressure difference @p dp: the root of
  /// pressure_drop(Q) = Δp; straight, \f$ Q = 2\Delta p / (r + \sqrt{r^2 + 4K|\Delta p|}) \f$ (no
  /// cancellation as K → 0); curved or developing, Newton's method within [0, that root] (φ ≥ 1,
  /// E(Q) Q ≥ 0), from @p guess where it lies there (a nearby flow: the last iterate's), else from
  /// the straight root.
  [[nodiscard]] double flow(double dp, double r, double guess = 0.0) const {
    const double q = 2.0 * dp / (r + std::sqrt(r * r + 4.0 * quadratic * std::abs(dp)));
    return dean > 0.0 || developing() ? bracketed_flow(dp, r, q, guess) : q;
  }
  /// @brief dQ/dΔp of `flow`: straight, \f$ 1 / \sqrt{r^2 + 4K|\Delta p|} \f$ (= 1/(r + 2K|Q|)).
  [[nodiscard]] double conductance(double dp, double r) const {
    return dean > 0.0 || developing() ? 1.0 / slope(flow(dp, r), r)
                                      : 1.0 / std::sqrt(r * r + 4.0 * quadratic * std::abs(dp));
  }
  /// @brief E(Q), the developing flow's excess drop.
  [[nodiscard]] double entrance_drop(double q) const;
  /// @brief dE/dQ.
  [[nodiscard]] double entrance_slope(double q) const;

 private:
  [[nodiscard]] double bracketed_flow(double dp, double r, double straight, double guess) const;
};

/// @brief One stenosis the network's radii show (`flow.losses.stenosis`, losses.hpp).
struct Stenosis {
  int branch = -1;
  int throat_node = -1;
  double s = 0.0;                 ///< m, the throat's arc length from the branch's first node
  double throat_radius = 0.0;     ///< m
  double reference_radius = 0.0;  ///< m, the lower shoulder
  double area_reduction = 0.0;    ///< 1 − A_s/A₀
  double coefficient = 0.0;       ///< K, Pa·s²/m⁶
  std::vector<int> segments;      ///< where K is spread (the throat to its distal widening)
};

enum class Model { Poiseuille, Rlc };
enum class SolverKind { Superposition, DenseInverse, Sparse, Petsc };
/// @brief Inertance per segment in the rlc model.
/// Poiseuille: \f$ L = \rho l / (\pi r^2) \f$ (flat profile, the usual 0D choice);
/// Womersley: \f$ L = 4\rho l / (3\pi r^2) \f$, the low-α limit of the impedance of
/// Womersley's solution (J. Physiol. 127, 553–563, 1955), Z = R(1 + iα²/6 + O(α⁴)); with R in
/// series it reproduces the Womersley flow amplitude and phase within about 1–4 % up to α ≈ 4.
enum class Inertance { Poiseuille, Womersley };
/// @brief Velocity profile reported by velocity queries.
/// Laminar: \f$ u(d) = \frac{2Q}{\pi r^2}(1 - d^2/r^2) \f$ (eq. 8 of the published method);
/// Womersley (Womersley 1955, profile.hpp; quasi-steady model,
/// periodic inlets of one period T, sine or table): each segment's flow over one period is
/// split into its mean and its first harmonics Q̂_n (n = 1..10, 128 samples a period); the
/// mean carries the parabola, harmonic n the Womersley profile of α√n, and what the ten
/// harmonics leave of Q(t) the parabola (quasi-steady), so the profile always carries Q(t).
enum class Profile { Laminar, Womersley };

std::string_view to_string(Model m);
std::string_view to_string(SolverKind s);

/// @brief The whole flow problem apart from the network.
struct FlowSpec {
  Model model = Model::Poiseuille;
  SolverKind solver = SolverKind::Superposition;
  double viscosity = 3.5e-3;  ///< Pa·s
  double density = 1060.0;    ///< kg/m³
  std::vector<InletBC> inlets;
  std::vector<OutletBC> outlets;
  Inertance inertance = Inertance::Poiseuille;
  Profile profile = Profile::Laminar;

  /// rlc model: wall compliance of a segment \f$ C = 3\pi r^3 l / (2 E h) \f$ (thin elastic
  /// wall, incompressible), with h = `wall_thickness_ratio`·r; half of it at each end node.
  double wall_youngs_modulus = 0.4e6;    ///< Pa
  double wall_thickness_ratio = 0.1;     ///< h / r
  std::vector<BranchWall> branch_walls;  ///< branches with a wall of their own
  /// (num_segments) each segment's law (`vessels.calibration`), or empty: Poiseuille everywhere.
  /// The factors scale the resistances of every model; a quadratic term makes the quasi-steady
  /// network nonlinear (solved by Newton's method each frame, solver "newton").
  std::vector<SegmentLaw> segment_laws;
  /// The stenoses whose Young–Tsai losses the segment laws hold (`flow.losses.stenosis`, losses.hpp).
  std::vector<Stenosis> stenoses;
  /// The segments with White's law of a bend (`flow.losses.curvature`, losses.hpp).
  int curved_segments = 0;
  /// The branch ends where flow develops again (`flow.losses.entrance`, losses.hpp).
  int entrances = 0;
  /// The junctions whose static pressure changes the unified model gives (`flow.losses.junction`,
  /// junction.hpp); empty: every branch meeting at a node has its pressure.
  std::vector<Junction> junctions;
  /// The segment laws are a calibration in total pressure (flow/calibration.hpp): the nodes hold
  /// p + ½ρū², but for the outlets (static values), and the laws of the segments that end at an
  /// outlet carry its dynamic pressure.
  bool total_pressure = false;
  /// (nodes, or empty) in total pressure, each outlet's kinetic energy factor α (its total is its
  /// static value plus α½ρ(Q/A)²); read by the finite-element comparison
  std::vector<double> end_alpha;
  double dt = 1e-3;                  ///< rlc time step (s)
  double rho_infinity = 0.5;         ///< rlc generalized-α spectral radius (1: trapezoidal-like, 0: most damping)
  double periodic_tolerance = 1e-6;  ///< rlc: relative change between cycles taken as periodic
  int max_cycles = 50;               ///< rlc: cycles run at most when looking for the periodic state

  /// dense_inverse refuses when K and K⁻¹ (2·8·(N+E)² bytes) exceed this many bytes;
  /// 0: half of the machine's physical memory.
  double dense_memory_limit = 0.0;
  /// petsc: preconditioner "gamg" or "hypre"; relative tolerance of CG.
  std::string petsc_pc = "gamg";
  double petsc_rtol = 1e-14;

  /// @brief rlc: the compliance of segment @p s (its branch's own wall, else the network's):
  /// \f$ \int 3\pi r^3 / (2 E h)\,dx \f$ over the segment, r linear between its ends.
  [[nodiscard]] double segment_compliance(const Network& net, int s) const;
  /// @brief The period after which every periodic inlet repeats (the least common multiple of
  /// their periods: T for inlets of T and T/2), or 0 if all are constant.
  [[nodiscard]] double cycle() const;
  /// @brief Whether the network is nonlinear (a segment law's quadratic term, Dean law or entrance, or
  /// a junction's losses).
  [[nodiscard]] bool has_nonlinear_losses() const;
};

/// @brief Inlet at the widest end with `inlet_pressure`, every other end at 0 Pa.
FlowSpec default_spec(const Network& net, const Waveform& inlet_pressure);

/// @brief Fill missing nodes: an inlet without node gets the widest end; the template outlet
/// (node -1, at most one) is copied to every end that is neither an inlet nor given an outlet
/// of its own (an empty list: 0 Pa there).
void resolve_nodes(FlowSpec& spec, const Network& net);

/// @brief Declare the keys of a scene's `flow:` section (type, default, unit, doc): the
/// ones from_config reads, part of the scene's one declaration (coupling::scene_schema).
void declare_scene_keys(config::Schema& schema);

/// @brief Read the `flow:` section of a validated scene (keys as declare_scene_keys declares them).
///
/// Keys: flow.model (poiseuille|rlc), flow.solver (superposition|dense_inverse|sparse|petsc),
/// flow.viscosity, flow.density, flow.inertance (poiseuille|womersley), flow.profile
/// (laminar|womersley), flow.inlet.node, flow.inlet.pressure (number, or section with
/// waveform: constant|sine|table, value, systolic, diastolic, period, file),
/// flow.inlet.flow (number, or the same section), flow.outlets.pressure,
/// flow.outlets.resistance, flow.outlets.distal_pressure, flow.outlets.rcr.{Rp,C,Rd,Pd},
/// flow.wall.youngs_modulus, flow.wall.thickness_ratio, solve.dt (rlc step).
/// The scene is one validated against that declaration (its defaults filled in).
/// @throws flowire::Error (input) naming the key where a value is inconsistent.
FlowSpec from_config(const config::Config& cfg, const Network& net);

}  // namespace flowire::flow
