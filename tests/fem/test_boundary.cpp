// The network's boundary conditions on the FEM: outlet resistances, a flow inlet, unequal
// resistances on a Y bifurcation (against Hagen–Poiseuille in series and against the
// network), and the quasi-steady pulsatile series built from one factorization (against
// direct solves at each frame's boundary values).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include "fem_test_cases.hpp"
#include "flowire/common/error.hpp"
#include "flowire/fem/boundary_values.hpp"
#include "flowire/fem/compare.hpp"
#include "flowire/fem/pulsatile.hpp"
#include "flowire/fem/network_mesh.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire_test.hpp"

namespace flowire::fem {
namespace {

constexpr double kR = 2e-3, kL = 30e-3, kEta = 3.5e-3;

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

BoundaryValues y_resistances() {
  BoundaryValues bv;
  bv.inlet_pressure = 200.0;
  const auto net = test::y_small(0.0);
  // Outlet resistances 1x and 4x the Poiseuille resistance of a daughter branch.
  double r_branch = 0.0;
  const int out0 = net.ends()[1] == net.widest_end() ? net.ends()[0] : net.ends()[1];
  const auto [b, e] = net.node_segments(out0);
  r_branch = flow::poiseuille_resistance(bv.viscosity, 10e-3, net.segment(*b).radius);
  int k = 0;
  for (int end : net.ends()) {
    if (end == net.widest_end()) continue;
    bv.outlets.push_back({end, OutletValue::Type::Resistance, 10.0, (k++ == 0 ? 1.0 : 4.0) * r_branch});
  }
  return bv;
}

TEST(FemBoundary, YWithUnequalOutletResistancesSplitsLikeTheNetwork) {
  const auto net = test::y_small(0.0);
  FemOptions opt;
  opt.write_png = false;
  const BoundaryValues bv = y_resistances();
  const CompareResult r = compare(net, bv, opt, "");
  ASSERT_EQ(r.outlets.size(), 2u);
  const double qn = r.outlets[0].flow_network + r.outlets[1].flow_network;
  const double qf = r.outlets[0].flow_fem + r.outlets[1].flow_fem;
  std::printf(
      "Y, outlet resistances 1:4: network split %.4f / %.4f, FEM %.4f / %.4f, split error %.3e, flow error "
      "%.3e; outlet pressures network %.3f / %.3f Pa, FEM %.3f / %.3f Pa\n",
      r.outlets[0].flow_network / qn, r.outlets[1].flow_network / qn, r.outlets[0].flow_fem / qf,
      r.outlets[1].flow_fem / qf, r.max_flow_split_error, r.max_flow_error, r.outlets[0].pressure_network,
      r.outlets[1].pressure_network, r.outlets[0].pressure_fem, r.outlets[1].pressure_fem);
  EXPECT_GT(std::abs(r.outlets[0].flow_network / qn - 0.5), 0.1);  // the resistances do change the split
  EXPECT_LT(r.max_flow_split_error, testing::tol(1e-2));
  EXPECT_LT(r.max_rel_diff_drop_away, testing::tol(2e-2));
  for (const auto& o : r.outlets) {  // each outlet obeys its resistance law in both models
    const auto& ov = bv.outlets[o.node == bv.outlets[0].node ? 0 : 1];
    EXPECT_NEAR(o.pressure_fem, ov.pressure + ov.resistance * o.flow_fem, 1e-9 * 200.0);
    EXPECT_NEAR(o.pressure_network, ov.pressure + ov.resistance * o.flow_network, 1e-9 * 200.0);
  }
}

TEST(FemBoundary, PulsatileFramesEqualDirectSolvesAndFollowTheNetwork) {
  const auto net = test::y_small(0.3);
  FemOptions opt;
  opt.write_png = false;
  opt.size_factor = 0.5;
  const BoundaryValues base = y_resistances();
  // Inlet pressure of the published sine (P1 = 300 Pa, P2 = 100 Pa above the distal pressure).
  const double period = 0.8;
  std::vector<double> times;
  std::vector<BoundaryValues> frames;
  for (int i = 0; i < 4; ++i) {
    times.push_back(period * i / 4.0);
    BoundaryValues bv = base;
    bv.inlet_pressure = 200.0 + 100.0 * std::sin(2.0 * std::numbers::pi * times.back() / period);
    frames.push_back(bv);
  }
  const auto dir = testing::scratch_dir("fem_pulsatile");
  const PulsatileResult p = compare_pulsatile(net, times, frames, base, 0.0, opt, dir.string());
  ASSERT_EQ(p.frames.size(), 4u);
  EXPECT_EQ(p.factorizations, 1);
  std::printf(
      "pulsatile Y (4 frames): max split error %.3e, max drop difference away %.3e; basis %.2f s, "
      "frames %.2f s\n",
      p.max_flow_split_error, p.max_rel_diff_drop_away, p.basis_seconds, p.frames_seconds);
  EXPECT_LT(p.max_flow_split_error, testing::tol(1e-2));
  EXPECT_LT(p.max_rel_diff_drop_away, testing::tol(2e-2));
  // Frame 1 (systole) against the steady comparison solved directly at its boundary values.
  const CompareResult direct = compare(net, frames[1], opt, "");
  ASSERT_EQ(direct.outlets.size(), p.frames[1].outlets.size());
  for (size_t k = 0; k < direct.outlets.size(); ++k) {
    EXPECT_NEAR(p.frames[1].outlets[k].flow_fem, direct.outlets[k].flow_fem,
                1e-9 * std::abs(direct.outlets[k].flow_fem));
    EXPECT_NEAR(p.frames[1].outlets[k].pressure_fem, direct.outlets[k].pressure_fem, 1e-9 * 300.0);
  }
  ASSERT_EQ(direct.samples.size(), p.frames[1].samples.size());
  for (size_t k = 0; k < direct.samples.size(); ++k)
    EXPECT_NEAR(p.frames[1].samples[k].pressure_fem, direct.samples[k].pressure_fem, 1e-9 * 300.0);
  // Files: a leading time column, one block of rows per frame.
  std::ifstream csv(dir / "fem_pulsatile.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("time,branch,s,x,y,z,pressure_network,pressure_fem,rel_diff", 0), 0u) << header;
  int rows = 0;
  for (std::string line; std::getline(csv, line);) ++rows;
  EXPECT_EQ(rows, static_cast<int>(4 * p.frames[0].samples.size()));
  std::ifstream outlets(dir / "fem_pulsatile_outlets.csv");
  std::getline(outlets, header);
  EXPECT_EQ(header, "time,outlet,flow_network,flow_fem,rel_diff,pressure_network,pressure_fem");
  for (const char* f : {"fem.pvd", "fem_0000.vtu", "fem_0003.vtu", "fem_compare.csv", "fem_outlets.csv"})
    EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
}

TEST(FemBoundary, NetworkBoundaryValuesFromAFlowSpec) {
  const auto net = test::y_small(0.0);
  flow::FlowSpec spec;
  flow::InletBC in;
  in.type = flow::InletBC::Type::Flow;
  in.waveform = flow::Waveform::sine(2e-6, 1e-6, 0.8);
  spec.inlets.push_back(in);
  flow::OutletBC o;
  o.type = flow::OutletBC::Type::Rcr;
  o.rp = 1e8;
  o.rd = 3e8;
  o.c = 1e-9;
  o.distal_pressure = 50.0;
  spec.outlets.push_back(o);
  flow::resolve_nodes(spec, net);
  const BoundaryValues bv = boundary_values(spec, net, 0.2);  // a quarter period: the systolic value
  EXPECT_EQ(bv.inlet_type, BoundaryValues::Inlet::Flow);
  EXPECT_NEAR(bv.inlet_flow, 2e-6, 1e-18);
  ASSERT_EQ(bv.outlets.size(), 2u);
  for (const auto& v : bv.outlets) {
    EXPECT_EQ(v.type, OutletValue::Type::Resistance);
    EXPECT_DOUBLE_EQ(v.resistance, 4e8);
    EXPECT_DOUBLE_EQ(v.pressure, 50.0);
  }
  spec.inlets.push_back(spec.inlets.front());
  EXPECT_THROW((void)boundary_values(spec, net, 0.0), Error);
}

}  // namespace
}  // namespace flowire::fem
