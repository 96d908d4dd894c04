#include "flowire/common/cmaes.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <deque>
#include <numeric>

#include "flowire/common/error.hpp"

namespace flowire::cmaes {

std::string to_string(Stop s) {
  switch (s) {
    case Stop::Target:
      return "target";
    case Stop::MaxEvaluations:
      return "max_evaluations";
    case Stop::TolX:
      return "tol_x";
    case Stop::TolFun:
      return "tol_fun";
    case Stop::ConditionCov:
      return "condition_cov";
  }
  return "unknown";
}

namespace {

Eigen::VectorXd clip_unit(const Eigen::VectorXd& x) { return x.cwiseMax(0.0).cwiseMin(1.0); }

}  // namespace

Result minimize(const BatchEvaluator& evaluate, const Eigen::VectorXd& x0, const Options& o, const Observer& observer) {
  const int n = static_cast<int>(x0.size());
  if (n == 0) throw_usage_error("CMA-ES: the start point has no coordinates");
  if (!(o.sigma0 > 0)) throw_usage_error(fmt::format("CMA-ES: sigma0 = {} must be positive", o.sigma0));
  if (o.unit_box && ((x0.array() < 0).any() || (x0.array() > 1).any()))
    throw_usage_error("CMA-ES: the start point lies outside the unit box");
  const double nd = n;

  // Strategy parameters: the tutorial's Table 1.
  const int lambda = o.lambda > 0 ? o.lambda : 4 + static_cast<int>(std::floor(3.0 * std::log(nd)));
  if (lambda < 2) throw_usage_error(fmt::format("CMA-ES: lambda = {} must be at least 2", lambda));
  const int mu = lambda / 2;
  Eigen::VectorXd w(mu);
  for (int i = 0; i < mu; ++i) w[i] = std::log((lambda + 1) / 2.0) - std::log(i + 1.0);
  w /= w.sum();
  const double mueff = 1.0 / w.squaredNorm();
  const double cs = (mueff + 2.0) / (nd + mueff + 5.0);
  const double ds = 1.0 + 2.0 * std::max(0.0, std::sqrt((mueff - 1.0) / (nd + 1.0)) - 1.0) + cs;
  const double cc = (4.0 + mueff / nd) / (nd + 4.0 + 2.0 * mueff / nd);
  const double c1 = 2.0 / ((nd + 1.3) * (nd + 1.3) + mueff);
  const double cmu = std::min(1.0 - c1, 2.0 * (mueff - 2.0 + 1.0 / mueff) / ((nd + 2.0) * (nd + 2.0) + mueff));
  const double chi_n = std::sqrt(nd) * (1.0 - 1.0 / (4.0 * nd) + 1.0 / (21.0 * nd * nd));
  const long max_evals = o.max_evaluations > 0 ? o.max_evaluations : 1000L * n * n + 1000L;
  const int hist_len = 10 + static_cast<int>(std::ceil(30.0 * nd / lambda));

  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);

  Eigen::VectorXd m = x0, ps = Eigen::VectorXd::Zero(n), pc = Eigen::VectorXd::Zero(n);
  Eigen::MatrixXd C = Eigen::MatrixXd::Identity(n, n), B = C;
  Eigen::VectorXd D = Eigen::VectorXd::Ones(n);
  double sigma = o.sigma0;

  Result res;
  res.x_best = o.unit_box ? clip_unit(x0) : x0;
  std::deque<double> best_history;
  Eigen::MatrixXd Z(n, lambda), Y(n, lambda), X(n, lambda), Xeval(n, lambda);
  std::vector<double> fit(lambda), ranked(lambda);
  std::vector<int> order(lambda);

  for (int g = 0;; ++g) {
    for (int k = 0; k < lambda; ++k) {
      for (int i = 0; i < n; ++i) Z(i, k) = gauss(rng);
      Y.col(k) = B * D.asDiagonal() * Z.col(k);
      X.col(k) = m + sigma * Y.col(k);
      Xeval.col(k) = o.unit_box ? clip_unit(X.col(k)) : Eigen::VectorXd(X.col(k));
    }
    fit = evaluate(Xeval);
    if (static_cast<int>(fit.size()) != lambda)
      throw_usage_error(fmt::format("CMA-ES: the evaluator returned {} values for {} points", fit.size(), lambda));
    res.evaluations += lambda;
    res.generations = g + 1;
    if (observer) {
      std::vector<Evaluation> batch;
      for (int k = 0; k < lambda; ++k) batch.push_back({g, Xeval.col(k), fit[k]});
      observer(batch);
    }

    // Ranking values: non-finite last; outside the box, the repaired value plus the penalty.
    double fmin = std::numeric_limits<double>::infinity(), fmax = -fmin;
    for (double f : fit)
      if (std::isfinite(f)) fmin = std::min(fmin, f), fmax = std::max(fmax, f);
    const double spread = std::isfinite(fmin) ? std::max(fmax - fmin, 1e-12 * std::max(1.0, std::abs(fmin))) : 1.0;
    const double gamma = spread / (sigma * sigma);
    for (int k = 0; k < lambda; ++k) {
      double r = std::isfinite(fit[k]) ? fit[k] : std::numeric_limits<double>::max();
      if (o.unit_box && std::isfinite(fit[k])) r += gamma * (X.col(k) - Xeval.col(k)).squaredNorm();
      ranked[k] = r;
      if (std::isfinite(fit[k]) && fit[k] < res.f_best) {
        res.f_best = fit[k];
        res.x_best = Xeval.col(k);
      }
    }
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return ranked[a] < ranked[b]; });

    // Recombination and updates (tutorial eq. 41–47).
    Eigen::VectorXd yw = Eigen::VectorXd::Zero(n), zw = Eigen::VectorXd::Zero(n);
    for (int i = 0; i < mu; ++i) {
      yw += w[i] * Y.col(order[i]);
      zw += w[i] * Z.col(order[i]);
    }
    m += sigma * yw;
    ps = (1.0 - cs) * ps + std::sqrt(cs * (2.0 - cs) * mueff) * (B * zw);  // C^{-1/2} yw = B zw
    const double ps_norm = ps.norm();
    const bool hsig = ps_norm / std::sqrt(1.0 - std::pow(1.0 - cs, 2.0 * (g + 1))) < (1.4 + 2.0 / (nd + 1.0)) * chi_n;
    pc = (1.0 - cc) * pc + (hsig ? std::sqrt(cc * (2.0 - cc) * mueff) : 0.0) * yw;
    const double dh = hsig ? 0.0 : cc * (2.0 - cc);
    Eigen::MatrixXd rank_mu = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < mu; ++i) rank_mu.noalias() += w[i] * Y.col(order[i]) * Y.col(order[i]).transpose();
    C = (1.0 - c1 - cmu + c1 * dh) * C + c1 * pc * pc.transpose() + cmu * rank_mu;
    sigma *= std::exp((cs / ds) * (ps_norm / chi_n - 1.0));

    // Decompose C = B D² Bᵀ (every generation: n is a handful of scene values).
    C = 0.5 * (C + C.transpose());
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(C);
    B = eig.eigenvectors();
    D = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();

    res.mean = m;
    res.sigma = sigma;
    // Stopping (tutorial Appendix B.3 criteria, reduced to those that apply here).
    const double fbest_gen = ranked[order[0]];
    best_history.push_back(fbest_gen);
    if (static_cast<int>(best_history.size()) > hist_len) best_history.pop_front();
    if (res.f_best <= o.target) return res.stop = Stop::Target, res;
    if (res.evaluations >= max_evals) return res.stop = Stop::MaxEvaluations, res;
    if (sigma * std::max(C.diagonal().cwiseSqrt().maxCoeff(), pc.norm()) < o.tol_x) return res.stop = Stop::TolX, res;
    const double gen_range = (std::isfinite(fmin) ? fmax - fmin : std::numeric_limits<double>::infinity());
    if (static_cast<int>(best_history.size()) == hist_len && gen_range < o.tol_fun &&
        *std::max_element(best_history.begin(), best_history.end()) -
                *std::min_element(best_history.begin(), best_history.end()) <
            o.tol_fun)
      return res.stop = Stop::TolFun, res;
    if (D.minCoeff() <= 0 || (D.maxCoeff() / D.minCoeff()) > 1e7) return res.stop = Stop::ConditionCov, res;
  }
}

Result minimize(const std::function<double(const Eigen::VectorXd&)>& f, const Eigen::VectorXd& x0,
                const Options& options) {
  return minimize(
      [&f](const Eigen::MatrixXd& pts) {
        std::vector<double> v(pts.cols());
        for (Eigen::Index k = 0; k < pts.cols(); ++k) v[k] = f(pts.col(k));
        return v;
      },
      x0, options);
}

}  // namespace flowire::cmaes
