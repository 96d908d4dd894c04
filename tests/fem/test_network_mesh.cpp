// The lumen of a vessel network meshed with gmsh (flow/fem/src/network_mesh.cpp): the same
// network gives the same mesh, and geometries a tube cannot follow are clear input errors.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "fem_test_cases.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/fem/network_mesh.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

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
}  // namespace flowire::flow::fem
