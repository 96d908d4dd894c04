// The reference elements (common/src/element.cpp): quadrature exact to its degree against
// the closed-form monomial integrals, P2/P1 bases nodal and reproducing every quadratic /
// linear field, gradients and second derivatives against finite differences.
#include "flowire/flow/fem/element.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

double factorial(int n) { return n <= 1 ? 1.0 : n * factorial(n - 1); }

TEST(FemElement, TetQuadratureIsExactToDegreeFive) {
  for (int a = 0; a <= 5; ++a)
    for (int b = 0; a + b <= 5; ++b)
      for (int c = 0; a + b + c <= 5; ++c) {
        double sum = 0.0;
        for (const auto& q : tet_quadrature())
          sum += q.weight * std::pow(q.xi[0], a) * std::pow(q.xi[1], b) * std::pow(q.xi[2], c);
        const double exact = factorial(a) * factorial(b) * factorial(c) / factorial(a + b + c + 3);
        EXPECT_NEAR(sum, exact, 1e-15) << a << b << c;
      }
}

TEST(FemElement, TheFourPointTetQuadratureIsExactToDegreeTwoAndNotThree) {
  double worst_cubic = 0.0;
  for (int a = 0; a <= 3; ++a)
    for (int b = 0; a + b <= 3; ++b)
      for (int c = 0; a + b + c <= 3; ++c) {
        double sum = 0.0;
        for (const auto& q : element::tet_quadrature_degree2())
          sum += q.weight * std::pow(q.xi[0], a) * std::pow(q.xi[1], b) * std::pow(q.xi[2], c);
        const double exact = factorial(a) * factorial(b) * factorial(c) / factorial(a + b + c + 3);
        if (a + b + c <= 2) {
          EXPECT_NEAR(sum, exact, 1e-16) << a << b << c;
        } else {
          worst_cubic = std::max(worst_cubic, std::abs(sum - exact));
        }
      }
  EXPECT_GT(worst_cubic, 1e-5);  // the rule's degree is 2, not more
}

TEST(FemElement, TriQuadratureIsExactToDegreeFour) {
  for (int a = 0; a <= 4; ++a)
    for (int b = 0; a + b <= 4; ++b) {
      double sum = 0.0;
      for (const auto& q : tri_quadrature()) sum += q.weight * std::pow(q.xi[0], a) * std::pow(q.xi[1], b);
      const double exact = factorial(a) * factorial(b) / factorial(a + b + 2);
      EXPECT_NEAR(sum, exact, 1e-14) << a << b;
    }
}

const std::array<std::array<double, 3>, 10> kTetNodes{{{0, 0, 0},
                                                       {1, 0, 0},
                                                       {0, 1, 0},
                                                       {0, 0, 1},
                                                       {.5, 0, 0},
                                                       {.5, .5, 0},
                                                       {0, .5, 0},
                                                       {0, 0, .5},
                                                       {.5, 0, .5},
                                                       {0, .5, .5}}};

TEST(FemElement, P2BasisIsNodalAndGradientsMatchDifferences) {
  const auto& nodes = kTetNodes;
  double v[10];
  for (int i = 0; i < 10; ++i) {
    tet_p2(nodes[static_cast<size_t>(i)], v);
    for (int j = 0; j < 10; ++j) EXPECT_NEAR(v[j], i == j ? 1.0 : 0.0, 1e-15);
  }
  const std::array<double, 3> x{0.21, 0.17, 0.33};
  double g[10][3], vp[10], vm[10];
  tet_p2_grad(x, g);
  for (int d = 0; d < 3; ++d) {
    auto xp = x, xm = x;
    xp[static_cast<size_t>(d)] += 1e-6;
    xm[static_cast<size_t>(d)] -= 1e-6;
    tet_p2(xp, vp);
    tet_p2(xm, vm);
    for (int i = 0; i < 10; ++i) EXPECT_NEAR(g[i][d], (vp[i] - vm[i]) / 2e-6, 1e-8);
  }
}

/// A quadratic in (ξ, η, ζ) with arbitrary coefficients, its gradient.
struct Quadratic {
  double c[10];
  [[nodiscard]] double operator()(const std::array<double, 3>& x) const {
    return c[0] + c[1] * x[0] + c[2] * x[1] + c[3] * x[2] + c[4] * x[0] * x[0] + c[5] * x[1] * x[1] +
           c[6] * x[2] * x[2] + c[7] * x[0] * x[1] + c[8] * x[1] * x[2] + c[9] * x[0] * x[2];
  }
  [[nodiscard]] std::array<double, 3> grad(const std::array<double, 3>& x) const {
    return {c[1] + 2 * c[4] * x[0] + c[7] * x[1] + c[9] * x[2], c[2] + 2 * c[5] * x[1] + c[7] * x[0] + c[8] * x[2],
            c[3] + 2 * c[6] * x[2] + c[8] * x[1] + c[9] * x[0]};
  }
};

TEST(FemElement, P2InterpolationReproducesEveryQuadraticAndItsGradient) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0), w(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Quadratic f{};
    for (double& c : f.c) c = u(rng);
    for (int k = 0; k < 10; ++k) {
      std::array<double, 3> x{w(rng), w(rng), w(rng)};
      const double s = x[0] + x[1] + x[2];
      if (s > 1.0)
        for (double& v : x) v /= 1.5 * s;
      double phi[10], g[10][3];
      tet_p2(x, phi);
      tet_p2_grad(x, g);
      double value = 0.0;
      std::array<double, 3> grad{0, 0, 0};
      for (int i = 0; i < 10; ++i) {
        const double fi = f(kTetNodes[static_cast<size_t>(i)]);
        value += fi * phi[i];
        for (int d = 0; d < 3; ++d) grad[static_cast<size_t>(d)] += fi * g[i][d];
      }
      EXPECT_NEAR(value, f(x), 1e-14);
      for (int d = 0; d < 3; ++d) EXPECT_NEAR(grad[static_cast<size_t>(d)], f.grad(x)[static_cast<size_t>(d)], 1e-13);
    }
  }
}

TEST(FemElement, P2HessianMatchesDifferencesOfTheGradient) {
  double h[10][3][3];
  tet_p2_hessian(h);
  const double eps = 1e-6;
  for (const std::array<double, 3> x : {std::array<double, 3>{0.1, 0.2, 0.3}, std::array<double, 3>{0.6, 0.05, 0.1}}) {
    for (int b = 0; b < 3; ++b) {
      auto xp = x, xm = x;
      xp[static_cast<size_t>(b)] += eps;
      xm[static_cast<size_t>(b)] -= eps;
      double gp[10][3], gm[10][3];
      tet_p2_grad(xp, gp);
      tet_p2_grad(xm, gm);
      for (int i = 0; i < 10; ++i)
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(h[i][a][b], (gp[i][a] - gm[i][a]) / (2 * eps), 1e-7) << i << a << b;
    }
  }
  // Symmetric, and the second derivatives of Σφ_i = 1 vanish.
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      double sum = 0.0;
      for (int i = 0; i < 10; ++i) {
        EXPECT_EQ(h[i][a][b], h[i][b][a]);
        sum += h[i][a][b];
      }
      EXPECT_NEAR(sum, 0.0, 1e-14);
    }
}

TEST(FemElement, P1IsTheBarycentricCoordinates) {
  const std::array<double, 3> x{0.2, 0.3, 0.1};
  double v[4];
  tet_p1(x, v);
  EXPECT_NEAR(v[0], 0.4, 1e-15);
  EXPECT_EQ(v[1], 0.2);
  EXPECT_EQ(v[2], 0.3);
  EXPECT_EQ(v[3], 0.1);
  for (int i = 0; i < 4; ++i) {
    tet_p1(kTetNodes[static_cast<size_t>(i)], v);
    for (int j = 0; j < 4; ++j) EXPECT_EQ(v[j], i == j ? 1.0 : 0.0);
  }
}

TEST(FemElement, TriangleP2IsNodalReproducesQuadraticsAndItsGradientMatchesDifferences) {
  const std::array<std::array<double, 3>, 6> nodes{
      {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {.5, 0, 0}, {.5, .5, 0}, {0, .5, 0}}};
  double v[6];
  for (int i = 0; i < 6; ++i) {
    tri_p2(nodes[static_cast<size_t>(i)], v);
    for (int j = 0; j < 6; ++j) EXPECT_NEAR(v[j], i == j ? 1.0 : 0.0, 1e-15);
  }
  auto f = [](const std::array<double, 3>& x) {
    return 0.3 - 1.1 * x[0] + 0.7 * x[1] + 2.0 * x[0] * x[0] - 0.4 * x[0] * x[1] + 1.3 * x[1] * x[1];
  };
  const std::array<double, 3> x{0.27, 0.41, 0.0};
  tri_p2(x, v);
  double value = 0.0;
  for (int i = 0; i < 6; ++i) value += f(nodes[static_cast<size_t>(i)]) * v[i];
  EXPECT_NEAR(value, f(x), 1e-14);
  double g[6][2], vp[6], vm[6];
  tri_p2_grad(x, g);
  for (int d = 0; d < 2; ++d) {
    auto xp = x, xm = x;
    xp[static_cast<size_t>(d)] += 1e-6;
    xm[static_cast<size_t>(d)] -= 1e-6;
    tri_p2(xp, vp);
    tri_p2(xm, vm);
    for (int i = 0; i < 6; ++i) EXPECT_NEAR(g[i][d], (vp[i] - vm[i]) / 2e-6, 1e-8);
  }
}

TEST(FemElement, QuadraturePointsLieInsideWithPositiveWeights) {
  for (const auto& q : tet_quadrature()) {
    EXPECT_GT(q.weight, 0.0);
    EXPECT_GT(std::min({q.xi[0], q.xi[1], q.xi[2], 1.0 - q.xi[0] - q.xi[1] - q.xi[2]}), 0.0);
  }
  EXPECT_EQ(tet_quadrature().size(), 14u);
  for (const auto& q : tri_quadrature()) {
    EXPECT_GT(q.weight, 0.0);
    EXPECT_GT(std::min({q.xi[0], q.xi[1], 1.0 - q.xi[0] - q.xi[1]}), 0.0);
    EXPECT_EQ(q.xi[2], 0.0);
  }
  EXPECT_EQ(tri_quadrature().size(), 6u);
}

}  // namespace
}  // namespace flowire::flow::fem
