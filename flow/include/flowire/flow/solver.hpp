#pragma once
/// @file solver.hpp
/// @brief Network flow solvers behind one interface.
///
/// A solver is created once for a network and a FlowSpec (`make_solver`): this assembles
/// the system and does the expensive part (factorization, inverse, per-source solves).
/// Then `advance(t)` moves it to time t (a frame) and the accessors read the state at
/// that time. The network must outlive the solver.
///
/// Quasi-steady Poiseuille model (the published method): every segment obeys
/// \f$ Q_s = (p_{from} - p_{to}) / R_s \f$ with \f$ R_s = 8\eta l_s / (\pi r_s^4) \f$ (its eq. 1,
/// the Hagen–Poiseuille law) and mass is conserved at every node (its eq. 3, AQ = 0); the
/// state at t depends only on the boundary values at t.
/// - `dense_inverse`: the published system \f$ K [Q; P] = [b; p_{source}(t)] \f$ (its eq. 6),
///   K = [A 0; C −Aᵀ] of size N+E, inverted densely once and multiplied every frame (eq. 7).
/// - `superposition`: the nodal conductance system G p = b factored once with CHOLMOD,
///   solved once per independent boundary source k; a frame is
///   \f$ p(t) = \sum_k f_k(t)\, p_k \f$ and only the nodes/segments asked for are evaluated.
/// - `sparse`: the nodal system factored once (Eigen SimplicialLDLT, independent of
///   CHOLMOD) and solved for the full right-hand side every frame (reference).
/// - `petsc`: the nodal system distributed with PETSc (KSPCG + GAMG or hypre), solved once
///   per source like superposition; every MPI rank ends with the whole answer.
/// - `newton` (chosen when a segment law has a quadratic term, FlowSpec::segment_laws):
///   Δp = R Q + K|Q|Q per segment, Newton's method on the node balances every frame, the
///   tangent conductance matrix refactored by CHOLMOD on the pattern analysed once.
/// Model::Rlc: segments also carry inertance and nodes compliance; `advance` integrates
/// in time (see rlc.hpp); it has its own sparse LU and ignores `spec.solver`.
#include <chrono>
#include <complex>
#include <map>
#include <memory>
#include <span>
#include <string>

#include "flowire/flow/profile.hpp"
#include "flowire/flow/spec.hpp"

namespace flowire::flow {

/// @brief Derived quantities of one segment at the solver's current time.
struct SegmentState {
  double flow_rate = 0.0;          ///< m³/s, positive from node_from to node_to
  double pressure_from = 0.0;      ///< Pa
  double pressure_to = 0.0;        ///< Pa
  double mean_velocity = 0.0;      ///< m/s, Q/(πr²), signed like Q
  double wall_shear_stress = 0.0;  ///< Pa, 4η|Q|/(πr³) (Poiseuille)
  double reynolds = 0.0;           ///< ρ|v̄|2r/η
  double womersley = 0.0;          ///< r·sqrt(ωρ/η) at the spec's cycle, 0 if steady
};

/// @brief What a body lying in a segment (a guidewire) does to the segment's flow; the
/// coupling computes it (coupling/occlusion.hpp) from the annular flow around the wire
/// (annulus.hpp). The default value is an empty segment.
struct SegmentOcclusion {
  double occupied_fraction = 0.0;  ///< occupied axial length / segment length, in [0, 1]
  /// resistance now / the empty rigid segment's: ≥ 1 with a body in it, < 1 where a wall that
  /// yields has widened it (coupling: wall.flow_radii), > 0
  double resistance_factor = 1.0;
  double inertance_factor = 1.0;  ///< inertance now / the empty rigid segment's, > 0 (flow.model: rlc)
  /// pressure gradient where the body lies / the empty tube's at equal flow (≥ 1): the
  /// undisturbed velocity that the drag law sees there is the empty tube's profile under
  /// that gradient
  double gradient_factor = 1.0;
};

/// @brief Seconds spent per phase of a solver's life.
struct SolverTimings {
  double assemble = 0.0;  ///< building the matrices
  double factor = 0.0;    ///< factorization / inverse / per-source solves / periodic search
  double frames = 0.0;    ///< accumulated time in advance()
  long frame_count = 0;
  double occlusion = 0.0;      ///< refactorizations and re-solves after set_occlusion
  long occlusion_updates = 0;  ///< set_occlusion calls that changed a resistance or inertance
  long harmonic_updates = 0;   ///< Womersley profile: periods resampled after an occlusion changed
};

class FlowSolver {
 public:
  virtual ~FlowSolver() = default;
  FlowSolver(const FlowSolver&) = delete;
  FlowSolver& operator=(const FlowSolver&) = delete;

  /// @brief Move to time t (s): quasi-steady models evaluate the boundary values at t;
  /// the rlc model integrates from the current time to t.
  void advance(double t);
  /// @brief advance(t), then fill the full pressure and flow arrays.
  void solve_at(double t, std::span<double> node_pressures, std::span<double> segment_flows);
  /// @brief Current time.
  [[nodiscard]] double time() const { return time_; }

  [[nodiscard]] virtual double node_pressure(int node) const = 0;
  [[nodiscard]] virtual double segment_flow(int segment) const;
  /// @brief Flow of a segment at time t without moving the solver (quasi-steady models:
  /// any t; rlc: linear between the last two steps, clamped to them).
  [[nodiscard]] virtual double segment_flow_at(int segment, double t) const = 0;
  /// @brief All node pressures (size num_nodes) / segment flows (size num_segments).
  virtual void node_pressures(std::span<double> out) const;
  virtual void segment_flows(std::span<double> out) const;

  [[nodiscard]] SegmentState segment_state(int segment) const;
  /// @brief Axial blood velocity (m/s, along node_from→node_to) at world point `p`, which
  /// the caller has located in `segment`; 0 outside the lumen. Allocation-free.
  [[nodiscard]] double axial_velocity_at(int segment, const Vec3& p) const;
  [[nodiscard]] double axial_velocity_at(int segment, const Vec3& p, double t) const;
  /// @brief The velocity vector: axial_velocity_at times the unit axis.
  [[nodiscard]] Vec3 velocity_at(int segment, const Vec3& p) const;
  [[nodiscard]] Vec3 velocity_at(int segment, const Vec3& p, double t) const;

  /// @brief Linear resistance of each segment without occlusion (Pa·s/m³): Poiseuille's, times the
  /// segment law's factor where the spec has one (FlowSpec::segment_laws).
  [[nodiscard]] double resistance(int segment) const { return resistance_[static_cast<size_t>(segment)]; }
  /// @brief The resistance with the segment's occlusion, resistance × resistance_factor.
  [[nodiscard]] double effective_resistance(int segment) const {
    return occlusion_.empty() ? resistance(segment)
                              : resistance(segment) * occlusion_[static_cast<size_t>(segment)].resistance_factor;
  }

  /// @brief Whether set_occlusion is available: superposition, sparse and rlc; the
  /// dense_inverse (the published fixed K⁻¹) and petsc solvers keep their matrix.
  [[nodiscard]] virtual bool supports_occlusion() const { return false; }
  /// @brief Set every segment's occlusion (size num_segments). Quasi-steady solvers
  /// refactor the nodal system (the symbolic analysis is kept) and re-solve their source
  /// responses, so the state at the current time is that of the new resistances; rlc
  /// refactors its step matrix and integrates on from its current state. Nothing is redone
  /// when no resistance or inertance factor changed.
  /// @throws flowire::Error (usage) if the size is wrong, a factor is below 1 or not
  /// finite, or the solver does not support occlusion.
  void set_occlusion(std::span<const SegmentOcclusion> occlusion);
  /// @brief The occlusion of every segment; empty until set_occlusion is called.
  [[nodiscard]] std::span<const SegmentOcclusion> occlusion() const { return occlusion_; }
  [[nodiscard]] const Network& network() const { return net_; }
  [[nodiscard]] const FlowSpec& spec() const { return spec_; }
  [[nodiscard]] const SolverTimings& timings() const { return timings_; }
  [[nodiscard]] virtual std::string_view name() const = 0;

 protected:
  FlowSolver(const Network& net, FlowSpec spec);
  /// Move the state to time t.
  virtual void do_advance(double t) = 0;
  /// Rebuild after occlusion_ changed (resistance or inertance factors).
  virtual void apply_occlusion() {}
  /// The flow harmonics of every segment for the Womersley profile (harmonic_); the
  /// default samples segment_flow_at over one period.
  virtual void compute_harmonics();
  /// Whether the occlusion moved past harmonics_occlusion_tolerance_ since the harmonics were sampled.
  [[nodiscard]] bool harmonics_stale() const;
  /// Drop harmonics below 1e-9 of `scale[s]` (a harmonic the waveform does not have).
  void drop_negligible_harmonics(std::span<const double> scale);
  /// Axial velocity given the segment, squared distance ratio d²/r² and time.
  [[nodiscard]] double profile_velocity(int segment, double rho2, double t) const;

  friend std::unique_ptr<FlowSolver> make_solver(const Network&, FlowSpec);
  /// Womersley profile: the first harmonics of every segment's flow over one period
  /// (quasi-steady model with periodic sources of one period); otherwise the laminar profile.
  void prepare_profile();
  static constexpr int kHarmonics = 10;          ///< harmonics with their own Womersley profile
  static constexpr int kSamplesPerPeriod = 128;  ///< samples of Q(t) for the harmonics

  const Network& net_;
  FlowSpec spec_;
  std::vector<Vec3> axis_;  // (num_segments) unit axis node_from -> node_to
  /// (num_segments × kHarmonics) Q̂_n of each segment, Q(t) ≈ Q̄ + Σ Re[Q̂_n e^{inωt}];
  /// empty unless the Womersley profile is on
  std::vector<std::complex<double>> harmonic_;
  /// (num_segments × kHarmonics) the Womersley shape of α√n, tabulated the first time a
  /// velocity in that segment is asked for; null until then and for a negligible harmonic
  mutable std::vector<std::shared_ptr<const WomersleyShape>> shape_;
  mutable std::map<double, std::shared_ptr<const WomersleyShape>> shape_by_alpha_;  ///< shared by equal α
  std::vector<double> resistance_;                                                  // (num_segments) without occlusion
  std::vector<SegmentOcclusion> occlusion_;  // (num_segments) or empty: no occlusion set
  /// Womersley profile: the occlusion's factors may move by this fraction of those the harmonics
  /// were sampled with before a period is resampled (0: at every change; a nonlinear network,
  /// whose period is 128 Newton solves, sets 1%: the profile still carries the current Q(t),
  /// only its split among the harmonics lags)
  double harmonics_occlusion_tolerance_ = 0.0;
  std::vector<SegmentOcclusion> harmonics_occlusion_;  // the occlusion the harmonics were sampled with
  double time_ = 0.0;
  double omega_ = 0.0;  // angular frequency of the spec's cycle
  SolverTimings timings_;
};

/// @brief Create the solver chosen by spec.solver / spec.model. Missing BC nodes are
/// resolved (resolve_nodes) first.
/// @throws flowire::Error: input (bad BC, dense_inverse too large, petsc not built),
/// numerical (a piece of the network without a pressure reference, singular matrix).
std::unique_ptr<FlowSolver> make_solver(const Network& net, FlowSpec spec);

/// @brief Finalize PETSc if the petsc solver initialized it (it also runs at exit). A
/// program that calls MPI_Init itself calls this before MPI_Finalize. No-op without PETSc.
void finalize_petsc();

/// @brief Poiseuille resistance \f$ R = 8\eta l/(\pi r^4) \f$: the Hagen–Poiseuille law of
/// steady laminar flow of a Newtonian fluid in a rigid circular tube (Bird, Stewart &
/// Lightfoot, Transport Phenomena, §2.3; eq. 1 of the published method).
[[nodiscard]] inline double poiseuille_resistance(double viscosity, double length, double radius) {
  constexpr double pi = 3.14159265358979323846;
  return 8.0 * viscosity * length / (pi * radius * radius * radius * radius);
}

/// @brief Poiseuille resistance of a conical frustum whose radius runs linearly from r1 to
/// r2 over the length l, the integral of 8η/(π r(x)⁴) along it (the Hagen–Poiseuille law
/// in every cross-section: the lubrication approximation of a slowly tapering tube):
/// \f[ R = \frac{8\eta l\,(r_1^2 + r_1 r_2 + r_2^2)}{3\pi r_1^3 r_2^3} \f]
/// (equal to `poiseuille_resistance` when r1 = r2; the mean radius would underestimate it).
[[nodiscard]] inline double frustum_resistance(double viscosity, double length, double r1, double r2) {
  constexpr double pi = 3.14159265358979323846;
  return 8.0 * viscosity * length * (r1 * r1 + r1 * r2 + r2 * r2) / (3.0 * pi * r1 * r1 * r1 * r2 * r2 * r2);
}

/// @brief The resistance of a network segment: the frustum between its end radii, times its
/// sections' shape factor (Segment::shape: 1 for circles).
[[nodiscard]] inline double segment_resistance(double viscosity, const vessels::Segment& seg) {
  return seg.shape * frustum_resistance(viscosity, seg.length, seg.radius_from, seg.radius_to);
}

/// @brief Wall-clock helper for timings.
class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  [[nodiscard]] double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace flowire::flow
