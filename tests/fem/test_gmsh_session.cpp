// The gmsh session the mesh builders share (mesh/src/gmsh_session.cpp): a size that is
// neither fixed nor a positive fraction of the radius is a usage error that passes through
// unchanged (not turned into a gmsh failure), and a build that failed inside the session
// leaves it clean: the next mesh is the one built before the failure, node for node.
#include <gtest/gtest.h>

#include <string>

#include "fem_test_cases.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/network_mesh.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

TEST(FemGmshSession, AFailedBuildLeavesTheSessionClean) {
  const auto net = test::tube(2e-3, 10e-3);
  MeshOptions good;
  good.size_factor = 0.6;
  const TetMesh before = build_mesh(net, good);
  MeshOptions bad;
  bad.size_factor = 0.0;  // and no mesh_size
  try {
    (void)build_mesh(net, bad);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    EXPECT_NE(std::string(e.what()).find("size_factor"), std::string::npos) << e.what();
  }
  const TetMesh after = build_mesh(net, good);
  ASSERT_EQ(after.num_nodes(), before.num_nodes());
  ASSERT_EQ(after.num_tets(), before.num_tets());
  EXPECT_EQ(after.tets, before.tets);
  EXPECT_EQ(after.faces, before.faces);
  for (size_t n = 0; n < before.nodes.size(); ++n) EXPECT_EQ(after.nodes[n], before.nodes[n]) << "node " << n;
}

}  // namespace
}  // namespace flowire::flow::fem
