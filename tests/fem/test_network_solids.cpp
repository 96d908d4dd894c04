// A network's tube as solids (mesh/network_solids.hpp): the pieces and spheres it is made of,
// and the distance to their surfaces that tells a wall's faces apart.
#include "flowire/mesh/network_solids.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "flowire/common/error.hpp"
#include "flowire/vessels/generators.hpp"

namespace flowire::mesh {
namespace {

using vessels::Vec3;

TEST(NetworkSolids, ABifurcationIsThreeCylindersAndOneSphereAtItsJunction) {
  const auto y = vessels::Network::build(vessels::y_bifurcation({.parent_radius = 3e-3}), {.max_segment_length = 4e-3});
  const NetworkSolids s = make_network_solids(y, "test");
  ASSERT_EQ(s.pieces.size(), 3u) << "each branch straight: one cylinder each, however many segments";
  ASSERT_EQ(s.spheres.size(), 1u);
  EXPECT_DOUBLE_EQ(s.spheres[0].radius, 3e-3) << "the widest radius at the junction";
  EXPECT_EQ(y.node_segments(s.spheres[0].node).second - y.node_segments(s.spheres[0].node).first, 3);
}

TEST(NetworkSolids, TheDistanceToTheSurfacesIsZeroOnEachAndTheOffsetOutside) {
  vessels::Centerlines bent;
  // Two legs of 2 cm, turning by 0.5 rad: split into 2 cm segments, the bend is a node.
  bent.branches.push_back(
      {"bent",
       {Vec3(0, 0, 0), Vec3(0.02, 0, 0), Vec3(0.02 + 0.02 * std::cos(0.5), 0.02 * std::sin(0.5), 0)},
       {2e-3, 2e-3, 2e-3}});
  const auto net = vessels::Network::build(bent, {.max_segment_length = 0.02, .max_chord_deviation = 0.0});
  const NetworkSolids s = make_network_solids(net, "test");
  ASSERT_EQ(s.pieces.size(), 2u);
  ASSERT_EQ(s.spheres.size(), 1u);
  auto same = [](double r, int) { return r; };
  auto grown = [](double r, int) { return r + 0.5e-3; };
  // On the first cylinder's side, on the sphere at the bend (also where a cylinder covers it),
  // and half a millimetre outside.
  EXPECT_NEAR(distance_to_network_solid_surfaces(net, s, Vec3(0.01, 2e-3, 0), same), 0.0, 1e-15);
  EXPECT_NEAR(distance_to_network_solid_surfaces(net, s, Vec3(0.02, 0, 2e-3), same), 0.0, 1e-15);
  EXPECT_NEAR(distance_to_network_solid_surfaces(net, s, Vec3(0.01, 0, -2.5e-3), grown), 0.0, 1e-15);
  EXPECT_NEAR(distance_to_network_solid_surfaces(net, s, Vec3(0.01, 0, -2.5e-3), same), 0.5e-3, 1e-15);
}

TEST(NetworkSolids, ATubeThatWouldFoldIsRefusedNamingWhere) {
  vessels::Centerlines sharp;
  // Two legs of 1 cm turning by 165 deg: a 2 mm tube's inner side folds 15 mm from the bend.
  const double a = 165.0 * std::acos(-1.0) / 180.0;
  sharp.branches.push_back({"sharp",
                            {Vec3(0, 0, 0), Vec3(0.01, 0, 0), Vec3(0.01 + 0.01 * std::cos(a), 0.01 * std::sin(a), 0)},
                            {2e-3, 2e-3, 2e-3}});
  const auto net = vessels::Network::build(sharp, {.max_segment_length = 0.01, .max_chord_deviation = 0.0});
  try {
    (void)make_network_solids(net, "the wall");
    FAIL() << "a bend whose inner side folds was accepted";
  } catch (const flowire::Error& e) {
    EXPECT_NE(std::string(e.what()).find("the wall"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace flowire::mesh
