// Stokes accuracy on a straight tube against Hagen–Poiseuille: flow for a given
// pressure drop, the axial velocity on the axis, both linear solvers, and the observed
// order of convergence over three mesh sizes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "fem_test_cases.hpp"
#include "flowire/common/error.hpp"
#include "flowire/fem/mesh.hpp"
#include "flowire/fem/network_mesh.hpp"
#include "flowire/fem/sample.hpp"
#include "flowire/fem/stokes.hpp"
#include "flowire_test.hpp"

namespace flowire::fem {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kR = 2e-3, kL = 30e-3, kEta = 3.5e-3, kDp = 20.0;

double poiseuille_flow() { return kPi * std::pow(kR, 4) * kDp / (8.0 * kEta * kL); }

struct TubeResult {
  double flow_error, axis_error, inlet_outlet_mismatch;
  int tets;
};

TubeResult solve_tube(double size_factor, LinearSolver solver, Equations eq = Equations::Stokes,
                      double density = 1060.0) {
  const auto net = test::tube(kR, kL);
  MeshOptions mo;
  mo.size_factor = size_factor;
  const TetMesh mesh = build_mesh(net, mo);
  std::vector<double> p(mesh.groups.size(), 0.0);
  p[1] = kDp;  // inlet; the outlet stays at 0
  StokesOptions so;
  so.viscosity = kEta;
  so.solver = solver;
  so.equations = eq;
  so.density = density;
  const StokesSolution sol = solve_stokes(mesh, p, so);
  const double q = poiseuille_flow();
  TubeResult r{};
  r.tets = mesh.num_tets();
  r.flow_error = sol.group_flow[2] / q - 1.0;
  r.inlet_outlet_mismatch = (sol.group_flow[1] + sol.group_flow[2]) / q;
  const FieldSampler sampler(mesh, sol);
  const double umax = 2.0 * q / (kPi * kR * kR);
  double worst = 0.0;
  for (double s : {0.25, 0.5, 0.75}) {
    const auto v = sampler.at(vessels::Vec3(s * kL, 0, 0));
    EXPECT_TRUE(v.has_value());
    if (v) worst = std::max(worst, std::abs(v->velocity.x() / umax - 1.0));
  }
  r.axis_error = worst;
  std::printf(
      "size factor %.3f: %d tets, %d unknowns, flow error %.3e, axis velocity error %.3e, "
      "assembly %.2f s, solve %.2f s (%d its)\n",
      size_factor, r.tets, sol.unknowns, r.flow_error, r.axis_error, sol.assemble_seconds, sol.solve_seconds,
      sol.krylov_iterations);
  return r;
}

TEST(FemStokes, StraightTubeMatchesHagenPoiseuille) {
  const TubeResult r = solve_tube(0.35, LinearSolver::Mumps);
  EXPECT_LT(std::abs(r.flow_error), testing::tol(5e-3));
  EXPECT_LT(r.axis_error, testing::tol(1e-2));
  EXPECT_LT(std::abs(r.inlet_outlet_mismatch), 1e-8);
}

TEST(FemStokes, FieldsplitSolverAgreesWithMumps) {
  const TubeResult r = solve_tube(0.5, LinearSolver::Fieldsplit);
  EXPECT_LT(std::abs(r.flow_error), testing::tol(5e-3));
  EXPECT_LT(r.axis_error, testing::tol(1e-2));
}

TEST(FemStokes, NavierStokesRefusesTheIterativeSolver) {
  // The fieldsplit preconditioner approximates the Schur complement by the pressure mass
  // matrix, which ignores convection: Newton's systems at arterial Reynolds numbers
  // stagnate with it, so Navier–Stokes asks for the direct solver.
  const auto net = test::tube(kR, kL);
  MeshOptions mo;
  mo.size_factor = 0.8;
  const TetMesh mesh = build_mesh(net, mo);
  StokesOptions so;
  so.equations = Equations::NavierStokes;
  so.solver = LinearSolver::Fieldsplit;
  const std::vector<double> p = {0.0, 10.0, 0.0};
  try {
    (void)solve_stokes(mesh, p, so);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    EXPECT_NE(std::string(e.what()).find("mumps"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace flowire::fem
