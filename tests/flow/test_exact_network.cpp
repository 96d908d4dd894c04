// The compliant network model (flow.model: rlc) against the exact periodic solution of the
// linearized 1D model (exact_network.hpp: every branch a transmission line, every outlet its
// impedance, solved per harmonic on the branch graph) everywhere in the network: the pressure
// at every node and the flow through every segment, harmonics 0 to 3, on a tree with a
// tapered branch, three kinds of outlet and walls of its own, and on a ring fed by two flow
// inlets of different waveforms (a circle of Willis in miniature), where how the flow splits
// around the loop is what is checked. The lumped model is a ladder of series R–L with half of
// each segment's compliance at either end node: a second-order discretization of the line in
// the segment length h, so the error of every harmonic falls as h².
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "exact_network.hpp"
#include "flow_test_networks.hpp"
#include "flowire/flow/rlc.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

using namespace flowire::flow::test;
constexpr double kPeriod = 0.5;         // s
constexpr int kHarmonics = 4;           // 0 (the mean) to 3
constexpr int kStepsPerPeriod = 4000;   // rlc steps: the time error stays well below the finest segments'
constexpr int kSamplesPerPeriod = 400;  // every 10th step
constexpr double kMmHg = 133.322387415;

/// The harmonics 0..3 of every node pressure and segment flow of the simulated periodic state.
struct Harmonics {
  std::vector<std::array<cd, kHarmonics>> pressure, flow;  // (num_nodes), (num_segments)
};

/// Run the rlc model to its periodic state and take ĉ_k of every pressure and flow from
/// kSamplesPerPeriod samples over one period.
Harmonics simulate(const Network& net, FlowSpec spec, int steps_per_period = kStepsPerPeriod) {
  spec.model = Model::Rlc;
  spec.dt = kPeriod / steps_per_period;
  spec.periodic_tolerance = 1e-10;  // the state a cycle apart; far below the errors measured
  spec.max_cycles = 199;            // odd: a search on a wrong period would also end out of phase
  auto solver = make_solver(net, spec);
  EXPECT_TRUE(periodic_info(*solver).converged) << periodic_info(*solver).last_change;
  const auto nn = static_cast<size_t>(net.num_nodes()), ns = static_cast<size_t>(net.num_segments());
  Harmonics h{std::vector<std::array<cd, kHarmonics>>(nn), std::vector<std::array<cd, kHarmonics>>(ns)};
  std::vector<double> p(nn), q(ns);
  for (int m = 0; m < kSamplesPerPeriod; ++m) {
    solver->solve_at(kPeriod * m / kSamplesPerPeriod, p, q);
    for (int k = 0; k < kHarmonics; ++k) {
      const cd e = std::polar(1.0 / kSamplesPerPeriod, -2.0 * M_PI * k * m / kSamplesPerPeriod);
      for (size_t i = 0; i < nn; ++i) h.pressure[i][static_cast<size_t>(k)] += p[i] * e;
      for (size_t s = 0; s < ns; ++s) h.flow[s][static_cast<size_t>(k)] += q[s] * e;
    }
  }
  return h;
}

/// Per harmonic k, the largest error over the network relative to the harmonic's largest
/// exact value over the network: max_i |P̂_i − P̂_i^exact| / max_i |P̂_i^exact| for the node
/// pressures, the same over the segment flows (against the exact flow at mid-segment).
struct Errors {
  std::array<double, kHarmonics> pressure{}, flow{};
  [[nodiscard]] double worst(int k) const {
    return std::max(pressure[static_cast<size_t>(k)], flow[static_cast<size_t>(k)]);
  }
};

Errors errors_against(const Harmonics& sim, const std::vector<ExactBranch>& branches, const FlowSpec& spec,
                      const Network& net) {
  Errors e;
  for (int k = 0; k < kHarmonics; ++k) {
    const ExactNetwork exact(branches, spec, net, kPeriod, k);
    const auto kk = static_cast<size_t>(k);
    double dp = 0.0, pmax = 0.0, dq = 0.0, qmax = 0.0;
    for (int i = 0; i < net.num_nodes(); ++i) {
      const cd x = exact.node_pressure(i);
      dp = std::max(dp, std::abs(sim.pressure[static_cast<size_t>(i)][kk] - x));
      pmax = std::max(pmax, std::abs(x));
    }
    for (int s = 0; s < net.num_segments(); ++s) {
      const cd x = exact.segment_flow(s);
      dq = std::max(dq, std::abs(sim.flow[static_cast<size_t>(s)][kk] - x));
      qmax = std::max(qmax, std::abs(x));
    }
    e.pressure[kk] = dp / pmax;
    e.flow[kk] = dq / qmax;
  }
  return e;
}

/// The network of @p branches at segments no longer than @p h, and the flow section @p yaml on it.
struct Case {
  Network net;
  FlowSpec spec;
};
Case build(const std::vector<ExactBranch>& branches, const std::string& yaml, double h) {
  Case c{Network::build(centerlines_of(branches), {.max_segment_length = h}), {}};
  const auto cfg = config::load_config_text(yaml, "exact-network.yaml", flow_schema());
  c.spec = from_config(cfg, c.net);
  return c;
}

/// The finest of the runs: its network and flow, what it simulated and its errors.
struct Finest {
  Case c;
  Harmonics sim;
  Errors errors;
};

/// The simulated network at segments of 4, 2 and 1 cm against the exact solution: per
/// harmonic 1..3 second order (each halving's slope at least 1.8) and the finest error below
/// @p bound; the mean is the resistor network's, exact at any h.
Finest expect_second_order(const char* what, const std::vector<ExactBranch>& branches, const std::string& yaml,
                           double bound) {
  const std::array<double, 3> hs = {0.04, 0.02, 0.01};
  std::vector<Errors> errors;
  Finest finest;
  for (double h : hs) {
    finest.c = build(branches, yaml, h);
    finest.sim = simulate(finest.c.net, finest.c.spec);
    errors.push_back(errors_against(finest.sim, branches, finest.c.spec, finest.c.net));
    const auto& e = errors.back();
    std::printf("%s h = %4.1f cm (%3d segments): relative error per harmonic k = 0..3 (pressure / flow)", what,
                100.0 * h, finest.c.net.num_segments());
    for (int k = 0; k < kHarmonics; ++k)
      std::printf("  %.2e / %.2e", e.pressure[static_cast<size_t>(k)], e.flow[static_cast<size_t>(k)]);
    std::printf("\n");
    EXPECT_LT(e.worst(0), 1e-7) << what << ": the mean is the resistor network's at any h (h = " << h << ")";
  }
  for (int k = 1; k < kHarmonics; ++k) {
    std::printf("%s harmonic %d: slopes", what, k);
    for (size_t i = 0; i + 1 < hs.size(); ++i) {
      const double slope = std::log(errors[i].worst(k) / errors[i + 1].worst(k)) / std::log(hs[i] / hs[i + 1]);
      std::printf(" %.2f", slope);
      EXPECT_GE(slope, 1.8) << what << " harmonic " << k << ", h " << hs[i] << " -> " << hs[i + 1] << ": "
                            << errors[i].worst(k) << " -> " << errors[i + 1].worst(k);
    }
    std::printf("\n");
    EXPECT_LT(errors.back().worst(k), bound) << what << " harmonic " << k;
  }
  finest.errors = errors.back();
  return finest;
}

/// A periodic table of 512 rows over kPeriod: mean + Σ_{k=1..3} a_k cos(kωt + φ_k), written
/// as CSV (time,value) into @p path; returns it.
std::string table_csv(const std::filesystem::path& path, double mean, std::array<double, 3> a,
                      std::array<double, 3> phi) {
  std::ofstream f(path);
  f << "time,value\n";
  f.precision(17);
  for (int i = 0; i <= 512; ++i) {
    const double t = kPeriod * i / 512, w = 2.0 * M_PI / kPeriod;
    double v = mean;
    for (int k = 0; k < 3; ++k)
      v += a[static_cast<size_t>(k)] * std::cos((k + 1) * w * t + phi[static_cast<size_t>(k)]);
    f << t << ',' << v << '\n';
  }
  return path.string();
}

// A trunk into two daughters, the left one tapered (3 → 2.4 mm) and dividing again: a
// pressure wave of three harmonics in; an RCR, a resistance to a distal pressure and a fixed
// pressure out; the tapered branch with a wall of its own absolute thickness, the right one
// stiffer. Every branch 8 cm long, so halving h halves every segment; metres.
const std::vector<ExactBranch> kTree = {
    {"trunk", Vec3(0, 0, 0), Vec3(0.08, 0, 0), 4e-3, 4e-3},
    {"left", Vec3(0.08, 0, 0), Vec3(0.144, 0.048, 0), 3e-3, 2.4e-3},
    {"right", Vec3(0.08, 0, 0), Vec3(0.144, -0.048, 0), 2.5e-3, 2.5e-3},
    {"left_up", Vec3(0.144, 0.048, 0), Vec3(0.144, 0.128, 0), 2e-3, 2e-3},
    {"left_on", Vec3(0.144, 0.048, 0), Vec3(0.224, 0.048, 0), 1.8e-3, 1.8e-3},
};

std::string tree_yaml() {
  return R"(
flow:
  inlet: {node: trunk, pressure: {waveform: table, file: )" +
         table_csv(flowire::testing::scratch_dir("exact-network") / "aortic.csv", 95 * kMmHg,
                   {15 * kMmHg, 6 * kMmHg, 3 * kMmHg}, {-1.2, 0.4, 2.0}) +
         R"(}}
  outlets:
    right: {rcr: {Rp: 3e7, C: 3e-10, Rd: 4e8, Pd: 600}}
    left_up: {resistance: 6e8, distal_pressure: 1000}
    left_on: {pressure: 8000}
  wall:
    youngs_modulus: 0.4 MPa
    thickness_ratio: 0.1
    left: {youngs_modulus: 0.6 MPa, thickness: 0.35 mm}
    right: {youngs_modulus: 1.0 MPa}
)";
}

// A square ring of 8 cm sides (a circle of Willis in miniature): two inlet vessels feed
// opposite corners A and C with flows of different waveforms, two outlet vessels leave the
// other corners B and D into an RCR and a resistance (all 4 cm long). The ring is lopsided, so the flow
// splits unevenly and in each harmonic differently: A–B 2 mm, B–C tapered 1.5 → 1.1 mm with
// a stiff wall of its own (a communicating artery), C–D 1.8 mm, D–A 1.2 mm.
const std::vector<ExactBranch> kRing = {
    {"ring_ab", Vec3(0, 0, 0), Vec3(0.08, 0, 0), 2e-3, 2e-3},
    {"ring_bc", Vec3(0.08, 0, 0), Vec3(0.08, 0.08, 0), 1.5e-3, 1.1e-3},
    {"ring_cd", Vec3(0.08, 0.08, 0), Vec3(0, 0.08, 0), 1.8e-3, 1.8e-3},
    {"ring_da", Vec3(0, 0.08, 0), Vec3(0, 0, 0), 1.2e-3, 1.2e-3},
    {"in_a", Vec3(-0.04, 0, 0), Vec3(0, 0, 0), 2.5e-3, 2.5e-3},
    {"in_c", Vec3(0.12, 0.08, 0), Vec3(0.08, 0.08, 0), 2.2e-3, 2.2e-3},
    {"out_b", Vec3(0.08, 0, 0), Vec3(0.08, -0.04, 0), 1.8e-3, 1.8e-3},
    {"out_d", Vec3(0, 0.08, 0), Vec3(-0.04, 0.08, 0), 1.6e-3, 1.6e-3},
};

/// The two inlets' flow tables, of different harmonics: the paths of A's and C's.
std::pair<std::string, std::string> ring_inflows() {
  const auto dir = flowire::testing::scratch_dir("exact-network");
  return {table_csv(dir / "inflow_a.csv", 4e-6, {2.5e-6, 1.2e-6, 0.6e-6}, {0.3, -0.8, 1.9}),
          table_csv(dir / "inflow_c.csv", 2.5e-6, {1.0e-6, 1.1e-6, 0.7e-6}, {2.4, 0.5, -1.3})};
}

/// A flow inlet's waveform section for the table at @p path.
std::string table(const std::string& path) { return "{waveform: table, file: " + path + "}"; }

/// The ring's flow section, the inlets' flow waveform sections @p inlet_a and @p inlet_c.
std::string ring_yaml(const std::string& inlet_a, const std::string& inlet_c) {
  return R"(
flow:
  inlets:
    - {node: in_a, flow: )" +
         inlet_a + R"(}
    - {node: in_c, flow: )" +
         inlet_c + R"(}
  outlets:
    out_b: {rcr: {Rp: 1e8, C: 5e-10, Rd: 9e8, Pd: 500}}
    out_d: {resistance: 1.1e9, distal_pressure: 800}
  wall:
    youngs_modulus: 0.4 MPa
    thickness_ratio: 0.1
    ring_bc: {youngs_modulus: 1.2 MPa, thickness: 0.25 mm}
)";
}

}  // namespace

// The uniform branch's closed form and the RK4 integration the tapered one needs agree, and
// a branch's two-port conserves what it should: det M = 1 (reciprocity).
TEST(ExactNetwork, TheTaperedLineIntegrationEqualsTheUniformClosedForm) {
  const std::vector<ExactBranch> one = {{"tube", Vec3(0, 0, 0), Vec3(0.1, 0, 0), 2e-3, 2e-3}};
  std::vector<ExactBranch> almost = one;
  almost[0].r_b = 2e-3 * (1.0 + 1e-12);  // not uniform: integrated
  const Network net = Network::build(centerlines_of(one), {.max_segment_length = 0.1});
  FlowSpec spec;
  for (int k : {0, 1, 3}) {
    const ExactNetwork a(one, spec, net, kPeriod, k), b(almost, spec, net, kPeriod, k);
    const auto ma = a.transfer(0, 0.0, 0.1), mb = b.transfer(0, 0.0, 0.1);
    for (size_t j = 0; j < 4; ++j) EXPECT_LT(std::abs(ma[j] - mb[j]), 1e-9 * std::abs(ma[j]) + 1e-300) << k << j;
    EXPECT_LT(std::abs(mb[0] * mb[3] - mb[1] * mb[2] - 1.0), 1e-10) << k;
  }
}

TEST(ExactNetwork, ATreeWithATaperedBranchAndItsOwnWallsConvergesEverywhereAtSecondOrder) {
  (void)expect_second_order("tree", kTree, tree_yaml(), 1e-3);
}

TEST(ExactNetwork, ARingFedByTwoFlowInletsSplitsItsFlowAsTheExactSolutionAtSecondOrder) {
  const auto [qa, qc] = ring_inflows();
  const auto [c, sim, finest] = expect_second_order("ring", kRing, ring_yaml(table(qa), table(qc)), 2e-3);

  // The check can fail: the finest simulation against the exact ring with its inlets'
  // waveforms swapped, and against the exact ring whose D–A side is 10% narrower (another flow
  // split around the loop), is off by far more than the bound and the error measured.
  const Case swapped = build(kRing, ring_yaml(table(qc), table(qa)), 0.01);
  std::vector<ExactBranch> narrower = kRing;
  narrower[3].r_a = narrower[3].r_b = 0.9 * 1.2e-3;
  const Errors e_swapped = errors_against(sim, kRing, swapped.spec, c.net);
  const Errors e_split = errors_against(sim, narrower, c.spec, c.net);
  for (int k = 0; k < kHarmonics; ++k) {
    std::printf("ring harmonic %d: error %.2e; against swapped inlets %.2e, against a narrower D-A %.2e\n", k,
                finest.worst(k), e_swapped.worst(k), e_split.worst(k));
    EXPECT_GT(e_swapped.worst(k), 0.05) << k;
    EXPECT_GT(e_split.worst(k), 0.005) << k;
    if (k > 0) {
      EXPECT_GT(e_split.worst(k), 10.0 * finest.worst(k)) << k;
    }
  }
}

// What is measured above is the segments' error, not the time step's: halving dt at the
// finest segments changes every harmonic by less than a tenth of the error measured there.
TEST(ExactNetwork, TheTimeStepErrorIsBelowTheFinestSegmentsError) {
  const auto [qa, qc] = ring_inflows();
  const Case c = build(kRing, ring_yaml(table(qa), table(qc)), 0.01);
  const Harmonics a = simulate(c.net, c.spec), b = simulate(c.net, c.spec, 2 * kStepsPerPeriod);
  const Errors e = errors_against(a, kRing, c.spec, c.net);
  for (int k = 1; k < kHarmonics; ++k) {
    const auto kk = static_cast<size_t>(k);
    double dp = 0.0, pmax = 0.0, dq = 0.0, qmax = 0.0;
    for (size_t i = 0; i < a.pressure.size(); ++i)
      dp = std::max(dp, std::abs(a.pressure[i][kk] - b.pressure[i][kk])),
      pmax = std::max(pmax, std::abs(b.pressure[i][kk]));
    for (size_t s = 0; s < a.flow.size(); ++s)
      dq = std::max(dq, std::abs(a.flow[s][kk] - b.flow[s][kk])), qmax = std::max(qmax, std::abs(b.flow[s][kk]));
    std::printf("harmonic %d: dt -> dt/2 changes pressures %.2e, flows %.2e; segment error %.2e / %.2e\n", k, dp / pmax,
                dq / qmax, e.pressure[kk], e.flow[kk]);
    EXPECT_LT(dp / pmax, 0.1 * e.pressure[kk]) << k;
    EXPECT_LT(dq / qmax, 0.1 * e.flow[kk]) << k;
  }
}

// Two inlets need not share a period: a sine of period T/2 at A (listed first) and the table
// of period T at C repeat together after T, and that is the period the model must settle on
// before its clock starts; the first inlet's period alone is never periodic (the state a half
// period apart differs by 10%), and the state a search on it hands over is out of phase.
TEST(ExactNetwork, InletsOfDifferentPeriodsSettleOnTheirCommonPeriod) {
  const auto [qa, qc] = ring_inflows();
  const Case c =
      build(kRing, ring_yaml("{waveform: sine, systolic: 6e-6, diastolic: 2e-6, period: 0.25 s}", table(qc)), 0.01);
  ASSERT_EQ(c.spec.inlets[0].waveform.cycle(), 0.5 * kPeriod);
  const Errors e = errors_against(simulate(c.net, c.spec), kRing, c.spec, c.net);
  for (int k = 0; k < kHarmonics; ++k) {
    std::printf("harmonic %d: pressure %.2e, flow %.2e\n", k, e.pressure[static_cast<size_t>(k)],
                e.flow[static_cast<size_t>(k)]);
    EXPECT_LT(e.worst(k), 2e-3) << k;
  }
}

}  // namespace flowire::flow
