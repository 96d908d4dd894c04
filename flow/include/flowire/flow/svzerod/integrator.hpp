#pragma once
/// @file integrator.hpp
/// @brief Generalized-α time integration (Jansen, Whiting & Hulbert 2000) of
/// \f$ f(y, \dot y, t) = E\dot y + F y + c + c_{nl}(y, \dot y) = 0 \f$ with spectral radius
/// \f$ \rho_\infty \f$ at infinite step:
/// \f[ \alpha_m = \tfrac{1}{2}\frac{3 - \rho_\infty}{1 + \rho_\infty},\quad
///     \alpha_f = \frac{1}{1 + \rho_\infty},\quad \gamma = \tfrac{1}{2} + \alpha_m - \alpha_f \f]
/// \f[ y_{n+1} = y_n + \Delta t\left((1-\gamma)\dot y_n + \gamma\dot y_{n+1}\right),\qquad
///     f(y_n + \alpha_f(y_{n+1} - y_n),\ \dot y_n + \alpha_m(\dot y_{n+1} - \dot y_n),\ t_n + \alpha_f\Delta t) = 0 \f]
/// The unknown is \f$ \dot y_{n+1} \f$, predicted as \f$ (1 - 1/\gamma)\dot y_n \f$ with
/// \f$ y_{n+1} = y_n \f$ (svZeroDSolver's predictor); a correction \f$ \delta \f$ of \f$ \dot y_{n+1} \f$
/// moves \f$ y_{n+1} \f$ by \f$ \gamma\Delta t\,\delta \f$, so the iteration matrix is
/// \f$ J = \alpha_m\,\partial f/\partial\dot y + \alpha_f\gamma\Delta t\,\partial f/\partial y \f$.
///
/// A linear system (no nonlinear block) is solved with one solve per step: the corrected
/// residual \f$ f + J\delta \f$ is zero up to rounding. When also E and F do not change with
/// time, J is constant and factorized once for the whole phase. With nonlinear blocks:
/// Newton iterations until \f$ \max|f| < \f$ `atol`, J refactorized numerically on the
/// symbolic analysis of the pattern.
#include <Eigen/Core>
#include <string>

#include "flowire/flow/svzerod/system.hpp"

namespace flowire::flow::svzerod {

/// @brief The network state.
struct State {
  Eigen::VectorXd y;   ///< (unknowns) pressures, flows, internal unknowns
  Eigen::VectorXd yd;  ///< (unknowns) their time derivatives
};

class GeneralizedAlpha {
 public:
  /// @param rho_infty spectral radius at infinite step, in [0, 1]
  /// @param max_iter Newton iterations allowed per step (nonlinear systems)
  GeneralizedAlpha(System& system, double rho_infty, double dt, double atol, int max_iter, std::string file);

  /// @brief Advance `s` from `time` to `time + dt` in place; allocates nothing.
  /// @throws flowire::Error (numerical): Newton not converging, singular J, non-finite state.
  void step(State& s, double time);

  [[nodiscard]] double alpha_m() const { return am_; }
  [[nodiscard]] double alpha_f() const { return af_; }
  [[nodiscard]] double gamma() const { return gamma_; }
  [[nodiscard]] long steps() const { return steps_; }
  /// @brief Linear solves per step (1 for a linear system).
  [[nodiscard]] double solves_per_step() const { return steps_ ? static_cast<double>(solves_) / steps_ : 0.0; }

 private:
  System& sys_;
  double dt_, atol_;
  int max_iter_;
  std::string file_;
  double am_ = 1.0, af_ = 1.0, gamma_ = 0.5;
  Eigen::VectorXd old_y_, old_yd_, yaf_, ydam_, f_;
  long steps_ = 0, solves_ = 0;
};

}  // namespace flowire::flow::svzerod
