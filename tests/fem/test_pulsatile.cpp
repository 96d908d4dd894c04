// Pulsatile series (flow/fem/src/pulsatile.cpp). Quasi-steady frames from one factorization
// equal direct solves at each frame's boundary values and follow the network, and the series
// files are written. Windkessel (RCR) outlets in the dynamic FEM series against the exact
// steady-periodic solution of the circuit. A straight tube with a sinusoidal inlet pressure P̂ e^{iωt} and
// one RCR outlet: with the tube a resistance R_t (Hagen–Poiseuille) the outlet flow is
// Q̂ = P̂ / Z, Z = R_t + R_p + R_d/(1 + iωR_dC) (the capacitor in parallel with R_d). With
// time-dependent Stokes the tube is Womersley's impedance instead: Z_t = 8ηL/(πR⁴) divided
// by Womersley's Q/Q_P. Asserted: amplitude and phase, and order 2 in the time step.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "fem_test_cases.hpp"
#include "flowire/flow/fem/boundary_values.hpp"
#include "flowire/flow/fem/compare.hpp"
#include "flowire/flow/fem/pulsatile.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

using cd = std::complex<double>;
using test::y_resistances;
constexpr double kPi = std::numbers::pi;
constexpr double kR = 2e-3, kL = 10e-3, kEta = 3.5e-3, kRho = 1060.0;
constexpr double kP0 = 200.0, kAmp = 100.0, kPeriod = 0.8;

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

struct TubeWindkessel {
  vessels::Network net = test::tube(kR, kL);
  int outlet = -1;
  flow::OutletBC wk;
  TubeWindkessel() {
    for (int e : net.ends())
      if (e != net.widest_end() || outlet >= 0) outlet = e;
    const double rt = 8 * kEta * kL / (kPi * std::pow(kR, 4));
    // R_d C = 0.2 s against ω = 7.85 rad/s: the capacitor takes most of the oscillation.
    wk = flow::OutletBC::rcr(0.5 * rt, 0.2 / (5 * rt), 5 * rt, 20.0);
    wk.node = outlet;
  }
  [[nodiscard]] BoundaryValues at(double t) const {
    BoundaryValues bv;
    bv.inlet_pressure = kP0 + kAmp * std::sin(2 * kPi * t / kPeriod);
    bv.outlets.push_back({outlet, OutletValue::Type::Resistance, wk.distal_pressure, wk.rp + wk.rd});
    bv.viscosity = kEta;
    bv.density = kRho;
    return bv;
  }
};

/// Complex amplitude of the outlet flow (e^{iωt} part) over the last period of the series.
cd outlet_amplitude(const TubeWindkessel& s, int steps, bool time_dependent, int frames = 16) {
  std::vector<double> times;
  std::vector<BoundaryValues> values;
  for (int i = 0; i < frames; ++i) {
    times.push_back(kPeriod * i / frames);
    values.push_back(s.at(times.back()));
  }
  FemOptions opt;
  opt.size_factor = 0.35;
  DynamicOptions dyn;
  dyn.period = kPeriod;
  dyn.values_at = [&s](double t) { return s.at(t); };
  dyn.windkessels = {s.wk};
  dyn.steps_per_period = steps;
  dyn.time_dependent = time_dependent;
  dyn.periodic_tolerance = 1e-9;
  const PulsatileResult r = compare_pulsatile(s.net, times, values, values[0], 0.0, opt, "", &dyn);
  const double omega = 2 * kPi / kPeriod;
  cd amp = 0.0;
  for (const auto& f : r.frames)
    for (const auto& o : f.outlets)
      if (o.node == s.outlet)
        amp += o.flow_fem * 2.0 * cd(0.0, 1.0) * std::exp(cd(0.0, -omega * f.time)) / double(frames);
  std::printf("%s, %d steps per period: %d periods to periodic (change %.1e), Q̂ = %.5e ∠ %.3f°\n",
              time_dependent ? "time-dependent" : "quasi-steady", r.steps_per_period, r.periods, r.periodic_change,
              std::abs(amp), std::arg(amp) * 180 / kPi);
  return amp;
}

cd circuit_flow(const TubeWindkessel& s, cd tube_impedance) {
  const double omega = 2 * kPi / kPeriod;
  const cd z = tube_impedance + s.wk.rp + s.wk.rd / (1.0 + cd(0.0, omega * s.wk.rd * s.wk.c));
  return kAmp / z;
}

TEST(FemWindkessel, QuasiSteadyTubeFollowsTheCircuitAtOrderTwo) {
  const TubeWindkessel s;
  const cd exact = circuit_flow(s, 8 * kEta * kL / (kPi * std::pow(kR, 4)));
  const int steps[3] = {32, 64, 512};
  cd q[3];
  for (int k = 0; k < 3; ++k) q[k] = outlet_amplitude(s, steps[k], false);
  std::printf("circuit: Q̂ = %.5e ∠ %.3f°; finest relative error %.2e\n", std::abs(exact), std::arg(exact) * 180 / kPi,
              std::abs(q[2] / exact - 1.0));
  // The capacitor shifts the outlet flow ahead of the inlet pressure by tens of degrees.
  EXPECT_GT(std::arg(exact) * 180 / kPi, 20.0);
  EXPECT_LT(std::abs(q[2] / exact - 1.0), testing::tol(2e-3));
  const double order = std::log(std::abs(q[0] / q[2] - 1.0) / std::abs(q[1] / q[2] - 1.0)) / std::log(2.0);
  std::printf("BDF2 capacitor: observed order %.2f\n", order);
  EXPECT_GT(order, 1.8);
}

TEST(FemWindkessel, TimeDependentTubeFollowsWomersleyAndTheCircuit) {
  const TubeWindkessel s;
  const double omega = 2 * kPi / kPeriod;
  const double alpha = kR * std::sqrt(omega * kRho / kEta);
  const cd lam = std::sqrt(cd(0.0, -1.0)) * alpha;
  const cd ratio =
      8.0 / (cd(0.0, 1.0) * alpha * alpha) * (1.0 - 2.0 * test::bessel_j(1, lam) / (lam * test::bessel_j(0, lam)));
  const cd exact = circuit_flow(s, 8 * kEta * kL / (kPi * std::pow(kR, 4)) / ratio);
  const cd quasi = circuit_flow(s, 8 * kEta * kL / (kPi * std::pow(kR, 4)));
  const cd q = outlet_amplitude(s, 320, true);
  std::printf("α = %.2f: exact Q̂ = %.5e ∠ %.3f° (quasi-steady tube %.5e ∠ %.3f°); FEM error %.2e\n", alpha,
              std::abs(exact), std::arg(exact) * 180 / kPi, std::abs(quasi), std::arg(quasi) * 180 / kPi,
              std::abs(q / exact - 1.0));
  EXPECT_LT(std::abs(q / exact - 1.0), testing::tol(3e-3));
  // The tube's inertia is visible: the quasi-steady answer is farther off.
  EXPECT_GT(std::abs(quasi / exact - 1.0), 3 * std::abs(q / exact - 1.0));
}

}  // namespace
}  // namespace flowire::flow::fem
