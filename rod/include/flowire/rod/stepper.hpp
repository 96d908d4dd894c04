#pragma once
/// @file stepper.hpp
/// @brief The rod's time stepper: one step (or the static equilibrium) of the free unknowns.
///
/// **Governing equations.** With M the lumped mass (and edge rotational inertia),
/// E the elastic energy (energies.hpp), f the loads and external forces:
/// - backward Euler: \f$ M (q_{n+1} - q_n - h v_n)/h^2 + \nabla E(q_{n+1}) = f(q_{n+1}, v_{n+1}) \f$,
///   \f$ v_{n+1} = (q_{n+1}-q_n)/h \f$ — stable at any step, damps high frequencies;
/// - implicit midpoint: a backward-Euler solve of h/2 to the midpoint z, then
///   \f$ q_{n+1} = 2z - q_n \f$, \f$ v_{n+1} = 2(z-q_n)/(h/2) - v_n \f$ — second order,
///   no numerical damping (for oscillation studies);
/// - static: \f$ \nabla E(q) = f(q) \f$ (equilibrium), load steps optional, a pseudo-transient
///   continuation where Newton from the start fails.
///
/// Each solve is a problem for Newton's method (newton.hpp; the rod's problem, the `Stage`, is
/// src/stepper_stage.cpp): the incremental potential plus the potential energy the external
/// forces report, the other loads by their trapezoidal work along the search ray. A failed step
/// is taken again as two halves (`SolverSettings::max_subdivisions`). The stepper asks the
/// `Feeder` (feeder.hpp) for the step's vertex set, held unknowns and feed predictor, the
/// `Loads` and the `ExternalForce`s for the forces; it owns the work buffers, sized once.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string_view>
#include <vector>

#include "flowire/rod/banded.hpp"
#include "flowire/rod/body.hpp"
#include "flowire/rod/external.hpp"
#include "flowire/rod/feeder.hpp"
#include "flowire/rod/loads.hpp"
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
  /// While the wire is fed (or was the step before), implicit Euler's Newton may also start
  /// from the wire's path extrapolated in time at each place along it (Feeder::predict_slide):
  /// where the last step was as long and left the wire where it is, from whichever of that and
  /// the guesses above came closer to the last step's solution.
  bool slide_guess = true;
};

/// @brief The external forces on a rod, shared by the simulator and its stepper.
using ExternalForces = std::vector<std::shared_ptr<ExternalForce>>;

class TimeStepper {
 public:
  /// The body, its feeder, its loads and external forces are kept by reference.
  TimeStepper(RodBody& body, Feeder& feeder, const Loads& loads, const ExternalForces& externals);
  ~TimeStepper();
  TimeStepper(const TimeStepper&) = delete;
  TimeStepper& operator=(const TimeStepper&) = delete;

  /// @brief Advance by @p dt with the configured integrator (feeding and adaptivity included);
  /// counted in totals(), a failure warned.
  StepReport step(double dt);
  /// @brief Equilibrium under the loads at the current base pose (velocities zeroed).
  StepReport solve_static();
  /// @brief The static residual at the current state over its tolerance (≤ 1: in equilibrium).
  [[nodiscard]] double static_imbalance();
  /// @brief The last implicit Euler step's residual at the current state over its tolerance.
  [[nodiscard]] double step_imbalance();
  void save_checkpoint();
  void restore_checkpoint(bool guess_from_current);
  /// @brief The feeder's adapt, the external forces told of the new vertices.
  bool adapt();
  /// @brief Negative eigenvalues of the static Hessian on the free unknowns.
  [[nodiscard]] int static_hessian_negative_eigenvalues();
  /// @brief What the external forces see of the current state (dt = 0: between steps).
  RodView current_view(double dt);

  SolverSettings& settings() { return settings_; }
  [[nodiscard]] const SolverSettings& settings() const { return settings_; }
  [[nodiscard]] const SolverTotals& totals() const { return totals_; }
  [[nodiscard]] const StepReport& last_report() const { return last_report_; }
  [[nodiscard]] const NewtonPhaseSeconds& phase_seconds() const { return newton_.phase_seconds(); }
  /// @brief The clamp's force and torque on the wire in the last step or solve.
  [[nodiscard]] const Eigen::Vector3d& base_force() const { return base_force_; }
  [[nodiscard]] const Eigen::Vector3d& base_torque() const { return base_torque_; }
  [[nodiscard]] const std::vector<TipSample>& trace() const { return trace_; }
  /// @brief The trace restarted at the current state (after a new layout).
  void reset_trace();

  /// @name One implicit Euler step solved together with other bodies (simulator.hpp)
  ///@{
  void coupled_begin(double dt);
  double coupled_assemble(bool matrix, bool psd);
  [[nodiscard]] double coupled_residual() const;
  [[nodiscard]] int dof_count() const { return 4 * body_.state.vertex_count() - 1; }
  void coupled_rhs(Eigen::Ref<Eigen::VectorXd> rhs) const;
  void coupled_matrix(std::vector<Eigen::Triplet<double>>& out, int offset) const;
  void coupled_velocities(std::vector<Eigen::Vector3d>& out) const;
  void coupled_accept();
  [[nodiscard]] double coupled_max_step(const Eigen::Ref<const Eigen::VectorXd>& dq) const;
  void coupled_trial(const Eigen::Ref<const Eigen::VectorXd>& dq, double alpha);
  [[nodiscard]] double coupled_nonconservative_work() const;
  void coupled_reject();
  void coupled_finish(double dt, const StepReport& rep);
  void save_state(int slot);
  void restore_state(int slot);
  ///@}

 private:
  struct Work;
  enum class Mode { Static, Dynamic };
  class Stage;

  StepReport step_subdivided(double dt, int depth);
  StepReport step_once(double dt);
  StepReport step_at_feed(double dt, double speed);
  StepReport step_force_fed(double dt);
  /// Snapshot the step start (x, v, θ, ω, frames; q0, mass, damping) and move the state to
  /// the inertial prediction q + h·v, with q̂ = that prediction; shared by both integrators.
  void begin_step(double h, bool extrapolate);
  /// Newton's start for an implicit stage of length @p h ending at inserted length @p L and
  /// base angle @p angle, @p fed fed since the step start: the feed predictor, the
  /// prescribed unknowns, the frames carried from the step start, time and arc lengths.
  void start_stage(double L, double angle, double fed, double h);
  /// Newton's start for an implicit Euler step of @p dt to inserted length @p L_new and base
  /// angle @p angle_new (the vertex set already fed): begin_step, the slide (if @p may_slide) or
  /// feed predictor, start_stage.
  void begin_euler_step(double dt, double L_new, double angle_new, bool may_slide);
  StepReport step_euler(double dt);
  /// The end of an implicit Euler step of @p dt: velocities, the base angle, the predictors'
  /// record (how far each guess was, if the step @p converged), the clamp's reaction.
  void end_euler_step(double dt, double angle_new, bool converged);
  StepReport step_midpoint(double dt);
  StepReport solve_static_once();
  /// Pseudo-transient continuation to the static equilibrium at @p load_scale from the
  /// current state: the fallback of a static Newton solve that failed, within @p budget
  /// Newton iterations (pseudo-steps and static ones together).
  StepReport relax_to_static(double load_scale, int budget);
  /// Back to the step start begin_step() kept: positions, angles, frames, reference twist.
  void rewind_to_step_start();
  /// Newton's method on the Stage: from the current state to a residual within force_scale(),
  /// or the status that stopped it. @p max_iterations < 0: the settings' limit for the mode.
  StepReport newton(Mode mode, double h, double load_scale, int max_iterations = -1);
  /// Max over the free unknowns [first_free, first_fixed) of |force| and |torque| / rest length.
  [[nodiscard]] double residual_norm(int first_free, int first_fixed) const;
  /// The iterate's positions, angles, frames and reference twists into the accepted slots
  /// the line search moves from (keep_iterate), and back (back_to_kept_iterate).
  void keep_iterate();
  void back_to_kept_iterate();
  /// The state at the accepted iterate + @p alpha @p dq (curvilinear update, frames transported).
  void move_along(const Eigen::Ref<const Eigen::VectorXd>& dq, double alpha);
  void gather(Eigen::Ref<Eigen::VectorXd> q) const;
  /// Incremental potential (elastic + inertial + external potential energy) at the
  /// current state; @p reuse_loads keeps the loads and external forces of the previous
  /// assembly (same configuration), so externals are evaluated once per configuration.
  double assemble(Mode mode, double h, double load_scale, Need need, bool psd = false, bool reuse_loads = false);
  void evaluate_loads(Mode mode, double h, double load_scale);
  [[nodiscard]] LoadSite load_site() const;
  void compute_base_reaction();
  [[nodiscard]] double force_scale(double load_scale) const;
  void report(const StepReport& r, const char* what);
  void record_trace();

  RodBody& body_;
  Feeder& feeder_;
  const Loads& loads_;
  const ExternalForces& externals_;
  std::unique_ptr<Work> work_;
  SolverSettings settings_;
  NewtonSolver newton_;  // Newton and its line search; the Stage is the problem it solves
  SolverTotals totals_;
  StepReport last_report_;
  long solve_serial_ = 0;  ///< RodView::solve_serial: counts the steps and stages begun
  Eigen::Vector3d base_force_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d base_torque_ = Eigen::Vector3d::Zero();
  double coupled_angle_ = 0.0;  // the base angle at the end of a coupled step
  std::vector<TipSample> trace_;
};

}  // namespace flowire::rod
