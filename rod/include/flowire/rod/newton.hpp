#pragma once
/// @file newton.hpp
/// @brief Newton's method with a backtracking line search, for a problem that minimizes a
/// merit over unknowns of which one contiguous range is free (the rest held): the rod's implicit
/// steps and static solves (RodSimulator implements `NewtonProblem` for each), or any other body
/// stepped the same way.
///
/// Each iteration: the residual against the tolerance; a direction from the problem's banded
/// matrix (LDLᵀ; the positive semi-definite matrix of the same residual where it is indefinite,
/// with a modified factorization as last resort; or a general sparse LDLᵀ) or, after a full step
/// that cut the residual a thousandfold, from the factorization kept (a chord step); then a
/// backtracking line search along it from at most the problem's trust-region length, each trial
/// judged by the problem's merit (Armijo), the next trial at the minimizer of the quadratic
/// through the merit's value and slope at 0 and its value at the rejected length (within a
/// quarter to a half of it) in dynamic solves, halving in static ones; near convergence, where
/// the merit's round-off hides the decrease, a full step is judged by the residual it leaves.
/// Converged when the residual is within the tolerance, when a full step is below the step
/// tolerance, or on a round-off plateau within 100× the tolerance.
#include <Eigen/Core>
#include <Eigen/SparseCholesky>

#include "flowire/rod/banded.hpp"

namespace flowire::rod {

enum class LinearSolver { Banded, SparseLDLT };

enum class SolveStatus {
  Converged,
  MaxIterations,     ///< Newton hit max_iterations; the last iterate is kept
  LineSearchFailed,  ///< no decrease along the Newton direction; the last iterate is kept
  NonFinite,         ///< NaN/Inf appeared; the state is rolled back to the step start
  SingularMatrix,    ///< the system could not be factorized even after regularization
};

[[nodiscard]] const char* to_string(SolveStatus s);

/// @brief Outcome of one step or static solve.
struct StepReport {
  SolveStatus status = SolveStatus::Converged;
  int newton_iterations = 0;  ///< iterations, chord iterations included
  int chord_iterations = 0;   ///< iterations that reused the previous factorization
  int line_search_cuts = 0;   ///< halvings summed over the iterations
  int regularizations = 0;    ///< diagonal shifts added to indefinite matrices
  int subdivisions = 0;       ///< levels of step halving a failed solve needed (0: none)
  double residual = 0.0;      ///< final scaled residual [N]
  double tolerance = 0.0;     ///< the force tolerance it was compared with [N]
  [[nodiscard]] bool converged() const { return status == SolveStatus::Converged; }
  /// @brief Continue this report with a later solve's: its counts added, its status,
  /// residual and tolerance taken (the last solve decides), the deeper subdivision kept.
  void then(const StepReport& later) {
    add_work(later);
    status = later.status;
    subdivisions = subdivisions > later.subdivisions ? subdivisions : later.subdivisions;
    residual = later.residual;
    tolerance = later.tolerance;
  }
  /// @brief Add another solve's iteration counts to this report's (its status aside).
  void add_work(const StepReport& other) {
    newton_iterations += other.newton_iterations;
    chord_iterations += other.chord_iterations;
    line_search_cuts += other.line_search_cuts;
    regularizations += other.regularizations;
  }
};

/// @brief Wall-clock seconds spent by the Newton solves, by phase, summed since construction
/// (a benchmark's per-phase breakdown). External forces are evaluated inside the first
/// and third (their own timers split them further).
struct NewtonPhaseSeconds {
  double assembly = 0.0;     ///< gradient and Newton matrix at accepted iterates
  double factorize = 0.0;    ///< LDLᵀ factorizations and solves
  double line_search = 0.0;  ///< trial configurations: state update, frames, merit (and gradient)
};

/// @brief What an assembly computes: the merit only (line-search trials), its gradient too, or
/// gradient and Newton matrix.
enum class Need { Value, Gradient, Matrix };

/// @brief The problem Newton's method solves: its unknowns q (of which [first_free(),
/// first_fixed()) are free), a merit φ(q) with its gradient and banded Newton matrix, and the
/// moves along a direction the line search tries.
class NewtonProblem {
 public:
  virtual ~NewtonProblem() = default;
  [[nodiscard]] virtual int dofs() const = 0;
  [[nodiscard]] virtual int first_free() const = 0;
  [[nodiscard]] virtual int first_fixed() const = 0;
  /// @brief φ at the current iterate, with its gradient (Need::Gradient) and matrix
  /// (Need::Matrix; @p psd: the positive semi-definite one); @p reuse_loads: the configuration
  /// is the last assembly's (its loads and external forces are kept).
  virtual double assemble(Need need, bool psd = false, bool reuse_loads = false) = 0;
  /// @brief The unknowns read from the current state, then assemble(@p need).
  virtual double assemble_current(Need need) = 0;
  /// @brief (dofs()) the gradient of the last assembly that computed one.
  [[nodiscard]] virtual const Eigen::VectorXd& gradient() const = 0;
  /// @brief The matrix of the last assembly with Need::Matrix (lower band; its held rows may
  /// be overwritten).
  virtual BandedMatrix& matrix() = 0;
  /// @brief The largest residual over the free unknowns, and the tolerance it must reach.
  [[nodiscard]] virtual double residual() const = 0;
  [[nodiscard]] virtual double tolerance() const = 0;
  /// @brief The largest fraction of @p dq the problem's trust region allows.
  [[nodiscard]] virtual double max_step(const Eigen::Ref<const Eigen::VectorXd>& dq) const = 0;
  /// @brief The current iterate becomes the base of a line search.
  virtual void keep() = 0;
  /// @brief Move to the base + @p alpha @p dq (not evaluated).
  virtual void trial(const Eigen::Ref<const Eigen::VectorXd>& dq, double alpha) = 0;
  /// @brief After a trial's assembly: the merits at the base and at the trial, from φ there
  /// (@p phi_base, @p phi_trial), by rule @p pass < merit_passes() (a problem may have a
  /// second, more conservative merit, tried when the first finds no decrease).
  virtual void merits(int pass, double phi_base, double phi_trial, double* at_base, double* at_trial) const = 0;
  [[nodiscard]] virtual int merit_passes() const { return 1; }
  /// @brief A stiffness of low rank outside the band, added to matrix() (none by default).
  [[nodiscard]] virtual const LowRankStiffness* low_rank() const { return nullptr; }
  /// @brief Back to the base after a rejected trial (its unknowns; the state follows the next trial).
  virtual void reject_trial() = 0;
  /// @brief Back to the base, state and all (the line search found nothing).
  virtual void back_to_base() = 0;
};

/// @brief Newton's method's settings for one solve.
struct NewtonOptions {
  int max_iterations = 30;
  int max_line_search_cuts = 30;
  LinearSolver linear_solver = LinearSolver::Banded;
  bool chord_iterations = true;
  /// Converged when a full step moves no free unknown by more than this (absolute).
  double step_tolerance = 0.0;
  /// The next trial at the quadratic's minimizer (dynamic solves) instead of half the step.
  bool quadratic_backtracking = true;
};

class NewtonSolver {
 public:
  /// @brief Buffers for up to @p max_dofs unknowns and matrices of half-band @p bandwidth (no
  /// allocation in solve() with the banded solver).
  void reserve(int max_dofs, int bandwidth);
  /// @brief From the problem's current state to a residual within its tolerance, or the status
  /// that stopped it.
  StepReport solve(NewtonProblem& problem, const NewtonOptions& options);
  [[nodiscard]] const NewtonPhaseSeconds& phase_seconds() const { return phase_seconds_; }
  /// @brief The number of negative pivots of @p matrix with its held rows as identities (−1 if
  /// it cannot be factorized): the unstable modes of an equilibrium.
  int negative_pivots(BandedMatrix& matrix, int first_free, int first_fixed);

 private:
  /// Newton's direction into dq_: with the kept factorization (a chord step), or by factorizing
  /// the problem's matrix with its fallbacks. False if no factorization succeeded.
  bool direction(NewtonProblem& p, const NewtonOptions& o, bool chord_step, StepReport& rep);
  /// Backtracking line search along dq_ from the problem's current state, which it moves to the
  /// accepted point (φ and the largest step updated); returns the step length, or 0 with nothing
  /// accepted.
  double line_search(NewtonProblem& p, const NewtonOptions& o, double& phi, double& max_step, StepReport& rep);
  Eigen::VectorXd rhs_, dq_;
  BandedLDLT ldlt_;                     ///< the factorization, kept for chord iterations
  LowRankSolve low_rank_;               ///< the low-rank term of that matrix, kept with it
  Eigen::SparseMatrix<double> sparse_;  ///< the general sparse back end (LinearSolver::SparseLDLT)
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> sparse_ldlt_;
  int sparse_pattern_size_ = -1;
  NewtonPhaseSeconds phase_seconds_;
};

}  // namespace flowire::rod
