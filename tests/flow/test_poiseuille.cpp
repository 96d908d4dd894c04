// Quasi-steady Poiseuille network flow against the analytic cases of the shared reference
// README (flow references 1–3), and the solvers against each other.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "flow_test_networks.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

using flowire::testing::tol;
using namespace flowire::flow::test;

const SolverKind kSolvers[] = {SolverKind::Superposition, SolverKind::Sparse, SolverKind::DenseInverse};

double rel(double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-300); }

// Reference 1: single tube L = 0.1 m, r = 2 mm, Δp = 100 Pa, η = 3.5e-3 Pa·s.
TEST(FlowPoiseuille, SingleTubeMatchesReference1) {
  const Network net = tube(0.1, 2e-3, 4);
  for (const auto kind : kSolvers) {
    FlowSpec spec = pressure_spec(net, 0, Waveform::constant(100.0), {{net.num_nodes() - 1, 0.0}});
    spec.solver = kind;
    auto s = make_solver(net, spec);
    s->advance(0.0);
    const double r_total = poiseuille_resistance(3.5e-3, 0.1, 2e-3);
    EXPECT_LT(rel(r_total, 5.57042e7), 1e-5);  // the README's rounded figure
    const double q = 100.0 / r_total;
    for (int seg = 0; seg < net.num_segments(); ++seg) {
      const auto st = s->segment_state(seg);
      EXPECT_LT(rel(st.flow_rate, q), tol(1e-12)) << to_string(kind);
      EXPECT_LT(rel(st.mean_velocity, q / (M_PI * 4e-6)), tol(1e-12));
      EXPECT_LT(rel(st.wall_shear_stress, 100.0 * 2e-3 / (2.0 * 0.1)), tol(1e-12));  // Δp·r/(2L) = 1 Pa
      EXPECT_NEAR(st.reynolds, 173.0, 0.5);
    }
    EXPECT_NEAR(q, 1.79520e-6, 1e-11);
    // Pressure linear along the tube.
    for (int i = 0; i < net.num_nodes(); ++i)
      EXPECT_NEAR(s->node_pressure(i), 100.0 * (1.0 - net.node(i).x() / 0.1), 1e-12 * 100.0);
    // Profile: mean 1/7, u_max 2/7, u(r/2) = 0.214286 m/s.
    const Vec3 mid = net.node(net.segment(1).node_from) + Vec3(0.0, 0.0, 0.0);
    EXPECT_LT(rel(s->axial_velocity_at(1, mid), q * 2.0 / (M_PI * 4e-6)), tol(1e-12));
    EXPECT_NEAR(s->axial_velocity_at(1, mid + Vec3(0.0, 1e-3, 0.0)), 0.214286, 1e-5);
    EXPECT_NEAR(s->velocity_at(1, mid + Vec3(0.0, 0.0, 1e-3)).x(), 0.214286, 1e-5);
    EXPECT_EQ(s->axial_velocity_at(1, mid + Vec3(0.0, 3e-3, 0.0)), 0.0);
  }
}

// Reference 2: Murray tree, 63 vessels, each generation's equivalent resistance R0.
TEST(FlowPoiseuille, MurrayTreeMatchesReference2) {
  const Network net = murray_tree(5);
  ASSERT_EQ(net.num_segments(), 63);
  std::vector<std::pair<int, double>> outlets;
  for (int e : net.ends())
    if (e != 0) outlets.emplace_back(e, 0.0);
  ASSERT_EQ(outlets.size(), 32u);
  for (const auto kind : kSolvers) {
    FlowSpec spec = pressure_spec(net, 0, Waveform::constant(1000.0), outlets);
    spec.solver = kind;
    auto s = make_solver(net, spec);
    s->advance(0.0);
    const double r0 = poiseuille_resistance(3.5e-3, 20e-3, 2e-3);
    EXPECT_LT(rel(r0, 1.11408e7), 1e-5);
    const double q0 = 1000.0 / (6.0 * r0);
    EXPECT_NEAR(q0, 1.4960e-5, 1e-9);
    for (int seg = 0; seg < net.num_segments(); ++seg) {
      const int gen = static_cast<int>(std::floor(std::log2(seg + 1)));
      EXPECT_LT(rel(s->segment_flow(seg), q0 / std::pow(2.0, gen)), tol(1e-12)) << "segment " << seg;
      // The pressure falls by 1000/6 per generation.
      const auto& sg = net.segment(seg);
      EXPECT_NEAR(s->node_pressure(sg.node_to), 1000.0 * (1.0 - (gen + 1) / 6.0), tol(1e-12) * 1000.0);
    }
  }
}

// Reference 3: Wheatstone loop with dimensionless resistances, and the affine time check.
TEST(FlowPoiseuille, WheatstoneLoopMatchesReference3) {
  const Network net = wheatstone();
  for (const auto kind : kSolvers) {
    FlowSpec spec = pressure_spec(net, kS, Waveform::constant(1.0), {{kT, 0.0}});
    spec.viscosity = kUnitViscosity;
    spec.solver = kind;
    auto s = make_solver(net, spec);
    s->advance(0.0);
    EXPECT_LT(rel(s->node_pressure(kA), 4.0 / 7.0), tol(1e-12));
    EXPECT_LT(rel(s->node_pressure(kB), 3.0 / 7.0), tol(1e-12));
    EXPECT_LT(rel(s->segment_flow(kAB), 1.0 / 7.0), tol(1e-12));
    EXPECT_LT(rel(s->segment_flow(0) + s->segment_flow(1), 5.0 / 7.0), tol(1e-12));
  }
  for (const auto kind : kSolvers) {
    // p_S(t) = 1 + 0.5 sin(2πt) is the sine with P1 = 1.5, P2 = 0.5, T = 1; p_T = 0.2.
    FlowSpec spec = pressure_spec(net, kS, Waveform::sine(1.5, 0.5, 1.0), {{kT, 0.2}});
    spec.viscosity = kUnitViscosity;
    spec.solver = kind;
    auto s = make_solver(net, spec);
    for (double t : {0.0, 0.1, 0.37, 0.5, 0.81, 2.3}) {
      s->advance(t);
      const double ps = 1.0 + 0.5 * std::sin(2.0 * M_PI * t);
      EXPECT_LT(rel(s->node_pressure(kS), ps), tol(1e-12));
      EXPECT_LT(rel(s->node_pressure(kA), 0.2 + (ps - 0.2) * 4.0 / 7.0), tol(1e-12)) << to_string(kind) << " t=" << t;
      EXPECT_LT(rel(s->node_pressure(kB), 0.2 + (ps - 0.2) * 3.0 / 7.0), tol(1e-12));
      EXPECT_LT(rel(s->segment_flow_at(kAB, t), (ps - 0.2) / 7.0), tol(1e-12));
    }
  }
}

TEST(FlowPoiseuille, MassIsConservedAtEveryNode) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Network net = random_network(300, 12, seed);
    FlowSpec spec = default_spec(net, Waveform::sine(120 * 133.322, 80 * 133.322, 0.8));
    // Mixed outlets: resistances on every other end.
    for (size_t i = 0; i < spec.outlets.size(); i += 2) {
      spec.outlets[i].type = OutletBC::Type::Resistance;
      spec.outlets[i].resistance = 1e9;
      spec.outlets[i].distal_pressure = 500.0;
    }
    for (const auto kind : kSolvers) {
      spec.solver = kind;
      auto s = make_solver(net, spec);
      s->advance(0.3);
      std::vector<double> q(static_cast<size_t>(net.num_segments()));
      std::vector<double> p(static_cast<size_t>(net.num_nodes()));
      s->segment_flows(q);
      s->node_pressures(p);
      const int inlet = spec.inlets[0].node;
      const auto [ib, ie] = net.node_segments(inlet);
      double inflow = 0.0;
      for (const int* it = ib; it != ie; ++it)
        inflow += net.segment(*it).node_from == inlet ? q[static_cast<size_t>(*it)] : -q[static_cast<size_t>(*it)];
      ASSERT_GT(inflow, 0.0);
      std::vector<char> is_outlet(static_cast<size_t>(net.num_nodes()), 0);
      for (const auto& o : spec.outlets) is_outlet[static_cast<size_t>(o.node)] = 1;
      double outflow = 0.0;
      for (int i = 0; i < net.num_nodes(); ++i) {
        double net_out = 0.0;
        const auto [b, e] = net.node_segments(i);
        for (const int* it = b; it != e; ++it)
          net_out += net.segment(*it).node_from == i ? q[static_cast<size_t>(*it)] : -q[static_cast<size_t>(*it)];
        if (i == inlet) continue;
        if (is_outlet[static_cast<size_t>(i)]) {
          outflow -= net_out;
          continue;
        }
        EXPECT_LT(std::abs(net_out), tol(1e-12) * inflow) << "node " << i << " " << to_string(kind);
      }
      EXPECT_LT(std::abs(outflow - inflow), tol(1e-12) * inflow);
    }
  }
}

TEST(FlowPoiseuille, SolversAgreeOnRandomNetworksWithLoops) {
  for (unsigned seed : {11u, 12u, 13u, 14u}) {
    const Network net = random_network(250, 20, seed);
    ASSERT_GT(net.counts().loops, 5);
    FlowSpec spec = default_spec(net, Waveform::sine(16000.0, 10600.0, 0.8));
    // A second, independent inlet with a flow table and a resistance outlet.
    InletBC q;
    q.node = spec.outlets.back().node;
    q.type = InletBC::Type::Flow;
    q.waveform = Waveform::table({0.0, 0.2, 0.8}, {1e-6, 3e-6, 1e-6});
    spec.outlets.pop_back();
    spec.inlets.push_back(q);
    spec.outlets.front().type = OutletBC::Type::Resistance;
    spec.outlets.front().resistance = 3e8;
    std::vector<std::unique_ptr<FlowSolver>> solvers;
    for (const auto kind : kSolvers) {
      spec.solver = kind;
      solvers.push_back(make_solver(net, spec));
    }
    for (double t : {0.0, 0.13, 0.55}) {
      std::vector<std::vector<double>> p(3, std::vector<double>(static_cast<size_t>(net.num_nodes())));
      std::vector<std::vector<double>> qq(3, std::vector<double>(static_cast<size_t>(net.num_segments())));
      for (size_t k = 0; k < 3; ++k) solvers[k]->solve_at(t, p[k], qq[k]);
      double pmax = 0.0, qmax = 0.0;
      for (double v : p[0]) pmax = std::max(pmax, std::abs(v));
      for (double v : qq[0]) qmax = std::max(qmax, std::abs(v));
      for (size_t k = 1; k < 3; ++k) {
        for (size_t i = 0; i < p[0].size(); ++i) EXPECT_NEAR(p[k][i], p[0][i], tol(1e-11) * pmax);
        for (size_t i = 0; i < qq[0].size(); ++i) EXPECT_NEAR(qq[k][i], qq[0][i], tol(1e-10) * qmax);
      }
      // Superposition's lazy per-segment answer at any t equals the full frame.
      for (int seg = 0; seg < net.num_segments(); seg += 7)
        EXPECT_NEAR(solvers[0]->segment_flow_at(seg, t), qq[1][static_cast<size_t>(seg)], tol(1e-10) * qmax);
    }
  }
}

TEST(FlowPoiseuille, DisconnectedPieceIsAClearError) {
  // Two tubes that do not touch; only the first has boundary conditions.
  std::vector<Vec3> nodes = {Vec3(0, 0, 0), Vec3(0.01, 0, 0), Vec3(0.02, 0, 0),
                             Vec3(0, 1, 0), Vec3(0.01, 1, 0), Vec3(0.02, 1, 0)};
  std::vector<vessels::Segment> segs = {
      {0, 1, 1e-3, 0.0, -1}, {1, 2, 1e-3, 0.0, -1}, {3, 4, 1e-3, 0.0, -1}, {4, 5, 1e-3, 0.0, -1}};
  const Network net = Network::from_graph(nodes, segs);
  for (const auto kind : kSolvers) {
    FlowSpec spec = pressure_spec(net, 0, Waveform::constant(100.0), {{2, 0.0}});
    spec.solver = kind;
    try {
      (void)make_solver(net, spec);
      FAIL() << "expected an error";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Numerical);
      EXPECT_NE(std::string(e.what()).find("no pressure reference"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("nodes 3, 4, 5"), std::string::npos) << e.what();
    }
  }
}

TEST(FlowPoiseuille, FlowInletAndResistanceOutlet) {
  const Network net = tube(0.1, 2e-3, 3);
  FlowSpec spec;
  InletBC in;
  in.node = 0;
  in.type = InletBC::Type::Flow;
  in.waveform = Waveform::constant(1e-6);
  spec.inlets.push_back(in);
  OutletBC out;
  out.node = net.num_nodes() - 1;
  out.type = OutletBC::Type::Resistance;
  out.resistance = 1e8;
  spec.outlets.push_back(out);
  for (const auto kind : kSolvers) {
    spec.solver = kind;
    auto s = make_solver(net, spec);
    EXPECT_NEAR(s->node_pressure(out.node), 1e-6 * 1e8, 1e-9);  // p_out = Q·R_out
    EXPECT_NEAR(s->segment_flow(0), 1e-6, 1e-18);
  }
}

TEST(FlowPoiseuille, PieceDrivenOnlyByFlowIsSingular) {
  std::vector<Vec3> nodes = {Vec3(0, 0, 0), Vec3(0.01, 0, 0), Vec3(0, 1, 0), Vec3(0.01, 1, 0)};
  std::vector<vessels::Segment> segs = {{0, 1, 1e-3, 0.0, -1}, {2, 3, 1e-3, 0.0, -1}};
  const Network net = Network::from_graph(nodes, segs);
  FlowSpec spec = pressure_spec(net, 0, Waveform::constant(100.0), {{1, 0.0}});
  InletBC q;
  q.node = 2;
  q.type = InletBC::Type::Flow;
  q.waveform = Waveform::constant(1e-6);
  spec.inlets.push_back(q);
  for (const auto kind : kSolvers) {
    spec.solver = kind;
    try {
      (void)make_solver(net, spec);
      FAIL() << "expected an error";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Numerical);
      EXPECT_NE(std::string(e.what()).find("nodes 2, 3"), std::string::npos) << e.what();
    }
  }
}

TEST(FlowPoiseuille, DenseInverseRefusesLargeNetworks) {
  const Network net = tube(0.1, 2e-3, 40);
  FlowSpec spec = pressure_spec(net, 0, Waveform::constant(100.0), {{net.num_nodes() - 1, 0.0}});
  spec.solver = SolverKind::DenseInverse;
  spec.dense_memory_limit = 1000.0;  // bytes
  try {
    (void)make_solver(net, spec);
    FAIL() << "expected a refusal";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("superposition"), std::string::npos) << e.what();
  }
}

TEST(FlowPoiseuille, SeveralInletsAndOutletKinds) {
  // Y: two pressure inlets feeding one outlet through a resistance.
  std::vector<Vec3> nodes = {Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(1, 0.5, 0), Vec3(2, 0.5, 0)};
  std::vector<vessels::Segment> segs = {{0, 2, 1.0, 1.0, -1}, {1, 2, 1.0, 2.0, -1}, {2, 3, 1.0, 1.0, -1}};
  const Network net = Network::from_graph(nodes, segs);
  FlowSpec spec;
  spec.viscosity = kUnitViscosity;  // R = l
  InletBC a, b;
  a.node = 0;
  a.waveform = Waveform::constant(3.0);
  b.node = 1;
  b.waveform = Waveform::constant(2.0);
  spec.inlets = {a, b};
  OutletBC o;
  o.node = 3;
  o.type = OutletBC::Type::Resistance;
  o.resistance = 1.0;
  o.distal_pressure = 0.5;
  spec.outlets = {o};
  for (const auto kind : kSolvers) {
    spec.solver = kind;
    auto s = make_solver(net, spec);
    // Node 2 at p, node 3 at p3: (3-p)/1 + (2-p)/2 = (p-p3)/1 = (p3-0.5)/1 → p3 = (p+0.5)/2.
    // 3 - p + 1 - p/2 = (p - 0.5)/2 → 4.25 = 2p → p = 2.125.
    EXPECT_NEAR(s->node_pressure(2), 2.125, 1e-12);
    EXPECT_NEAR(s->node_pressure(3), 1.3125, 1e-12);
  }
}

TEST(FlowPoiseuille, RcrOutletUsesTotalResistanceWithAWarning) {
  const Network net = tube(0.1, 2e-3, 2);
  FlowSpec spec = pressure_spec(net, 0, Waveform::constant(1000.0), {});
  OutletBC o;
  o.node = net.num_nodes() - 1;
  o.type = OutletBC::Type::Rcr;
  o.rp = 1e7;
  o.c = 1e-9;
  o.rd = 9e7;
  o.distal_pressure = 100.0;
  spec.outlets = {o};
  flowire::testing::ExpectWarnings w;
  auto s = make_solver(net, spec);
  EXPECT_TRUE(w.contains("Rp + Rd"));
  const double r = poiseuille_resistance(3.5e-3, 0.1, 2e-3);
  EXPECT_LT(rel(s->segment_flow(0), 900.0 / (r + 1e8)), 1e-12);
}

}  // namespace
}  // namespace flowire::flow
