// The rlc model: Womersley correction of the quasi-steady error (reference 5), steady
// limit equal to Poiseuille, periodic steady state with RCR outlets and compliant walls.
#include <gtest/gtest.h>
#include "flowire/common/config.hpp"
#include "flowire/common/error.hpp"

#include <cmath>
#include <complex>
#include <cstdio>

#include "exact_network.hpp"
#include "flow_test_networks.hpp"
#include "flowire/flow/profile.hpp"
#include "flowire/flow/rlc.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

using namespace flowire::flow::test;
constexpr double kEta = 3.5e-3, kRho = 1060.0, kR = 2e-3, kL = 0.05;

/// Complex flow amplitude over the quasi-steady Poiseuille amplitude, measured over one
/// periodic cycle of a rigid tube driven by a sinusoidal pressure difference at Womersley α.
std::complex<double> measured_ratio(double alpha, Inertance inertance, int steps_per_cycle = 400) {
  const Network net = tube(kL, kR, 1);
  const double omega = alpha * alpha * kEta / (kRho * kR * kR);
  const double period = 2.0 * M_PI / omega;
  const double amp = 100.0;
  FlowSpec spec = pressure_spec(net, 0, Waveform::sine(1000.0 + amp, 1000.0 - amp, period), {{1, 1000.0}});
  spec.model = Model::Rlc;
  spec.inertance = inertance;
  spec.wall_youngs_modulus = 0.0;  // rigid, as Womersley's solution
  spec.dt = period / steps_per_cycle;
  spec.rho_infinity = 1.0;
  spec.periodic_tolerance = 1e-10;
  auto s = make_solver(net, spec);
  EXPECT_TRUE(periodic_info(*s).converged);
  double a = 0.0, b = 0.0;
  for (int k = 0; k < steps_per_cycle; ++k) {
    const double t = period * k / steps_per_cycle;
    s->advance(t);
    a += 2.0 / steps_per_cycle * s->segment_flow(0) * std::sin(omega * t);
    b += 2.0 / steps_per_cycle * s->segment_flow(0) * std::cos(omega * t);
  }
  const double q_poiseuille = amp / poiseuille_resistance(kEta, kL, kR);
  // Q_osc = a sin + b cos = Re[(b − i a) e^{iωt}], Δp_osc = amp sin = Re[−i amp e^{iωt}].
  return std::complex<double>(b, -a) / std::complex<double>(0.0, -q_poiseuille);
}

// Reference 5 (Womersley): α = 2: 0.825, −33°; α = 3: 0.548, −54°; α = 4 from the exact
// solution (checked against the table by FlowProfile.BesselAndWomersleyTableOfReference5).
TEST(FlowRlc, WomersleyInertanceCorrectsTheQuasiSteadyError) {
  const double table[][3] = {{2.0, 0.825, -33.0}, {3.0, 0.548, -54.0}, {4.0, 0.0, 0.0}};
  for (const auto& row : table) {
    const double alpha = row[0];
    const auto exact = womersley_flow_ratio(alpha);
    const double mag = row[1] > 0 ? row[1] : std::abs(exact);
    const double phase = row[1] > 0 ? row[2] : std::arg(exact) * 180.0 / M_PI;
    const auto rlc = measured_ratio(alpha, Inertance::Womersley);
    std::printf(
        "alpha %.0f: Womersley |Q/QP| %.3f phase %.1f deg; rlc (4rho l/3pi r^2) %.3f %.1f deg; quasi-steady 1.000 0.0 "
        "deg\n",
        alpha, mag, phase, std::abs(rlc), std::arg(rlc) * 180.0 / M_PI);
    const double quasi_steady_error = std::abs(1.0 - mag) / mag;  // plain Poiseuille: |ratio| = 1, phase 0
    const double rlc_error = std::abs(std::abs(rlc) - mag) / mag;
    EXPECT_LT(rlc_error, 0.04) << "alpha " << alpha << " |Q/QP| " << std::abs(rlc) << " vs " << mag;
    EXPECT_LT(rlc_error, 0.2 * quasi_steady_error) << "alpha " << alpha;
    // Phase: quasi-steady Poiseuille has none (error |phase|); the rlc model is within 5°.
    EXPECT_NEAR(std::arg(rlc) * 180.0 / M_PI, phase, 5.0) << "alpha " << alpha;
    EXPECT_LT(std::abs(std::arg(rlc) * 180.0 / M_PI - phase), 0.1 * std::abs(phase));
    // The plain ρl/(πr²) inertance lies between the quasi-steady and the Womersley answer.
    const auto plain = measured_ratio(alpha, Inertance::Poiseuille);
    EXPECT_GT(std::abs(plain), std::abs(rlc));
    EXPECT_LT(std::abs(plain), 1.0);
  }
}

TEST(FlowRlc, SteadyInletEqualsPoiseuille) {
  const Network net = random_network(200, 10, 7);
  FlowSpec spec = default_spec(net, Waveform::constant(13000.0));
  for (size_t i = 0; i < spec.outlets.size(); i += 3) {
    spec.outlets[i].type = OutletBC::Type::Resistance;
    spec.outlets[i].resistance = 2e9;
    spec.outlets[i].distal_pressure = 1000.0;
  }
  auto ref = make_solver(net, spec);
  spec.model = Model::Rlc;
  auto rlc = make_solver(net, spec);
  rlc->advance(0.05);
  double qmax = 0.0;
  for (int s = 0; s < net.num_segments(); ++s) qmax = std::max(qmax, std::abs(ref->segment_flow(s)));
  for (int s = 0; s < net.num_segments(); ++s) EXPECT_NEAR(rlc->segment_flow(s), ref->segment_flow(s), 1e-10 * qmax);
  for (int i = 0; i < net.num_nodes(); ++i) EXPECT_NEAR(rlc->node_pressure(i), ref->node_pressure(i), 1e-9 * 13000.0);
}

TEST(FlowRlc, RcrOutletsReachAPeriodicState) {
  const Network net = murray_tree(3);
  FlowSpec spec = default_spec(net, Waveform::sine(120 * 133.322, 80 * 133.322, 0.8));
  for (auto& o : spec.outlets) {
    o.type = OutletBC::Type::Rcr;
    o.rp = 1e8;
    o.c = 1e-10;
    o.rd = 1.5e9;
    o.distal_pressure = 0.0;
  }
  spec.model = Model::Rlc;
  spec.dt = 0.8 / 400;
  auto s = make_solver(net, spec);
  const auto info = periodic_info(*s);
  EXPECT_TRUE(info.converged);
  EXPECT_GT(info.cycles, 1);
  std::vector<double> q0(static_cast<size_t>(net.num_segments())), q1 = q0;
  std::vector<double> p0(static_cast<size_t>(net.num_nodes())), p1 = p0;
  s->solve_at(0.1, p0, q0);
  s->solve_at(0.9, p1, q1);
  for (size_t i = 0; i < q0.size(); ++i) EXPECT_NEAR(q1[i], q0[i], 1e-5 * std::abs(q0[0]));
  // Compliance stores volume: the inflow differs from the outflow within the cycle but
  // not on average over a cycle.
  double in = 0.0, out = 0.0;
  const int n = 400;
  for (int k = 0; k < n; ++k) {
    s->advance(0.9 + 0.8 * k / n);
    in += s->segment_flow(0);
    for (const auto& o : spec.outlets) {
      const auto [b, e] = net.node_segments(o.node);
      out += s->segment_flow(*b);
    }
  }
  EXPECT_NEAR(out, in, 1e-5 * std::abs(in));
  // And the Poiseuille model with the RCR total resistance gives the same mean flow.
  spec.model = Model::Poiseuille;
  flowire::testing::ExpectWarnings w;
  auto qs = make_solver(net, spec);
  double mean_qs = 0.0;
  for (int k = 0; k < n; ++k) {
    qs->advance(0.8 * k / n);
    mean_qs += qs->segment_flow(0);
  }
  EXPECT_NEAR(in / n, mean_qs / n, 1e-3 * std::abs(mean_qs / n));
}

// The boundary waveforms enter only the right-hand side: the step matrix is factorized once
// for the steady state and once for the time step, and again only when a wire changes a
// segment's resistance or inertance (then the flow through it drops).
TEST(FlowRlc, StepMatrixIsFactorizedOncePerPhaseAndPerOcclusionChange) {
  const Network net = murray_tree(3);
  FlowSpec spec = default_spec(net, Waveform::sine(120 * 133.322, 80 * 133.322, 0.8));
  for (auto& o : spec.outlets) {
    o.type = OutletBC::Type::Rcr;
    o.rp = 1e8;
    o.c = 1e-10;
    o.rd = 1.5e9;
  }
  spec.model = Model::Rlc;
  spec.dt = 0.8 / 200;
  auto s = make_solver(net, spec);
  ASSERT_GT(periodic_info(*s).cycles, 1);
  EXPECT_EQ(rlc_factorizations(*s), 2);
  s->advance(1.6);
  EXPECT_EQ(rlc_factorizations(*s), 2);
  std::vector<SegmentOcclusion> occ(static_cast<size_t>(net.num_segments()));
  s->set_occlusion(occ);  // all factors 1: J unchanged
  s->advance(2.4);
  EXPECT_EQ(rlc_factorizations(*s), 2);
  const double q_free = s->segment_flow(1);
  occ[1].resistance_factor = 20.0;
  occ[1].inertance_factor = 1.5;
  s->set_occlusion(occ);
  EXPECT_EQ(rlc_factorizations(*s), 3);
  s->advance(4.0);  // two periods later: the same phase of the cycle
  EXPECT_EQ(rlc_factorizations(*s), 3);
  std::printf("segment 1 flow at the same phase: free %.6g, occluded %.6g m^3/s\n", q_free, s->segment_flow(1));
  EXPECT_LT(std::abs(s->segment_flow(1)), std::abs(q_free));
  spec.model = Model::Poiseuille;
  flowire::testing::ExpectWarnings w;
  EXPECT_EQ(rlc_factorizations(*make_solver(net, spec)), 0);
}

}  // namespace

TEST(FlowRlc, ABranchWithItsOwnWallFollowsTheExactTransmissionLine) {
  // A straight 30 cm tube of two named branches, the distal one stiffer (flow.wall.distal:
  // E = 2 MPa, h = 1 mm against the network's 0.4 MPa and h = r/10), fed a 4 Hz pressure
  // wave and drained through a mismatched resistance: the inlet flow's harmonic against the
  // exact linear solution of the two transmission lines in series. The same with the
  // network's wall everywhere differs from it by far more than the tolerance.
  vessels::Centerlines c;
  c.branches.push_back({"proximal", {Vec3(0, 0, 0), Vec3(0.15, 0, 0)}, {5e-3, 5e-3}});
  c.branches.push_back({"distal", {Vec3(0.15, 0, 0), Vec3(0.3, 0, 0)}, {5e-3, 5e-3}});
  const Network net = Network::build(c, {.max_segment_length = 2.5e-3});
  config::Schema schema;
  declare_scene_keys(schema);
  const double T = 0.25;
  const auto cfg = config::load_config_text(R"(
flow:
  model: rlc
  inlet: {pressure: {waveform: sine, systolic: 1100, diastolic: 900, period: 0.25 s}, node: proximal}
  outlets: {resistance: 1.5e8}
  wall:
    youngs_modulus: 0.4 MPa
    thickness_ratio: 0.1
    distal: {youngs_modulus: 2 MPa, thickness: 1 mm}
)",
                                            "s.yaml", schema);
  FlowSpec spec = from_config(cfg, net);
  spec.dt = T / 400;  // (solve.dt in a scene)
  ASSERT_EQ(spec.branch_walls.size(), 1u);
  auto solver = make_solver(net, spec);
  ASSERT_TRUE(periodic_info(*solver).converged);
  const int n = 400;
  int inlet_seg = -1;
  for (int sgm = 0; sgm < net.num_segments(); ++sgm)
    if (net.segment(sgm).node_from == spec.inlets[0].node || net.segment(sgm).node_to == spec.inlets[0].node)
      inlet_seg = sgm;
  const double sign = net.segment(inlet_seg).node_from == spec.inlets[0].node ? 1.0 : -1.0;
  std::complex<double> q1 = 0.0;
  for (int k = 0; k < n; ++k) {
    const double t = 10.0 * T + T * k / n;
    solver->advance(t);
    q1 += sign * solver->segment_flow(inlet_seg) * std::exp(std::complex<double>(0.0, -2.0 * M_PI * k / n));
  }
  q1 /= static_cast<double>(n);
  // The exact inlet flow of the two lines in series (exact_network.hpp), with the distal
  // branch's own wall and with the network's wall everywhere.
  const std::vector<ExactBranch> lines = {{"proximal", Vec3(0, 0, 0), Vec3(0.15, 0, 0), 5e-3},
                                          {"distal", Vec3(0.15, 0, 0), Vec3(0.3, 0, 0), 5e-3}};
  FlowSpec network_wall = spec;
  network_wall.branch_walls.clear();
  const auto exact = ExactNetwork(lines, spec, net, T, 1).flow_at(0, 0.0);
  const auto uniform = ExactNetwork(lines, network_wall, net, T, 1).flow_at(0, 0.0);
  EXPECT_LT(std::abs(q1 / exact - 1.0), 0.01) << "simulated " << q1 << " exact " << exact;
  EXPECT_GT(std::abs(uniform / exact - 1.0), 0.1) << "the override would not show";
  // A wall for a branch the network does not have.
  try {
    (void)from_config(config::load_config_text("flow:\n  wall:\n    nowhere: {thickness: 1 mm}\n", "s.yaml", schema),
                      net);
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("s.yaml:3: flow.wall.nowhere: no branch named 'nowhere'"), std::string::npos)
        << e.what();
  }
}

}  // namespace flowire::flow
