// openBF models as compliant lumped networks (flow/openbf.hpp), checked against what they
// did not compute: the exact frequency-domain solution of the linearized 1D model (every
// vessel a transmission line, every outlet its windkessel impedance), the mean pressure a
// resistance chain must carry, and the physiological pressures of the published ADAN56 model.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <fstream>
#include <map>
#include <numbers>
#include <set>

#include "flowire/common/error.hpp"
#include "flowire/flow/openbf.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::openbf {
namespace {

namespace fs = std::filesystem;
using cd = std::complex<double>;
constexpr double kPi = std::numbers::pi;
constexpr double kMmHg = 133.322387415;

/// A bifurcation of my own: a root into two daughters with different radii, walls (E, h0)
/// and windkessels, fed by a flow of three harmonics (period 0.5 s).
Model bifurcation() {
  Model m;
  m.file = "bifurcation (test)";
  m.name = "bifurcation";
  m.rho = 1060.0;
  m.mu = 4e-3;
  m.cycles = 40;  // the slowest windkessel, R2·C ≈ 1 s, settled to round-off
  const double T = 0.5;
  for (int i = 0; i <= 400; ++i) {
    const double t = T * i / 400.0, w = 2.0 * kPi / T;
    m.inlet_time.push_back(t);
    m.inlet_flow.push_back(1e-4 + 6e-5 * std::sin(w * t) + 3e-5 * std::sin(2.0 * w * t + 0.7) +
                           1.5e-5 * std::cos(3.0 * w * t));
  }
  Vessel root{.label = "root", .sn = 1, .tn = 2, .length = 0.2, .youngs_modulus = 4e5, .rp = 0.01, .rd = 0.01};
  root.h0 = 1e-3;
  Vessel left{.label = "left", .sn = 2, .tn = 3, .length = 0.3, .youngs_modulus = 6e5, .rp = 6e-3, .rd = 6e-3};
  left.h0 = 0.8e-3;
  left.r1 = 1.5e7, left.r2 = 1.6e8, left.cc = 6e-9;
  Vessel right{.label = "right", .sn = 2, .tn = 4, .length = 0.25, .youngs_modulus = 9e5, .rp = 5e-3, .rd = 5e-3};
  right.h0 = 0.6e-3;
  right.r1 = 3e7, right.r2 = 2.4e8, right.cc = 3e-9;
  m.vessels = {root, left, right};
  return m;
}

/// Input impedance of a uniform vessel terminated by @p load at angular frequency ω.
cd line_input_impedance(const Model& m, const Vessel& v, double w, cd load) {
  const double r = v.rp;
  const double Rp = 2.0 * (v.gamma + 2.0) * m.mu / (kPi * std::pow(r, 4));
  const double Lp = m.rho / (kPi * r * r);
  const double Cp = 3.0 * kPi * r * r * r / (2.0 * v.youngs_modulus * wall_thickness(v, r));
  if (w == 0.0) return load + Rp * v.length;
  const cd z(Rp, w * Lp), y(0.0, w * Cp);
  const cd zc = std::sqrt(z / y), g = std::sqrt(z * y);
  const cd th = std::tanh(g * v.length);
  return zc * (load + zc * th) / (zc + load * th);
}

cd windkessel(const Vessel& v, double w) { return v.r1 + v.r2 / cd(1.0, w * v.r2 * v.cc); }

/// Exact input impedance of bifurcation() at its inlet.
cd exact_root_impedance(const Model& m, double w) {
  const cd zl = line_input_impedance(m, m.vessels[1], w, windkessel(m.vessels[1], w));
  const cd zr = line_input_impedance(m, m.vessels[2], w, windkessel(m.vessels[2], w));
  return line_input_impedance(m, m.vessels[0], w, 1.0 / (1.0 / zl + 1.0 / zr));
}

/// Harmonic n of the samples of one period (the last sample, the period's end, left out).
cd harmonic(const std::vector<double>& x, int n) {
  const int N = static_cast<int>(x.size());
  cd s = 0.0;
  for (int k = 0; k < N; ++k) s += x[static_cast<size_t>(k)] * std::exp(cd(0.0, -2.0 * kPi * n * k / N));
  return s / static_cast<double>(N);
}

/// max over harmonics 0..3 of |P̂ − Z_exact Q̂| / |Z_exact Q̂| at the inlet (Q̂ the flow the
/// run took in: the table's linear interpolation is the network's input, not the sines).
double impedance_error(const Model& m, double segment) {
  Options o;
  o.max_segment_length = segment;
  o.steps_per_cycle = 4000;
  const Waveforms w = simulate(m, o);
  std::vector<double> p, q;
  for (size_t i = 0; i < w.names.size(); ++i)
    if (w.names[i] == "root") p.push_back(w.pressure_in[i]), q.push_back(w.flow_in[i]);
  p.pop_back(), q.pop_back();  // one period: [0, T)
  const double T = m.inlet_time.back() - m.inlet_time.front();
  double e = 0.0;
  for (int n = 0; n <= 3; ++n) {
    const cd want = exact_root_impedance(m, 2.0 * kPi * n / T) * harmonic(q, n);
    e = std::max(e, std::abs(harmonic(p, n) - want) / std::abs(want));
  }
  return e;
}

TEST(Openbf, TheNetworkConvergesToTheExactTransmissionLineSolutionPerHarmonic) {
  // Each vessel lumped into segments of 10, 5 and 2.5 cm: the inlet pressure's harmonics
  // 0–3 (mean, 2, 4, 6 Hz; wavelengths 0.6–3 m against vessels of 0.2–0.3 m) approach those
  // of the exact linear 1D solution at second order (the staggered line of openbf.hpp).
  const Model m = bifurcation();
  const double e1 = impedance_error(m, 0.10), e2 = impedance_error(m, 0.05), e3 = impedance_error(m, 0.025);
  EXPECT_GT(std::log2(e1 / e2), 1.8) << e1 << " " << e2;
  EXPECT_GT(std::log2(e2 / e3), 1.8) << e2 << " " << e3;
  EXPECT_LT(e3, 0.01);
}

TEST(Openbf, TheMeanInletPressureIsTheMeanFlowThroughTheResistanceChain) {
  // A tapered vessel into a windkessel: over a periodic cycle the capacitors pass no mean
  // flow, so p̄_in = Q̄ (∫R' dx + R1 + R2) + Pout, with ∫ 8μ/(πr⁴) dx exact for a linear r.
  Model m = bifurcation();
  Vessel v{.label = "tapered", .sn = 1, .tn = 2, .length = 0.15, .youngs_modulus = 5e5, .rp = 0.008, .rd = 0.005};
  v.r1 = 2e7, v.r2 = 1.5e8, v.cc = 8e-9, v.pout = 500.0;
  m.vessels = {v};
  m.cycles = 20;
  const Waveforms w = simulate(m, {});
  double p = 0.0, q = 0.0;
  int n = 0;
  for (size_t i = 0; i + 1 < w.names.size(); ++i) p += w.pressure_in[i], q += w.flow_in[i], ++n;
  p /= n, q /= n;
  const double s = (v.rd - v.rp) / v.length;
  const double R = 8.0 * m.mu / kPi * (1.0 / std::pow(v.rp, 3) - 1.0 / std::pow(v.rd, 3)) / (3.0 * s);
  EXPECT_NEAR(q, 1e-4, 1e-7);  // the table's mean flow
  EXPECT_NEAR(p, q * (R + v.r1 + v.r2) + v.pout, 1e-3 * p) << "periodicity " << w.periodicity;
}

TEST(Openbf, Adan56IsPeriodicWithPhysiologicalPressures) {
  // Boileau et al. 2015's 56-artery model, 10 cycles as the model asks: its pressures where
  // the paper draws them, against the physiological ranges of a healthy adult (systolic
  // 100–150 mmHg, diastolic 60–95, mean 85–115; the pulse widening towards the periphery).
  FLOWIRE_REQUIRE_SHARED("peers/openbf-models/boileau2015/adan56/adan56.yaml");
  const auto file = flowire::testing::shared_dir() / "peers/openbf-models/boileau2015/adan56/adan56.yaml";
  const Model m = read(file.string());
  EXPECT_EQ(m.vessels.size(), 77u);
  const Waveforms w = simulate(m, {});
  EXPECT_LT(w.periodicity, 0.01);
  struct Stats {
    double sys = -1e300, dia = 1e300, mean = 0.0;
    int n = 0;
  };
  std::map<std::string, Stats> at;
  for (size_t i = 0; i + 1 < w.names.size(); ++i) {
    if (w.names[i + 1] != w.names[i]) continue;  // a vessel's period end repeats its start
    auto& s = at[w.names[i]];
    const double p = w.pressure_in[i] / kMmHg;
    s.sys = std::max(s.sys, p), s.dia = std::min(s.dia, p), s.mean += p, ++s.n;
  }
  for (const char* v : {"aortic_arch_I", "common_carotid_R", "radial_R", "femoral_R_I"}) {
    ASSERT_TRUE(at.count(v)) << v;
    const auto& s = at[v];
    const double mean = s.mean / s.n;
    EXPECT_GT(s.sys, 100.0) << v;
    EXPECT_LT(s.sys, 150.0) << v;
    EXPECT_GT(s.dia, 60.0) << v;
    EXPECT_LT(s.dia, 95.0) << v;
    EXPECT_GT(mean, 85.0) << v;
    EXPECT_LT(mean, 115.0) << v;
  }
  EXPECT_GT(at["femoral_R_I"].sys - at["femoral_R_I"].dia, at["aortic_arch_I"].sys - at["aortic_arch_I"].dia);
}

void write(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

TEST(Openbf, BadModelsNameTheFileTheLineAndTheVessel) {
  const auto dir = flowire::testing::scratch_dir("openbf-bad");
  write(dir / "m_inlet.dat", "0 0\n0.5 1e-4\n1 0\n");
  const std::string head = "project_name: m\nblood: {rho: 1060, mu: 0.004}\nsolver: {cycles: 3}\nnetwork:\n";
  const std::string root = "  - {label: a, sn: 1, tn: 2, L: 0.1, E: 4e5, R0: 0.01}\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {root + "  - {label: b, sn: 2, tn: 3, L: 0.1, E: 4e5, R0: 0.0}\n", "m.yaml:6: vessel `b`: R0 = 0 must be > 0"},
      {root + "  - {label: b, sn: 2, tn: 3, E: 4e5, R0: 0.01}\n", "m.yaml:6: vessel `b`: `L` is missing"},
      {root + "  - {label: b, sn: 2, tn: 3, L: 0.1, E: 4e5, R0: 0.01, R1: -1e7, Cc: 1e-9}\n",
       "vessel `b`: R1 = -10000000 must be > 0"},
      {root + "  - {label: b, sn: 2, tn: 3, L: 0.1, E: 4e5, R0: 0.01, colour: red}\n",
       "vessel `b`: unknown key `colour`"},
      {root + "  - {label: b, sn: 7, tn: 8, L: 0.1, E: 4e5, R0: 0.01}\n", "vessel `b` is not connected to the inlet"},
      {root + "  - {label: b, sn: 2, tn: 3, L: 0.1, E: 4e5, Rp: 0.01}\n",
       "m.yaml:6: vessel `b`: give R0, or Rp and Rd"},
      {root + "  - {label: a, sn: 2, tn: 3, L: 0.1, E: 4e5, R0: 0.01}\n", "vessel `a`: the label is used twice"},
  };
  for (const auto& [net, message] : cases) {
    write(dir / "m.yaml", head + net);
    try {
      (void)read((dir / "m.yaml").string());
      ADD_FAILURE() << "accepted: " << net;
    } catch (const flowire::Error& e) {
      EXPECT_EQ(e.kind(), flowire::ErrorKind::Input);
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
  write(dir / "m.yaml", head + root);
  write(dir / "m_inlet.dat", "0 0\n0.5 1e-4\n0.4 0\n");
  try {
    (void)read((dir / "m.yaml").string());
    ADD_FAILURE() << "accepted a table going back in time";
  } catch (const flowire::Error& e) {
    EXPECT_NE(std::string(e.what()).find("m_inlet.dat:3: time 0.4 does not increase"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace flowire::flow::openbf

namespace flowire::flow::openbf {
namespace {

double polyline_length(const vessels::Polyline& p) {
  double s = 0.0;
  for (size_t i = 1; i < p.points.size(); ++i) s += (p.points[i] - p.points[i - 1]).norm();
  return s;
}

/// Every vessel of @p m laid out at its own length, Rp to Rd, from where its source node lies;
/// the network's total length within @p network_tolerance of the model's (a bowed vessel's
/// segments are chords of its arc within a tenth of its radius).
void expect_faithful_layout(const Model& m, double network_tolerance = 1e-9) {
  const vessels::Centerlines c = layout(m);
  ASSERT_EQ(c.branches.size(), m.vessels.size());
  std::map<int, vessels::Vec3> at;
  for (size_t k = 0; k < m.vessels.size(); ++k) {
    const Vessel& v = m.vessels[k];
    const auto& p = c.branches[k];
    SCOPED_TRACE(v.label);
    EXPECT_EQ(p.name, v.label);
    EXPECT_NEAR(polyline_length(p), v.length, 1e-9 * v.length);
    EXPECT_DOUBLE_EQ(p.radii.front(), v.rp);
    EXPECT_NEAR(p.radii.back(), v.rd, 1e-12 * v.rd);
    for (const auto& [node, x] : {std::pair{v.sn, p.points.front()}, std::pair{v.tn, p.points.back()}}) {
      if (at.count(node)) {
        EXPECT_NEAR((at[node] - x).norm(), 0.0, 1e-12) << "node " << node << " in two places";
      }
      at[node] = x;
    }
  }
  // The network joins the vessels at their nodes: one branch each, one end per model end.
  const Network net = network(m, {.max_segment_length = 0.01});
  EXPECT_EQ(net.counts().branches, static_cast<int>(m.vessels.size()));
  std::set<int> sources, targets;
  for (const auto& v : m.vessels) sources.insert(v.sn), targets.insert(v.tn);
  int model_ends = 1;  // node 1
  for (int t : targets) model_ends += sources.count(t) ? 0 : 1;
  EXPECT_EQ(net.counts().ends, model_ends);
  double total = 0.0;
  for (const auto& v : m.vessels) total += v.length;
  EXPECT_NEAR(net.counts().total_length, total, network_tolerance * total);
}

}  // namespace

TEST(OpenbfLayout, EveryVesselLiesAtItsOwnLengthAndTaperInTheBodyOrInATree) {
  FLOWIRE_REQUIRE_SHARED("peers/openbf-models/boileau2015/adan56/adan56.yaml");
  const auto root = flowire::testing::shared_dir() / "peers/openbf-models";
  for (const char* f : {"boileau2015/adan56/adan56.yaml", "matthys2007/invitro_model.yaml",
                        "boileau2015/ibif/ibif.yaml", "boileau2015/uta/uta.yaml"}) {
    SCOPED_TRACE(f);
    expect_faithful_layout(read((root / f).string()));
  }
  // ADAN56 in the body: the aorta runs down from the arch, the legs end below the pelvis and
  // the carotids above the arch.
  const Model adan = read((root / "boileau2015/adan56/adan56.yaml").string());
  const vessels::Centerlines c = layout(adan);
  auto end_of = [&](const std::string& label) {
    for (const auto& b : c.branches)
      if (b.name == label) return b.points.back();
    ADD_FAILURE() << label;
    return vessels::Vec3(0, 0, 0);
  };
  EXPECT_LT(end_of("abdominal_aorta_V").z(), end_of("thoracic_aorta_I").z() - 0.2);
  EXPECT_LT(end_of("posterior_tibial_R").z(), end_of("abdominal_aorta_V").z() - 0.5);
  EXPECT_GT(end_of("internal_carotid_L").z(), end_of("aortic_arch_I").z() + 0.1);
  EXPECT_LT(end_of("radial_R").x() * end_of("radial_L").x(), 0.0) << "the arms on both sides";
}

TEST(OpenbfLayout, ALoopClosesWithAnArcOfItsOwnLengthOrIsRefusedNamingTheVessel) {
  // A ring: two vessels from node 2 to nodes 3 and 4, a third joining 3 to 4 (a loop) and an
  // outlet from 4. Its closing vessel, longer than the chord, is an arc of its own length;
  // shorter than the chord it cannot be placed.
  auto ring = [](double closing_length) {
    Model m;
    m.file = "ring.yaml";
    m.inlet_time = {0.0, 1.0};
    m.inlet_flow = {1e-6, 1e-6};
    auto vessel = [](std::string label, int sn, int tn, double L) {
      Vessel v;
      v.label = std::move(label);
      v.sn = sn, v.tn = tn, v.length = L, v.youngs_modulus = 4e5, v.rp = v.rd = 2e-3, v.r1 = 1e8, v.cc = 1e-10;
      return v;
    };
    m.vessels = {vessel("in", 1, 2, 0.05), vessel("a", 2, 3, 0.05), vessel("b", 2, 4, 0.05),
                 vessel("closing", 3, 4, closing_length), vessel("out", 4, 5, 0.05)};
    return m;
  };
  expect_faithful_layout(ring(0.2), 2e-3);
  try {
    (void)layout(ring(0.01));
    ADD_FAILURE() << "a loop shorter than its chord was laid out";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("vessel `closing` closes a loop"), std::string::npos) << e.what();
  }
}

}  // namespace flowire::flow::openbf
