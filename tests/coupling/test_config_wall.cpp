// The wall: section (coupling/src/config_wall.cpp): its keys, the wall they build, and each
// refusal naming the key or the vessels at fault.
#include <gtest/gtest.h>

#include "flowire/coupling/deformable_wall.hpp"
#include "flowire/vessels/generators.hpp"
#include "flowire/vessels/network.hpp"
#include "scene_config_test.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {
namespace {

vessels::Network tube() {
  return vessels::Network::build(vessels::straight_tube({.length = 0.03, .radius = 3e-3}),
                                 {.max_segment_length = 5e-3});
}

TEST(ConfigWall, DeclaresTheWallKeysOfTheScene) {
  test::expect_section_of_scene(test::declared_paths(declare_wall_keys), {"wall"});
}

TEST(ConfigWall, NoSectionNoWall) {
  nlohmann::json facts;
  EXPECT_EQ(make_scene_wall(test::scene("wire: {}\n"), tube(), facts), nullptr);
  EXPECT_FALSE(facts.contains("wall"));
}

TEST(ConfigWall, TheWallOfAStraightVesselIsBuiltWithItsThicknessFromTheRadius) {
  nlohmann::json facts;
  const auto c = test::scene("wall:\n  thickness_ratio: 0.2\n  youngs_modulus: 2 MPa\n  mesh_size: 2 mm\n");
  const auto wall = make_scene_wall(c, tube(), facts);
  ASSERT_NE(wall, nullptr);
  EXPECT_NEAR(facts["wall"]["thickness"].get<double>(), 0.2 * 3e-3, 1e-15);
  EXPECT_DOUBLE_EQ(facts["wall"]["youngs_modulus"].get<double>(), 2e6);
  EXPECT_DOUBLE_EQ(facts["wall"]["poisson_ratio"].get<double>(), 0.45);
  EXPECT_GT(facts["wall"]["tets"].get<int>(), 0);
  const auto* deformable = dynamic_cast<const DeformableWall*>(wall.get());
  ASSERT_NE(deformable, nullptr);
  EXPECT_EQ(deformable->mesh().num_nodes(), facts["wall"]["nodes"].get<int>());
}

TEST(ConfigWall, RefusesWhatItCannotBuildNamingTheKey) {
  nlohmann::json facts;
  const auto nu = test::scene("wall:\n  poisson_ratio: 0.5\n");
  EXPECT_NE(
      test::input_error([&] { (void)make_scene_wall(nu, tube(), facts); }).find("scene.yaml:2: wall.poisson_ratio"),
      std::string::npos);
  const auto with_catheter = test::scene("catheter: {}\nwall: {}\n");
  EXPECT_NE(test::input_error([&] { (void)make_scene_wall(with_catheter, tube(), facts); }).find("catheter"),
            std::string::npos);
  const auto y = vessels::Network::build(vessels::y_bifurcation({}), {.max_segment_length = 5e-3});
  EXPECT_NE(test::input_error([&] { (void)make_scene_wall(test::scene("wall: {}\n"), y, facts); }).find("3 branches"),
            std::string::npos);
  for (const char* bad :
       {"wall:\n  thickness: 0 mm\n", "wall:\n  youngs_modulus: -1 MPa\n", "wall:\n  support: 1 Pa\n"})
    EXPECT_NE(test::input_error([&] { (void)test::scene(bad); }).find("scene.yaml:2: wall."), std::string::npos) << bad;
  EXPECT_FALSE(facts.contains("wall")) << "nothing reported of a wall that was refused";
}

}  // namespace
}  // namespace flowire::coupling
