// The wire: and loads: sections (coupling/src/config_wire.cpp): their keys, the wire they
// describe, its entry into the network, and the loads on it.
#include <gtest/gtest.h>

#include "flowire/rod/simulator.hpp"
#include "scene_config_test.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {
namespace {

const char* const kTube = "vessels:\n  generator: {type: straight_tube, length: 50 mm, radius: 3 mm}\n";

TEST(ConfigWire, DeclaresTheWireAndLoadKeysOfTheScene) {
  test::expect_section_of_scene(test::declared_paths(declare_wire_keys), {"wire"});
  test::expect_section_of_scene(test::declared_paths(declare_load_keys), {"loads"});
}

TEST(ConfigWire, ValuesGivenInTheSceneAreRead) {
  const rod::WireSpec w = scene_wire_spec(
      test::scene("wire:\n  length: 0.5\n  radius: 0.2 mm\n  segment_length: 5 mm\n  tip: {shape: j, length: 2 cm}\n"
                  "insertion: {initial_length: 3 cm}\n"));
  EXPECT_DOUBLE_EQ(w.length, 0.5);
  EXPECT_DOUBLE_EQ(w.radius, 0.2e-3);
  EXPECT_EQ(w.segments, 0);
  EXPECT_DOUBLE_EQ(w.segment_length, 5e-3);
  EXPECT_EQ(w.tip.shape, rod::TipShape::J);
  EXPECT_DOUBLE_EQ(w.tip.length, 0.02);
  EXPECT_DOUBLE_EQ(w.inserted_length, 0.03);
  EXPECT_DOUBLE_EQ(w.youngs_modulus, 60e9);  // declared
}

TEST(ConfigWire, BadWireValuesAreRejectedNamingFileLineAndKey) {
  // Out of their declared ranges: refused as the scene is read.
  EXPECT_NE(test::input_error([] {
              (void)test::scene("wire:\n  adapt:\n    split_angle: 2 rad\n");
            }).find("scene.yaml:3: wire.adapt.split_angle"),
            std::string::npos);
  EXPECT_NE(test::input_error([] { (void)test::scene("wire:\n  radius: 0\n"); }).find("must be positive"),
            std::string::npos);
  // Relative to another value: refused by the reader.
  const auto merge = test::scene("wire:\n  adapt:\n    split_angle: 0.2 rad\n    merge_angle: 0.15 rad\n");
  EXPECT_NE(test::input_error([&] { (void)scene_wire_spec(merge); }).find("scene.yaml:4: wire.adapt.merge_angle"),
            std::string::npos);
}

TEST(ConfigWire, TheWireEntersAtTheFarthestEndOrTheNodeGiven) {
  const auto c = test::scene(std::string(kTube) + "wire: {}\n");
  const vessels::Network net = build_scene_network(c);
  rod::WireSpec w = scene_wire_spec(c);
  const int entry = enter_network(c, net, w);
  EXPECT_EQ(entry, net.farthest_end(net.widest_end()));
  EXPECT_TRUE(w.base_position.isApprox(net.node(entry)));
  EXPECT_NEAR(w.base_direction.norm(), 1.0, 1e-12);
  // Without insertion: the declared insertion.initial_length (2 cm).
  EXPECT_DOUBLE_EQ(w.inserted_length, 0.02);

  const auto bad = test::scene(std::string(kTube) + "wire:\n  entry: 3\n");
  rod::WireSpec wb = scene_wire_spec(bad);
  EXPECT_NE(test::input_error([&] { (void)enter_network(bad, net, wb); }).find("scene.yaml:4: wire.entry"),
            std::string::npos);
}

TEST(ConfigWire, TheWireEntersAtTheEndOfABranchNamed) {
  // By branch name, as an outlet is named: the end of the left subclavian artery of the arch.
  const std::string arch = "vessels:\n  generator: {type: aortic_arch}\n";
  const auto c = test::scene(arch + "wire: {entry: left_subclavian}\n");
  const vessels::Network net = build_scene_network(c);
  int end = -1;
  for (const auto& b : net.branches())
    if (b.name == "left_subclavian") end = net.degree(b.nodes.back()) == 1 ? b.nodes.back() : b.nodes.front();
  ASSERT_GE(end, 0);
  rod::WireSpec w = scene_wire_spec(c);
  EXPECT_EQ(enter_network(c, net, w), end);
  EXPECT_TRUE(w.base_position.isApprox(net.node(end)));
  // A name the network does not have: the branches with an end are listed.
  const auto bad = test::scene(arch + "wire: {entry: left_renal}\n");
  rod::WireSpec wb = scene_wire_spec(bad);
  const std::string msg = test::input_error([&] { (void)enter_network(bad, net, wb); });
  EXPECT_NE(msg.find("wire.entry: 'left_renal' is neither auto, a node id nor a branch with an end"), std::string::npos)
      << msg;
  EXPECT_NE(msg.find("left_subclavian"), std::string::npos) << msg;
}

TEST(ConfigWire, ALoadWithoutItsValueOrArcLengthIsRejectedNamingFileLineAndKey) {
  const auto c = test::scene("wire: {}\nloads:\n  - {type: point_force, value: [0, 0, 1e-3]}\n");
  rod::RodSimulator sim(scene_wire_spec(c));
  EXPECT_NE(test::input_error([&] { apply_loads(c, sim, nullptr); }).find("scene.yaml:3: loads[0].type"),
            std::string::npos);
  const auto ok = test::scene("wire: {}\nloads:\n  - {type: point_force, value: [0, 0, 1e-3], s: 0.5}\n");
  apply_loads(ok, sim, nullptr);
  // Beyond the wire's end (wire.length 1 m, declared) a point force would act nowhere.
  const auto beyond = test::scene("wire: {}\nloads:\n  - {type: point_force, value: [0, 0, 1e-3], s: 1.5}\n");
  EXPECT_NE(test::input_error([&] { apply_loads(beyond, sim, nullptr); }).find("scene.yaml:3: loads[0].s"),
            std::string::npos);
}

}  // namespace
}  // namespace flowire::coupling
