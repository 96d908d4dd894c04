// The fem: section (coupling/src/config_fem.cpp): its keys and their checks at setup (the
// comparison itself is tested in tests/fem).
#include <gtest/gtest.h>

#include "scene_config_test.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {
namespace {

TEST(ConfigFem, DeclaresTheFemKeysOfTheScene) {
  test::expect_section_of_scene(test::declared_paths(declare_fem_keys), {"fem"});
}

TEST(ConfigFem, TheGeometryDecidesWhetherTheComparisonIsOnTheNetwork) {
  EXPECT_TRUE(fem_on_network(test::scene("")));
  EXPECT_TRUE(fem_on_network(test::scene("fem: {}\n")));
  EXPECT_TRUE(fem_on_network(test::scene("fem: {geometry: lumen}\n")));
  EXPECT_FALSE(fem_on_network(test::scene("fem: {geometry: dfg_3d_1z}\n")));
}

TEST(ConfigFem, BadFemValuesAreRejectedAtSetupNamingFileLineAndKey) {
  const auto frames = test::scene("fem:\n  geometry: dfg_3d_1z\n  frames: 3\n");
  EXPECT_NE(test::input_error([&] { check_fem(frames, nullptr, nullptr); }).find("scene.yaml:3: fem.frames"),
            std::string::npos);
  // A value out of its declared range is refused as the scene is read.
  EXPECT_NE(test::input_error([] {
              (void)test::scene("fem:\n  geometry: dfg_3d_1z\n  mesh_growth: 0\n");
            }).find("scene.yaml:3: fem.mesh_growth"),
            std::string::npos);
  check_fem(test::scene("fem: {geometry: dfg_3d_1z}\n"), nullptr, nullptr);  // the defaults are valid
  const auto no_flow = test::scene("fem: {}\n");
  EXPECT_NE(test::input_error([&] { check_fem(no_flow, nullptr, nullptr); }).find("needs a flow: section"),
            std::string::npos);
}

}  // namespace
}  // namespace flowire::coupling
