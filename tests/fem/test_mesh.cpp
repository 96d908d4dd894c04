// Reference element and quadrature exactness, and the lumen meshes built with gmsh:
// volumes and areas of curved P2 meshes, boundary groups, reproducibility, clear errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "fem_test_cases.hpp"
#include "flowire/common/error.hpp"
#include "flowire/fem/element.hpp"
#include "flowire/fem/mesh.hpp"
#include "flowire_test.hpp"

namespace flowire::fem {
namespace {

double factorial(int n) { return n <= 1 ? 1.0 : n * factorial(n - 1); }

TEST(FemElement, TetQuadratureIsExactToDegreeFive) {
  for (int a = 0; a <= 5; ++a)
    for (int b = 0; a + b <= 5; ++b)
      for (int c = 0; a + b + c <= 5; ++c) {
        double sum = 0.0;
        for (const auto& q : tet_quadrature())
          sum += q.weight * std::pow(q.xi[0], a) * std::pow(q.xi[1], b) * std::pow(q.xi[2], c);
        const double exact = factorial(a) * factorial(b) * factorial(c) / factorial(a + b + c + 3);
        EXPECT_NEAR(sum, exact, 1e-15) << a << b << c;
      }
}

TEST(FemElement, TriQuadratureIsExactToDegreeFour) {
  for (int a = 0; a <= 4; ++a)
    for (int b = 0; a + b <= 4; ++b) {
      double sum = 0.0;
      for (const auto& q : tri_quadrature()) sum += q.weight * std::pow(q.xi[0], a) * std::pow(q.xi[1], b);
      const double exact = factorial(a) * factorial(b) / factorial(a + b + 2);
      EXPECT_NEAR(sum, exact, 1e-14) << a << b;
    }
}

TEST(FemElement, P2BasisIsNodalAndGradientsMatchDifferences) {
  const std::array<std::array<double, 3>, 10> nodes{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {.5, 0, 0},
                                                     {.5, .5, 0}, {0, .5, 0}, {0, 0, .5}, {.5, 0, .5}, {0, .5, .5}}};
  double v[10];
  for (int i = 0; i < 10; ++i) {
    tet_p2(nodes[static_cast<size_t>(i)], v);
    for (int j = 0; j < 10; ++j) EXPECT_NEAR(v[j], i == j ? 1.0 : 0.0, 1e-15);
  }
  const std::array<double, 3> x{0.21, 0.17, 0.33};
  double g[10][3], vp[10], vm[10];
  tet_p2_grad(x, g);
  for (int d = 0; d < 3; ++d) {
    auto xp = x, xm = x;
    xp[static_cast<size_t>(d)] += 1e-6;
    xm[static_cast<size_t>(d)] -= 1e-6;
    tet_p2(xp, vp);
    tet_p2(xm, vm);
    for (int i = 0; i < 10; ++i) EXPECT_NEAR(g[i][d], (vp[i] - vm[i]) / 2e-6, 1e-8);
  }
}

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
  c.branches.push_back({"hairpin", {vessels::Vec3(0, 0, 0), vessels::Vec3(10e-3, 0, 0), vessels::Vec3(0, 1e-3, 0)},
                        {2e-3, 2e-3, 2e-3}});
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
