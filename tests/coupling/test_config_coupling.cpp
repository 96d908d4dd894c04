// The obstacles: and coupling: sections (coupling/src/config_coupling.cpp): their keys, the
// blood drag, the tip forces and the wire–flow coupling they set, from the scene or, where it
// has no coupling:, from the declared defaults.
#include <gtest/gtest.h>

#include <numbers>

#include "flowire/coupling/tip_forces.hpp"
#include "flowire/vessels/spatial.hpp"
#include "scene_config_test.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {
namespace {

const char* const kTube = "vessels:\n  generator: {type: straight_tube, length: 50 mm, radius: 3 mm}\n";

TEST(ConfigCoupling, DeclaresTheObstacleAndCouplingKeysOfTheScene) {
  test::expect_section_of_scene(test::declared_paths(declare_obstacle_keys), {"obstacles"});
  test::expect_section_of_scene(test::declared_paths(declare_coupling_keys), {"coupling"});
}

TEST(ConfigCoupling, TheDragIsTheSceneOrTheDeclaredOneAndNoneWithoutFlow) {
  const auto given = test::scene("wire: {}\nflow: {viscosity: 4 cP}\ncoupling: {drag: slender_body, drag_scale: 2}\n");
  const rod::WireSpec w = scene_wire_spec(given);
  const DragModel d = drag_model(given, w, true);
  EXPECT_EQ(d.law, DragLaw::SlenderBody);
  EXPECT_DOUBLE_EQ(d.scale, 2.0);
  EXPECT_DOUBLE_EQ(d.viscosity, 4e-3);
  EXPECT_DOUBLE_EQ(d.wire_radius, w.radius);
  EXPECT_DOUBLE_EQ(d.mass_per_length, w.density * std::numbers::pi * w.radius * w.radius);
  EXPECT_EQ(drag_model(given, w, false).law, DragLaw::None);
  // No coupling: the declared cylinder drag at scale 1, with the flow's declared blood.
  const auto absent = test::scene("wire: {}\nflow: {}\n");
  const DragModel a = drag_model(absent, w, true);
  EXPECT_EQ(a.law, DragLaw::Cylinder);
  EXPECT_DOUBLE_EQ(a.scale, 1.0);
  EXPECT_DOUBLE_EQ(a.viscosity, 3.5e-3);
  EXPECT_DOUBLE_EQ(a.density, 1060.0);
  // Once a step by default; every iterate when the scene asks.
  EXPECT_TRUE(a.once_per_step);
  EXPECT_FALSE(
      drag_model(test::scene("wire: {}\nflow: {}\ncoupling: {drag_update: iterate}\n"), w, true).once_per_step);
}

TEST(ConfigCoupling, OcclusionAndFlowEveryFollowTheScene) {
  const CouplingSettings absent = coupling_settings(test::scene(""));
  EXPECT_TRUE(absent.occlusion);
  EXPECT_FALSE(absent.occlusion_given);
  EXPECT_EQ(absent.flow_every, 1);
  const CouplingSettings given = coupling_settings(test::scene("coupling: {occlusion: none, flow_every: 5}\n"));
  EXPECT_FALSE(given.occlusion);
  EXPECT_TRUE(given.occlusion_given);
  EXPECT_EQ(given.flow_every, 5);
  // At least every step: 0 is refused where it is written, not quietly taken as 1.
  const std::string e = test::input_error([] { (void)test::scene("coupling:\n  flow_every: 0\n"); });
  EXPECT_NE(e.find("scene.yaml:2: coupling.flow_every = 0"), std::string::npos) << e;
}

TEST(ConfigCoupling, WallForcesAreNullOnlyWithoutContactAndDrag) {
  const auto c = test::scene(std::string(kTube) + "wire: {}\n");
  const vessels::Network net = build_scene_network(c);
  const vessels::SpatialIndex index(net, 4);
  const rod::WireSpec w = scene_wire_spec(c);
  EXPECT_NE(make_vessel_forces(c, index, w, nullptr), nullptr);  // contact by default
  const auto off = test::scene(std::string(kTube) + "wire: {}\ncontact: {enabled: false}\n");
  EXPECT_EQ(make_vessel_forces(off, index, w, nullptr), nullptr);
}

TEST(ConfigCoupling, BadObstaclesAndSteeringAreRejectedNamingFileLineAndKey) {
  const auto c = test::scene(std::string(kTube) + "obstacles:\n  - {center: [0, 0, 0], force: 1 mN}\n");
  const vessels::Network net = build_scene_network(c);
  // The item has no line of its own: the file and the item are named.
  const std::string missing = test::input_error([&] { (void)make_tip_forces(c, &net); });
  EXPECT_NE(missing.find("scene.yaml: obstacles[0]"), std::string::npos) << missing;
  EXPECT_NE(missing.find("an obstacle needs radius"), std::string::npos) << missing;
  const auto ok = test::scene(std::string(kTube) + "obstacles:\n  - {center: [0, 0, 0], radius: 2 mm, force: 1 mN}\n");
  EXPECT_NE(make_tip_forces(ok, &net), nullptr);
  EXPECT_EQ(make_tip_forces(test::scene(kTube), &net), nullptr);
  const auto steer = test::scene(std::string(kTube) + "coupling:\n  steering:\n    branch: nowhere\n");
  const std::string e = test::input_error([&] { (void)make_tip_forces(steer, &net); });
  EXPECT_NE(e.find("scene.yaml:5: coupling.steering.branch"), std::string::npos) << e;
  EXPECT_NE(e.find("no branch 'nowhere'"), std::string::npos) << e;
}

}  // namespace
}  // namespace flowire::coupling
