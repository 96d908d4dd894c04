// The banded LDLᵀ against Eigen's general sparse LDLᵀ on random SPD banded systems, its
// inertia count, and the simulator giving the same step with either solver.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <random>

#include "flowire/rod/banded.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire_test.hpp"
#include "rod_test_util.hpp"

namespace flowire::rod {
namespace {

BandedMatrix random_banded(int n, int b, std::mt19937& rng, double shift) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  BandedMatrix a(n, b);
  for (int i = 0; i < n; ++i)
    for (int j = std::max(0, i - b); j < i; ++j) a.lower(i, j) = u(rng);
  for (int i = 0; i < n; ++i) a.lower(i, i) = shift + 2.0 * b * (1.0 + std::abs(u(rng)));
  return a;
}

TEST(RodBanded, MatchesGeneralSparseSolveOnRandomSpdSystems) {
  std::mt19937 rng(1234);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 20 + 37 * trial;
    const int b = 1 + trial % 11;
    const BandedMatrix a = random_banded(n, b, rng, 0.0);
    Eigen::VectorXd rhs(n);
    for (int i = 0; i < n; ++i) rhs(i) = u(rng);

    BandedLDLT ldlt;
    ldlt.reserve(n, b);
    ASSERT_TRUE(ldlt.factorize(a));
    EXPECT_EQ(ldlt.negative_pivots(), 0);
    Eigen::VectorXd x = rhs;
    ldlt.solve_in_place(x);

    Eigen::SparseMatrix<double> s;
    a.to_sparse_lower(s);
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> general(s);
    ASSERT_EQ(general.info(), Eigen::Success);
    const Eigen::VectorXd y = general.solve(rhs);
    EXPECT_LE((x - y).norm(), 1e-12 * y.norm()) << "n=" << n << " b=" << b;
    // And the residual through the band product.
    Eigen::VectorXd ax(n);
    a.multiply(x, ax);
    EXPECT_LE((ax - rhs).norm(), 1e-12 * rhs.norm());
  }
}

TEST(RodBanded, CountsNegativeEigenvalues) {
  std::mt19937 rng(99);
  const int n = 60, b = 4;
  BandedMatrix a = random_banded(n, b, rng, 0.0);
  Eigen::MatrixXd dense(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) dense(i, j) = a(i, j);
  const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(dense).eigenvalues();
  const double shift = 0.5 * (ev(5) + ev(6));  // exactly 6 eigenvalues below
  a.add_to_diagonal(-shift);
  BandedLDLT ldlt;
  ASSERT_TRUE(ldlt.factorize(a));
  EXPECT_EQ(ldlt.negative_pivots(), 6);
  // The modified factorization is positive definite and says so.
  ASSERT_TRUE(ldlt.factorize(a, 1e-8));
  EXPECT_GE(ldlt.modified_pivots(), 1);
  EXPECT_GT(ldlt.min_pivot(), -1e300);
}

TEST(RodBanded, SimulatorStepIsTheSameWithEitherSolver) {
  auto run = [](LinearSolver solver) {
    WireSpec spec = unit_rod_spec(40);
    RodSimulator sim(spec);
    sim.settings().linear_solver = solver;
    sim.set_gravity({0.0, 0.0, -9.81});
    sim.set_rotation_speed(3.0);
    for (int i = 0; i < 10; ++i) EXPECT_TRUE(sim.step(1e-2).converged());
    return std::vector<Eigen::Vector3d>(sim.positions().begin(), sim.positions().end());
  };
  const auto a = run(LinearSolver::Banded);
  const auto b = run(LinearSolver::SparseLDLT);
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) EXPECT_LE((a[k] - b[k]).norm(), 1e-9) << k;
}

}  // namespace
}  // namespace flowire::rod
