// The meshed gmsh model read into a TetMesh (mesh/src/extract.cpp), on a network
// lumen with a junction and on a domain built in code with two no-slip groups: every
// straight tetrahedron has positive volume, each vertex has one pressure unknown and edge
// nodes none, and the boundary triangles close the mesh with outward normals: the
// divergence theorem over them gives the volume of the straight-sided tetrahedra to
// round-off (a triangle turned inwards, or missing, would change it by its own share).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <vector>

#include "fem_test_cases.hpp"
#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/network_mesh.hpp"
#include "flowire/flow/fem/shape_domain.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

void expect_extracted_well(const TetMesh& m) {
  ASSERT_GT(m.num_tets(), 0);
  ASSERT_EQ(m.face_group.size(), m.faces.size());
  auto x = [&](int n) -> const Vec3& { return m.nodes[static_cast<size_t>(n)]; };
  double v_tets = 0.0, v_min = std::numeric_limits<double>::infinity();
  std::vector<char> is_vertex(m.nodes.size(), 0);
  for (const auto& t : m.tets) {
    const double v = (x(t[1]) - x(t[0])).cross(x(t[2]) - x(t[0])).dot(x(t[3]) - x(t[0])) / 6.0;
    v_min = std::min(v_min, v);
    v_tets += v;
    for (int k = 0; k < 4; ++k) is_vertex[static_cast<size_t>(t[static_cast<size_t>(k)])] = 1;
  }
  EXPECT_GT(v_min, 0.0);
  ASSERT_EQ(m.vertex_index.size(), m.nodes.size());
  std::vector<int> unknowns(static_cast<size_t>(m.num_vertices), 0);
  for (size_t n = 0; n < m.nodes.size(); ++n) {
    const int v = m.vertex_index[n];
    if (!is_vertex[n]) {
      EXPECT_EQ(v, -1) << "edge node " << n;
      continue;
    }
    ASSERT_GE(v, 0);
    ASSERT_LT(v, m.num_vertices);
    ++unknowns[static_cast<size_t>(v)];
  }
  for (int c : unknowns) EXPECT_EQ(c, 1);
  std::vector<int> per_group(m.groups.size(), 0);
  double v_faces = 0.0;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const int g = m.face_group[f];
    ASSERT_GE(g, 0);
    ASSERT_LT(g, static_cast<int>(m.groups.size()));
    ++per_group[static_cast<size_t>(g)];
    const auto& tri = m.faces[f];
    v_faces += x(tri[0]).dot(x(tri[1]).cross(x(tri[2]))) / 6.0;
  }
  for (size_t g = 0; g < m.groups.size(); ++g) EXPECT_GT(per_group[g], 0) << m.groups[g].name;
  std::printf("%d tets, %zu boundary triangles: divergence theorem %.3e from the tetrahedra's volume\n", m.num_tets(),
              m.faces.size(), v_faces / v_tets - 1.0);
  EXPECT_NEAR(v_faces / v_tets, 1.0, 1e-9);
}

TEST(FemMeshExtract, NetworkLumenIsClosedOutwardAndNumbered) {
  MeshOptions mo;
  mo.size_factor = 0.6;
  expect_extracted_well(build_mesh(test::y_small(0.3), mo));
}

TEST(FemMeshExtract, DomainWithAWireIsClosedOutwardAndNumbered) {
  const TetMesh m = build_mesh(test::tube_with_wire(1e-3, 2e-3, 0.2e-3, 0.5e-3, 0.15e-3));
  ASSERT_EQ(m.groups.size(), 4u);
  expect_extracted_well(m);
}

}  // namespace
}  // namespace flowire::flow::fem
