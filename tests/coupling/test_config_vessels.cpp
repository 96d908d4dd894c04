// The vessels: section (coupling/src/config_vessels.cpp): its keys, and the network they build.
#include <gtest/gtest.h>

#include "scene_config_test.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {
namespace {

TEST(ConfigVessels, DeclaresTheVesselKeysOfTheScene) {
  test::expect_section_of_scene(test::declared_paths(declare_vessel_keys), {"vessels"});
}

TEST(ConfigVessels, AGeneratorGivenInTheSceneBuildsThatNetwork) {
  const auto c = test::scene("vessels:\n  generator: {type: straight_tube, length: 50 mm, radius: 3 mm}\n");
  const vessels::Network net = build_scene_network(c);
  EXPECT_NEAR(net.counts().total_length, 0.05, 1e-12);
  EXPECT_NEAR(net.counts().radius_max, 3e-3, 1e-15);
  EXPECT_EQ(net.counts().ends, 2);
  // max_segment_length (5 mm declared): 50 mm in 10 cylinders.
  EXPECT_EQ(net.counts().segments, 10);
}

TEST(ConfigVessels, BadVesselsAreRejectedNamingFileLineAndKey) {
  EXPECT_NE(test::input_error([] {
              (void)test::scene("vessels:\n  generator:\n    type: straight_tube\n    radius: -2 mm\n");
            }).find("scene.yaml:4: vessels.generator.radius"),
            std::string::npos);
  const auto both = test::scene("vessels:\n  file: a.vtp\n  generator: {type: aortic_arch}\n");
  EXPECT_NE(test::input_error([&] {
              (void)build_scene_network(both);
            }).find("exactly one of vessels.file or vessels.generator"),
            std::string::npos);
}

}  // namespace
}  // namespace flowire::coupling
