// Field evaluation on the curved P2 mesh (flow/fem/src/sample.cpp), on meshes written out
// here by hand (a box cut into Kuhn tetrahedra): P2 velocity and P1 pressure reproduce a
// quadratic and a linear field exactly anywhere inside, points outside are refused, and on a
// bulged (curved) face every point of the quadratic map is found in its own element at its
// own reference coordinates, including those beyond the straight face.
#include "flowire/flow/fem/sample.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include "flowire/flow/fem/element.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

/// The box [0, 2] × [0, 1.5] × [0, 1] in n³ cells, each cut into six tetrahedra around its
/// main diagonal (Kuhn), with straight edge nodes at the midpoints.
TetMesh kuhn_box(int n) {
  TetMesh m;
  const Vec3 size(2.0, 1.5, 1.0);
  auto vid = [n](int i, int j, int k) { return (k * (n + 1) + j) * (n + 1) + i; };
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) m.nodes.push_back(size.cwiseProduct(Vec3(i, j, k)) / n);
  m.num_vertices = static_cast<int>(m.nodes.size());
  std::map<std::pair<int, int>, int> edge_node;
  auto midpoint = [&](int a, int b) {
    const auto key = std::minmax(a, b);
    auto it = edge_node.find(key);
    if (it != edge_node.end()) return it->second;
    m.nodes.push_back(0.5 * (m.nodes[static_cast<size_t>(a)] + m.nodes[static_cast<size_t>(b)]));
    const int id = static_cast<int>(m.nodes.size()) - 1;
    edge_node.emplace(key, id);
    return id;
  };
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& p : perms) {
          int c[3] = {i, j, k};
          std::array<int, 4> v{};
          v[0] = vid(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            v[static_cast<size_t>(s + 1)] = vid(c[0], c[1], c[2]);
          }
          const auto& x = m.nodes;
          const double vol = (x[static_cast<size_t>(v[1])] - x[static_cast<size_t>(v[0])])
                                 .cross(x[static_cast<size_t>(v[2])] - x[static_cast<size_t>(v[0])])
                                 .dot(x[static_cast<size_t>(v[3])] - x[static_cast<size_t>(v[0])]);
          if (vol < 0) std::swap(v[1], v[2]);
          std::array<int, 10> t{};
          for (int a = 0; a < 4; ++a) t[static_cast<size_t>(a)] = v[static_cast<size_t>(a)];
          for (int e = 0; e < 6; ++e)
            t[static_cast<size_t>(4 + e)] = midpoint(v[static_cast<size_t>(kTetEdges[static_cast<size_t>(e)][0])],
                                                     v[static_cast<size_t>(kTetEdges[static_cast<size_t>(e)][1])]);
          m.tets.push_back(t);
        }
  m.vertex_index.assign(m.nodes.size(), -1);
  for (int i = 0; i < m.num_vertices; ++i) m.vertex_index[static_cast<size_t>(i)] = i;
  return m;
}

Vec3 quadratic_velocity(const Vec3& x) {
  return Vec3(x.x() * x.x() - 0.5 * x.y() * x.z(), 1.0 + x.x() * x.y() - x.z(),
              0.3 * x.z() * x.z() - x.y() * x.y() + 2.0);
}
double linear_pressure(const Vec3& x) { return 3.0 + 2.0 * x.x() - x.y() + 0.5 * x.z(); }

StokesSolution fields_on(const TetMesh& m) {
  StokesSolution s;
  for (const Vec3& x : m.nodes) s.velocity.push_back(quadratic_velocity(x));
  for (int i = 0; i < m.num_vertices; ++i) s.pressure.push_back(linear_pressure(m.nodes[static_cast<size_t>(i)]));
  return s;
}

TEST(FemSample, QuadraticVelocityAndLinearPressureAreReproducedEverywhereInside) {
  const TetMesh mesh = kuhn_box(3);
  const StokesSolution sol = fields_on(mesh);
  const FieldSampler sampler(mesh, sol);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 500; ++i) {
    const Vec3 x(2.0 * u(rng), 1.5 * u(rng), u(rng));
    const auto v = sampler.at(x);
    ASSERT_TRUE(v.has_value()) << x.transpose();
    EXPECT_LT((v->velocity - quadratic_velocity(x)).norm(), 1e-12) << x.transpose();
    EXPECT_NEAR(v->pressure, linear_pressure(x), 1e-12);
    EXPECT_GE(v->tet, 0);
  }
  // Corners and faces of the box are inside (within the tolerance).
  for (const Vec3& x : {Vec3(0, 0, 0), Vec3(2, 1.5, 1), Vec3(1, 0, 0.5), Vec3(2, 0.7, 0.2)}) {
    const auto v = sampler.at(x);
    ASSERT_TRUE(v.has_value()) << x.transpose();
    EXPECT_LT((v->velocity - quadratic_velocity(x)).norm(), 1e-12);
  }
}

TEST(FemSample, PointsOutsideTheMeshAreRefused) {
  const TetMesh mesh = kuhn_box(2);
  const StokesSolution sol = fields_on(mesh);
  const FieldSampler sampler(mesh, sol);
  for (const Vec3& x : {Vec3(2.01, 0.5, 0.5), Vec3(-0.01, 0.5, 0.5), Vec3(1, 1.6, 0.5), Vec3(1, 0.5, -0.2),
                        Vec3(10, 10, 10), Vec3(-3, 0.5, 0.5)})
    EXPECT_FALSE(sampler.at(x).has_value()) << x.transpose();
}

TEST(FemSample, EveryPointOfACurvedElementIsFoundAtItsOwnReferenceCoordinates) {
  // Bulge the face x = 2 outwards: its edge nodes move by 0.15 sin(πy/1.5) sin(πz) along +x,
  // so the elements on it are curved and reach beyond the straight face.
  TetMesh mesh = kuhn_box(2);
  for (int i = mesh.num_vertices; i < mesh.num_nodes(); ++i) {
    Vec3& x = mesh.nodes[static_cast<size_t>(i)];
    if (x.x() == 2.0) x.x() += 0.15 * std::sin(M_PI * x.y() / 1.5) * std::sin(M_PI * x.z());
  }
  const StokesSolution sol = fields_on(mesh);
  const FieldSampler sampler(mesh, sol);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int curved = 0, beyond = 0;
  for (int e = 0; e < mesh.num_tets(); ++e) {
    const auto& t = mesh.tets[static_cast<size_t>(e)];
    bool on_face = false;
    for (int k = 4; k < 10; ++k) on_face |= mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(k)])].x() > 2.0;
    if (!on_face) continue;
    ++curved;
    for (int trial = 0; trial < 20; ++trial) {
      // Reference coordinates at least 0.02 inside every face of the reference element.
      std::array<double, 4> l{};
      double sum = 0.0;
      for (double& b : l) sum += (b = 0.02 + u(rng));
      std::array<double, 3> xi{};
      for (int d = 0; d < 3; ++d) {
        l[static_cast<size_t>(d + 1)] /= sum;
        l[static_cast<size_t>(d + 1)] = 0.02 + (1.0 - 4 * 0.02) * l[static_cast<size_t>(d + 1)];
        xi[static_cast<size_t>(d)] = l[static_cast<size_t>(d + 1)];
      }
      double phi[10];
      tet_p2(xi, phi);
      Vec3 x = Vec3::Zero();
      for (int k = 0; k < 10; ++k) x += phi[k] * mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(k)])];
      beyond += x.x() > 2.0;
      std::array<double, 3> found{};
      const int got = sampler.locate(x, 1e-8, found);
      ASSERT_EQ(got, e) << "point " << x.transpose();
      for (int d = 0; d < 3; ++d) EXPECT_NEAR(found[static_cast<size_t>(d)], xi[static_cast<size_t>(d)], 1e-10);
      // The interpolated field there is the nodal values' P2 combination at ξ.
      Vec3 expected = Vec3::Zero();
      for (int k = 0; k < 10; ++k) expected += phi[k] * sol.velocity[static_cast<size_t>(t[static_cast<size_t>(k)])];
      EXPECT_LT((sampler.at(x)->velocity - expected).norm(), 1e-10);
    }
  }
  EXPECT_GT(curved, 4);
  EXPECT_GT(beyond, 10);  // the bulge is exercised
}

}  // namespace
}  // namespace flowire::flow::fem
