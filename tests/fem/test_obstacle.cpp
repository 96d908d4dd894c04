// The obstacle domains (flow/fem/src/obstacle.cpp) meshed and measured against their closed
// forms: the DFG 3D-1Z channel (box minus the cylinder), a wire along a tube, off axis (the
// annulus π(R² − a²)L, the wire's surface 2πaL, the tube's 2πRL) and a wire across one, and
// fem_forces.csv read back.
#include "flowire/flow/fem/obstacle.hpp"
#include "flowire/flow/fem/shape_domain.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <set>
#include <sstream>
#include <string>

#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

constexpr double kPi = std::numbers::pi;

double rel(double a, double b) { return std::abs(a - b) / std::abs(b); }

std::set<std::string> group_names(const TetMesh& m) {
  std::set<std::string> out;
  for (const auto& g : m.groups) out.insert(g.name);
  return out;
}

TEST(FemObstacle, TheDfgChannelIsTheBoxMinusTheCylinder) {
  const TetMesh mesh = build_mesh(dfg_3d_1z_domain({.mesh_size = 0.14, .obstacle_mesh_size = 0.035, .growth = 0.3}));
  EXPECT_EQ(group_names(mesh), (std::set<std::string>{"wall", "obstacle", "inlet", "outlet"}));
  const double h = 0.41, r = 0.05;
  EXPECT_LT(rel(mesh.volume(), 2.5 * h * h - kPi * r * r * h), 1e-4);
  EXPECT_LT(rel(mesh.area(mesh.group_named("obstacle")), 2 * kPi * r * h), 1e-3);
  EXPECT_LT(rel(mesh.area(mesh.group_named("inlet")), h * h), 1e-12);
  EXPECT_LT(rel(mesh.area(mesh.group_named("outlet")), h * h), 1e-12);
  // The channel's four side walls, less the two holes where the cylinder meets top and bottom.
  EXPECT_LT(rel(mesh.area(mesh.group_named("wall")), 4 * 2.5 * h - 2 * kPi * r * r), 1e-4);
  // Every obstacle node lies on the cylinder (x − 0.5)² + (y − 0.2)² = r².
  double worst = 0.0;
  const int obstacle = mesh.group_named("obstacle");
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.face_group[f] != obstacle) continue;
    for (int n : mesh.faces[f]) {
      const Vec3& x = mesh.nodes[static_cast<size_t>(n)];
      worst = std::max(worst, std::abs(std::hypot(x.x() - 0.5, x.y() - 0.2) - r));
    }
  }
  EXPECT_LT(worst, 1e-6 * r);
}

TEST(FemObstacle, AWireAlongATubeLeavesTheAnnulus) {
  const double R = 1.5e-3, a = 0.2e-3, L = 2e-3, offset = 0.6e-3;
  const TetMesh mesh = build_mesh(
      wire_along_tube_domain(R, L, a, offset, {.mesh_size = 0.5e-3, .obstacle_mesh_size = 0.12e-3, .growth = 0.5}));
  EXPECT_EQ(group_names(mesh), (std::set<std::string>{"wall", "obstacle", "inlet", "outlet"}));
  EXPECT_LT(rel(mesh.volume(), kPi * (R * R - a * a) * L), 1e-4);
  EXPECT_LT(rel(mesh.area(mesh.group_named("obstacle")), 2 * kPi * a * L), 1e-3);
  EXPECT_LT(rel(mesh.area(mesh.group_named("wall")), 2 * kPi * R * L), 1e-4);
  EXPECT_LT(rel(mesh.area(mesh.group_named("inlet")), kPi * (R * R - a * a)), 1e-4);
  // The wire's nodes lie at distance a from its axis (0, offset, ·).
  double worst = 0.0;
  const int obstacle = mesh.group_named("obstacle");
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.face_group[f] != obstacle) continue;
    for (int n : mesh.faces[f]) {
      const Vec3& x = mesh.nodes[static_cast<size_t>(n)];
      worst = std::max(worst, std::abs(std::hypot(x.y() - offset, x.z()) - a));
    }
  }
  EXPECT_LT(worst, 1e-6 * a);
}

TEST(FemObstacle, AWireAcrossATubeTakesItsChordsOutOfTheFluid) {
  const double R = 1.5e-3, a = 0.1e-3, L = 4e-3;
  const TetMesh mesh = build_mesh(
      wire_in_tube_domain(R, L, a, true, 1.5e-3, {.mesh_size = 0.6e-3, .obstacle_mesh_size = 0.08e-3, .growth = 0.5}));
  EXPECT_EQ(group_names(mesh), (std::set<std::string>{"wall", "obstacle", "inlet", "outlet"}));
  EXPECT_LT(rel(mesh.area(mesh.group_named("inlet")), kPi * R * R), 1e-4);
  EXPECT_LT(rel(mesh.area(mesh.group_named("outlet")), kPi * R * R), 1e-4);
  // The fluid is the tube less the wire's part inside it: over the wire's section
  // (u, w) ∈ disk(a), a chord 2√(R² − w²) of the tube, so V = ∫ 2√(a² − w²)·2√(R² − w²) dw;
  // the wire's surface inside is ∫ 2√(R² − a² sin²θ) a dθ (both by the midpoint rule).
  const int n = 20000;
  double v_wire = 0.0, a_wire = 0.0;
  for (int i = 0; i < n; ++i) {
    const double w = -a + 2 * a * (i + 0.5) / n, th = 2 * kPi * (i + 0.5) / n;
    v_wire += 2 * std::sqrt(a * a - w * w) * 2 * std::sqrt(R * R - w * w) * 2 * a / n;
    a_wire += 2 * std::sqrt(R * R - a * a * std::sin(th) * std::sin(th)) * a * 2 * kPi / n;
  }
  EXPECT_LT(rel(mesh.volume(), kPi * R * R * L - v_wire), 1e-4);
  EXPECT_LT(rel(mesh.area(mesh.group_named("obstacle")), a_wire), 1e-3);
}

TEST(FemObstacle, ForcesFileReadsBack) {
  const auto dir = flowire::testing::scratch_dir("fem_obstacle_forces");
  write_forces(dir.string(), {{"wall", Vec3(1.5, -2e-3, 0.0)}, {"obstacle", Vec3(0.125, 3.25e-7, -1e-12)}});
  std::ifstream in(dir / "fem_forces.csv");
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "boundary,fx,fy,fz");
  std::vector<std::string> names;
  std::vector<Vec3> forces;
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::string name, c;
    std::getline(s, name, ',');
    Vec3 f;
    for (int k = 0; k < 3; ++k) {
      std::getline(s, c, ',');
      f[k] = std::stod(c);
    }
    names.push_back(name);
    forces.push_back(f);
  }
  ASSERT_EQ(names, (std::vector<std::string>{"wall", "obstacle"}));
  EXPECT_LT((forces[0] - Vec3(1.5, -2e-3, 0.0)).norm(), 1e-12);
  EXPECT_LT((forces[1] - Vec3(0.125, 3.25e-7, -1e-12)).norm(), 1e-15);
}

}  // namespace
}  // namespace flowire::flow::fem
