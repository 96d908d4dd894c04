// The wall: section (coupling/src/config_wall.cpp): its keys, the wall they build, and each
// refusal naming the key or the vessels at fault.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

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
  EXPECT_EQ(make_scene_wall(test::scene("wire: {}\n"), tube(), nullptr, facts), nullptr);
  EXPECT_FALSE(facts.contains("wall"));
}

TEST(ConfigWall, TheWallOfAStraightVesselIsBuiltWithItsThicknessFromTheRadius) {
  nlohmann::json facts;
  const auto c = test::scene("wall:\n  thickness_ratio: 0.2\n  youngs_modulus: 2 MPa\n  mesh_size: 2 mm\n");
  const auto wall = make_scene_wall(c, tube(), nullptr, facts);
  ASSERT_NE(wall, nullptr);
  EXPECT_NEAR(facts["wall"]["thinnest"].get<double>(), 0.2 * 3e-3, 1e-15);
  EXPECT_DOUBLE_EQ(facts["wall"]["thickness_ratio"].get<double>(), 0.2);
  EXPECT_DOUBLE_EQ(facts["wall"]["youngs_modulus"].get<double>(), 2e6);
  EXPECT_DOUBLE_EQ(facts["wall"]["poisson_ratio"].get<double>(), 0.45);
  EXPECT_GT(facts["wall"]["tets"].get<int>(), 0);
  const auto* deformable = dynamic_cast<const DeformableWall*>(wall.get());
  ASSERT_NE(deformable, nullptr);
  EXPECT_EQ(deformable->mesh().num_nodes(), facts["wall"]["nodes"].get<int>());
}

TEST(ConfigWall, TheWallOfABifurcationHoldsEveryEndAndItsLumenIsTheNetworksCapsules) {
  const auto y = vessels::Network::build(
      vessels::y_bifurcation({.parent_radius = 3e-3, .parent_length = 20e-3, .child_length = 20e-3}),
      {.max_segment_length = 5e-3});
  nlohmann::json facts;
  const auto wall =
      make_scene_wall(test::scene("wall:\n  thickness: 0.6 mm\n  mesh_size: 1.5 mm\n"), y, nullptr, facts);
  const auto* deformable = dynamic_cast<const DeformableWall*>(wall.get());
  ASSERT_NE(deformable, nullptr);
  const mesh::TetMesh& m = deformable->mesh();
  // Every lumen node lies on the union of the network's capsules (what the wire's contact sees),
  // every outer node 0.6 mm outside it.
  const int lumen = m.group_named("lumen"), outer = m.group_named("outer");
  auto distance = [&](const Vec3& x) {
    double d = std::numeric_limits<double>::infinity();
    for (int k = 0; k < y.num_segments(); ++k) {
      const auto& seg = y.segment(k);
      const Vec3 a = y.node(seg.node_from), b = y.node(seg.node_to);
      const double t = std::clamp((x - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      d = std::min(d, (x - (a + t * (b - a))).norm() - seg.radius);
    }
    return d;
  };
  double worst_lumen = 0.0, worst_outer = 0.0;
  int faces_lumen = 0;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    for (int node : m.faces[f]) {
      const Vec3& x = m.nodes[static_cast<size_t>(node)];
      if (m.face_group[f] == lumen) worst_lumen = std::max(worst_lumen, std::abs(distance(x)));
      if (m.face_group[f] == outer) worst_outer = std::max(worst_outer, std::abs(distance(x) - 0.6e-3));
    }
    faces_lumen += m.face_group[f] == lumen ? 1 : 0;
  }
  EXPECT_GT(faces_lumen, 100);
  EXPECT_LT(worst_lumen, 1e-6);
  EXPECT_LT(worst_outer, 1e-6);
  // Held at its three ends, the wall's tangent is definite (it was factorized): each end a group.
  for (int e : y.ends()) EXPECT_GE(m.group_named(fmt::format("end_{}", e)), 0);
}

TEST(ConfigWall, RefusesWhatItCannotBuildNamingTheKey) {
  nlohmann::json facts;
  const auto nu = test::scene("wall:\n  poisson_ratio: 0.5\n");
  EXPECT_NE(test::input_error([&] {
              (void)make_scene_wall(nu, tube(), nullptr, facts);
            }).find("scene.yaml:2: wall.poisson_ratio"),
            std::string::npos);
  // A centerline that turns back on itself: no tube can be built along it.
  vessels::Centerlines hairpin;
  hairpin.branches.push_back({"hairpin", {Vec3(0, 0, 0), Vec3(0.01, 0, 0), Vec3(0, 0.0005, 0)}, {1e-3, 1e-3, 1e-3}});
  const auto folded = vessels::Network::build(hairpin, {.max_segment_length = 0.02, .max_chord_deviation = 0.0});
  EXPECT_NE(test::input_error([&] {
              (void)make_scene_wall(test::scene("wall: {}\n"), folded, nullptr, facts);
            }).find("turns back"),
            std::string::npos);
  for (const char* bad :
       {"wall:\n  thickness: 0 mm\n", "wall:\n  youngs_modulus: -1 MPa\n", "wall:\n  support_stiffness: 1 Pa\n"})
    EXPECT_NE(test::input_error([&] { (void)test::scene(bad); }).find("scene.yaml:2: wall."), std::string::npos) << bad;
  // A branch's modulus for a branch the network does not have: named, with the branches it has.
  const auto unknown = test::scene("wall:\n  mesh_size: 3 mm\n  aorta:\n    youngs_modulus: 3 MPa\n");
  const std::string msg = test::input_error([&] { (void)make_scene_wall(unknown, tube(), nullptr, facts); });
  EXPECT_NE(msg.find(": wall.aorta: "), std::string::npos) << msg;
  EXPECT_NE(msg.find("no branch named 'aorta'"), std::string::npos) << msg;
  EXPECT_NE(test::input_error([&] {
              (void)test::scene("wall:\n  b:\n    youngs_modulus: 0 Pa\n");
            }).find("wall.b.youngs_modulus"),
            std::string::npos);
  EXPECT_FALSE(facts.contains("wall")) << "nothing reported of a wall that was refused";
}

TEST(ConfigWall, ABranchsModulusIsTakenByItsWallAndReported) {
  nlohmann::json facts;
  const auto net = tube();
  const std::string name = net.branches().front().name;
  ASSERT_FALSE(name.empty());
  const auto c = test::scene(
      fmt::format("wall:\n  thickness_ratio: 0.2\n  mesh_size: 2 mm\n  {}:\n    youngs_modulus: 3 MPa\n", name));
  const auto wall = make_scene_wall(c, net, nullptr, facts);
  ASSERT_NE(wall, nullptr);
  EXPECT_DOUBLE_EQ(facts["wall"]["branch_youngs_modulus"][name].get<double>(), 3e6);
  const auto* deformable = dynamic_cast<const DeformableWall*>(wall.get());
  ASSERT_NE(deformable, nullptr);
}

TEST(ConfigWall, ABranchsThicknessIsItsOwnElseTheFlowsWallOfThatBranch) {
  // A Y bifurcation: one child's thickness from wall.<child>, the other's from the flow's wall of
  // that branch (flow.wall.<branch>, or an openBF model's h0 and E), which wall.<branch> would
  // override; the trunk keeps the section's. Reported per branch; the thinnest wall is the
  // thinnest branch's, and the default mesh size twice it.
  const auto y = vessels::Network::build(
      vessels::y_bifurcation({.parent_radius = 3e-3, .parent_length = 20e-3, .child_length = 20e-3}),
      {.max_segment_length = 5e-3});
  ASSERT_EQ(y.num_branches(), 3);
  std::vector<std::string> names;
  for (const auto& b : y.branches()) names.push_back(b.name);
  const int first = 1, second = 2;
  const std::vector<flow::BranchWall> flow_walls = {{second, 2e6, 0.4e-3, 0.0}};
  nlohmann::json facts;
  const auto wall = make_scene_wall(
      test::scene(fmt::format("wall:\n  thickness: 0.6 mm\n  {}:\n    thickness: 0.5 mm\n", names[first])), y, nullptr,
      facts, flow_walls);
  ASSERT_NE(wall, nullptr);
  EXPECT_DOUBLE_EQ(facts["wall"]["branch_thickness"][names[first]]["thickness"].get<double>(), 0.5e-3);
  EXPECT_DOUBLE_EQ(facts["wall"]["branch_thickness"][names[second]]["thickness"].get<double>(), 0.4e-3);
  EXPECT_DOUBLE_EQ(facts["wall"]["branch_youngs_modulus"][names[second]].get<double>(), 2e6);
  EXPECT_FALSE(facts["wall"]["branch_thickness"].contains(names[0]));
  EXPECT_NEAR(facts["wall"]["thinnest"].get<double>(), 0.4e-3, 1e-15);
  EXPECT_NEAR(facts["wall"]["mesh_size"].get<double>(), 0.8e-3, 1e-15);
  // wall.<branch> before the flow's wall of it.
  nlohmann::json again;
  (void)make_scene_wall(test::scene(fmt::format("wall:\n  thickness: 0.6 mm\n  mesh_size: 1.5 mm\n  {}:\n    "
                                                "thickness_ratio: 0.3\n",
                                                names[second])),
                        y, nullptr, again, flow_walls);
  EXPECT_DOUBLE_EQ(again["wall"]["branch_thickness"][names[second]]["thickness_ratio"].get<double>(), 0.3);
  EXPECT_NE(
      test::input_error([&] { (void)test::scene("wall:\n  b:\n    thickness: 0 mm\n"); }).find("wall.b.thickness"),
      std::string::npos);
}

}  // namespace
}  // namespace flowire::coupling
