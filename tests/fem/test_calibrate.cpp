// The network fitted to the 3D solution (flow/fem/src/calibrate.cpp): on an asymmetric Y at
// Reynolds numbers where inertia changes the split, the calibrated network (in total pressure)
// against the 3D solutions it was fitted to and one it was not; at Stokes flow, factors near 1 and no quadratic term;
// the calibration file written and read back, and refused for another network.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <string>

#include "fem_test_cases.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/calibration.hpp"
#include "flowire/flow/fem/calibrate.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

constexpr double kEta = 3.5e-3, kRho = 1060.0;

/// A flow into the parent (radius 1 mm) at inlet Reynolds number `re`, both outlets at 0 Pa.
BoundaryValues flow_at_reynolds(double re) {
  BoundaryValues bv;
  bv.inlet_type = BoundaryValues::Inlet::Flow;
  bv.inlet_flow = re * kEta * std::numbers::pi * 1e-3 / (2.0 * kRho);
  bv.viscosity = kEta;
  bv.density = kRho;
  return bv;
}

FemOptions coarse(Equations eq) {
  FemOptions opt;
  opt.equations = eq;
  opt.size_factor = 0.6;
  opt.samples_per_branch = 6;
  opt.write_png = false;
  opt.write_vtu = false;
  return opt;
}

double rel(double a, double b) { return std::abs(a / b - 1.0); }

double worst_outlet_flow(const CompareResult& r) {
  double w = 0.0;
  for (const auto& o : r.outlets) w = std::max(w, rel(o.flow_network, o.flow_fem));
  return w;
}

TEST(FemCalibrate, TheCalibratedYMatchesNavierStokesAtItsFlowsAndAtOneItWasNotFittedTo) {
  const auto net = test::y_small(0.3);
  const CalibrationResult r = calibrate(net, flow_at_reynolds(300.0), coarse(Equations::NavierStokes));
  ASSERT_EQ(r.runs.size(), 4u);
  for (const auto& run : r.runs) {
    const double p_after = rel(run.after.inlet_pressure_network, run.after.inlet_pressure_fem);
    std::printf(
        "Y at Re %.0f (%s): inlet pressure network/3D before %.4f after %.4f; outlet flows before %.2e after %.2e; "
        "max drop difference away from junctions before %.3f after %.3f\n",
        run.before.reynolds, run.fitted ? "fitted" : "check",
        run.before.inlet_pressure_network / run.before.inlet_pressure_fem,
        run.after.inlet_pressure_network / run.after.inlet_pressure_fem, worst_outlet_flow(run.before),
        worst_outlet_flow(run.after), run.before.max_rel_diff_drop_away, run.after.max_rel_diff_drop_away);
    EXPECT_LT(p_after, run.fitted ? 0.01 : 0.03) << run.factor;
    EXPECT_LT(worst_outlet_flow(run.after), run.fitted ? 0.01 : 0.03) << run.factor;
    // Along the branches away from the junction, in total pressure, within 3% of the drop.
    EXPECT_LT(run.after.max_rel_diff_drop_away, 0.03) << run.factor;
    EXPECT_TRUE(run.after.total_pressure);
  }
  // Inertia: Poiseuille misses the split at the largest flow by more than 5% of an outlet's flow,
  // and a branch's fit carries a quadratic term worth more than 5% of its linear one there.
  EXPECT_GT(worst_outlet_flow(r.runs[2].before), 0.05);
  double nonlinear = 0.0;
  for (const auto& f : r.calibration.fits) {
    std::printf("%s: a/R_P %.4f, K Q/a %.3f at the largest flow, residual %.1e, %d pieces%s\n", f.name.c_str(),
                f.linear / f.poiseuille_resistance, f.quadratic * f.flows.back() / f.linear, f.residual, f.pieces,
                f.bounded ? ", bound active" : "");
    nonlinear = std::max(nonlinear, f.quadratic * f.flows.back() / f.linear);
  }
  EXPECT_GT(nonlinear, 0.05);
  EXPECT_EQ(r.calibration.laws.size(), static_cast<size_t>(net.num_segments()));
  EXPECT_EQ(r.calibration.equations, "navier_stokes");
}

TEST(FemCalibrate, AtStokesFlowTheFitIsLinearAndCloseToPoiseuille) {
  const auto net = test::y_small(0.3);
  CalibrateOptions co;
  co.factors = {1.0, 2.0};
  co.check_factor = 0.0;
  const CalibrationResult r = calibrate(net, flow_at_reynolds(300.0), coarse(Equations::Stokes), co);
  ASSERT_EQ(r.runs.size(), 2u);
  for (const auto& f : r.calibration.fits) {
    const double qmax = f.flows.back();
    std::printf("%s: a/R_P %.4f, K Q/a %.2e, residual %.1e, %d pieces\n", f.name.c_str(),
                f.linear / f.poiseuille_resistance, f.quadratic * qmax / f.linear, f.residual, f.pieces);
    EXPECT_NEAR(f.linear / f.poiseuille_resistance, 1.0, 0.15) << f.name;
    EXPECT_LT(f.quadratic * qmax, 1e-6 * f.linear) << f.name;
  }
  for (const auto& run : r.runs) EXPECT_LT(rel(run.after.inlet_pressure_network, run.after.inlet_pressure_fem), 1e-3);
}

TEST(FemCalibrate, TheFileIsReadBackForItsNetworkAndRefusedForAnother) {
  const auto net = test::y_small(0.3);
  flow::Calibration c;
  flow::identify(c, net);
  c.equations = "stokes";
  c.inlet_flows = {1e-6};
  for (int s = 0; s < net.num_segments(); ++s) c.laws.push_back({1.0 + 0.01 * s, 1e9 * s});
  c.pressure = "total";
  c.end_alpha.assign(static_cast<size_t>(net.num_nodes()), 1.0);
  c.end_alpha[static_cast<size_t>(net.ends().back())] = 1.7;
  flow::BranchFit f;
  f.branch = 0;
  f.name = "parent";
  f.poiseuille_resistance = 2.0;
  f.linear = 2.2;
  f.flows = {1e-6};
  f.drops = {2.2e-6};
  c.fits.push_back(f);
  const auto dir = std::filesystem::temp_directory_path() / "flowire_test_calibration";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "calibration.json").string();
  flow::write_calibration(path, c);
  const flow::Calibration back = flow::read_calibration(path, net);
  ASSERT_EQ(back.laws.size(), c.laws.size());
  for (size_t s = 0; s < c.laws.size(); ++s) {
    EXPECT_DOUBLE_EQ(back.laws[s].resistance_factor, c.laws[s].resistance_factor);
    EXPECT_DOUBLE_EQ(back.laws[s].quadratic, c.laws[s].quadratic);
  }
  EXPECT_EQ(back.fits.front().name, "parent");
  EXPECT_EQ(back.pressure, "total");
  ASSERT_EQ(back.end_alpha.size(), c.end_alpha.size());
  EXPECT_DOUBLE_EQ(back.end_alpha[static_cast<size_t>(net.ends().back())], 1.7);
  EXPECT_DOUBLE_EQ(back.end_alpha.front(), 1.0);
  try {
    (void)flow::read_calibration(path, test::y_small(0.0), "vessels.calibration");
    FAIL() << "another network was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    const std::string m = e.what();
    EXPECT_NE(m.find("calibration.json"), std::string::npos) << m;
    EXPECT_NE(m.find("vessels.calibration"), std::string::npos) << m;
    EXPECT_NE(m.find("another network"), std::string::npos) << m;
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace flowire::flow::fem
