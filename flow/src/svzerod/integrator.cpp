#include "flowire/flow/svzerod/integrator.hpp"

#include <fmt/format.h>

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
  old_y_ = s.y;
  old_yd_ = s.yd;
  s.yd *= 1.0 - 1.0 / gamma_;  // predictor; y_{n+1} = y_n
  const double t = time + af_ * dt_;
  const double a_y = af_ * gamma_ * dt_;
  ++steps_;
  sys_.update_time(t);
  if (!sys_.nonlinear()) {
    ydam_ = old_yd_ + (s.yd - old_yd_) * am_;
    sys_.residual(s.y, ydam_, f_);  // y at α_f equals y_n for the predictor
    if (f_.cwiseAbs().maxCoeff() >= atol_) {
      sys_.factorize(am_, a_y);
      f_ = -f_;
      sys_.solve(f_);
      s.yd += f_;
      s.y += f_ * (gamma_ * dt_);
      ++solves_;
    }
  } else {
    for (int i = 0;; ++i) {
      ydam_ = old_yd_ + (s.yd - old_yd_) * am_;
      yaf_ = old_y_ + (s.y - old_y_) * af_;
      sys_.update_solution(t, yaf_, ydam_);
      sys_.residual(yaf_, ydam_, f_);
      if (f_.cwiseAbs().maxCoeff() < atol_) break;
      if (i == max_iter_ - 1)
        throw_numerical_error(
            fmt::format("{}: maximum number of non-linear iterations reached at time {}", file_, time));
      sys_.factorize(am_, a_y);
      f_ = -f_;
      sys_.solve(f_);
      s.yd += f_;
      s.y += f_ * (gamma_ * dt_);
      ++solves_;
    }
  }
  if (!s.y.allFinite()) throw_numerical_error(fmt::format("{}: the solution is not finite at time {}", file_, time));
}

}  // namespace flowire::flow::svzerod
