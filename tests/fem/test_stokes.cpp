// Stokes (flow/fem/src/stokes.cpp) on a straight tube against Hagen–Poiseuille: flow for a
// given pressure drop, the axial velocity on the axis, both linear solvers; and the
// conditions of the open boundaries: an outlet resistance (against Hagen–Poiseuille in
// series), a flow inlet, the basis combination against a direct solve, and conditions
// that leave the pressure level free refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "fem_test_cases.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/network_mesh.hpp"
#include "flowire/flow/fem/sample.hpp"
#include "flowire/flow/fem/stokes.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
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

double tube_resistance() { return flow::poiseuille_resistance(kEta, kL, kR); }

/// Mesh of the standard tube (about 5.5k tets), groups: 0 wall, 1 inlet, 2 outlet.
const TetMesh& tube_mesh() {
  static const TetMesh mesh = [] {
    MeshOptions mo;
    mo.size_factor = 0.35;
    return build_mesh(test::tube(kR, kL), mo);
  }();
  return mesh;
}

StokesOptions stokes() {
  StokesOptions so;
  so.viscosity = kEta;
  return so;
}

TEST(FemBoundary, TubeWithOutletResistanceCarriesDropOverSeriesResistance) {
  const TetMesh& mesh = tube_mesh();
  const double rt = tube_resistance(), r_out = 1.5 * rt, p_in = 20.0, p_d = 2.0;
  std::vector<GroupCondition> c(mesh.groups.size());
  c[1] = GroupCondition::at_pressure(p_in);
  c[2] = GroupCondition::with_resistance(r_out, p_d);
  const StokesSolution sol = solve_stokes(mesh, std::span<const GroupCondition>(c), stokes());
  const double q_exact = (p_in - p_d) / (rt + r_out);
  const double q = sol.group_flow[2];
  std::printf("tube + outlet resistance: Q = %.6e m^3/s, (R_tube + R) formula %.6e, error %.3e; outlet p %.5f Pa\n", q,
              q_exact, q / q_exact - 1.0, sol.group_pressure[2]);
  EXPECT_LT(std::abs(q / q_exact - 1.0), testing::tol(5e-3));
  // The outlet pressure is the one of the resistance law, to round-off.
  EXPECT_NEAR(sol.group_pressure[2], p_d + r_out * q, 1e-9 * p_in);
  EXPECT_NEAR(sol.group_pressure[1], p_in, 1e-12);
  EXPECT_LT(std::abs(sol.group_flow[1] + sol.group_flow[2]) / q_exact, 1e-8);
}

TEST(FemBoundary, TubeWithFlowInletHasTheHagenPoiseuilleDrop) {
  const TetMesh& mesh = tube_mesh();
  const double q_in = 4e-7, p_out = 100.0;  // 0.4 mL/s into the tube
  std::vector<GroupCondition> c(mesh.groups.size());
  c[1] = GroupCondition::with_flow(-q_in);  // outward flow through the inlet face is -Q
  c[2] = GroupCondition::at_pressure(p_out);
  const StokesSolution sol = solve_stokes(mesh, std::span<const GroupCondition>(c), stokes());
  const double drop = sol.group_pressure[1] - p_out, drop_exact = q_in * tube_resistance();
  std::printf("tube with flow inlet: drop %.6f Pa, Hagen–Poiseuille %.6f Pa, error %.3e\n", drop, drop_exact,
              drop / drop_exact - 1.0);
  EXPECT_LT(std::abs(drop / drop_exact - 1.0), testing::tol(5e-3));
  EXPECT_NEAR(-sol.group_flow[1], q_in, 1e-9 * q_in);  // the imposed flow, to round-off
  EXPECT_NEAR(sol.group_flow[2], q_in, 1e-8 * q_in);   // mass conservation
}

TEST(FemBoundary, BasisCombinationEqualsDirectSolveToRoundOff) {
  const TetMesh& mesh = tube_mesh();
  const StokesBasis basis(mesh, stokes());
  ASSERT_EQ(basis.open_groups().size(), 2u);
  // Symmetry of the flux matrix (reciprocity of Stokes) and zero flow for equal pressures.
  const auto& f = basis.unit_flux();
  EXPECT_NEAR(f[0][2], f[1][1], 1e-9 * std::abs(f[0][2]));
  EXPECT_NEAR(f[0][1] + f[1][1], 0.0, 1e-9 * std::abs(f[0][1]));
  for (int k = 0; k < 3; ++k) {
    std::vector<GroupCondition> c(mesh.groups.size());
    if (k == 1)
      c[1] = GroupCondition::with_flow(-3e-7);
    else
      c[1] = GroupCondition::at_pressure(10.0 + 7.0 * k);
    c[2] = k == 0 ? GroupCondition::at_pressure(1.5) : GroupCondition::with_resistance(tube_resistance() * k, 0.5 * k);
    const StokesSolution a = basis.solve(c);
    const StokesSolution b = solve_stokes(mesh, std::span<const GroupCondition>(c), stokes());
    double du = 0.0, umax = 0.0, dp = 0.0, pmax = 0.0;
    for (size_t n = 0; n < a.velocity.size(); ++n) {
      du = std::max(du, (a.velocity[n] - b.velocity[n]).norm());
      umax = std::max(umax, b.velocity[n].norm());
    }
    for (size_t v = 0; v < a.pressure.size(); ++v) {
      dp = std::max(dp, std::abs(a.pressure[v] - b.pressure[v]));
      pmax = std::max(pmax, std::abs(b.pressure[v]));
    }
    std::printf("frame %d: basis vs direct: velocity %.2e, pressure %.2e (relative)\n", k, du / umax, dp / pmax);
    EXPECT_LT(du / umax, 1e-9);
    EXPECT_LT(dp / pmax, 1e-9);
    for (size_t g = 1; g < 3; ++g) {
      EXPECT_NEAR(a.group_flow[g], b.group_flow[g], 1e-9 * std::abs(b.group_flow[2]));
      EXPECT_NEAR(a.group_pressure[g], b.group_pressure[g], 1e-9 * pmax);
    }
  }
}

TEST(FemBoundary, ConditionsThatDoNotFixThePressureAreUsageErrors) {
  const TetMesh& mesh = tube_mesh();
  std::vector<GroupCondition> c(mesh.groups.size());
  c[1] = GroupCondition::with_flow(-1e-7);
  c[2] = GroupCondition::with_flow(1e-7);
  try {
    (void)solve_stokes(mesh, std::span<const GroupCondition>(c), stokes());
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    EXPECT_NE(std::string(e.what()).find("pressure level"), std::string::npos) << e.what();
  }
  c[2] = GroupCondition::with_resistance(-1.0, 0.0);
  EXPECT_THROW((void)solve_stokes(mesh, std::span<const GroupCondition>(c), stokes()), Error);
}

}  // namespace
}  // namespace flowire::flow::fem
