// The quasi-steady network with quadratic losses (flow/src/newton_solver.cpp): the segment law's
// flow and tangent conductance against central differences, two segments in series and a Y against
// their closed forms (a quadratic, and a scalar root found here by bisection), the linear limit
// equal to the superposition solver, an occlusion and a time-dependent inlet, and the
// combinations it refuses.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "flow_test_networks.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/solver.hpp"

namespace flowire::flow {
namespace {

using test::kUnitViscosity;

TEST(NewtonSolver, TheSegmentLawsFlowAndConductanceMatchItsRootAndCentralDifferences) {
  const SegmentLaw law{1.0, 3.7};
  const double r = 0.8;
  for (const double dp : {-5.0, -0.3, -1e-6, 1e-6, 0.02, 1.0, 40.0}) {
    const double q = law.flow(dp, r);
    EXPECT_NEAR(r * q + law.quadratic * std::abs(q) * q, dp, 1e-13 * std::max(1.0, std::abs(dp))) << dp;
    const double h = 1e-6 * std::max(1e-3, std::abs(dp));
    const double fd = (law.flow(dp + h, r) - law.flow(dp - h, r)) / (2.0 * h);
    EXPECT_NEAR(law.conductance(dp, r), fd, 1e-7 * std::abs(fd)) << dp;
  }
  EXPECT_DOUBLE_EQ(SegmentLaw{}.flow(2.0, 0.5), 4.0);  // K = 0: Poiseuille
}

TEST(NewtonSolver, TwoSegmentsInSeriesMatchTheRootOfTheirSummedLaw) {
  // R = l with the unit viscosity: segments of 1 and 2, K = 3 and 5, Δp = 10 over the pair.
  const Network net = test::tube(3.0, 1.0, 3);  // three unit segments; the last two share a law
  FlowSpec spec = default_spec(net, Waveform::constant(10.0));
  spec.viscosity = kUnitViscosity;
  spec.segment_laws = {{1.0, 3.0}, {1.0, 2.5}, {1.0, 2.5}};
  const auto solver = make_solver(net, spec);
  EXPECT_EQ(solver->name(), "newton");
  // 3Q + 8Q² = 10
  const double q = (-3.0 + std::sqrt(9.0 + 320.0)) / 16.0;
  // The solver converges to a node imbalance of 1e-10 of the largest flow.
  EXPECT_NEAR(solver->segment_flow(0), q, 1e-9 * q);
  EXPECT_NEAR(solver->segment_flow(2), q, 1e-9 * q);
  EXPECT_NEAR(solver->node_pressure(1), 10.0 - (q + 3.0 * q * q), 1e-8);
  // The quadratic losses lower the flow below Poiseuille's 10/3.
  EXPECT_LT(q, 10.0 / 3.0 * 0.5);
}

TEST(NewtonSolver, AYSplitsItsFlowWhereBothDaughtersDropTheSamePressure) {
  // Parent 0→1 (R 1, K 2), daughters 1→2 (R 2, K 1) and 1→3 (R 1, K 6) to 0 Pa; 3 m³/s in.
  const std::vector<Vec3> nodes{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 1, 0), Vec3(2, -1, 0)};
  const std::vector<vessels::Segment> segs{{0, 1, 1.0, 1.0, -1}, {1, 2, 1.0, 2.0, -1}, {1, 3, 1.0, 1.0, -1}};
  const Network net = Network::from_graph(nodes, segs);
  FlowSpec spec;
  spec.viscosity = kUnitViscosity;
  InletBC in;
  in.node = 0;
  in.type = InletBC::Type::Flow;
  in.waveform = Waveform::constant(3.0);
  spec.inlets = {in};
  spec.segment_laws = {{1.0, 2.0}, {1.0, 1.0}, {1.0, 6.0}};
  const auto solver = make_solver(net, spec);
  // Bisection on Q1 in [0, 3]: 2Q1 + Q1² = Q2 + 6Q2², Q2 = 3 − Q1.
  double lo = 0.0, hi = 3.0;
  for (int i = 0; i < 200; ++i) {
    const double m = 0.5 * (lo + hi), q2 = 3.0 - m;
    ((2.0 * m + m * m) - (q2 + 6.0 * q2 * q2) < 0.0 ? lo : hi) = m;
  }
  const double q1 = 0.5 * (lo + hi), q2 = 3.0 - q1;
  EXPECT_NEAR(solver->segment_flow(1), q1, 1e-9);
  EXPECT_NEAR(solver->segment_flow(2), q2, 1e-9);
  EXPECT_NEAR(solver->node_pressure(1), 2.0 * q1 + q1 * q1, 1e-8);
  EXPECT_NEAR(solver->node_pressure(0), solver->node_pressure(1) + 3.0 + 2.0 * 9.0, 1e-8);
}

TEST(NewtonSolver, ResistanceFactorsAloneKeepTheLinearSolverAndScaleItsResistances) {
  const Network net = test::murray_tree(3);
  FlowSpec plain = default_spec(net, Waveform::constant(100.0));
  FlowSpec scaled = plain;
  scaled.segment_laws.assign(static_cast<size_t>(net.num_segments()), SegmentLaw{2.0, 0.0});
  const auto a = make_solver(net, plain);
  const auto b = make_solver(net, scaled);
  EXPECT_EQ(b->name(), "superposition");
  for (int s = 0; s < net.num_segments(); ++s) {
    EXPECT_NEAR(b->resistance(s), 2.0 * a->resistance(s), 1e-12 * a->resistance(s));
    EXPECT_NEAR(b->segment_flow(s), 0.5 * a->segment_flow(s), 1e-12 * std::abs(a->segment_flow(s)));
  }
}

TEST(NewtonSolver, TinyQuadraticTermsGiveTheLinearAnswerAndNewtonIsUsed) {
  const Network net = test::murray_tree(4);
  FlowSpec lin = default_spec(net, Waveform::constant(100.0));
  FlowSpec quad = lin;
  quad.segment_laws.assign(static_cast<size_t>(net.num_segments()), SegmentLaw{1.0, 1e-30});
  const auto a = make_solver(net, lin);
  const auto b = make_solver(net, quad);
  EXPECT_EQ(b->name(), "newton");
  for (int i = 0; i < net.num_nodes(); ++i) EXPECT_NEAR(b->node_pressure(i), a->node_pressure(i), 1e-9 * 100.0);
}

TEST(NewtonSolver, AnOcclusionScalesTheLinearPartAndATimeDependentInletIsSolvedPerFrame) {
  const Network net = test::tube(2.0, 1.0, 2);
  FlowSpec spec = default_spec(net, Waveform::sine(15.0, 5.0, 1.0));  // 10 + 5 sin(2πt)
  spec.viscosity = kUnitViscosity;
  spec.segment_laws = {{1.0, 1.0}, {1.0, 1.0}};
  const auto solver = make_solver(net, spec);
  ASSERT_TRUE(solver->supports_occlusion());
  std::vector<SegmentOcclusion> occ(2);
  occ[1].resistance_factor = 3.0;
  solver->set_occlusion(occ);
  for (const double t : {0.0, 0.25, 0.6}) {
    solver->advance(t);
    const double dp = 10.0 + 5.0 * std::sin(2.0 * std::numbers::pi * t);
    // (1 + 3) Q + 2 Q² = Δp
    const double q = (-4.0 + std::sqrt(16.0 + 8.0 * dp)) / 4.0;
    EXPECT_NEAR(solver->segment_flow(0), q, 1e-9) << t;
    EXPECT_NEAR(solver->segment_flow_at(1, 0.1),
                (-4.0 + std::sqrt(16.0 + 8.0 * (10.0 + 5.0 * std::sin(0.2 * std::numbers::pi)))) / 4.0, 1e-9);
  }
}

TEST(NewtonSolver, RefusesQuadraticLossesWhereTheyCannotBeSolvedAndBadLaws) {
  const Network net = test::tube(2.0, 1.0, 2);
  FlowSpec spec = default_spec(net, Waveform::constant(1.0));
  spec.segment_laws = {{1.0, 1.0}, {1.0, 0.0}};
  for (const SolverKind k : {SolverKind::DenseInverse, SolverKind::Petsc}) {
    FlowSpec s = spec;
    s.solver = k;
    try {
      (void)make_solver(net, s);
      FAIL() << to_string(k);
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
      EXPECT_NE(std::string(e.what()).find("nonlinear"), std::string::npos) << e.what();
    }
  }
  FlowSpec wrong = spec;
  wrong.segment_laws.pop_back();
  EXPECT_THROW((void)make_solver(net, wrong), Error);
  FlowSpec negative = spec;
  negative.segment_laws[0].quadratic = -1.0;
  EXPECT_THROW((void)make_solver(net, negative), Error);
  negative.segment_laws[0] = {0.0, 0.0};
  EXPECT_THROW((void)make_solver(net, negative), Error);
}

TEST(NewtonSolver, FramesStartedFromTheLastOnesExtrapolatedEndWhereAColdStartEnds) {
  // A pulsatile inlet through a tree with quadratic losses: frames 1 ms apart (each started from
  // the last frames' pressures extrapolated to its time), then a jump back and a long step
  // (started from the last frame), against a fresh solver at each time.
  const Network net = test::murray_tree(4);
  FlowSpec spec = default_spec(net, Waveform::sine(100.0 * 133.3, 30.0 * 133.3, 0.8));
  for (int s = 0; s < net.num_segments(); ++s) spec.segment_laws.push_back({1.0 + 0.1 * (s % 3), 1e8 * (1 + s % 4)});
  const auto stepped = make_solver(net, spec);
  ASSERT_EQ(stepped->name(), "newton");
  std::vector<double> times;
  for (int k = 0; k <= 40; ++k) times.push_back(0.1 + 1e-3 * k);
  times.push_back(0.05);
  times.push_back(0.6);
  for (const double t : times) {
    stepped->advance(t);
    const auto cold = make_solver(net, spec);
    cold->advance(t);
    for (int i = 0; i < net.num_nodes(); ++i)
      EXPECT_NEAR(stepped->node_pressure(i), cold->node_pressure(i), 1e-8 * 130.0 * 133.3)
          << "t " << t << " node " << i;
    for (int s = 0; s < net.num_segments(); ++s)
      EXPECT_NEAR(stepped->segment_flow(s), cold->segment_flow(s), 1e-8 * std::abs(cold->segment_flow(0))) << t;
  }
}

}  // namespace
}  // namespace flowire::flow
