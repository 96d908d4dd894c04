// FlowSpec from a validated scene (keys as flow::declare_scene_keys declares them for the scene).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>

#include "flow_test_networks.hpp"
#include "flowire/common/config.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/flow/spec.hpp"
#include "flowire/vessels/generators.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

using test::flow_schema;

/// Each scene (flow section text) refused as bad input whose message contains its fragment.
void expect_refused(const Network& net, const std::vector<std::pair<std::string, std::string>>& cases) {
  for (const auto& [scene, message] : cases) {
    try {
      (void)from_config(config::load_config_text(scene, "s.yaml", flow_schema()), net);
      ADD_FAILURE() << "accepted: " << scene;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

TEST(FlowSpec, TheFlowDeclaresOnlyFlowKeysEachWithADoc) {
  const auto s = flow_schema();
  ASSERT_GT(s.keys().size(), 30u);
  EXPECT_EQ(s.keys().front().path, "flow");
  for (const auto& k : s.keys()) {
    EXPECT_EQ(k.path.rfind("flow", 0), 0u) << k.path;
    EXPECT_FALSE(k.doc.empty()) << k.path;
  }
}

TEST(FlowSpec, ABadViscosityIsRejectedNamingFileLineAndKey) {
  const Network net = test::murray_tree(1);
  EXPECT_EQ(from_config(config::load_config_text("flow:\n  viscosity: 4 cP\n", "s.yaml", flow_schema()), net).viscosity,
            4e-3);
  try {
    // Refused as the scene is read: the declared range of flow.viscosity.
    (void)from_config(
        config::load_config_text("flow:\n  model: rlc\n  viscosity: -1 cP\n", "scene.yaml", flow_schema()), net);
    FAIL() << "a negative viscosity was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("scene.yaml:3: flow.viscosity"), std::string::npos) << e.what();
  }
}

TEST(FlowSpec, SineInletAndResistanceOutletsFromAScene) {
  const Network net = test::murray_tree(2);
  const auto cfg = config::load_config_text(R"(
flow:
  solver: sparse
  viscosity: 4 cP
  inlet:
    pressure: {waveform: sine, systolic: 120 mmHg, diastolic: 80 mmHg, period: 0.75 s}
  outlets:
    resistance: 1.2 mmHg*s/mL
    distal_pressure: 5 mmHg
)",
                                            "scene.yaml", flow_schema());
  const FlowSpec s = from_config(cfg, net);
  EXPECT_EQ(s.solver, SolverKind::Sparse);
  EXPECT_DOUBLE_EQ(s.viscosity, 4e-3);
  ASSERT_EQ(s.inlets.size(), 1u);
  EXPECT_EQ(s.inlets[0].node, net.widest_end());
  EXPECT_EQ(s.inlets[0].waveform.kind, Waveform::Kind::Sine);
  EXPECT_NEAR(s.inlets[0].waveform(0.75 / 4), 120 * units::mmHg, 1e-9);
  EXPECT_NEAR(s.inlets[0].waveform.mean(), 100 * units::mmHg, 1e-9);
  EXPECT_DOUBLE_EQ(s.cycle(), 0.75);
  ASSERT_EQ(s.outlets.size(), 4u);
  for (const auto& o : s.outlets) {
    EXPECT_EQ(o.type, OutletBC::Type::Resistance);
    EXPECT_NEAR(o.resistance, 1.2 * units::mmHg * 1e6, 1.0);
    EXPECT_NEAR(o.distal_pressure, 5 * units::mmHg, 1e-9);
  }
}

TEST(FlowSpec, ConstantTableFlowAndMurrayScaledRcr) {
  const Network net = test::murray_tree(1);
  const auto dir = flowire::testing::scratch_dir("flow_spec");
  std::ofstream(dir / "q.csv") << "time,flow\n0,1e-6\n0.5,3e-6\n1.0,1e-6\n";
  auto cfg = config::load_config_text(R"(
flow:
  inlet: {flow: {file: q.csv}}
  outlets:
    scaling: murray
    rcr: {Rp: 1e8, C: 1e-9, Rd: 1e9}
)",
                                      (dir / "scene.yaml").string(), flow_schema());
  cfg.set_file((dir / "scene.yaml").string());
  const FlowSpec s = from_config(cfg, net);
  EXPECT_EQ(s.inlets[0].type, InletBC::Type::Flow);
  EXPECT_EQ(s.inlets[0].waveform.kind, Waveform::Kind::Table);
  EXPECT_NEAR(s.inlets[0].waveform(0.25), 2e-6, 1e-18);
  EXPECT_NEAR(s.inlets[0].waveform(1.25), 2e-6, 1e-18);  // periodic
  ASSERT_EQ(s.outlets.size(), 2u);
  // Two equal daughters: each gets twice the total (parallel) values, half the compliance.
  for (const auto& o : s.outlets) {
    EXPECT_NEAR(o.rp, 2e8, 1e-3);
    EXPECT_NEAR(o.rd, 2e9, 1e-2);
    EXPECT_NEAR(o.c, 0.5e-9, 1e-21);
  }
  const auto cfg2 = config::load_config_text("flow:\n  inlet: {pressure: 13000, node: 5}\n", "s.yaml", flow_schema());
  try {
    (void)from_config(cfg2, net);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("node 5"), std::string::npos) << e.what();
  }
}

TEST(FlowSpec, ASineTakesOnlyTheDefaultsTheSchemaDeclares) {
  const Network net = test::murray_tree(1);
  // Nothing given: the declared default inlet, the 120/80 mmHg sine of 0.8 s.
  const auto s = from_config(config::load_config_text("flow: {}\n", "s.yaml", flow_schema()), net);
  ASSERT_EQ(s.inlets.size(), 1u);
  EXPECT_EQ(s.inlets[0].type, InletBC::Type::Pressure);
  EXPECT_NEAR(s.inlets[0].waveform(0.2), 120 * units::mmHg, 1e-9);
  EXPECT_NEAR(s.inlets[0].waveform(0.6), 80 * units::mmHg, 1e-9);
  // A flow sine has no default amplitude.
  const auto cfg = config::load_config_text("flow:\n  inlet:\n    flow: {waveform: sine, diastolic: 1e-6}\n", "s.yaml",
                                            flow_schema());
  try {
    (void)from_config(cfg, net);
    FAIL() << "a flow sine without systolic was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("s.yaml:3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("flow.inlet.flow.systolic"), std::string::npos) << e.what();
  }
}

TEST(FlowSpec, EachOutletItsOwnByBranchNameOrNodeTheRestByDefault) {
  // The arch's six ends: the root is the inlet; the left subclavian gets its own windkessel,
  // the right iliac a pressure, the left iliac's end (by node id) a resistance; the rest
  // (brachiocephalic, left carotid) share the default resistance split by Murray's law over
  // them alone: in parallel they are the default's total.
  const Network net = Network::build(vessels::aortic_arch(), {.max_segment_length = 5e-3});
  int left_iliac_end = -1;
  for (const auto& b : net.branches())
    if (b.name == "left_iliac_femoral")
      left_iliac_end = net.degree(b.nodes.back()) == 1 ? b.nodes.back() : b.nodes.front();
  ASSERT_GE(left_iliac_end, 0);
  const std::string text = fmt::format(R"(
flow:
  outlets:
    resistance: 1 mmHg*s/mL
    scaling: murray
    left_subclavian: {{rcr: {{Rp: 1e7, C: 2e-9, Rd: 1.5e8, Pd: 5 mmHg}}}}
    right_iliac_femoral: {{pressure: 10 mmHg}}
    "{}": {{resistance: 3e8, distal_pressure: 2 mmHg}}
)",
                                       left_iliac_end);
  const FlowSpec s = from_config(config::load_config_text(text, "s.yaml", flow_schema()), net);
  ASSERT_EQ(s.outlets.size(), 5u);
  const double mmHg = 133.322387415;
  double parallel = 0.0;
  int named = 0;
  for (const auto& o : s.outlets) {
    if (o.defaulted) {
      EXPECT_EQ(o.type, OutletBC::Type::Resistance);
      parallel += 1.0 / o.resistance;
      continue;
    }
    ++named;
    if (o.type == OutletBC::Type::Rcr) {
      EXPECT_DOUBLE_EQ(o.rp, 1e7);
      EXPECT_DOUBLE_EQ(o.c, 2e-9);
      EXPECT_DOUBLE_EQ(o.rd, 1.5e8);
      EXPECT_NEAR(o.distal_pressure, 5 * mmHg, 1e-9);
    } else if (o.type == OutletBC::Type::Pressure) {
      EXPECT_NEAR(o.pressure.value, 10 * mmHg, 1e-9);
    } else {
      EXPECT_EQ(o.node, left_iliac_end);
      EXPECT_DOUBLE_EQ(o.resistance, 3e8);
      EXPECT_NEAR(o.distal_pressure, 2 * mmHg, 1e-9);
    }
  }
  EXPECT_EQ(named, 3);
  EXPECT_NEAR(1.0 / parallel, mmHg * 1e6, 1e-6 * mmHg * 1e6);

  // Bad outlets: one line naming the file, the line and the key.
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"flow:\n  outlets:\n    nowhere: {pressure: 0}\n", "s.yaml:3: flow.outlets.nowhere: no branch named 'nowhere'"},
      {"flow:\n  outlets:\n    ascending_aorta: {pressure: 0}\n", "branch 'ascending_aorta' has no outlet"},
      {"flow:\n  outlets:\n    left_subclavian: {pressure: 0, resistance: 1e8}\n",
       "flow.outlets.left_subclavian: give one of pressure, resistance, rcr, coronary or flow"},
      {"flow:\n  outlets:\n    left_subclavian: {rcr: {Rp: -1, C: 1e-9, Rd: 1e8}}\n",
       "flow.outlets.left_subclavian.rcr.Rp"},
      {"flow:\n  outlets:\n    left_subclavian: {colour: red}\n", "unknown key 'flow.outlets.*.colour'"},
  };
  expect_refused(net, bad);
}

TEST(FlowSpec, SeveralInletsFeedOneOutletAsTheResistorNetworkDoes) {
  // A parent and two daughters, fed at both daughters' ends (1000 and 600 Pa) and drained at
  // the parent's (0 Pa): the junction's pressure is the conductance-weighted mean of the
  // three ends, exactly, and the flows follow.
  const Network net = test::murray_tree(1);
  const auto cfg = config::load_config_text(R"(
flow:
  inlets:
    - {node: 2, pressure: 1000}
    - {node: 3, pressure: {waveform: constant, value: 600}}
)",
                                            "s.yaml", flow_schema());
  const FlowSpec spec = from_config(cfg, net);
  ASSERT_EQ(spec.inlets.size(), 2u);
  ASSERT_EQ(spec.outlets.size(), 1u);
  EXPECT_EQ(spec.outlets[0].node, 0);
  auto solver = make_solver(net, spec);
  solver->advance(0.0);
  double g[3], p[3] = {0.0, 1000.0, 600.0};
  for (int i = 0; i < 3; ++i) {
    const auto& seg = net.segment(i);
    g[i] = 1.0 / poiseuille_resistance(spec.viscosity, seg.length, seg.radius);
  }
  const double pj = (g[0] * p[0] + g[1] * p[1] + g[2] * p[2]) / (g[0] + g[1] + g[2]);
  EXPECT_NEAR(solver->node_pressure(1), pj, 1e-10 * pj);
  EXPECT_NEAR(std::abs(solver->segment_flow(0)), g[0] * pj, 1e-10 * g[0] * pj);

  const std::vector<std::pair<std::string, std::string>> bad = {
      {"flow:\n  inlet: {node: 2}\n  inlets:\n    - {node: 3, pressure: 1}\n",
       "give flow.inlet (one inlet) or flow.inlets"},
      {"flow:\n  inlets:\n    - {pressure: 1}\n", "flow.inlets[0]: an inlet needs its node"},
      {"flow:\n  inlets:\n    - {node: 2, pressure: 1, flow: 1e-6}\n", "flow.inlets[0]: give its pressure or its flow"},
      {"flow:\n  inlets:\n    - {node: 1, pressure: 1}\n", "flow.inlets[0]: node 1 is not a network end"},
      {"flow:\n  inlets:\n    - {node: 2, pressure: 1}\n    - {node: 2, flow: 1e-6}\n", "node 2 is already an inlet"},
      {"flow:\n  inlets:\n    - {node: 2, pressure: {waveform: sine, systolic: 2}}\n", "a sine waveform needs"},
  };
  expect_refused(net, bad);
}

}  // namespace
}  // namespace flowire::flow
