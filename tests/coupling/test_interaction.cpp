// Interaction laws against finite differences, including near-degenerate inputs.
#include "flowire/coupling/interaction.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>
#include <random>

#include "flowire/common/error.hpp"
#include "flowire_test.hpp"

using namespace flowire::coupling;

namespace {

constexpr double kH = 1e-7;

template <class F>
Vec3 fd_gradient(const F& f, const Vec3& x) {
  Vec3 g;
  for (int k = 0; k < 3; ++k) {
    Vec3 e = Vec3::Zero();
    e[k] = kH;
    g[k] = (f(x + e) - f(x - e)) / (2 * kH);
  }
  return g;
}

template <class F>
Mat3 fd_jacobian(const F& f, const Vec3& x) {
  Mat3 J;
  for (int k = 0; k < 3; ++k) {
    Vec3 e = Vec3::Zero();
    e[k] = kH;
    J.col(k) = (f(x + e) - f(x - e)) / (2 * kH);
  }
  return J;
}

}  // namespace

TEST(Interaction, CapsuleDistanceGradientAndHessianMatchFiniteDifferences) {
  const Vec3 a(0, 0, 0), b(0.01, 0.002, 0);
  const double r = 2e-3;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 300; ++i) {
    // Points along the cylinder and past both caps.
    const Vec3 x = Vec3(0.005 + 0.009 * u(rng), 0.001 + 3e-3 * u(rng), 3e-3 * u(rng));
    Vec3 g;
    Mat3 H;
    capsule_distance(x, a, b, r, &g, &H);
    auto d = [&](const Vec3& y) { return capsule_distance(y, a, b, r, nullptr, nullptr); };
    auto grad = [&](const Vec3& y) {
      Vec3 gg;
      capsule_distance(y, a, b, r, &gg, nullptr);
      return gg;
    };
    EXPECT_LT((g - fd_gradient(d, x)).norm(), 1e-6) << x.transpose();
    EXPECT_LT((H - fd_jacobian(grad, x)).norm(), 1e-4 * (1 + H.norm())) << x.transpose();
  }
}

TEST(Interaction, TheWallPenaltysSmoothedOnsetHasExactDerivativesAndNoJumpInItsStiffness) {
  // contact.onset w: the force k φ′(δ) ramps in over |δ| < w/2 (δ = d + a), k/2 δ² beyond it.
  // Central differences of the energy and of the gradient, inside the band, at its edges and
  // beyond, and the stiffness along the normal continuous where the sharp penalty jumps.
  const Vec3 a(0, 0, 0), b(0.02, 0, 0);
  const double R = 2e-3, wire = 0.45e-3, k = 3e4, w = 0.2 * wire;
  auto at = [&](const Vec3& x) {
    Vec3 n;
    Mat3 H;
    const double d = capsule_distance(x, a, b, R, &n, &H);
    return wall_penalty(d, n, H, wire, k, w);
  };
  auto energy = [&](const Vec3& x) { return at(x).energy; };
  auto gradient = [&](const Vec3& x) { return at(x).gradient; };
  const Vec3 dir(0, 0.6, 0.8);
  for (double delta : {-0.49 * w, -0.3 * w, -0.01 * w, 0.0, 0.2 * w, 0.45 * w, 0.55 * w, 2.0 * w}) {
    const Vec3 x = Vec3(0.01, 0, 0) + (R - wire + delta) * dir;
    const auto p = at(x);
    EXPECT_GT(p.energy, 0.0) << delta;
    EXPECT_NEAR(p.normal_force, p.gradient.norm(), 1e-12 * (1 + p.normal_force)) << delta;
    EXPECT_NEAR(p.penetration, std::max(delta, 0.0), 1e-15) << delta;
    EXPECT_LT((p.gradient - fd_gradient(energy, x)).norm(), 1e-6 * (1 + p.gradient.norm())) << delta;
    EXPECT_LT((p.hessian - fd_jacobian(gradient, x)).norm(), 1e-4 * (1 + p.hessian.norm())) << delta;
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Mat3>(p.hessian).eigenvalues().minCoeff(), -1e-9) << delta;
    if (delta >= 0.5 * w) {  // beyond the band: the sharp penalty's force
      EXPECT_NEAR(p.normal_force, k * delta, 1e-12 * k * delta) << delta;
    }
  }
  // Before the band: nothing. Across both band edges: the normal stiffness n·H·n is continuous.
  EXPECT_EQ(at(Vec3(0.01, 0, 0) + (R - wire - 0.51 * w) * dir).energy, 0.0);
  for (double edge : {-0.5 * w, 0.5 * w}) {
    const double e = 1e-12;
    const double below = dir.dot(at(Vec3(0.01, 0, 0) + (R - wire + edge - e) * dir).hessian * dir);
    const double above = dir.dot(at(Vec3(0.01, 0, 0) + (R - wire + edge + e) * dir).hessian * dir);
    EXPECT_NEAR(below, above, 1e-6 * k) << edge;
  }
  // The sharp onset (w = 0) jumps by k at first touch.
  Vec3 n;
  Mat3 H;
  const Vec3 x0 = Vec3(0.01, 0, 0) + (R - wire) * dir;
  const double d0 = capsule_distance(x0, a, b, R, &n, &H);
  EXPECT_NEAR(dir.dot(wall_penalty(d0 + 1e-12, n, H, wire, k).hessian * dir) -
                  dir.dot(wall_penalty(d0 - 1e-12, n, H, wire, k).hessian * dir),
              k, 1e-3 * k);
}

TEST(Interaction, WallPenaltyDerivativesMatchFiniteDifferences) {
  const Vec3 a(0, 0, 0), b(0.02, 0, 0);
  const double R = 2e-3, wire = 0.45e-3, k = 1e4;
  auto energy = [&](const Vec3& x) {
    Vec3 n;
    Mat3 H;
    const double d = capsule_distance(x, a, b, R, &n, &H);
    return wall_penalty(d, n, H, wire, k).energy;
  };
  auto gradient = [&](const Vec3& x) {
    Vec3 n;
    Mat3 H;
    const double d = capsule_distance(x, a, b, R, &n, &H);
    return wall_penalty(d, n, H, wire, k).gradient;
  };
  for (double rho : {1.0e-3, 1.5e-3, 1.56e-3, 1.7e-3, 2.0e-3, 2.5e-3}) {  // free, grazing, penetrating
    const Vec3 x(0.01, rho * 0.6, rho * 0.8);
    Vec3 n;
    Mat3 H;
    const double d = capsule_distance(x, a, b, R, &n, &H);
    const auto p = wall_penalty(d, n, H, wire, k);
    EXPECT_NEAR(p.penetration, std::max(0.0, rho + wire - R), 1e-15);
    EXPECT_LT((p.gradient - fd_gradient(energy, x)).norm(), 1e-6 * (1 + p.gradient.norm())) << rho;
    if (std::abs(rho + wire - R) > 1e-6) {  // the Hessian jumps at first contact
      EXPECT_LT((p.hessian - fd_jacobian(gradient, x)).norm(), 1e-4 * (1 + p.hessian.norm())) << rho;
    }
    // Positive semi-definite.
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Mat3>(p.hessian).eigenvalues().minCoeff(), -1e-9);
  }
}

TEST(Interaction, FrictionForceIsMinusTheGradientOfItsDissipationPotential) {
  const Vec3 n = Vec3(0.2, -0.3, 1).normalized();
  const double N = 0.7, mu = 0.3;
  for (double eps : {1e-4, 1e-2}) {
    for (const Vec3& v : {Vec3(1e-3, 2e-3, 0), Vec3(1e-6, 0, 3e-6), Vec3(0.1, -0.05, 0.2), Vec3(0, 0, 0)}) {
      const auto f = coulomb_friction(v, n, N, mu, eps);
      auto D = [&](const Vec3& w) { return coulomb_friction(w, n, N, mu, eps).dissipation; };
      auto F = [&](const Vec3& w) { return coulomb_friction(w, n, N, mu, eps).force; };
      EXPECT_LT((f.force + fd_gradient(D, v)).norm(), 1e-6 * (1 + f.force.norm()));
      EXPECT_LT((f.dfdv - fd_jacobian(F, v)).norm(), 1e-5 * (1 + f.dfdv.norm()));
      EXPECT_LE(f.force.norm(), mu * N * (1 + 1e-12));                                         // never more than μN
      EXPECT_NEAR(f.force.dot(n), 0.0, 1e-12);                                                 // tangential
      EXPECT_LE(Eigen::SelfAdjointEigenSolver<Mat3>(f.dfdv).eigenvalues().maxCoeff(), 1e-12);  // dissipative
    }
  }
  // Sliding well above the slip speed: the force is μN against the motion.
  const auto slide = coulomb_friction(Vec3(0.1, 0, 0), Vec3::UnitZ(), 2.0, 0.5, 1e-5);
  EXPECT_NEAR(slide.force.x(), -1.0, 1e-8);
}
