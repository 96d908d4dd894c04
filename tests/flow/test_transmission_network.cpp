// The compliant network (flow.model: rlc) against the exact solution of the linearized 1D
// model on whole networks: each branch a transmission line, each outlet its catalogue
// impedance, solved per harmonic on the graph of branches, loops included. A ring fed by two
// inlets (one pressure, one flow) and drained through an RCR and a coronary bed (a circle of
// Willis in miniature), and a tree with three kinds of outlet and a stiffer branch: the
// network's harmonics converge to the exact ones at second order as its segments shrink.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <map>

#include "exact_network.hpp"
#include "flowire/common/config.hpp"
#include "flowire/flow/rlc.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/flow/spec.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

using namespace flowire::flow::test;
constexpr double kPeriod = 0.5;

/// Largest relative error, over harmonics 1 and 2, of the simulated inlet flows and pressures
/// and outlet flows of the scene at segments of @p h, against the exact solution; the mean's
/// relative error in @p mean_error.
double network_error(const std::vector<ExactBranch>& lines, const std::string& flow_yaml, double h,
                     double* mean_error) {
  const Network net = Network::build(centerlines_of(lines), {.max_segment_length = h});
  config::Schema schema;
  declare_scene_keys(schema);
  const auto cfg = config::load_config_text(flow_yaml, "net.yaml", schema);
  FlowSpec spec = from_config(cfg, net);
  spec.model = Model::Rlc;
  spec.dt = kPeriod / 4000;  // its error (second order in dt) well below the finest segments'
  spec.rho_infinity = 1.0;
  spec.periodic_tolerance = 1e-11;
  spec.max_cycles = 400;
  auto solver = make_solver(net, spec);
  EXPECT_TRUE(periodic_info(*solver).converged);
  // Samples over a period of every end's pressure and of the flow through every end.
  std::vector<int> ends = net.ends();
  auto end_flow = [&](int e) {  // into the network at end e
    const int s = *net.node_segments(e).first;
    return net.segment(s).node_from == e ? solver->segment_flow(s) : -solver->segment_flow(s);
  };
  const int n = 1000;
  std::map<int, std::vector<double>> p, q;
  const double t0 = solver->time() + 20.0 * kPeriod;
  for (int i = 0; i < n; ++i) {
    solver->advance(t0 + kPeriod * i / n);
    for (int e : ends) p[e].push_back(solver->node_pressure(e)), q[e].push_back(end_flow(e));
  }
  auto coef = [](const std::vector<double>& v, int k) { return sampled_harmonic(v, k); };
  // The flow through an end node: its segment's flow (staggered, between nodes) plus what the
  // node's own compliance (half its segment's) takes, C dP/dt; without it the comparison would
  // be off by that current, O(h).
  auto end_compliance = [&](int e) { return 0.5 * spec.segment_compliance(net, *net.node_segments(e).first); };
  double worst = 0.0;
  for (int k = 0; k <= 2; ++k) {
    const ExactNetwork ex(lines, spec, net, kPeriod, k);
    for (int e : ends) {
      // The exact flow into the network at this end, and its pressure.
      const int s = *net.node_segments(e).first;
      const cd qx = net.segment(s).node_from == e ? ex.segment_flow_at_node(s, e) : -ex.segment_flow_at_node(s, e);
      const cd px = ex.node_pressure(e);
      // What an inlet prescribes is not compared: a pressure inlet's pressure, a flow inlet's flow.
      bool pressure_given = false, flow_given = false;
      for (const auto& in : spec.inlets)
        if (in.node == e) (in.type == InletBC::Type::Pressure ? pressure_given : flow_given) = true;
      const cd qn = coef(q[e], k) + cd(0.0, 2.0 * M_PI * k / kPeriod) * end_compliance(e) * coef(p[e], k);
      const double dq = flow_given ? 0.0 : std::abs(qn - qx) / std::abs(qx);
      const double dp = pressure_given ? 0.0 : std::abs(coef(p[e], k) - px) / std::abs(px);
      if (k == 0) {
        *mean_error = std::max({*mean_error, dq, dp});
      } else {
        worst = std::max({worst, dq, dp});
      }
    }
  }
  return worst;
}

/// The errors at segments of 4, 2 and 1 cm: second order, and the finest below @p bound.
void expect_second_order(const std::vector<ExactBranch>& lines, const std::string& yaml, double bound) {
  std::vector<double> hs = {0.04, 0.02, 0.01}, errors;
  for (double h : hs) {
    double mean = 0.0;
    errors.push_back(network_error(lines, yaml, h, &mean));
    EXPECT_LT(mean, 1e-4) << "the mean is the resistor network's, at any segment length (h = " << h << ")";
  }
  for (size_t i = 0; i + 1 < hs.size(); ++i) {
    const double slope = std::log(errors[i] / errors[i + 1]) / std::log(hs[i] / hs[i + 1]);
    EXPECT_GE(slope, 1.8) << "h " << hs[i] << " -> " << hs[i + 1] << ": " << errors[i] << " -> " << errors[i + 1];
  }
  EXPECT_LT(errors.back(), bound) << errors.back();
}

std::string flow_table_csv() {
  // Q(t) = 2 + 1.5 sin(ωt + 0.7) + 0.8 cos(2ωt) mL/s over one period, 256 rows.
  const auto path = flowire::testing::scratch_dir("transmission-network") / "inflow.csv";
  std::ofstream f(path);
  f << "time,flow\n";
  for (int i = 0; i <= 256; ++i) {
    const double t = kPeriod * i / 256, w = 2.0 * M_PI / kPeriod;
    f << t << ',' << 1e-6 * (2.0 + 1.5 * std::sin(w * t + 0.7) + 0.8 * std::cos(2.0 * w * t)) << '\n';
  }
  return path.string();
}

}  // namespace

TEST(TransmissionNetwork, ARingFedByTwoInletsConvergesToTheExactSolutionAtSecondOrder) {
  // A square ring of 8 cm sides (r = 2 mm), fed at two opposite corners through 4 cm inlets
  // (r = 3 mm): a pressure wave at one, a measured-like flow table at the other; drained at
  // the two other corners through 4 cm outlets (r = 1.5 mm) into an RCR and a coronary bed,
  // one outlet with a stiffer wall of its own.
  const double L = 0.08, l = 0.04;
  const std::vector<ExactBranch> lines = {
      {"ring_ab", Vec3(0, 0, 0), Vec3(L, 0, 0), 2e-3},  {"ring_bc", Vec3(L, 0, 0), Vec3(L, L, 0), 2e-3},
      {"ring_cd", Vec3(L, L, 0), Vec3(0, L, 0), 2e-3},  {"ring_da", Vec3(0, L, 0), Vec3(0, 0, 0), 2e-3},
      {"in_a", Vec3(-l, 0, 0), Vec3(0, 0, 0), 3e-3},    {"in_c", Vec3(L + l, L, 0), Vec3(L, L, 0), 3e-3},
      {"out_b", Vec3(L, 0, 0), Vec3(L, -l, 0), 1.5e-3}, {"out_d", Vec3(0, L, 0), Vec3(-l, L, 0), 1.5e-3},
  };
  const std::string yaml = R"(
flow:
  inlets:
    - {node: in_a, pressure: {waveform: sine, systolic: 1400, diastolic: 1000, period: 0.5 s}}
    - {node: in_c, flow: {waveform: table, file: )" +
                           flow_table_csv() +
                           R"(}}
  outlets:
    out_b: {rcr: {Rp: 2e7, C: 2e-9, Rd: 1.5e8, Pd: 100}}
    out_d: {coronary: {Ra: 3e7, Ca: 1e-9, Ram: 5e7, Cim: 4e-9, Rv: 7e7, Pim: 500, Pv: 200}}
  wall:
    youngs_modulus: 0.4 MPa
    thickness_ratio: 0.1
    out_d: {youngs_modulus: 1.5 MPa, thickness: 0.3 mm}
)";
  expect_second_order(lines, yaml, 1e-3);
}

TEST(TransmissionNetwork, ATreeWithThreeKindsOfOutletConvergesToTheExactSolutionAtSecondOrder) {
  // A trunk (r = 4 mm) into two daughters, one of which divides again: a resistance, an RCR
  // and a coronary bed at the three ends, the first daughter stiffer; fed a flow table.
  const std::vector<ExactBranch> lines = {
      {"trunk", Vec3(0, 0, 0), Vec3(0.08, 0, 0), 4e-3},
      {"left", Vec3(0.08, 0, 0), Vec3(0.16, 0.04, 0), 3e-3},
      {"right", Vec3(0.08, 0, 0), Vec3(0.16, -0.04, 0), 2.5e-3},
      {"left_up", Vec3(0.16, 0.04, 0), Vec3(0.16, 0.12, 0), 2e-3},
      {"left_on", Vec3(0.16, 0.04, 0), Vec3(0.24, 0.04, 0), 2e-3},
  };
  const std::string yaml = R"(
flow:
  inlet: {node: trunk, flow: {waveform: table, file: )" +
                           flow_table_csv() +
                           R"(}}
  outlets:
    right: {resistance: 3e8, distal_pressure: 300}
    left_up: {rcr: {Rp: 4e7, C: 1e-9, Rd: 3e8}}
    left_on: {coronary: {Ra: 5e7, Ca: 5e-10, Ram: 1e8, Cim: 2e-9, Rv: 1e8, Pv: 100}}
  wall:
    youngs_modulus: 0.5 MPa
    thickness_ratio: 0.1
    left: {youngs_modulus: 2 MPa}
)";
  expect_second_order(lines, yaml, 1e-3);
}

}  // namespace flowire::flow
