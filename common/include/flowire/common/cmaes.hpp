#pragma once
/// @file cmaes.hpp
/// @brief The (μ/μ_W, λ)-CMA-ES: derivative-free minimisation of a noisy or non-smooth
/// function of a few real parameters (used to fit scene values to a measured trace).
///
/// Hansen's standard algorithm as given in N. Hansen, "The CMA Evolution Strategy: A
/// Tutorial", arXiv:1604.00772 (2016), Table 1 and Appendix A, with positive recombination
/// weights only (no active update):
///   - sampling  \f$ x_k = m + \sigma B D z_k,\; z_k \sim N(0, I) \f$, \f$ C = B D^2 B^T \f$;
///   - recombination \f$ m \leftarrow m + \sigma \sum_{i \le \mu} w_i y_{i:\lambda} \f$ (c_m = 1);
///   - cumulative step-size adaptation (CSA) on the conjugate path \f$ p_\sigma \f$ (eq. 43–44);
///   - rank-one update from the evolution path \f$ p_c \f$ with the stall indicator h_σ, and the
///     rank-μ update (eq. 45–47).
/// Default parameters (λ = 4 + ⌊3 ln n⌋, μ = ⌊λ/2⌋, w_i ∝ ln((λ+1)/2) − ln i, c_σ, d_σ, c_c,
/// c_1, c_μ) are those of the tutorial's Table 1.
///
/// Box bounds: the search runs in the unit box [0, 1]^n (the caller maps each parameter's
/// [lo, hi] onto it, so one σ suits all coordinates). A sample outside the box is evaluated at
/// its projection onto the box (repair), and ranked by the repaired value plus a quadratic
/// penalty γ‖x − repair(x)‖², with γ = (spread of the generation's values)/σ² so that a
/// sample one step size outside ranks behind every feasible sample of a flat generation and
/// the penalty keeps the scale of the function (the repair-and-penalise scheme of the
/// tutorial's Appendix B.3, with a per-generation weight). The distribution is updated with
/// the unrepaired samples, so the mean is drawn back into the box.
///
/// The optimiser knows nothing of what it minimises: `minimize` hands each generation to an
/// evaluator as a batch, which the caller may evaluate in parallel.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace flowire::cmaes {

struct Options {
  int lambda = 0;                                            ///< population size; 0: 4 + ⌊3 ln n⌋
  double sigma0 = 0.3;                                       ///< initial step size (in the coordinates of `x0`)
  std::uint64_t seed = 1;                                    ///< std::mt19937_64 seed: equal seeds give equal runs
  long max_evaluations = 0;                                  ///< stop after this many evaluations; 0: 1000·n²+ 1000
  double target = -std::numeric_limits<double>::infinity();  ///< stop when f ≤ target
  double tol_x = 1e-12;                                      ///< stop when σ·max(√diag C, ‖p_c‖) < tol_x
  double tol_fun = 1e-12;  ///< stop when the generation's value range (and the recent best values) < tol_fun
  bool unit_box = false;   ///< restrict the search to [0, 1]^n (repair and penalty, see the file comment)
};

/// @brief Why a run stopped.
enum class Stop { Target, MaxEvaluations, TolX, TolFun, ConditionCov };
std::string to_string(Stop s);

struct Result {
  Eigen::VectorXd x_best;  ///< best point evaluated (repaired into the box if unit_box)
  double f_best = std::numeric_limits<double>::infinity();
  long evaluations = 0;
  int generations = 0;
  Stop stop = Stop::MaxEvaluations;
  Eigen::VectorXd mean;  ///< final distribution mean
  double sigma = 0;      ///< final step size
};

/// @brief One evaluated point, in the order evaluated (for a history table).
struct Evaluation {
  int generation = 0;
  Eigen::VectorXd x;  ///< the point handed to the evaluator (repaired if unit_box)
  double f = 0;
};

/// Evaluates a batch of points (the columns of the matrix) and returns one value per point.
/// Non-finite values are ranked last.
using BatchEvaluator = std::function<std::vector<double>(const Eigen::MatrixXd& points)>;
/// Called after each evaluated generation with its points and values.
using Observer = std::function<void(const std::vector<Evaluation>&)>;

/// @brief Minimise from `x0` (inside [0, 1]^n when `unit_box`).
/// @throws flowire::Error (usage) for an empty x0, σ0 ≤ 0, λ < 2 or x0 outside the unit box.
Result minimize(const BatchEvaluator& f, const Eigen::VectorXd& x0, const Options& options,
                const Observer& observer = {});

/// @brief Convenience: a scalar function evaluated one point after another.
Result minimize(const std::function<double(const Eigen::VectorXd&)>& f, const Eigen::VectorXd& x0,
                const Options& options);

}  // namespace flowire::cmaes
