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
