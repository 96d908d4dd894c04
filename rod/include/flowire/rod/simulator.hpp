#pragma once
/// @file simulator.hpp
/// @brief The guidewire simulator: a discrete elastic rod stepped implicitly in O(n).
///
/// **Unknowns.** Vertex positions and one twist angle per edge, interleaved
/// (x_0, θ_0, x_1, θ_1, …, x_n): 4n+3 unknowns, Hessian banded with half-width 10.
/// Vertex 0 is the distal tip; the last two vertices are behind the entry point and held
/// by the clamp (their positions and the angle of the edge between them are prescribed).
///
/// **Governing equations.** With M the lumped mass (and edge rotational inertia),
/// E the elastic energy (energies.hpp), f the loads and external forces:
/// - backward Euler: \f$ M (q_{n+1} - q_n - h v_n)/h^2 + \nabla E(q_{n+1}) = f(q_{n+1}, v_{n+1}) \f$,
///   \f$ v_{n+1} = (q_{n+1}-q_n)/h \f$ — stable at any step, damps high frequencies;
/// - implicit midpoint: a backward-Euler solve of h/2 to the midpoint z, then
///   \f$ q_{n+1} = 2z - q_n \f$, \f$ v_{n+1} = 2(z-q_n)/(h/2) - v_n \f$ — second order,
///   no numerical damping (for oscillation studies);
/// - static: \f$ \nabla E(q) = f(q) \f$ (equilibrium), load steps optional.
///
/// Each solve is Newton's method (newton.hpp, `NewtonSolver`; the rod's problem is
/// src/stage.cpp) with a backtracking line search on the incremental
/// potential plus the potential energy external forces report (`add_energy`, e.g. penalty
/// contact); the other loads (dead loads, friction, drag) enter through the trapezoidal
/// work along the search ray. The full step is evaluated with its gradient; shorter trials
/// for the merit only. Loads and external forces are evaluated once per configuration. The matrix is the exact Hessian;
/// where it is indefinite (strong bends far from rest, compressed edges) that iteration uses the Gauss–Newton matrix of
/// the same residual, which is positive semi-definite. Position updates follow the rotation of each edge
/// (`curvilinear_update`) so stiff stretching does not throttle large rotations. Converged when the scaled residual
/// (forces, torques / h) is below `force_tolerance`·F + a round-off floor of the stretching forces (F: a force scale
/// from stiffness and loads), when a full Newton step is below `step_tolerance`·h, or when progress stops within 100×
/// that tolerance (round-off plateau). Anything else is reported in the returned `StepReport` *and* through
/// `flowire::warn` — never silently. Reference frames are re-transported after every accepted update so gradients and
/// Hessians are exact in the time-parallel chart.
///
/// **Clamps.** The base clamp holds the last two vertices on the insertion line and the
/// angle of the edge between them; the clamp vertex owns only the half cell in front of
/// it, which puts the clamp exactly at that vertex and keeps the scheme second order.
/// The clamp vertex is the first grid point at or behind the entry, so while feeding the
/// effective clamp sits up to one segment behind the entry point.
/// `clamp_tip` optionally holds the distal edge too (rods clamped at both ends).
///
/// **Feeding.** `set_insertion_speed` moves the entry point along the wire: grid points
/// that pass the entry are released, new grid points are appended behind it, and points
/// pulled back behind the entry are snapped onto the insertion line and clamped. Only the
/// inserted part plus one clamped edge is simulated.
///
/// **Adaptivity.** With `WireSpec::adapt` enabled, each step (and each round of a static
/// solve) starts with `adapt()`: free edges are split where the wire is bent and merged
/// where it is straight, on a dyadic hierarchy in the material coordinate (model.hpp).
/// Vertices at or behind the entry (after the step's pull-back) stay feeding-grid points,
/// so feeding is unaffected. The state is carried over consistently: a new vertex lies on the cubic
/// Hermite curve through its edge's end points and vertex tangents (on a circular arc this
/// keeps the bending energy to second order; the edge strain changes by O(φ²/32) at turning
/// φ), velocities are interpolated linearly, each new edge's reference frame is the old
/// edge's transported to the new tangent, spin rates carried over, and the material angles
/// are re-swept from the clamp so that every vertex carries the old twist density times its
/// new cell (uniform twist is kept exactly). External forces are told through
/// `ExternalForce::remap`.
///
/// **Allocation.** Every buffer is sized for the whole wire at construction; `step` and
/// `solve_static` do not allocate (the tip trace grows by amortized push_back only).
///
/// Usage:
/// @code
/// flowire::rod::WireSpec spec;  spec.length = 0.5;  spec.youngs_modulus = 5e9;
/// flowire::rod::RodSimulator sim(spec);
/// sim.set_gravity({0, 0, -9.81});
/// sim.set_insertion_speed(0.05);
/// for (int i = 0; i < 100; ++i) { auto r = sim.step(1e-3); if (!r.converged()) ...; }
/// @endcode
#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <functional>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "flowire/rod/banded.hpp"
#include "flowire/rod/drive.hpp"
#include "flowire/rod/energies.hpp"
#include "flowire/rod/external.hpp"
#include "flowire/rod/loads.hpp"
#include "flowire/rod/model.hpp"
#include "flowire/rod/newton.hpp"

namespace flowire::rod {

enum class Integrator { ImplicitEuler, ImplicitMidpoint };

/// @brief "implicit_euler" | "implicit_midpoint" (scene files). @throws flowire::Error (usage).
[[nodiscard]] Integrator parse_integrator(std::string_view name);
[[nodiscard]] const char* to_string(Integrator integrator);

/// @brief What the dynamic steps have cost so far, summed over every step taken with step()
/// (step halvings and force-feed retakes included): the per-step figures a benchmark or a
/// summary reports beside the time.
struct SolverTotals {
  long steps = 0;              ///< calls of step()
  long newton_iterations = 0;  ///< chord iterations included
  long chord_iterations = 0;   ///< iterations that reused a factorization
  long factorizations = 0;     ///< matrix factorizations (Newton iterations that were not chord steps, plus fallbacks)
  long line_search_cuts = 0;
  long subdivided_steps = 0;  ///< steps retaken as halves
  long unconverged_steps = 0;
  void add(const StepReport& r) {
    ++steps;
    newton_iterations += r.newton_iterations;
    chord_iterations += r.chord_iterations;
    factorizations += r.newton_iterations - r.chord_iterations + r.regularizations;
    line_search_cuts += r.line_search_cuts;
    subdivided_steps += r.subdivisions > 0 ? 1 : 0;
    unconverged_steps += r.converged() ? 0 : 1;
  }
};

/// @brief Newton and linear-solver settings.
struct SolverSettings {
  int max_iterations = 30;  ///< per dynamic step
  int max_static_iterations =
      400;                        ///< per static load step (a pseudo-time continuation after a failed Newton included)
  double force_tolerance = 1e-8;  ///< relative to the force scale
  double step_tolerance = 1e-10;  ///< relative to the segment length
  int max_line_search_cuts = 30;
  LinearSolver linear_solver = LinearSolver::Banded;
  Integrator integrator = Integrator::ImplicitEuler;
  int static_load_steps = 1;  ///< loads ramped in this many increments
  /// Newton updates of positions follow the rotation of each edge (lengths changed only to
  /// first order): large rotations are taken in few iterations despite stiff stretching.
  bool curvilinear_update = true;
  /// A step whose solve fails is retaken from its start as two half steps, at most this
  /// many levels deep (dt/2^n); 0 keeps a failed step's last iterate at once.
  int max_subdivisions = 3;
  /// After a full Newton step that cut the residual a thousandfold, the next iteration reuses
  /// that step's factorization (a chord step) instead of a new matrix; it falls back to Newton
  /// when the chord step does not cut the residual tenfold. Same converged states (the same
  /// tolerances), less work per step.
  bool chord_iterations = true;
  /// Implicit Euler's Newton starts from q + h q̇ + h (q̇ − q̇_prev) (the last step's
  /// acceleration held) where the vertex has not moved since that step; else q + h q̇.
  bool second_order_guess = true;
};

/// @brief One sample of the tip trace.
struct TipSample {
  double time = 0.0;
  double inserted_length = 0.0;
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();
};

/// @brief Energies of the current state [J].
struct RodEnergy {
  double kinetic = 0.0;
  double stretching = 0.0;
  double bending_twisting = 0.0;
  [[nodiscard]] double total() const { return kinetic + stretching + bending_twisting; }
};

/// @brief The changing state (sizes in comments; vertex 0 = distal tip).
struct RodState {
  std::vector<Eigen::Vector3d> x;  ///< (n_vertices) positions [m]
  std::vector<Eigen::Vector3d> v;  ///< (n_vertices) velocities [m/s]
  std::vector<double> theta;       ///< (n_edges) material angle w.r.t. reference frame [rad]
  std::vector<double> omega;       ///< (n_edges) dθ/dt [rad/s]
  std::vector<EdgeFrame> frame;    ///< (n_edges) reference frames (time-parallel)
  std::vector<double> ref_twist;   ///< (n_vertices) reference twist (interior vertices)
  std::vector<double> u;           ///< (n_vertices) material coordinate from the tip [m]
  double time = 0.0;               ///< [s]
  double inserted_length = 0.0;    ///< [m] wire length in front of the entry point
  double base_angle = 0.0;         ///< [rad] rotation of the clamp
  [[nodiscard]] int vertex_count() const { return static_cast<int>(x.size()); }
  [[nodiscard]] int edge_count() const { return static_cast<int>(x.size()) - 1; }
};

class RodSimulator {
 public:
  explicit RodSimulator(const WireSpec& spec);
  ~RodSimulator();
  RodSimulator(const RodSimulator&) = delete;
  RodSimulator& operator=(const RodSimulator&) = delete;

  // --- stepping -----------------------------------------------------------------------
  /// @brief Advance by @p dt with the configured integrator.
  StepReport step(double dt);
  /// @brief Equilibrium under the current loads at the current base pose (velocities are
  /// zeroed). Loads (tip force and moment, point forces, gravity; not external forces)
  /// are ramped in `settings().static_load_steps` increments.
  StepReport solve_static();
  /// @brief How far the current state is from static equilibrium under the full loads and
  /// the external forces as they now are: the largest residual force (torques over the rest
  /// length) over the tolerance solve_static() converges to. ≤ 1: in equilibrium. For solvers
  /// that couple this rod to another body (a catheter over a wire) and must know that both
  /// balance together, not only each against the other's last state.
  [[nodiscard]] double static_imbalance();
  /// @brief Keep the current state, and what the next step's initial guess is made from, to
  /// come back to with restore_checkpoint(): for a solver that takes a step of this rod again
  /// from the same start, as one that iterates two bodies within a step does.
  void save_checkpoint();
  /// @p guess_from_current: the state being left becomes the next step's initial guess (a step
  /// taken again with a little changed load starts from the last solution, not the predictor).
  void restore_checkpoint(bool guess_from_current = false);
  /// @brief After an implicit Euler step: the residual of that step's equations at the current
  /// state with the external forces as they now are, over the tolerance the step converged to
  /// (≤ 1: the state solves the step). For a coupled solver that changed another body after
  /// this rod's step and must know whether this rod's step still holds.
  /// @throws flowire::Error (usage) with the implicit midpoint rule or before any step.
  [[nodiscard]] double step_imbalance();

  // --- controls and loads ---------------------------------------------------------------
  void set_integrator(Integrator integrator) { settings_.integrator = integrator; }
  /// @brief Feeding speed [m/s], > 0 pushes in, < 0 pulls back.
  void set_insertion_speed(double speed) { drive_.set_insertion_speed(speed); }
  /// @brief Force-limited feeding: a step that starts with the clamp pushing the wire in
  /// harder than @p force [N] (base_force() along the insertion direction) feeds nothing,
  /// as a force-limited drive or an operator's hand would; 0 (default): no limit.
  void set_max_insertion_force(double force) { drive_.set_max_insertion_force(force); }
  /// @brief Force-driven feeding: the base is pushed along the insertion direction with a
  /// constant force @p force [N] (> 0; 0 returns to the kinematic feed) and the feed of each
  /// step is the one for which the clamp's axial force at the step's end, base_force()·d,
  /// equals it (a quasi-static drive: its own mass and compliance are left out). The wire
  /// then advances at the speed the resisting forces (inertia, damping, drag, friction)
  /// allow, and stops where the wire's axial reaction against an obstacle reaches the force.
  /// Replaces set_insertion_speed while set; rotation_speed still turns the base.
  void set_push_force(double force) { drive_.set_push_force(force); }
  [[nodiscard]] double push_force() const { return drive_.push_force(); }
  /// @brief Feed speed of the last force-driven step [m/s].
  [[nodiscard]] double force_feed_speed() const { return drive_.force_feed_speed(); }
  /// @brief Secant iterations (extra step solves) spent by force-driven feeding so far.
  [[nodiscard]] long force_feed_iterations() const { return drive_.force_feed_iterations(); }
  /// @brief Force-driven steps whose axial force stayed off F by more than the tolerance
  /// (the per-step feed limit of half a segment reached, or the iteration limit).
  [[nodiscard]] long force_feed_unbalanced() const { return drive_.force_feed_unbalanced(); }
  /// @brief Steps in which feeding was held by the force limit.
  [[nodiscard]] long held_steps() const { return drive_.held_steps(); }
  /// @brief Clamp rotation speed, right-handed about the insertion direction [rad/s].
  void set_rotation_speed(double omega) { drive_.set_rotation_speed(omega); }
  /// @brief Set the clamp rotation angle [rad], right-handed about the insertion direction
  /// (takes effect at the next step/solve).
  void set_base_angle(double angle) { drive_.set_base_angle(angle); }
  /// @brief The clamp's drive (feeding and turning rules, what they did).
  [[nodiscard]] const Drive& drive() const { return drive_; }
  /// @brief Dead force on the distal tip vertex [N].
  void set_tip_force(const Eigen::Vector3d& f) { loads_.tip_force.force = f; }
  /// @brief Moment on the distal edge [N m]: the component along the edge twists it, the
  /// rest acts as a force couple on its two vertices.
  void set_tip_moment(const Eigen::Vector3d& m) { loads_.tip_moment.moment = m; }
  /// @brief Gravitational acceleration [m/s²].
  void set_gravity(const Eigen::Vector3d& g) { loads_.gravity.acceleration = g; }
  /// @brief Dead force at arc length s from the entry (shared by the two nearest
  /// vertices). Returns its index.
  int add_point_force(double s, const Eigen::Vector3d& f);
  void clear_point_forces() { loads_.point_forces.points.clear(); }
  /// @brief The loads set above (loads.hpp), each its own object.
  [[nodiscard]] const Loads& loads() const { return loads_; }
  /// @brief Register an external force provider (contact, drag); kept alive by the rod.
  void add_external(std::shared_ptr<ExternalForce> force);
  void clear_externals() { externals_.clear(); }
  /// @brief Hold the distal edge: vertex 0 at @p tip, vertex 1 at @p next (|next − tip|
  /// should be the segment length), its twist angle at the current value. For rods
  /// clamped at both ends (test cases); feeding still works at the base.
  void clamp_tip(const Eigen::Vector3d& tip, const Eigen::Vector3d& next);
  void release_tip() { tip_clamped_ = false; }
  /// @brief Lay the free (inserted) part at rest on a curve: vertex k at @p along(s_k), s_k
  /// its arc length from the entry (e.g. a vessel path from the entry, so a long wire
  /// starts inside the lumen); frames parallel-transported from the clamp, so no twist.
  /// The rest shape of a pre-shaped tip is not applied: it springs back in the first
  /// static solve or steps. Call before add_external().
  void lay_along(const std::function<Eigen::Vector3d(double)>& along);
  [[nodiscard]] bool tip_clamped() const { return tip_clamped_; }
  SolverSettings& settings() { return settings_; }
  [[nodiscard]] const SolverSettings& settings() const { return settings_; }

  // --- results ---------------------------------------------------------------------------
  [[nodiscard]] const RodModel& model() const { return model_; }
  [[nodiscard]] const RodState& state() const { return state_; }
  [[nodiscard]] int vertex_count() const { return state_.vertex_count(); }
  [[nodiscard]] std::span<const Eigen::Vector3d> positions() const { return state_.x; }
  [[nodiscard]] std::span<const Eigen::Vector3d> velocities() const { return state_.v; }
  /// @brief (n_vertices) arc length from the entry point [m]: > 0 inserted, ≤ 0 clamped.
  [[nodiscard]] std::span<const double> arc_lengths() const { return arc_length_; }
  /// @brief Index of the first clamped vertex (the one at or just behind the entry).
  [[nodiscard]] int first_clamped_vertex() const { return first_clamped_; }
  [[nodiscard]] const Eigen::Vector3d& tip_position() const { return state_.x.front(); }
  [[nodiscard]] double inserted_length() const { return state_.inserted_length; }
  [[nodiscard]] double time() const { return state_.time; }
  /// @brief Material frame (m1, m2) of edge j.
  [[nodiscard]] std::pair<Eigen::Vector3d, Eigen::Vector3d> material_frame(int edge) const;
  /// @brief Force the clamp exerts on the wire in the last step/solve [N] (a haptic
  /// device renders its negative).
  [[nodiscard]] const Eigen::Vector3d& base_force() const { return base_force_; }
  /// @brief Torque the clamp exerts on the wire about the entry point [N m].
  [[nodiscard]] const Eigen::Vector3d& base_torque() const { return base_torque_; }
  [[nodiscard]] const StepReport& last_report() const { return last_report_; }
  [[nodiscard]] const NewtonPhaseSeconds& phase_seconds() const { return newton_.phase_seconds(); }
  /// @brief Newton work of the dynamic steps so far (step() calls).
  [[nodiscard]] const SolverTotals& solver_totals() const { return totals_; }
  [[nodiscard]] const std::vector<TipSample>& tip_trace() const { return trace_; }
  [[nodiscard]] RodEnergy energy() const;
  /// @brief max over free edges of |ℓ/ℓ̄ − 1|.
  [[nodiscard]] double max_strain() const;
  /// @brief |Σℓ − Σℓ̄| / Σℓ̄ over all simulated edges.
  [[nodiscard]] double length_drift() const;
  /// @brief Resample the free part (see Adaptivity above); returns true if the vertex set
  /// changed. Called by step() and solve_static(); a no-op unless `WireSpec::adapt` is on.
  bool adapt();
  /// @brief Constants of the simulated vertices and edges (rest lengths, masses, …).
  [[nodiscard]] const Discretization& discretization() const { return disc_; }
  /// @brief (n_vertices) material coordinate of each vertex, distance from the tip [m].
  [[nodiscard]] std::span<const double> material_coordinates() const { return state_.u; }
  /// @brief Vertices added and removed by adaptivity so far.
  [[nodiscard]] long adapt_splits() const { return adapt_splits_; }
  [[nodiscard]] long adapt_merges() const { return adapt_merges_; }
  /// @brief Number of negative eigenvalues of the static Hessian (free unknowns) at the
  /// current state — 0 means the equilibrium is stable.
  [[nodiscard]] int static_hessian_negative_eigenvalues();

  /// @name One implicit Euler step solved together with other bodies
  /// The parts of step() for a solver that takes one Newton iteration over several rods coupled
  /// by external forces that depend on both (coupling/pair_newton.hpp): begin the step, then
  /// per iteration assemble, give the gradient and matrix, try points along a direction and
  /// keep or reject them, and finish. Implicit Euler and kinematic feeding only.
  ///@{
  /// @brief The step's start for a step of @p dt (as step(): feed, predictor, prescribed unknowns).
  void coupled_begin(double dt);
  /// @brief The incremental potential at the current iterate (external potentials included),
  /// its gradient and with @p matrix the Newton matrix (@p psd: the positive semi-definite one).
  double coupled_assemble(bool matrix, bool psd = false);
  /// @brief The residual over its tolerance (≤ 1: this rod's step is solved).
  [[nodiscard]] double coupled_residual() const;
  /// @brief Number of unknowns (4 per vertex, minus one).
  [[nodiscard]] int coupled_dofs() const { return dof_count(); }
  /// @brief −gradient on the free unknowns, 0 on the held ones (the Newton right-hand side).
  void coupled_rhs(Eigen::Ref<Eigen::VectorXd> rhs) const;
  /// @brief The Newton matrix's lower triangle, held unknowns as identity rows, at row and column
  /// @p offset of a larger system.
  void coupled_matrix(std::vector<Eigen::Triplet<double>>& out, int offset) const;
  /// @brief Whether vertex @p k's position is an unknown (not held by the clamp or a tip clamp).
  [[nodiscard]] bool coupled_free_vertex(int k) const;
  /// @brief The vertex velocities of the current iterate, (x − x₀)/Δt (velocities() is the
  /// step's start until coupled_finish).
  void coupled_velocities(std::vector<Eigen::Vector3d>& out) const;
  /// @brief Keep the current iterate as the base of the line search.
  void coupled_accept();
  /// @brief The largest fraction of @p dq the trust region allows (no vertex moves more than half
  /// its shortest edge, no edge turns more than 0.5 rad).
  [[nodiscard]] double coupled_max_step(const Eigen::Ref<const Eigen::VectorXd>& dq) const;
  /// @brief Move to the accepted iterate + @p alpha @p dq (frames transported).
  void coupled_trial(const Eigen::Ref<const Eigen::VectorXd>& dq, double alpha);
  /// @brief The trapezoidal work of the non-conservative external forces from the accepted
  /// iterate to the current one (after an assembly there): the merit is potential − this work.
  [[nodiscard]] double coupled_nonconservative_work() const;
  /// @brief Back to the accepted iterate (its loads kept).
  void coupled_reject();
  /// @brief End the step: velocities, the clamp's reaction (from the last assembly's gradient),
  /// the trace, the externals' end_step, and @p rep counted in solver_totals().
  void coupled_finish(double dt, const StepReport& rep);
  /// @brief Keep / bring back the step's start for taking it again in two halves.
  void coupled_save(int slot) { save_state(slot); }
  void coupled_restore(int slot) { restore_state(slot); }
  ///@}

 private:
  struct Work;
  enum class Mode { Static, Dynamic };

  void build_initial_state(double inserted);
  /// Positions, frames and zero velocities/angles of the rest shape on the current vertices.
  void layout_rest_shape();
  void record_trace_reset();
  /// View of the current state for external forces (dt = 0: between steps).
  RodView current_view(double dt);
  void update_vertex_set(double new_inserted);
  /// The inserted length at the end of a step of @p dt at the feed speed (held at the wire's
  /// ends, with a warning), with the vertex set updated to it.
  double feed_vertex_set(double dt);
  /// Newton's start for an implicit stage of length @p h ending at inserted length @p L and
  /// base angle @p angle, @p fed fed since the step start: the feed predictor, the
  /// prescribed unknowns, the frames carried from the step start, time and arc lengths.
  void start_stage(double L, double angle, double fed, double h);
  void set_prescribed(double inserted, double angle, std::vector<Eigen::Vector3d>& x, std::vector<double>& theta) const;
  void refresh_arc_lengths();
  /// Replace the vertex set by the one at material coordinates @p u_new (a dyadic
  /// refinement/coarsening of the current one), carrying the state over.
  void resample(const std::vector<double>& u_new);
  void predict_feed(double fed, double h);
  StepReport step_at_feed(double dt, double speed);
  StepReport step_force_fed(double dt);
  void vertex_params(int k, VertexParams& p) const;
  /// One solve as a Newton problem (stage.hpp): the incremental potential of a stage of
  /// length h (or the static potential) at a load ramp, for newton_.
  class Stage;
  /// Newton's method (newton.hpp) on that problem: from the current state to a residual within
  /// force_scale(), or the status that stopped it.
  /// @p max_iterations: the limit (< 0: the settings' limit for the mode).
  StepReport newton(Mode mode, double h, double load_scale, int max_iterations = -1);
  /// Back to the step start begin_step() kept: positions, angles, frames, reference twist.
  void rewind_to_step_start();
  /// Max over the free unknowns [first_free, first_fixed) of |force| and |torque| / rest length.
  [[nodiscard]] double residual_norm(int first_free, int first_fixed) const;
  StepReport solve_static_once();
  /// Pseudo-transient continuation to the static equilibrium at @p load_scale from the
  /// current state (stepping.cpp): the fallback of a static Newton solve that failed, within
  /// @p budget Newton iterations (pseudo-steps and static ones together).
  StepReport relax_to_static(double load_scale, int budget);
  /// adapt() with the grid kept over the length a pull-back of @p pull_back moves into the clamp.
  bool adapt_for(double pull_back);
  /// Snapshot the step start (x, v, θ, ω, frames; q0, mass, damping) and move the state to
  /// the inertial prediction q + h·v, with q̂ = that prediction; shared by both integrators.
  void begin_step(double h, bool extrapolate);
  StepReport step_euler(double dt);
  /// The end of an implicit Euler step of @p dt: velocities, the base angle, the predictor's
  /// record, the clamp's reaction.
  void end_euler_step(double dt, double angle_new);
  /// The iterate's positions, angles, frames and reference twists into the accepted slots
  /// the line search moves from (keep_iterate), and back (back_to_kept_iterate).
  void keep_iterate();
  void back_to_kept_iterate();
  /// The state at the accepted iterate + @p alpha @p dq (curvilinear update, frames transported).
  void move_along(const Eigen::Ref<const Eigen::VectorXd>& dq, double alpha);
  StepReport step_once(double dt);
  StepReport step_subdivided(double dt, int depth);
  void save_state(int depth);
  void restore_state(int depth);
  StepReport step_midpoint(double dt);
  void gather(Eigen::Ref<Eigen::VectorXd> q) const;
  void transport_frames_to(const std::vector<Eigen::Vector3d>& x_new, const std::vector<EdgeFrame>& frame_from,
                           const std::vector<double>& twist_from, std::vector<EdgeFrame>& frame_to,
                           std::vector<double>& twist_to) const;
  /// Incremental potential (elastic + inertial + external potential energy) at the
  /// current state; @p reuse_loads keeps the loads and external forces of the previous
  /// assembly (same configuration), so externals are evaluated once per configuration.
  double assemble(Mode mode, double h, double load_scale, Need need, bool psd = false, bool reuse_loads = false);
  void evaluate_loads(Mode mode, double h, double load_scale);
  /// The current configuration as the loads see it.
  [[nodiscard]] LoadSite load_site() const;
  void compute_base_reaction();
  [[nodiscard]] double force_scale(double load_scale) const;
  [[nodiscard]] int dof_count() const { return 4 * state_.vertex_count() - 1; }
  void report(const StepReport& r, const char* what);
  void record_trace();

  RodModel model_;
  RodState state_;
  Discretization disc_;  // constants of the simulated vertices (state_.u)
  long adapt_splits_ = 0, adapt_merges_ = 0;
  SolverSettings settings_;
  long solve_serial_ = 0;  ///< RodView::solve_serial: counts the steps and stages begun
  std::unique_ptr<Work> work_;
  std::vector<double> arc_length_;
  std::vector<std::shared_ptr<ExternalForce>> externals_;
  Loads loads_;  // gravity, tip force, point forces, tip moment
  Eigen::Vector3d base_force_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d base_torque_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d base_d1_ = Eigen::Vector3d::Zero();  // clamp frame at zero rotation
  Eigen::Vector3d base_d2_ = Eigen::Vector3d::Zero();
  Drive drive_;              // feeding and turning at the clamp
  double feed_speed_ = 0.0;  // this step's feeding speed (the drive's, unless held at the wire's end)
  int first_clamped_ = 0;
  bool tip_clamped_ = false;
  Eigen::Vector3d tip_clamp_x0_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d tip_clamp_x1_ = Eigen::Vector3d::Zero();
  double tip_clamp_theta_ = 0.0;
  StepReport last_report_;
  double coupled_angle_ = 0.0;  // the base angle at the end of a coupled step
  double coupled_phi_ = 0.0;    // the potential of the accepted iterate
  NewtonSolver newton_;         // Newton and its line search; the Stage is the problem it solves
  SolverTotals totals_;
  std::vector<TipSample> trace_;
};

}  // namespace flowire::rod
