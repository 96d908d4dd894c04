// CMA-ES (common/cmaes) on the standard test functions, against published convergence figures,
// and its box handling.
//
// Reference figures: N. Hansen, S. D. Müller, P. Koumoutsakos, "Reducing the time complexity
// of the derandomized evolution strategy with covariance matrix adaptation (CMA-ES)",
// Evolutionary Computation 11(1):1–18 (2003), the figures of function evaluations to reach
// f_stop = 1e-10 for the default population size (λ = 10 at n = 10), and the same setting in
// N. Hansen, "The CMA Evolution Strategy: A Tutorial", arXiv:1604.00772, whose reference code
// (purecmaes) runs Rosenbrock to 1e-10. Read off the published plots at n = 10:
// sphere ≈ 1.5e3, ellipsoid (condition 1e6) ≈ 6e3, Rosenbrock ≈ 6e3 evaluations; the mean
// over seeds must lie within a factor 2 of these. The growth with n (sphere linear, ellipsoid
// following the covariance's learning time, quadratic asymptotically) is fitted as log-log
// slopes over n = 4…32, and the evaluations at n = 40 are compared with the run logs published
// with two other implementations (each test says what it asserts and why).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <vector>

#include "flowire/common/cmaes.hpp"
#include "flowire/common/error.hpp"

namespace {

using flowire::cmaes::minimize;
using flowire::cmaes::Options;
using flowire::cmaes::Stop;

double sphere(const Eigen::VectorXd& x) { return x.squaredNorm(); }

double ellipsoid(const Eigen::VectorXd& x) {
  const auto n = x.size();
  double f = 0;
  for (Eigen::Index i = 0; i < n; ++i)
    f += std::pow(1e6, static_cast<double>(i) / static_cast<double>(n - 1)) * x[i] * x[i];
  return f;
}

double rosenbrock(const Eigen::VectorXd& x) {
  double f = 0;
  for (Eigen::Index i = 0; i + 1 < x.size(); ++i)
    f += 100.0 * std::pow(x[i] * x[i] - x[i + 1], 2) + std::pow(x[i] - 1.0, 2);
  return f;
}

/// Mean evaluations to f ≤ 1e-10 over `runs` seeds; every run must reach the target.
double mean_evaluations(const std::function<double(const Eigen::VectorXd&)>& f, int n, double x0, double sigma0,
                        int runs = 5) {
  double total = 0;
  for (int s = 0; s < runs; ++s) {
    Options o;
    o.sigma0 = sigma0;
    o.seed = 1000 + s;
    o.target = 1e-10;
    o.max_evaluations = 200000;
    const auto r = minimize(f, Eigen::VectorXd::Constant(n, x0), o);
    EXPECT_EQ(r.stop, Stop::Target) << "seed " << o.seed << " stopped by " << flowire::cmaes::to_string(r.stop);
    EXPECT_LE(r.f_best, 1e-10);
    total += static_cast<double>(r.evaluations);
  }
  return total / runs;
}

TEST(Cmaes, ReachesTheTargetInThePublishedNumberOfEvaluations) {
  struct Case {
    const char* name;
    double (*f)(const Eigen::VectorXd&);
    double x0, sigma0, published;
  };
  for (const Case& c : {Case{"sphere", sphere, 1.0, 1.0, 1.5e3}, Case{"ellipsoid", ellipsoid, 1.0, 1.0, 6e3},
                        Case{"rosenbrock", rosenbrock, 0.0, 0.5, 6e3}}) {
    const double evals = mean_evaluations(c.f, 10, c.x0, c.sigma0);
    RecordProperty(c.name, std::to_string(evals));
    EXPECT_GT(evals, c.published / 2) << c.name;
    EXPECT_LT(evals, c.published * 2) << c.name;
  }
}

/// Least-squares slope of log y against log x.
double loglog_slope(const std::vector<double>& x, const std::vector<double>& y) {
  std::vector<double> lx, ly;
  for (size_t i = 0; i < x.size(); ++i) lx.push_back(std::log(x[i])), ly.push_back(std::log(y[i]));
  const double mx = std::accumulate(lx.begin(), lx.end(), 0.0) / static_cast<double>(lx.size());
  const double my = std::accumulate(ly.begin(), ly.end(), 0.0) / static_cast<double>(ly.size());
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < lx.size(); ++i) sxy += (lx[i] - mx) * (ly[i] - my), sxx += (lx[i] - mx) * (lx[i] - mx);
  return sxy / sxx;
}

/// The covariance's learning time in evaluations, λ / (c_1 + c_μ), with the default λ and
/// learning rates of the tutorial's Table 1 (the same formulas as cmaes.cpp, restated here).
double learning_time(int n) {
  const double nd = n;
  const int lambda = 4 + static_cast<int>(std::floor(3.0 * std::log(nd)));
  const int mu = lambda / 2;
  double sw = 0, sw2 = 0;
  for (int i = 0; i < mu; ++i) sw += std::log((lambda + 1) / 2.0) - std::log(i + 1.0);
  for (int i = 0; i < mu; ++i) sw2 += std::pow((std::log((lambda + 1) / 2.0) - std::log(i + 1.0)) / sw, 2);
  const double mueff = 1.0 / sw2;
  const double c1 = 2.0 / ((nd + 1.3) * (nd + 1.3) + mueff);
  const double cmu = std::min(1.0 - c1, 2.0 * (mueff - 2.0 + 1.0 / mueff) / ((nd + 2.0) * (nd + 2.0) + mueff));
  return lambda / (c1 + cmu);
}

// The growth of the evaluations with the dimension, fitted as the slope of log(mean evaluations
// to 1e-10) against log n over n = 4, 8, 16, 32 (6 seeds each, x0 = 1, σ0 = 1).
//  - Sphere: linear in n. With its step size kept near the optimum by cumulative step-size
//    adaptation the ES gains a constant factor in f per ≈ n evaluations; that step-size
//    adaptation is what lets "the number of evaluations scale linearly with increasing dimension
//    (like on the sphere function)" (N. Hansen, CMA-ES/pycma issue #130). Asserted: slope in
//    [0.8, 1.4].
//  - Ellipsoid (condition 1e6): the covariance has to be learned first, at the rates
//    c_1 ≈ 2/n² and c_μ ≈ μ_eff/n² (tutorial arXiv:1604.00772, Sect. 3.2 (rank-μ) and 3.3
//    (rank-one), defaults in its Table 1), so
//    the evaluations follow the learning time λ/(c_1 + c_μ): quadratic in n asymptotically, the
//    "quadratic time complexity" of the default population size (Hansen, Müller & Koumoutsakos
//    2003, abstract). Over n = 4…32 the +1.3, +2 and μ_eff offsets of those rates still matter:
//    λ/(c_1 + c_μ) itself has a slope of 1.69 there. Asserted: the ellipsoid's slope within 0.2
//    of that of λ/(c_1 + c_μ); evaluations / learning time constant within a factor 1.5 over the
//    four n; and the slope of the last doubling (16 → 32), where n² dominates, in [1.6, 2.3].
TEST(Cmaes, EvaluationsScaleWithDimensionAsPublished) {
  const std::vector<double> dims{4, 8, 16, 32};
  std::vector<double> e_sphere, e_elli, t_learn;
  for (const double n : dims) {
    e_sphere.push_back(mean_evaluations(sphere, static_cast<int>(n), 1.0, 1.0, 6));
    e_elli.push_back(mean_evaluations(ellipsoid, static_cast<int>(n), 1.0, 1.0, 6));
    t_learn.push_back(learning_time(static_cast<int>(n)));
    std::printf("n %2.0f: sphere %6.0f, ellipsoid %6.0f evaluations; learning time %5.0f, ellipsoid / it %.1f\n", n,
                e_sphere.back(), e_elli.back(), t_learn.back(), e_elli.back() / t_learn.back());
  }
  const double s_sphere = loglog_slope(dims, e_sphere), s_elli = loglog_slope(dims, e_elli);
  const double s_learn = loglog_slope(dims, t_learn);
  const double s_last = std::log(e_elli[3] / e_elli[2]) / std::log(2.0);
  std::printf("slopes: sphere %.3f, ellipsoid %.3f (16 -> 32: %.3f), learning time %.3f\n", s_sphere, s_elli, s_last,
              s_learn);
  RecordProperty("sphere_slope", std::to_string(s_sphere));
  RecordProperty("ellipsoid_slope", std::to_string(s_elli));
  EXPECT_GT(s_sphere, 0.8);
  EXPECT_LT(s_sphere, 1.4);
  EXPECT_NEAR(s_elli, s_learn, 0.2);
  double lo = 1e300, hi = 0;
  for (size_t i = 0; i < dims.size(); ++i)
    lo = std::min(lo, e_elli[i] / t_learn[i]), hi = std::max(hi, e_elli[i] / t_learn[i]);
  EXPECT_LT(hi / lo, 1.5);
  EXPECT_GT(s_last, 1.6);
  EXPECT_LT(s_last, 2.3);
}

// Against the run logs published with two other implementations of the same (μ/μ_W, λ)-CMA-ES
// (tutorial defaults, λ = 15) on the same functions at n = 40, from x0 = 3·1 with σ0 = 2:
// pypop7 (pypop7/optimizers/es/_repeat_cmaes.py, seed 0, f logged every 3000 evaluations) and
// CyberAgentAILab/cmaes (the ellipsoid log of examples/ellipsoid_function.py quoted in its pull
// request #82). Sphere: f = 7.5e-4 at 3000 and 4.8e-10 at 6000 evaluations, so 1e-10 at ≈ 6300
// (log-linear between the two). Ellipsoid (condition 1e6): f = 3.4e-6 at 45000 and 4.3e-11 at
// 48000 (pypop7), 3.7e-4 at 45000 and < 5e-6 at 48000 (cmaes): 1e-10 at ≈ 47800. Both use the
// tutorial's negative weights for the worst samples (active covariance update), which this
// implementation leaves out; that update speeds up learning an ill-conditioned covariance, so
// ours may take more evaluations on the ellipsoid. Asserted: mean over 4 seeds within a factor
// 1.25 of the sphere's 6300 and within [1, 2] times the ellipsoid's 47800.
TEST(Cmaes, MatchesPublishedRunsOfOtherImplementationsIn40Dimensions) {
  const double sphere40 = mean_evaluations(sphere, 40, 3.0, 2.0, 4);
  const double elli40 = mean_evaluations(ellipsoid, 40, 3.0, 2.0, 4);
  std::printf("n 40: sphere %.0f (others ~6300), ellipsoid %.0f (others ~47800) evaluations\n", sphere40, elli40);
  EXPECT_GT(sphere40, 6300 / 1.25);
  EXPECT_LT(sphere40, 6300 * 1.25);
  EXPECT_GT(elli40, 47800 * 1.0);
  EXPECT_LT(elli40, 47800 * 2.0);
}

TEST(Cmaes, EqualSeedsGiveEqualRuns) {
  Options o;
  o.seed = 7;
  o.max_evaluations = 500;
  const auto a = minimize(rosenbrock, Eigen::VectorXd::Zero(4), o),
             b = minimize(rosenbrock, Eigen::VectorXd::Zero(4), o);
  EXPECT_EQ(a.f_best, b.f_best);
  EXPECT_EQ(a.evaluations, b.evaluations);
  o.seed = 8;
  EXPECT_NE(minimize(rosenbrock, Eigen::VectorXd::Zero(4), o).f_best, a.f_best);
}

TEST(Cmaes, StaysInTheUnitBoxAndFindsAnOptimumOnItsFace) {
  // Minimum of the unconstrained function at (1.3, 0.4, −0.2): the box optimum is (1, 0.4, 0).
  const Eigen::Vector3d c(1.3, 0.4, -0.2);
  bool left_box = false;
  auto f = [&](const Eigen::VectorXd& x) {
    if ((x.array() < 0).any() || (x.array() > 1).any()) left_box = true;
    return (x - c).squaredNorm();
  };
  Options o;
  o.unit_box = true;
  o.sigma0 = 0.3;
  o.max_evaluations = 3000;
  const auto r = minimize(f, Eigen::Vector3d(0.2, 0.8, 0.5), o);
  EXPECT_FALSE(left_box);
  EXPECT_NEAR(r.x_best[0], 1.0, 1e-4);
  EXPECT_NEAR(r.x_best[1], 0.4, 1e-4);
  EXPECT_NEAR(r.x_best[2], 0.0, 1e-4);
  // The mean is drawn back to the box (not left drifting outside).
  EXPECT_LT((r.mean - Eigen::Vector3d(1.0, 0.4, 0.0)).norm(), 0.05);
}

TEST(Cmaes, RejectsBadSettings) {
  Options o;
  o.sigma0 = 0;
  EXPECT_THROW(minimize(sphere, Eigen::VectorXd::Ones(2), o), flowire::Error);
  o = Options{};
  o.unit_box = true;
  EXPECT_THROW(minimize(sphere, Eigen::VectorXd::Constant(2, 1.5), o), flowire::Error);
  EXPECT_THROW(minimize(sphere, Eigen::VectorXd(), Options{}), flowire::Error);
}

}  // namespace
