// The catheter: section (coupling/src/config_catheter.cpp): its keys and the catheter they
// describe, checked against the wire in its lumen.
#include <gtest/gtest.h>

#include "scene_config_test.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {
namespace {

TEST(ConfigCatheter, DeclaresTheCatheterKeysOfTheScene) {
  test::expect_section_of_scene(test::declared_paths(declare_catheter_keys), {"catheter"});
}

TEST(ConfigCatheter, ValuesGivenInTheSceneAreRead) {
  const auto c = test::scene(
      "wire: {radius: 0.3 mm}\ncatheter: {outer_radius: 1.2 mm, inner_radius: 0.7 mm, "
      "insertion: {speed: 1 cm/s}}\n");
  const CatheterSpec k = scene_catheter_spec(c, scene_wire_spec(c));
  EXPECT_DOUBLE_EQ(k.outer_radius, 1.2e-3);
  EXPECT_DOUBLE_EQ(k.inner_radius, 0.7e-3);
  EXPECT_DOUBLE_EQ(k.speed, 0.01);
  EXPECT_DOUBLE_EQ(k.initial_length, 0.02);  // declared
}

TEST(ConfigCatheter, ALumenNarrowerThanTheWireIsRejectedNamingFileLineAndKey) {
  const auto c = test::scene("wire: {radius: 0.5 mm}\ncatheter:\n  inner_radius: 0.4 mm\n");
  const std::string e = test::input_error([&] { (void)scene_catheter_spec(c, scene_wire_spec(c)); });
  EXPECT_NE(e.find("scene.yaml:3: catheter.inner_radius"), std::string::npos) << e;
  const auto thin = test::scene("wire: {}\ncatheter:\n  outer_radius: 0.5 mm\n");
  EXPECT_NE(test::input_error([&] {
              (void)scene_catheter_spec(thin, scene_wire_spec(thin));
            }).find("scene.yaml:3: catheter.outer_radius"),
            std::string::npos);
}

}  // namespace
}  // namespace flowire::coupling
