// Boundary conditions into sources and the nodal conductance system (flow/src/assembly.cpp):
// a four-node network whose matrix, right-hand sides and Dirichlet values are written out
// by hand from Kirchhoff's law, the frustum resistance of a tapered segment, and the errors
// (two conditions on a node, a node not in the network, a piece without pressure reference).
#include "assembly.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "flow_test_networks.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

using namespace flowire::flow::test;

/// 0 —(l = 1)— 1 —(l = 2)— 2, and 1 —(l = 4)— 3; r = 1 and η = π/8, so R = l and the
/// conductances are 1, 1/2, 1/4.
Network star() {
  std::vector<Vec3> nodes = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 2, 0), Vec3(1, -4, 0)};
  std::vector<vessels::Segment> segs = {{0, 1, 1.0, 0.0, -1}, {1, 2, 1.0, 0.0, -1}, {1, 3, 1.0, 0.0, -1}};
  return Network::from_graph(nodes, segs);
}

/// Sine pressure at 0, 10 Pa at 2, a resistance 4 to a distal 8 Pa at 3.
FlowSpec star_spec() {
  FlowSpec spec = pressure_spec(star(), 0, Waveform::sine(3.0, 1.0, 1.0), {{2, 10.0}});
  spec.viscosity = kUnitViscosity;
  OutletBC o;
  o.node = 3;
  o.type = OutletBC::Type::Resistance;
  o.resistance = 4.0;
  o.distal_pressure = 8.0;
  spec.outlets.push_back(o);
  return spec;
}

TEST(FlowAssembly, AFourNodeNetworkByHand) {
  const Network net = star();
  const FlowSpec spec = star_spec();
  std::vector<double> resistance;
  const detail::Assembly a = detail::assemble(net, spec, resistance);
  ASSERT_EQ(resistance.size(), 3u);
  EXPECT_NEAR(resistance[0], 1.0, 1e-15);
  EXPECT_NEAR(resistance[1], 2.0, 1e-15);
  EXPECT_NEAR(resistance[2], 4.0, 1e-15);
  EXPECT_EQ(a.dirichlet, (std::vector<char>{1, 0, 1, 0}));
  EXPECT_EQ(a.node_of_unknown, (std::vector<int>{1, 3}));
  EXPECT_EQ(a.unknown_of_node, (std::vector<int>{-1, 0, -1, 1}));
  EXPECT_EQ(a.outlet_conductance, (std::vector<double>{0, 0, 0, 0.25}));
  ASSERT_EQ(a.num_sources(), 2);  // the constants, and the sine
  double f[2];
  a.coefficients(0.25, f);  // the sine's peak
  EXPECT_EQ(f[0], 1.0);
  EXPECT_NEAR(f[1], 3.0, 1e-15);

  // Kirchhoff at node 1: (p0 − p1)·1 + (p2 − p1)/2 + (p3 − p1)/4 = 0;
  // at node 3: (p1 − p3)/4 + (8 − p3)/4 = 0.
  Eigen::Matrix2d g_hand;
  g_hand << 1.75, -0.25, -0.25, 0.5;
  EXPECT_LT((Eigen::MatrixXd(detail::nodal_matrix(net, a)) - g_hand).norm(), 1e-15);
  Eigen::VectorXd b0 = Eigen::VectorXd::Zero(2), b1 = Eigen::VectorXd::Zero(2);
  detail::add_nodal_rhs(net, a, a.sources[0], 1.0, b0);  // p2 = 10 through g = 1/2; 8/4 at node 3
  detail::add_nodal_rhs(net, a, a.sources[1], 2.0, b1);  // p0 = 2·1 through g = 1
  EXPECT_LT((b0 - Eigen::Vector2d(5.0, 2.0)).norm(), 1e-15);
  EXPECT_LT((b1 - Eigen::Vector2d(2.0, 0.0)).norm(), 1e-15);
  double p[4] = {0, 0, 0, 0};
  detail::add_dirichlet(a, a.sources[0], 1.0, p);
  detail::add_dirichlet(a, a.sources[1], 3.0, p);
  EXPECT_EQ(p[0], 3.0);
  EXPECT_EQ(p[2], 10.0);
  EXPECT_EQ(p[1], 0.0);
  EXPECT_EQ(p[3], 0.0);  // not a pressure node: its source value is a flow

  // The solver built on it gives the hand system's solution at the sine's peak (p0 = 3).
  const Eigen::Vector2d pu = g_hand.lu().solve(Eigen::Vector2d(5.0 + 3.0, 2.0));
  auto s = make_solver(net, spec);
  s->advance(0.25);
  EXPECT_NEAR(s->node_pressure(1), pu[0], 1e-12);
  EXPECT_NEAR(s->node_pressure(3), pu[1], 1e-12);
}

TEST(FlowAssembly, ATaperedSegmentHasTheFrustumResistance) {
  // r from 1 to 2 over l = 3 with η = π/8: ∫ 8η/(π r⁴) dx = (r1² + r1 r2 + r2²) l/(3 r1³ r2³) = 7/8.
  std::vector<Vec3> nodes = {Vec3(0, 0, 0), Vec3(3, 0, 0)};
  vessels::Segment seg{0, 1, 1.5, 0.0, -1, 1.0, 2.0};
  const Network net = Network::from_graph(nodes, {seg});
  FlowSpec spec = pressure_spec(net, 0, Waveform::constant(1.0), {{1, 0.0}});
  spec.viscosity = kUnitViscosity;
  std::vector<double> r;
  (void)detail::assemble(net, spec, r);
  EXPECT_NEAR(r[0], 7.0 / 8.0, 1e-15);
  // The same by a midpoint quadrature of 8η/(π r(x)⁴).
  double q = 0.0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) q += 3.0 / n / std::pow(1.0 + (i + 0.5) / n, 4);
  EXPECT_NEAR(r[0], q, 1e-9);
}

TEST(FlowAssembly, RcrOutletsAreTheirTotalResistanceOnlyInTheSteadyModel) {
  const Network net = star();
  FlowSpec spec = star_spec();
  spec.outlets.back().type = OutletBC::Type::Rcr;
  spec.outlets.back().rp = 1.0;
  spec.outlets.back().rd = 3.0;
  spec.outlets.back().c = 1e-3;
  std::vector<double> r;
  {
    testing::ExpectWarnings w;
    const auto a = detail::assemble(net, spec, r, true);
    EXPECT_TRUE(w.contains("Rp + Rd"));
    EXPECT_EQ(a.outlet_conductance[3], 0.25);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(2);
    detail::add_nodal_rhs(net, a, a.sources[0], 1.0, b);
    EXPECT_EQ(b[1], 2.0);  // Pd/(Rp + Rd) = 8/4
  }
  // The dynamic model keeps the windkessel itself: no resistance here, no warning, and the
  // node still counts as referenced (no singular-piece error).
  const auto a = detail::assemble(net, spec, r, false);
  EXPECT_EQ(a.outlet_conductance[3], 0.0);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(2);
  detail::add_nodal_rhs(net, a, a.sources[0], 1.0, b);
  EXPECT_EQ(b[1], 0.0);
}

std::string error_of(const Network& net, const FlowSpec& spec, ErrorKind* kind = nullptr) {
  std::vector<double> r;
  try {
    (void)detail::assemble(net, spec, r);
  } catch (const Error& e) {
    if (kind) *kind = e.kind();
    return e.what();
  }
  return "";
}

TEST(FlowAssembly, BadConditionsAreClearErrors) {
  const Network net = star();
  ErrorKind kind{};
  FlowSpec twice = star_spec();
  twice.outlets.front().node = 3;  // node 3 gets a pressure and a resistance
  EXPECT_NE(error_of(net, twice, &kind).find("node 3 has 2 boundary conditions"), std::string::npos);
  EXPECT_EQ(kind, ErrorKind::Usage);
  FlowSpec outside = star_spec();
  outside.inlets.front().node = 7;
  EXPECT_NE(error_of(net, outside, &kind).find("inlet node 7 is not in the network (0..3)"), std::string::npos);
  FlowSpec viscosity = star_spec();
  viscosity.viscosity = 0.0;
  EXPECT_NE(error_of(net, viscosity, &kind).find("viscosity"), std::string::npos);
  FlowSpec resistance = star_spec();
  resistance.outlets.back().resistance = -1.0;
  EXPECT_NE(error_of(net, resistance, &kind).find("outlet at node 3: resistance -1"), std::string::npos);
  // Only a flow into node 0 and pressures nowhere in reach: the piece {0, 1, 2, 3} floats.
  FlowSpec floating;
  floating.viscosity = kUnitViscosity;
  InletBC in;
  in.node = 0;
  in.type = InletBC::Type::Flow;
  in.waveform = Waveform::constant(1.0);
  floating.inlets.push_back(in);
  const std::string msg = error_of(net, floating, &kind);
  EXPECT_EQ(kind, ErrorKind::Numerical);
  EXPECT_NE(msg.find("4 node(s) (nodes 0, 1, 2, 3) has no pressure reference"), std::string::npos) << msg;
}

}  // namespace
}  // namespace flowire::flow
