#pragma once
/// @file simulator.hpp
/// @brief The guidewire simulator: a discrete elastic rod stepped implicitly in O(n).
///
/// A façade over the rod's parts (body.hpp): the `Feeder` (feeder.hpp: the vertex set, the
/// clamps, feeding and adaptive resampling), the `TimeStepper` (stepper.hpp: the integrators,
/// each solve a problem for Newton's method), the `Loads` (loads.hpp) and the registered
/// `ExternalForce`s (external.hpp). Callers talk to it alone; the parts are reachable for
/// those that need one (`feeder()`, `stepper()`).
///
/// **Unknowns.** Vertex positions and one twist angle per edge, interleaved
/// (x_0, θ_0, x_1, θ_1, …, x_n): 4n+3 unknowns, Hessian banded with half-width 10.
/// Vertex 0 is the distal tip; the last two vertices are held by the clamp: the boundary vertex
/// at the entry point and one a segment behind it (their positions and the angle of the edge
/// between them are prescribed).
///
/// Each solve is Newton's method (newton.hpp, `NewtonSolver`; the rod's problem is
/// src/stepper_stage.cpp) with a backtracking line search on the incremental
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
/// The clamp vertex is the material point at the entry whatever the inserted length (its
/// edge's rest length follows the feed, feeder.hpp), so the free wire is exactly as long as
/// the inserted length and the clamp's force changes continuously while feeding.
/// `clamp_tip` optionally holds the distal edge too (rods clamped at both ends).
///
/// **Feeding.** `set_insertion_speed` moves the entry point along the wire: the last free
/// edge (from the last free grid point to the entry) grows and shrinks with the feed, a grid
/// point is inserted on it when it would pass one and a half segments and removed when it
/// would fall below half of one. Only the inserted part plus one clamped edge is simulated.
///
/// **Adaptivity.** With `WireSpec::adapt` enabled, each step (and each round of a static
/// solve) starts with `adapt()`: free edges are split where the wire is bent and merged
/// where it is straight, on a dyadic hierarchy in the material coordinate (model.hpp).
/// The boundary edge follows the level of the edge before it, so feeding inserts points of
/// the level the wire has there. The state is carried over consistently: a new vertex lies on the cubic
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
#include "flowire/rod/body.hpp"
#include "flowire/rod/drive.hpp"
#include "flowire/rod/energies.hpp"
#include "flowire/rod/external.hpp"
#include "flowire/rod/feeder.hpp"
#include "flowire/rod/loads.hpp"
#include "flowire/rod/model.hpp"
#include "flowire/rod/newton.hpp"
#include "flowire/rod/stepper.hpp"

namespace flowire::rod {

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
  void set_integrator(Integrator integrator) { stepper_.settings().integrator = integrator; }
  /// @brief Feeding speed [m/s], > 0 pushes in, < 0 pulls back.
  void set_insertion_speed(double speed) { feeder_.drive().set_insertion_speed(speed); }
  /// @brief Force-limited feeding: a step that starts with the clamp pushing the wire in
  /// harder than @p force [N] (base_force() along the insertion direction) feeds nothing,
  /// as a force-limited drive or an operator's hand would; 0 (default): no limit.
  void set_max_insertion_force(double force) { feeder_.drive().set_max_insertion_force(force); }
  /// @brief Force-driven feeding: the base is pushed along the insertion direction with a
  /// constant force @p force [N] (> 0; 0 returns to the kinematic feed) and the feed of each
  /// step is the one for which the clamp's axial force at the step's end, base_force()·d,
  /// equals it (a quasi-static drive: its own mass and compliance are left out). The wire
  /// then advances at the speed the resisting forces (inertia, damping, drag, friction)
  /// allow, and stops where the wire's axial reaction against an obstacle reaches the force.
  /// Replaces set_insertion_speed while set; rotation_speed still turns the base.
  void set_push_force(double force) { feeder_.drive().set_push_force(force); }
  [[nodiscard]] double push_force() const { return feeder_.drive().push_force(); }
  /// @brief Feed speed of the last force-driven step [m/s].
  [[nodiscard]] double force_feed_speed() const { return feeder_.drive().force_feed_speed(); }
  /// @brief Secant iterations (extra step solves) spent by force-driven feeding so far.
  [[nodiscard]] long force_feed_iterations() const { return feeder_.drive().force_feed_iterations(); }
  /// @brief Force-driven steps whose axial force stayed off F by more than the tolerance
  /// (the per-step feed limit of half a segment reached, or the iteration limit).
  [[nodiscard]] long force_feed_unbalanced() const { return feeder_.drive().force_feed_unbalanced(); }
  /// @brief Steps in which feeding was held by the force limit.
  [[nodiscard]] long held_steps() const { return feeder_.drive().held_steps(); }
  /// @brief Clamp rotation speed, right-handed about the insertion direction [rad/s].
  void set_rotation_speed(double omega) { feeder_.drive().set_rotation_speed(omega); }
  /// @brief Set the clamp rotation angle [rad], right-handed about the insertion direction
  /// (takes effect at the next step/solve).
  void set_base_angle(double angle) { feeder_.drive().set_base_angle(angle); }
  /// @brief The clamp's drive (feeding and turning rules, what they did).
  [[nodiscard]] const Drive& drive() const { return feeder_.drive(); }
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
  void release_tip() { feeder_.release_tip(); }
  /// @brief Lay the free (inserted) part at rest on a curve: vertex k at @p along(s_k), s_k
  /// its arc length from the entry (e.g. a vessel path from the entry, so a long wire
  /// starts inside the lumen); frames parallel-transported from the clamp, so no twist.
  /// The rest shape of a pre-shaped tip is not applied: it springs back in the first
  /// static solve or steps. Call before add_external().
  void lay_along(const std::function<Eigen::Vector3d(double)>& along);
  [[nodiscard]] bool tip_clamped() const { return feeder_.tip_clamped(); }
  SolverSettings& settings() { return stepper_.settings(); }
  [[nodiscard]] const SolverSettings& settings() const { return stepper_.settings(); }

  // --- results ---------------------------------------------------------------------------
  [[nodiscard]] const RodModel& model() const { return body_.model; }
  [[nodiscard]] const RodState& state() const { return body_.state; }
  [[nodiscard]] int vertex_count() const { return body_.state.vertex_count(); }
  [[nodiscard]] std::span<const Eigen::Vector3d> positions() const { return body_.state.x; }
  [[nodiscard]] std::span<const Eigen::Vector3d> velocities() const { return body_.state.v; }
  /// @brief (n_vertices) arc length from the entry point [m]: > 0 inserted, ≤ 0 clamped.
  [[nodiscard]] std::span<const double> arc_lengths() const { return feeder_.arc_lengths(); }
  /// @brief Index of the first clamped vertex (the boundary vertex, at the entry).
  [[nodiscard]] int first_clamped_vertex() const { return feeder_.first_clamped(); }
  [[nodiscard]] const Eigen::Vector3d& tip_position() const { return body_.state.x.front(); }
  [[nodiscard]] double inserted_length() const { return body_.state.inserted_length; }
  [[nodiscard]] double time() const { return body_.state.time; }
  /// @brief Material frame (m1, m2) of edge j.
  [[nodiscard]] std::pair<Eigen::Vector3d, Eigen::Vector3d> material_frame(int edge) const;
  /// @brief Force the clamp exerts on the wire in the last step/solve [N] (a haptic
  /// device renders its negative).
  [[nodiscard]] const Eigen::Vector3d& base_force() const { return stepper_.base_force(); }
  /// @brief Torque the clamp exerts on the wire about the entry point [N m].
  [[nodiscard]] const Eigen::Vector3d& base_torque() const { return stepper_.base_torque(); }
  [[nodiscard]] const StepReport& last_report() const { return stepper_.last_report(); }
  [[nodiscard]] const NewtonPhaseSeconds& phase_seconds() const { return stepper_.phase_seconds(); }
  /// @brief Newton work of the dynamic steps so far (step() calls).
  [[nodiscard]] const SolverTotals& solver_totals() const { return stepper_.totals(); }
  [[nodiscard]] const std::vector<TipSample>& tip_trace() const { return stepper_.trace(); }
  [[nodiscard]] RodEnergy energy() const;
  /// @brief max over free edges of |ℓ/ℓ̄ − 1|.
  [[nodiscard]] double max_strain() const;
  /// @brief |Σℓ − Σℓ̄| / Σℓ̄ over all simulated edges.
  [[nodiscard]] double length_drift() const;
  /// @brief Resample the free part (see Adaptivity above); returns true if the vertex set
  /// changed. Called by step() and solve_static(); a no-op unless `WireSpec::adapt` is on.
  bool adapt();
  /// @brief Constants of the simulated vertices and edges (rest lengths, masses, …).
  [[nodiscard]] const Discretization& discretization() const { return body_.disc; }
  /// @brief (n_vertices) material coordinate of each vertex, distance from the tip [m].
  [[nodiscard]] std::span<const double> material_coordinates() const { return body_.state.u; }
  /// @brief Vertices added and removed by adaptivity so far.
  [[nodiscard]] long adapt_splits() const { return feeder_.adapt_splits(); }
  [[nodiscard]] long adapt_merges() const { return feeder_.adapt_merges(); }
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
  void coupled_begin(double dt) { stepper_.coupled_begin(dt); }
  /// @brief The incremental potential at the current iterate (external potentials included),
  /// its gradient and with @p matrix the Newton matrix (@p psd: the positive semi-definite one).
  double coupled_assemble(bool matrix, bool psd = false) { return stepper_.coupled_assemble(matrix, psd); }
  /// @brief The residual over its tolerance (≤ 1: this rod's step is solved).
  [[nodiscard]] double coupled_residual() const { return stepper_.coupled_residual(); }
  /// @brief Number of unknowns (4 per vertex, minus one).
  [[nodiscard]] int coupled_dofs() const { return stepper_.dof_count(); }
  /// @brief −gradient on the free unknowns, 0 on the held ones (the Newton right-hand side).
  void coupled_rhs(Eigen::Ref<Eigen::VectorXd> rhs) const { stepper_.coupled_rhs(rhs); }
  /// @brief The Newton matrix's lower triangle, held unknowns as identity rows, at row and column
  /// @p offset of a larger system.
  void coupled_matrix(std::vector<Eigen::Triplet<double>>& out, int offset) const {
    stepper_.coupled_matrix(out, offset);
  }
  /// @brief Whether vertex @p k's position is an unknown (not held by the clamp or a tip clamp).
  [[nodiscard]] bool coupled_free_vertex(int k) const { return feeder_.free_vertex(k); }
  /// @brief The vertex velocities of the current iterate, (x − x₀)/Δt (velocities() is the
  /// step's start until coupled_finish).
  void coupled_velocities(std::vector<Eigen::Vector3d>& out) const { stepper_.coupled_velocities(out); }
  /// @brief Keep the current iterate as the base of the line search.
  void coupled_accept() { stepper_.coupled_accept(); }
  /// @brief The largest fraction of @p dq the trust region allows (no vertex moves more than half
  /// its shortest edge, no edge turns more than 0.5 rad).
  [[nodiscard]] double coupled_max_step(const Eigen::Ref<const Eigen::VectorXd>& dq) const {
    return stepper_.coupled_max_step(dq);
  }
  /// @brief Move to the accepted iterate + @p alpha @p dq (frames transported).
  void coupled_trial(const Eigen::Ref<const Eigen::VectorXd>& dq, double alpha) { stepper_.coupled_trial(dq, alpha); }
  /// @brief The trapezoidal work of the non-conservative external forces from the accepted
  /// iterate to the current one (after an assembly there): the merit is potential − this work.
  [[nodiscard]] double coupled_nonconservative_work() const { return stepper_.coupled_nonconservative_work(); }
  /// @brief Back to the accepted iterate (its loads kept).
  void coupled_reject() { stepper_.coupled_reject(); }
  /// @brief End the step: velocities, the clamp's reaction (from the last assembly's gradient),
  /// the trace, the externals' end_step, and @p rep counted in solver_totals().
  void coupled_finish(double dt, const StepReport& rep) { stepper_.coupled_finish(dt, rep); }
  /// @brief Keep / bring back the step's start for taking it again in two halves.
  void coupled_save(int slot) { stepper_.save_state(slot); }
  void coupled_restore(int slot) { stepper_.restore_state(slot); }
  ///@}

  /// @name The parts (for callers that need one: a test of a part, a solver over several rods)
  ///@{
  [[nodiscard]] const Feeder& feeder() const { return feeder_; }
  [[nodiscard]] TimeStepper& stepper() { return stepper_; }
  [[nodiscard]] const TimeStepper& stepper() const { return stepper_; }
  ///@}

 private:
  RodBody body_;  // the model, the state and the simulated vertices' constants
  Loads loads_;   // gravity, tip force, point forces, tip moment
  ExternalForces externals_;
  Feeder feeder_;        // the vertex set, the clamps, feeding, adaptive resampling
  TimeStepper stepper_;  // the integrators and their solves
};

}  // namespace flowire::rod
