// The banded LDLᵀ against Eigen's general sparse LDLᵀ on random SPD banded systems, its
// inertia count, the simulator giving the same step with either solver, and a low-rank
// stiffness off the band (Woodbury) against a dense solve and in a Newton solve.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <random>

#include "flowire/rod/banded.hpp"
#include "flowire/rod/external.hpp"
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
    // A right-hand side zero above a row: the forward sweep started there gives the same bits.
    const int first = n / 3;
    Eigen::VectorXd tail = rhs;
    tail.head(first).setZero();
    Eigen::VectorXd whole = tail, from = tail;
    ldlt.solve_in_place(whole);
    ldlt.solve_in_place(from, first);
    EXPECT_EQ(whole, from) << "n=" << n << " b=" << b;
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

TEST(RodBanded, ALowRankTermIsSolvedExactlyByWoodbury) {
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 64, b = 6, m = 5, first_free = 3, first_fixed = n - 4;
  BandedMatrix a = random_banded(n, b, rng, 0.0);
  LowRankStiffness term;
  for (int j = 0; j < m; ++j) {
    term.dofs.push_back(4 * (2 + 3 * j));  // also one column reaching the held tail below
    term.directions.emplace_back(u(rng), u(rng), u(rng));
  }
  term.dofs.back() = first_fixed - 1;  // its 3-vector straddles the held unknowns
  // R symmetric and indefinite (as the part of a contact stiffness off the band may be).
  Eigen::MatrixXd r = Eigen::MatrixXd::Random(m, m);
  r = 0.5 * (r + r.transpose());
  term.core = r;
  for (int d = first_fixed; d < n; ++d) a.set_identity_row(d);
  for (int d = 0; d < first_free; ++d) a.set_identity_row(d);
  BandedLDLT ldlt;
  ldlt.reserve(n, b);
  ASSERT_TRUE(ldlt.factorize(a));
  LowRankSolve solve;
  ASSERT_TRUE(
      solve.prepare(term, n, first_free, first_fixed, [&](auto col, int first) { ldlt.solve_in_place(col, first); }));
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  for (int i = first_free; i < first_fixed; ++i) rhs(i) = u(rng);
  Eigen::VectorXd x = rhs;
  ldlt.solve_in_place(x);
  solve.correct(x);
  // Dense reference: the band plus U R Uᵀ restricted to the free unknowns.
  Eigen::SparseMatrix<double> s;
  a.to_sparse_lower(s);
  Eigen::MatrixXd dense = Eigen::MatrixXd(s).selfadjointView<Eigen::Lower>();
  Eigen::MatrixXd uu = Eigen::MatrixXd::Zero(n, m);
  for (int j = 0; j < m; ++j)
    for (int c = 0; c < 3; ++c) {
      const int d = term.dofs[static_cast<size_t>(j)] + c;
      if (d >= first_free && d < first_fixed) uu(d, j) = term.directions[static_cast<size_t>(j)][c];
    }
  dense += uu * r * uu.transpose();
  const Eigen::VectorXd y = dense.lu().solve(rhs);
  EXPECT_LE((x - y).norm(), 1e-11 * y.norm());
  EXPECT_EQ(x.head(first_free).norm(), 0.0);
  EXPECT_EQ(x.tail(n - first_fixed).norm(), 0.0);
}

/// A rod pulled at four vertices by springs coupled through a dense stiffness S (as the
/// contacts of one deformable wall are): E = ½ gᵀ S g, g_i = z_i − target.
std::shared_ptr<ExternalForce> coupled_springs(bool coupled_jacobian) {
  return std::make_shared<ExternalForceFunction>([coupled_jacobian](const RodView& rod, ForceAccumulator& out) {
    const std::vector<int> vertices = {8, 16, 24, 32};
    const int m = 4;
    Eigen::MatrixXd stiffness = 50.0 * (Eigen::MatrixXd::Identity(m, m) + 0.9 * Eigen::MatrixXd::Ones(m, m));
    Eigen::VectorXd g(m);
    for (int i = 0; i < m; ++i) g[i] = rod.position(vertices[static_cast<size_t>(i)]).z() - 0.05 * (i + 1);
    const Eigen::VectorXd f = -(stiffness * g);
    out.add_energy(0.5 * g.dot(stiffness * g));
    const std::vector<Eigen::Vector3d> directions(4, Eigen::Vector3d::UnitZ());
    for (int i = 0; i < m; ++i) out.add_conservative_force(vertices[static_cast<size_t>(i)], f[i] * directions[0]);
    if (coupled_jacobian) {
      out.add_coupled_stiffness(vertices, directions, stiffness);
    } else {
      for (int i = 0; i < m; ++i) {
        Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
        j(2, 2) = -stiffness(i, i);
        out.add_position_jacobian(vertices[static_cast<size_t>(i)], j);
      }
    }
  });
}

TEST(RodBanded, ForcesCoupledAcrossTheWireConvergeWithTheirLowRankStiffness) {
  auto run = [](bool coupled, LinearSolver solver, bool* converged, int* iterations) {
    RodSimulator sim(unit_rod_spec(40));
    sim.settings().linear_solver = solver;
    sim.add_external(coupled_springs(coupled));
    const StepReport rep = sim.solve_static();
    *converged = rep.converged();
    *iterations = rep.newton_iterations;
    return std::vector<Eigen::Vector3d>(sim.positions().begin(), sim.positions().end());
  };
  int exact = 0, diagonal = 0, sparse = 0;
  bool exact_ok = false, diagonal_ok = false, sparse_ok = false;
  const auto a = run(true, LinearSolver::Banded, &exact_ok, &exact);
  const auto c = run(true, LinearSolver::SparseLDLT, &sparse_ok, &sparse);
  {
    // Without the coupling in its matrix Newton's direction is poor: many more iterations,
    // or none of them reaching the tolerance (then the library warns).
    testing::ExpectWarnings warnings;
    (void)run(false, LinearSolver::Banded, &diagonal_ok, &diagonal);
  }
  std::printf("Newton iterations: coupled stiffness %d, its diagonal only %d (%s), sparse back end %d\n", exact,
              diagonal, diagonal_ok ? "converged" : "not converged", sparse);
  EXPECT_TRUE(exact_ok);
  EXPECT_TRUE(sparse_ok);
  for (size_t k = 0; k < a.size(); ++k) EXPECT_LE((a[k] - c[k]).norm(), 1e-9) << k;
  EXPECT_LE(exact, 20);
  EXPECT_LE(std::abs(sparse - exact), 2);  // (the banded path takes chord iterations)
  EXPECT_GT(diagonal, 3 * exact);
}

}  // namespace
}  // namespace flowire::rod
