// The lumen meshes built with gmsh: volumes and areas of curved P2 meshes, boundary groups,
// reproducibility, clear errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "fem_test_cases.hpp"
#include "flowire/common/error.hpp"
#include "flowire/fem/mesh.hpp"
#include "flowire/fem/network_mesh.hpp"
#include "flowire_test.hpp"

namespace flowire::fem {
namespace {

TEST(FemMesh, StraightTubeVolumeAreaAndGroups) {
  const auto net = test::tube(2e-3, 20e-3);
  MeshOptions opt;
  opt.size_factor = 0.4;
  const TetMesh m = build_mesh(net, opt);
  ASSERT_GT(m.num_tets(), 100);
  ASSERT_EQ(m.groups.size(), 3u);
  EXPECT_EQ(m.groups[1].kind, BoundaryGroup::Kind::Inlet);
  const double r = 2e-3, l = 20e-3, pi = std::numbers::pi;
  // Quadratic boundary: volume and areas close to the exact cylinder.
  EXPECT_NEAR(m.volume() / (pi * r * r * l), 1.0, 2e-4);
  EXPECT_NEAR(m.area(1) / (pi * r * r), 1.0, 2e-4);
  EXPECT_NEAR(m.area(2) / (pi * r * r), 1.0, 2e-4);
  EXPECT_NEAR(m.area(0) / (2 * pi * r * l), 1.0, 2e-4);
}

TEST(FemMesh, SameNetworkGivesTheSameMesh) {
  const auto net = test::y_small();
  const TetMesh a = build_mesh(net), b = build_mesh(net);
  EXPECT_EQ(a.num_tets(), b.num_tets());
  EXPECT_EQ(a.num_nodes(), b.num_nodes());
  std::printf("Y bifurcation: %d tets, %d nodes, meshed in %.2f s\n", a.num_tets(), a.num_nodes(), a.mesh_seconds);
  ASSERT_EQ(a.groups.size(), 4u);
  for (int g = 1; g < 4; ++g) EXPECT_GT(a.area(g), 0.0);
}

TEST(FemMesh, TooSharpBendIsAnInputError) {
  vessels::Centerlines c;
  c.branches.push_back(
      {"hairpin", {vessels::Vec3(0, 0, 0), vessels::Vec3(10e-3, 0, 0), vessels::Vec3(0, 1e-3, 0)}, {2e-3, 2e-3, 2e-3}});
  const auto net = vessels::Network::build(c);
  try {
    (void)build_mesh(net);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("node"), std::string::npos) << e.what();
  }
}

TEST(FemMesh, SelfIntersectingBranchesAreAnInputError) {
  vessels::Centerlines c;
  // A loop-like branch that passes close to its own start.
  c.branches.push_back({"coil",
                        {vessels::Vec3(0, 0, 0), vessels::Vec3(20e-3, 0, 0), vessels::Vec3(20e-3, 20e-3, 0),
                         vessels::Vec3(10e-3, 20e-3, 0), vessels::Vec3(10e-3, -10e-3, 0.5e-3)},
                        {1e-3, 1e-3, 1e-3, 1e-3, 1e-3}});
  const auto net = vessels::Network::build(c);
  EXPECT_THROW((void)build_mesh(net), Error);
}

}  // namespace
}  // namespace flowire::fem
