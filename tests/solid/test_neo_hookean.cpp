// The neo-Hookean law (solid/src/neo_hookean.cpp): its stress is the derivative of its
// energy and its tangent the derivative of its stress (central differences), it reduces to
// linear elasticity at F = I, it is frame-indifferent, refuses an inverted F, and refuses the
// parameters a compressible law cannot have.
#include "flowire/solid/neo_hookean.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "flowire/common/error.hpp"
#include "flowire_test.hpp"

namespace flowire::solid {
namespace {

/// A random displacement gradient H (F = I + H).
Mat3 random_deformation(std::mt19937& rng, double size) {
  std::uniform_real_distribution<double> d(-size, size);
  Mat3 f = Mat3::Zero();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) f(i, j) += d(rng);
  return f;
}

const NeoHookean kLaw = NeoHookean::from_young_poisson(1e6, 0.45);

TEST(NeoHookean, StressIsTheEnergysDerivative) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 5; ++trial) {
    const Mat3 H = random_deformation(rng, 0.3);
    const Mat3 P = kLaw.stress(H);
    const double h = 1e-6;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        Mat3 fp = H, fm = H;
        fp(a, b) += h;
        fm(a, b) -= h;
        const double fd = (kLaw.energy(fp) - kLaw.energy(fm)) / (2 * h);
        EXPECT_NEAR(P(a, b), fd, 1e-6 * P.norm()) << a << b;
      }
  }
}

TEST(NeoHookean, TangentIsTheStresssDerivative) {
  std::mt19937 rng(4);
  for (int trial = 0; trial < 5; ++trial) {
    const Mat3 H = random_deformation(rng, 0.3);
    const Tangent A = kLaw.tangent(H);
    const double h = 1e-6;
    for (int c = 0; c < 3; ++c)
      for (int d = 0; d < 3; ++d) {
        Mat3 fp = H, fm = H;
        fp(c, d) += h;
        fm(c, d) -= h;
        const Mat3 fd = (kLaw.stress(fp) - kLaw.stress(fm)) / (2 * h);
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) EXPECT_NEAR(A(a + 3 * b, c + 3 * d), fd(a, b), 1e-6 * A.norm());
      }
    EXPECT_LT((A - A.transpose()).norm(), 1e-9 * A.norm());  // the second derivative of W
  }
}

TEST(NeoHookean, AtRestItIsLinearElasticityWithLamesConstants) {
  const double E = 2e6, nu = 0.3;
  const NeoHookean law = NeoHookean::from_young_poisson(E, nu);
  EXPECT_NEAR(law.mu, E / (2 * (1 + nu)), 1e-9 * E);
  EXPECT_NEAR(law.lambda, E * nu / ((1 + nu) * (1 - 2 * nu)), 1e-9 * E);
  EXPECT_EQ(law.energy(Mat3::Zero()), 0.0);
  EXPECT_EQ(law.stress(Mat3::Zero()).norm(), 0.0);
  // Uniaxial stress: σ_xx = E ε with lateral strain −ν ε, to first order in ε.
  const double eps = 1e-7;
  Mat3 H = Mat3::Zero();
  H(0, 0) = eps;
  H(1, 1) = -nu * eps;
  H(2, 2) = -nu * eps;
  const Mat3 P = law.stress(H);
  EXPECT_NEAR(P(0, 0), E * eps, 1e-6 * E * eps);  // relative 1e-7 nonlinear, not 1e-9 round-off
  EXPECT_NEAR(P(1, 1), 0.0, 1e-6 * E * eps);
  // The energy: ½ σ ε to the same order, computed without cancellation at ε = 1e-7.
  EXPECT_NEAR(law.energy(H), 0.5 * E * eps * eps, 1e-6 * E * eps * eps);
}

TEST(NeoHookean, ATinyStrainsStressHasFullPrecision) {
  // At |H| = 1e-10 the nonlinear terms are 1e-10 of the linear ones; evaluated from F the
  // stress would carry an error of 1e-16 / 1e-10 = 1e-6 of itself.
  std::mt19937 rng(6);
  const Mat3 H = random_deformation(rng, 1e-10);
  const Mat3 linear = kLaw.mu * (H + H.transpose()) + kLaw.lambda * H.trace() * Mat3::Identity();
  EXPECT_LT((kLaw.stress(H) - linear).norm(), 1e-8 * linear.norm());
  const double linear_energy = 0.5 * (linear.array() * H.array()).sum();
  EXPECT_NEAR(kLaw.energy(H), linear_energy, 1e-8 * linear_energy);
}

TEST(NeoHookean, ARotationStoresNoEnergyAndRotatesTheStress) {
  std::mt19937 rng(5);
  const Mat3 F = Mat3::Identity() + random_deformation(rng, 0.2);
  const Mat3 R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Mat3 I = Mat3::Identity();
  EXPECT_NEAR(kLaw.energy(R - I), 0.0, 1e-9 * kLaw.mu);
  EXPECT_NEAR(kLaw.energy(R * F - I), kLaw.energy(F - I), 1e-9 * kLaw.energy(F - I));
  EXPECT_LT((kLaw.stress(R * F - I) - R * kLaw.stress(F - I)).norm(), 1e-9 * kLaw.stress(F - I).norm());
}

TEST(NeoHookean, AnInvertedDeformationHasInfiniteEnergy) {
  Mat3 H = Mat3::Zero();
  H(2, 2) = -1.1;  // F_zz = −0.1
  EXPECT_TRUE(std::isinf(kLaw.energy(H)));
  H(2, 2) = -1.0;  // flat
  EXPECT_TRUE(std::isinf(kLaw.energy(H)));
}

TEST(NeoHookean, RefusesAModulusOrARatioACompressibleLawCannotHave) {
  EXPECT_THROW((void)NeoHookean::from_young_poisson(0.0, 0.3), Error);
  EXPECT_THROW((void)NeoHookean::from_young_poisson(-1e6, 0.3), Error);
  EXPECT_THROW((void)NeoHookean::from_young_poisson(std::nan(""), 0.3), Error);
  EXPECT_THROW((void)NeoHookean::from_young_poisson(1e6, 0.5), Error);
  EXPECT_THROW((void)NeoHookean::from_young_poisson(1e6, -1.0), Error);
  try {
    (void)NeoHookean::from_young_poisson(1e6, 0.5, "wall.poisson_ratio");
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("wall.poisson_ratio"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace flowire::solid
