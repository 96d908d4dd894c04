// The quadratic tetrahedral mesh (mesh/src/tet_mesh.cpp): volume and areas of a curved P2
// mesh against the exact cylinder, and its boundary groups.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fem_test_cases.hpp"
#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/network_mesh.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
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

}  // namespace
}  // namespace flowire::flow::fem
