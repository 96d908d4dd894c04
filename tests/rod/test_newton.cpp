// Newton's method (newton.hpp) as a part of its own, on problems that are not a rod: a chain of
// nonlinear springs with a known minimizer (reached from far, quadratically at the end, chord
// steps there, held unknowns untouched), a double well whose matrix is indefinite where it
// starts (the positive semi-definite fallback, then the minimizer), and the trust region
// bounding every step.
#include "flowire/rod/newton.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "flowire_test.hpp"

using namespace flowire::rod;

namespace {

/// φ(q) = Σᵢ w(qᵢ − aᵢ) + ½ k Σᵢ (qᵢ₊₁ − qᵢ − (aᵢ₊₁ − aᵢ))², minimized at q = a, with
/// w(x) = cosh(x) − 1 (convex) or the double well ¼x⁴ − ½x² (minima at ±1). Unknowns
/// [first_free, first_fixed) free. The trust region: no unknown moves more than `reach`.
class Chain final : public NewtonProblem {
 public:
  Chain(int n, bool well, double k) : n_(n), well_(well), k_(k), q_(n), base_(n), a_(n), g_(n) {
    for (int i = 0; i < n; ++i) a_[i] = 0.3 * std::sin(1.7 * i);
    H_.reserve(n, 1);
  }
  Eigen::VectorXd& q() { return q_; }
  const Eigen::VectorXd& a() const { return a_; }
  int free_begin = 0, free_end = 0;
  double reach = 1e9;
  int psd_assemblies = 0;

  [[nodiscard]] int dofs() const override { return n_; }
  [[nodiscard]] int first_free() const override { return free_begin; }
  [[nodiscard]] int first_fixed() const override { return free_end; }
  double assemble(Need need, bool psd, bool /*reuse_loads*/) override {
    if (psd) ++psd_assemblies;
    double phi = 0.0;
    if (need != Need::Value) g_.setZero();
    if (need == Need::Matrix) H_.resize(n_);
    for (int i = 0; i < n_; ++i) {
      const double x = q_[i] - a_[i];
      double d1 = 0.0, d2 = 0.0;
      if (well_) {
        phi += 0.25 * x * x * x * x - 0.5 * x * x;
        d1 = x * x * x - x;
        d2 = 3 * x * x - 1;
      } else {
        phi += std::cosh(x) - 1.0;
        d1 = std::sinh(x);
        d2 = std::cosh(x);
      }
      if (need != Need::Value) g_[i] += d1;
      if (need == Need::Matrix) H_.lower(i, i) += psd ? std::max(d2, 0.0) : d2;
      if (i + 1 < n_) {
        const double s = q_[i + 1] - q_[i] - (a_[i + 1] - a_[i]);
        phi += 0.5 * k_ * s * s;
        if (need != Need::Value) g_[i + 1] += k_ * s, g_[i] -= k_ * s;
        if (need == Need::Matrix) {
          H_.lower(i, i) += k_;
          H_.lower(i + 1, i + 1) += k_;
          H_.lower(i + 1, i) -= k_;
        }
      }
    }
    return phi;
  }
  double assemble_current(Need need) override { return assemble(need, false, false); }
  [[nodiscard]] const Eigen::VectorXd& gradient() const override { return g_; }
  BandedMatrix& matrix() override { return H_; }
  [[nodiscard]] double residual() const override {
    return g_.segment(free_begin, free_end - free_begin).cwiseAbs().maxCoeff();
  }
  [[nodiscard]] double tolerance() const override { return 1e-12; }
  [[nodiscard]] double max_step(const Eigen::Ref<const Eigen::VectorXd>& dq) const override {
    const double m = dq.cwiseAbs().maxCoeff();
    max_move = std::max(max_move, std::min(m, reach));
    return m > reach ? reach / m : 1.0;
  }
  void keep() override { base_ = q_; }
  void trial(const Eigen::Ref<const Eigen::VectorXd>& dq, double alpha) override { q_ = base_ + alpha * dq; }
  void merits(int /*pass*/, double phi_base, double phi_trial, double* at_base, double* at_trial) const override {
    *at_base = phi_base;
    *at_trial = phi_trial;
  }
  void reject_trial() override { q_ = base_; }
  void back_to_base() override { q_ = base_; }
  mutable double max_move = 0.0;

 private:
  int n_;
  bool well_;
  double k_;
  Eigen::VectorXd q_, base_, a_, g_;
  BandedMatrix H_;
};

}  // namespace

TEST(Newton, ReachesAChainsMinimizerFromFarWithChordStepsAtTheEndAndLeavesHeldUnknownsAlone) {
  const int n = 40;
  Chain c(n, /*well=*/false, 5.0);
  c.free_begin = 2;
  c.free_end = n - 3;
  for (int i = 0; i < n; ++i) c.q()[i] = c.a()[i] + (i >= c.free_begin && i < c.free_end ? 3.0 : 0.0);
  const Eigen::VectorXd held = c.q();
  NewtonSolver newton;
  newton.reserve(n, 1);
  NewtonOptions o;
  o.max_iterations = 50;
  const StepReport r = newton.solve(c, o);
  ASSERT_TRUE(r.converged()) << to_string(r.status);
  EXPECT_LE(r.residual, 1e-12);
  for (int i = 0; i < n; ++i) {
    if (i >= c.free_begin && i < c.free_end) {
      EXPECT_NEAR(c.q()[i], c.a()[i], 1e-11) << i;
    } else {
      EXPECT_EQ(c.q()[i], held[i]) << "held unknown " << i << " moved";
    }
  }
  // cosh from 3 away: damped steps first, then quadratic convergence, the last with the kept
  // factorization.
  EXPECT_LT(r.newton_iterations, 15);
  EXPECT_GE(r.chord_iterations, 1);
  EXPECT_GT(newton.phase_seconds().factorize, 0.0);
}

TEST(Newton, AnIndefiniteMatrixTakesThePositiveSemiDefiniteOneAndStillFindsAMinimum) {
  const int n = 10;
  Chain c(n, /*well=*/true, 0.1);
  c.free_end = n;
  for (int i = 0; i < n; ++i) c.q()[i] = c.a()[i] + 0.05;  // near the well's top: 3x² − 1 < 0
  NewtonSolver newton;
  newton.reserve(n, 1);
  const StepReport r = newton.solve(c, NewtonOptions{.max_iterations = 100});
  ASSERT_TRUE(r.converged()) << to_string(r.status);
  EXPECT_GE(r.regularizations, 1);
  EXPECT_GE(c.psd_assemblies, 1);
  // Every unknown in the well at +1 (the spring keeps them together; the start leaned that way).
  for (int i = 0; i < n; ++i) EXPECT_NEAR(c.q()[i] - c.a()[i], 1.0, 1e-9) << i;
  // The static solve halves (no quadratic backtracking) and converges the same.
  Chain d(n, true, 0.1);
  d.free_end = n;
  for (int i = 0; i < n; ++i) d.q()[i] = d.a()[i] + 0.05;
  const StepReport rd = newton.solve(d, NewtonOptions{.max_iterations = 100, .quadratic_backtracking = false});
  ASSERT_TRUE(rd.converged());
  for (int i = 0; i < n; ++i) EXPECT_NEAR(d.q()[i], c.q()[i], 1e-9);
}

TEST(Newton, NoStepGoesBeyondTheProblemsTrustRegion) {
  const int n = 20;
  Chain c(n, false, 1.0);
  c.free_end = n;
  for (int i = 0; i < n; ++i) c.q()[i] = c.a()[i] - 5.0;
  c.reach = 0.25;
  NewtonSolver newton;
  newton.reserve(n, 1);
  const StepReport r = newton.solve(c, NewtonOptions{.max_iterations = 100});
  ASSERT_TRUE(r.converged());
  EXPECT_LE(c.max_move, 0.25);
  // Twenty steps of a quarter at least to come back from 5 away.
  EXPECT_GE(r.newton_iterations, 20);
}
