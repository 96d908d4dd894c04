// Mynard & Valen-Sendstad's unified junction model (flow/junction.hpp): its limits written out
// (Borda–Carnot's sudden expansion, a straight continuation), the authors' T-junction in the
// plane against the model's formulas evaluated here by hand, its independence of the frame, its
// derivatives against finite differences, and a network solved with it through make_solver.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <vector>

#include "flow_test_networks.hpp"
#include "flowire/common/config.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/junction.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/flow/spec.hpp"
#include "flowire/vessels/generators.hpp"

namespace flowire::flow {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kRho = 1060.0;

Junction planar(const std::vector<double>& angles, const std::vector<double>& areas) {
  Junction j;
  j.node = 0;
  for (size_t i = 0; i < angles.size(); ++i) {
    JunctionBranch b;
    b.segment = static_cast<int>(i);
    b.area = areas[i];
    b.direction = Vec3(std::cos(angles[i]), std::sin(angles[i]), 0.0);
    j.branches.push_back(b);
  }
  return j;
}

std::vector<double> drops(const Junction& j, const std::vector<double>& outward) {
  std::vector<double> d(outward.size());
  unified_junction_drops(j, kRho, outward.data(), d.data());
  return d;
}

TEST(UnifiedJunction, OneSupplierIntoAWiderCollectorInLineIsBordaCarnotsSuddenExpansion) {
  const double a0 = kPi * 1e-6, a1 = kPi * 4e-6, q = 2e-6;
  const Junction j = planar({kPi, 0.0}, {a0, a1});
  const auto d = drops(j, {-q, q});
  const double u0 = q / a0, u1 = q / a1;
  EXPECT_EQ(d[0], 0.0);  // the supplier holds the junction's pressure
  // Momentum across the expansion: p0 − p1 = ρU1(U1 − U0) (a recovery: negative).
  EXPECT_NEAR(d[1], kRho * u1 * (u1 - u0), 1e-12 * kRho * u0 * u0);
  // The same area straight on: no change.
  const auto same = drops(planar({kPi, 0.0}, {a0, a0}), {-q, q});
  EXPECT_NEAR(same[1], 0.0, 1e-12 * kRho * u0 * u0);
}

TEST(UnifiedJunction, TheAuthorsTJunctionInThePlaneFollowsTheirFormulasWrittenOut) {
  // Diverging flow in a T of equal areas: the supplier at angle π, collectors at 0 (straight on)
  // and π/2 (the side), half the flow each (the authors' example, U = [100, −50, −50]).
  const double a = 2e-6, q = 1e-6;
  const Junction j = planar({kPi, 0.0, kPi / 2}, {a, a, a});
  const auto c = unified_junction_coefficients(j, std::vector<double>{-2 * q, q, q}.data());
  // Pseudo-collector at π/4, pseudo-supplier at 3π/4 from it; the straight collector lies on the
  // far side (σ = −1), the side branch on the supplier's (σ = +1); λ = 1/2.
  const double theta = 3 * kPi / 4, lambda = 0.5, ubar = 2 * q / a;
  auto expected = [&](double sigma, double phi) {
    const double eta = (0.8 * (kPi - theta) * sigma - 0.2) * (1 - lambda);
    const double area = 2 * q / ((1 - eta) * ubar);
    return (1 - std::exp(-lambda / 0.02)) * (1 - std::cos(0.75 * (kPi - phi)) / (area / a * lambda));
  };
  EXPECT_EQ(c[0], 0.0);
  EXPECT_NEAR(c[1], expected(-1.0, kPi), 1e-12);
  EXPECT_NEAR(c[2], expected(+1.0, kPi / 2), 1e-12);
  EXPECT_NEAR(c[1], -1.8283, 1e-4);  // the straight branch recovers pressure,
  EXPECT_NEAR(c[2], 0.3985, 1e-4);   // the side branch loses it
  const auto d = drops(j, {-2 * q, q, q});
  EXPECT_NEAR(d[2], c[2] * kRho * (q / a) * (q / a), 1e-12 * std::abs(d[2]));
}

TEST(UnifiedJunction, TheDropsDoNotDependOnTheFrame) {
  // A non-planar junction of four branches, two supplying: turned and reflected as a whole, the
  // same drops.
  Junction j = planar({kPi, 2.5, -0.4, 1.2}, {3e-6, 2e-6, 1.5e-6, 1e-6});
  j.branches[3].direction = Vec3(0.3, 0.5, 0.8).normalized();
  const std::vector<double> o{-3e-6, -1e-6, 2.5e-6, 1.5e-6};
  const auto d = drops(j, o);
  Junction turned = j;
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.7, Vec3(1, -2, 0.5).normalized()).toRotationMatrix();
  for (auto& b : turned.branches) b.direction = Vec3(-(rot * b.direction));
  const auto dt = drops(turned, o);
  for (size_t i = 0; i < d.size(); ++i) EXPECT_NEAR(dt[i], d[i], 1e-12 * std::abs(d[2]));
  EXPECT_EQ(d[0], 0.0);
  EXPECT_EQ(d[1], 0.0);
  EXPECT_NE(d[2], 0.0);
}

TEST(UnifiedJunction, ItsDerivativesAgreeWithFiniteDifferences) {
  Junction j = planar({kPi, 2.5, -0.4, 1.2}, {3e-6, 2e-6, 1.5e-6, 1e-6});
  j.branches[3].direction = Vec3(0.3, 0.5, 0.8).normalized();
  for (const std::vector<double>& o :
       {std::vector<double>{-3e-6, -1e-6, 2.5e-6, 1.5e-6}, std::vector<double>{-4e-6, 0.5e-6, 2.5e-6, 1e-6},
        std::vector<double>{-2e-6, 1.9e-6, 0.08e-6, 0.02e-6}}) {
    const size_t n = o.size();
    std::vector<double> d(n), jac(n * n);
    unified_junction_drops(j, kRho, o.data(), d.data(), jac.data());
    const auto plain = drops(j, o);
    double largest = 0.0;
    for (double v : jac) largest = std::max(largest, std::abs(v));
    for (size_t k = 0; k < n; ++k) {
      EXPECT_EQ(d[k], plain[k]);
      const double h = 1e-6 * std::abs(o[k]);
      auto op = o, om = o;
      op[k] += h;
      om[k] -= h;
      const auto dp = drops(j, op), dm = drops(j, om);
      for (size_t i = 0; i < n; ++i)
        EXPECT_NEAR(jac[i * n + k], (dp[i] - dm[i]) / (2 * h), 1e-6 * largest) << "d drop_" << i << " / d o_" << k;
    }
  }
  // A symmetric Y fed by its parent: the pseudo-supplier exactly opposite the pseudo-collector.
  const Junction y = planar({kPi, 0.6, -0.6}, {3e-6, 2e-6, 1.5e-6});
  const std::vector<double> o{-3e-6, 1.8e-6, 1.2e-6};
  std::vector<double> d(3), jac(9);
  unified_junction_drops(y, kRho, o.data(), d.data(), jac.data());
  for (size_t k = 0; k < 3; ++k) {
    const double h = 1e-6 * std::abs(o[k]);
    auto op = o, om = o;
    op[k] += h;
    om[k] -= h;
    const auto dp = drops(y, op), dm = drops(y, om);
    for (size_t i = 0; i < 3; ++i) EXPECT_NEAR(jac[i * 3 + k], (dp[i] - dm[i]) / (2 * h), 1e-6 * std::abs(jac[4]));
  }
}

/// A Y at carotid scale: parent radius 3 mm, 24 mm branches, daughters 30% asymmetric (Murray).
Network carotid_y() {
  vessels::YBifurcationParams yp;
  yp.parent_radius = 3e-3;
  yp.parent_length = 24e-3;
  yp.child_length = 24e-3;
  yp.asymmetry = 0.3;
  vessels::BuildOptions bo;
  bo.max_segment_length = 6e-3;
  return Network::build(vessels::y_bifurcation(yp), bo);
}

/// That Y with every node's pressure and every segment's flow.
struct YFlow {
  Network net;
  std::unique_ptr<FlowSolver> solver;
};

YFlow y_flow(const std::string& inlet, const std::string& junction) {
  YFlow y;
  y.net = carotid_y();
  const auto cfg = config::load_config_text(
      "flow:\n  inlet: " + inlet + "\n  outlets: {pressure: 0}\n  losses: {junction: " + junction + "}\n",
      "junction.yaml", test::flow_schema());
  y.solver = make_solver(y.net, from_config(cfg, y.net));
  y.solver->advance(0.0);
  return y;
}

TEST(UnifiedJunctionNetwork, EveryJunctionSegmentObeysItsLawWithTheDropsAtItsEnds) {
  for (const std::string inlet : {"{flow: 9.3e-6}", "{pressure: 30}"}) {
    const YFlow y = y_flow(inlet, "unified");
    EXPECT_EQ(y.solver->name(), "newton");
    const auto& spec = y.solver->spec();
    ASSERT_EQ(spec.junctions.size(), 1u);
    const Junction& j = spec.junctions[0];
    std::vector<double> o;
    for (const auto& b : j.branches) o.push_back(b.outward * y.solver->segment_flow(b.segment));
    const auto d = drops(j, o);
    double mass = 0.0, scale = 0.0;
    for (size_t i = 0; i < o.size(); ++i) {
      mass += o[i];
      scale = std::max(scale, std::abs(o[i]));
      const int s = j.branches[i].segment;
      const auto& seg = y.net.segment(s);
      const double pj = y.solver->node_pressure(j.node) - d[i];
      const double far = y.solver->node_pressure(seg.node_from == j.node ? seg.node_to : seg.node_from);
      // Poiseuille's law of the segment between its far node and its end at the junction.
      const double q = y.solver->segment_flow(s);
      const double dp = seg.node_from == j.node ? pj - far : far - pj;
      EXPECT_NEAR(dp, y.solver->effective_resistance(s) * q, 1e-8 * std::abs(dp)) << inlet << " branch " << i;
    }
    EXPECT_NEAR(mass, 0.0, 1e-10 * scale);
    // The daughters' drops are not zero: the model acts.
    EXPECT_GT(std::abs(d[1]) + std::abs(d[2]), 1e-3 * std::abs(y.solver->node_pressure(j.node)));
  }
}

TEST(UnifiedJunctionNetwork, WhereTheRecoveredPressureOutgrowsTheResistanceThereIsNoSteadyFlowAndItSaysSo) {
  // This Y's daughters are 26% wider than its parent: the static pressure they recover grows as Q²
  // and the network's drop p_in = R Q − c Q² peaks near 40 Pa; at 60 Pa there is no steady flow.
  try {
    (void)y_flow("{pressure: 60}", "unified");
    ADD_FAILURE() << "a steady flow was reported";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Numerical);
    EXPECT_NE(std::string(e.what()).find("junction losses"), std::string::npos) << e.what();
  }
}

TEST(UnifiedJunctionNetwork, TheRlcModelReachesTheQuasiSteadyModelsFlowUnderAConstantInlet) {
  // The same Y, its junction in the rlc model (flows are its unknowns there): under a constant
  // inflow and outlet resistances its steady state and the state it keeps over a few steps are the
  // quasi-steady Newton solution's.
  const Network net = carotid_y();
  auto solver = [&](const std::string& model) {
    const auto cfg = config::load_config_text("flow:\n  model: " + model +
                                                  "\n  inlet: {flow: 9.3e-6}\n  outlets: {resistance: 2e6}\n"
                                                  "  losses: {junction: unified}\n",
                                              "junction.yaml", test::flow_schema());
    return make_solver(net, from_config(cfg, net));
  };
  auto quasi = solver("poiseuille");
  auto rlc = solver("rlc");
  quasi->advance(0.0);
  EXPECT_EQ(rlc->spec().junctions.size(), 1u);
  double pscale = 0.0;
  for (int n = 0; n < net.num_nodes(); ++n) pscale = std::max(pscale, std::abs(quasi->node_pressure(n)));
  for (const double t : {0.0, 0.01}) {
    rlc->advance(t);
    for (int n = 0; n < net.num_nodes(); ++n)
      EXPECT_NEAR(rlc->node_pressure(n), quasi->node_pressure(n), 1e-8 * pscale) << "node " << n << " t " << t;
    for (int k = 0; k < net.num_segments(); ++k)
      EXPECT_NEAR(rlc->segment_flow(k), quasi->segment_flow(k), 1e-8 * 9.3e-6) << "segment " << k << " t " << t;
  }
  // The drops act: without them the split differs.
  const auto cfg = config::load_config_text("flow:\n  inlet: {flow: 9.3e-6}\n  outlets: {resistance: 2e6}\n",
                                            "plain.yaml", test::flow_schema());
  auto plain = make_solver(net, from_config(cfg, net));
  plain->advance(0.0);
  const int daughter = quasi->spec().junctions[0].branches[1].segment;
  EXPECT_GT(std::abs(plain->segment_flow(daughter) - quasi->segment_flow(daughter)), 1e-4 * 9.3e-6);
}

}  // namespace
}  // namespace flowire::flow
