#include "flowire/flow/svzerod/integrator.hpp"

#include <fmt/format.h>

#include <cmath>

#include "flowire/common/error.hpp"

namespace flowire::flow::svzerod {

GeneralizedAlpha::GeneralizedAlpha(System& system, double rho_infty, double dt, double atol, int max_iter,
                                   std::string file)
    : sys_(system), dt_(dt), atol_(atol), max_iter_(max_iter), file_(std::move(file)) {
  am_ = 0.5 * (3.0 - rho_infty) / (1.0 + rho_infty);
  af_ = 1.0 / (1.0 + rho_infty);
  gamma_ = 0.5 + am_ - af_;
  const int n = sys_.size();
  old_y_.resize(n);
  old_yd_.resize(n);
  yaf_.resize(n);
  ydam_.resize(n);
  f_.resize(n);
}

void GeneralizedAlpha::step(State& s, double time) {
  const double t = time + af_ * dt_;
  const double a_y = af_ * gamma_ * dt_;
  const double predict = 1.0 - 1.0 / gamma_;  // ẏ_{n+1} predicted as (1 − 1/γ) ẏ_n, y_{n+1} = y_n
  ++steps_;
  sys_.update_time(t);
  if (!sys_.nonlinear()) {
    // ẏ at α_m for the predictor: ẏ_n + α_m((1 − 1/γ)ẏ_n − ẏ_n) = (1 − α_m/γ) ẏ_n; y at α_f is y_n.
    if (sys_.residual(s.y, s.yd, 1.0 - am_ / gamma_, f_) < atol_) {
      s.yd *= predict;
    } else {
      sys_.factorize(am_, a_y);
      sys_.solve(f_);  // the correction is −f_
      const double c = gamma_ * dt_;
      double* y = s.y.data();
      double* yd = s.yd.data();
      const double* x = f_.data();
      double check = 0.0;
      for (Eigen::Index i = 0; i < f_.size(); ++i) {
        yd[i] = predict * yd[i] - x[i];
        y[i] -= c * x[i];
        check += x[i];
      }
      ++solves_;
      if (!std::isfinite(check))
        throw_numerical_error(fmt::format("{}: the solution is not finite at time {}", file_, time));
    }
    return;
  }
  old_y_ = s.y;
  old_yd_ = s.yd;
  s.yd *= predict;
  for (int i = 0;; ++i) {
    ydam_ = old_yd_ + (s.yd - old_yd_) * am_;
    yaf_ = old_y_ + (s.y - old_y_) * af_;
    sys_.update_solution(t, yaf_, ydam_);
    sys_.residual(yaf_, ydam_, f_);
    if (f_.cwiseAbs().maxCoeff() < atol_) break;
    if (i == max_iter_ - 1)
      throw_numerical_error(fmt::format("{}: maximum number of non-linear iterations reached at time {}", file_, time));
    sys_.factorize(am_, a_y);
    sys_.solve(f_);
    s.yd -= f_;
    s.y -= f_ * (gamma_ * dt_);
    ++solves_;
  }
  if (!s.y.allFinite()) throw_numerical_error(fmt::format("{}: the solution is not finite at time {}", file_, time));
}

}  // namespace flowire::flow::svzerod
