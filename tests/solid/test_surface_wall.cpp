// The wall grown around a triangulated lumen surface (solid/src/surface_wall.cpp): a faceted
// tube's wall against the annulus it should be (volume, the lumen's nodes on the facets, the
// outer surface a thickness away, the ends named by the network's end nodes), inflated against
// Lamé's thick tube; a real abdominal aorta's wall (its carina thinned, not crossed) where
// ../shared is present; and the surfaces no wall can be grown around.
#include "flowire/solid/surface_wall.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "faceted_tube.hpp"
#include "flowire/common/error.hpp"
#include "flowire/solid/elastic_solid.hpp"
#include "flowire/solid/tube_wall.hpp"
#include "flowire/vessels/io.hpp"
#include "flowire_test.hpp"

namespace flowire::solid {
namespace {

using vessels::Vec3;
constexpr double kR = 3e-3, kL = 30e-3, kT = 0.6e-3;

/// A tube of n facets around and m rings along z from −L/2 to L/2, open at both ends.
vessels::LumenSurface faceted_tube(int n, int m) { return flowire::test::faceted_tube(n, m, kR, kL); }

std::string end_name(int node) { return "end_" + std::to_string(node); }

SurfaceWall wall_of(double thickness, double ratio, double mesh_size) {
  SurfaceWall w;
  w.thickness = thickness;
  w.thickness_ratio = ratio;
  w.mesh_size = mesh_size;
  return w;
}

vessels::Network tube_network() {
  vessels::Centerlines c;
  c.branches.push_back({"tube", {Vec3(0, 0, -0.5 * kL), Vec3(0, 0, 0.5 * kL)}, {kR, kR}});
  return vessels::Network::build(c, {.max_segment_length = 5e-3});
}

TEST(SurfaceWall, AFacetedTubesWallIsTheAnnulusAroundIt) {
  const int facets = 64;
  const vessels::LumenSurface lumen = faceted_tube(facets, 40);
  const vessels::Network net = tube_network();
  SurfaceWallStats stats;
  const mesh::TetMesh m = mesh_surface_wall(lumen, net, wall_of(kT, 0.0, 0.8e-3), &stats);
  EXPECT_EQ(stats.thinned_vertices, 0);
  EXPECT_DOUBLE_EQ(stats.min_thickness, kT);
  ASSERT_GE(m.group_named("lumen"), 0);
  ASSERT_GE(m.group_named("outer"), 0);
  const int end0 = m.group_named(end_name(net.ends().front()));
  const int end1 = m.group_named(end_name(net.ends().back()));
  ASSERT_GE(end0, 0);
  ASSERT_GE(end1, 0);
  // The polygon's annulus: the lumen polygon of area (n/2)R² sin(2π/n), the offset polygon's
  // vertices R/cos(π/n)... : both within 0.2% of the circles at 64 facets; the volume within 1%.
  const double annulus = std::numbers::pi * ((kR + kT) * (kR + kT) - kR * kR) * kL;
  EXPECT_NEAR(m.volume(), annulus, 0.01 * annulus);
  // Each end is an annulus too.
  const double ring = std::numbers::pi * ((kR + kT) * (kR + kT) - kR * kR);
  EXPECT_NEAR(m.area(end0), ring, 0.02 * ring);
  EXPECT_NEAR(m.area(end1), ring, 0.02 * ring);
  // The lumen's vertex nodes on the facets, its edge nodes too but in the few tetrahedra whose
  // curved map folded (straight edges: within the chord's sagitta ℓ²/8R of its longest edge ℓ);
  // the outer surface a thickness out.
  const int lumen_group = m.group_named("lumen"), outer_group = m.group_named("outer");
  double longest = 0.0, vertex_off = 0.0, edge_off = 0.0, outer_off = 0.0;
  for (size_t f = 0; f < m.faces.size(); ++f)
    for (int k = 0; k < 6; ++k) {
      const Vec3& y = m.nodes[static_cast<size_t>(m.faces[f][static_cast<size_t>(k)])];
      if (m.face_group[f] == lumen_group) {
        (k < 3 ? vertex_off : edge_off) = std::max(k < 3 ? vertex_off : edge_off, std::abs(lumen.distance(y).distance));
        if (k < 3)
          longest = std::max(longest,
                             (y - m.nodes[static_cast<size_t>(m.faces[f][static_cast<size_t>((k + 1) % 3)])]).norm());
      }
      if (m.face_group[f] == outer_group)
        outer_off = std::max(outer_off, std::abs(std::hypot(y.x(), y.y()) - (kR + kT)));
    }
  EXPECT_LT(vertex_off, 1e-9 * kR);
  EXPECT_LT(edge_off, longest * longest / (8 * kR));
  EXPECT_LT(outer_off, longest * longest / (8 * kR));
}

TEST(SurfaceWall, AnInflatedFacetedTubeSwellsAsLamesThickTube) {
  // Held ends: plane strain at mid-length. 2 kPa on a 1 MPa wall: linear to 1e-3.
  const vessels::LumenSurface lumen = faceted_tube(64, 40);
  const vessels::Network net = tube_network();
  const double E = 1e6, nu = 0.45, p = 2e3;
  ElasticSolid s(mesh_surface_wall(lumen, net, wall_of(kT, 0.0, 0.6e-3)), NeoHookean::from_young_poisson(E, nu));
  for (int e : net.ends()) s.hold(s.mesh().group_named(end_name(e)));
  s.set_pressure(s.mesh().group_named("lumen"), p);
  ASSERT_TRUE(s.solve().converged);
  const double a = kR, b = kR + kT;
  const double lame = (1 + nu) * p * a * a / (E * (b * b - a * a)) * ((1 - 2 * nu) * a + b * b / a);
  double worst = 0.0;
  int seen = 0;
  const int lumen_group = s.mesh().group_named("lumen");
  for (size_t f = 0; f < s.mesh().faces.size(); ++f) {
    if (s.mesh().face_group[f] != lumen_group) continue;
    for (int k : s.mesh().faces[f]) {
      const Vec3& x = s.mesh().nodes[static_cast<size_t>(k)];
      if (std::abs(x.z()) > 2e-3) continue;
      const Vec3 u = s.displacement(k);
      const double r = std::hypot(x.x(), x.y());
      worst = std::max(worst, std::abs((u.x() * x.x() + u.y() * x.y()) / r - lame));
      ++seen;
    }
  }
  ASSERT_GT(seen, 16);
  EXPECT_LT(worst, 0.05 * lame) << "Lamé " << lame * 1e6 << " um";
}

TEST(SurfaceWall, ARealBifurcationsWallIsThinnedAtItsCarinaNotCrossed) {
  const auto root = flowire::testing::shared_dir() / "data/real/vmtk-abdominal-aorta-bifurcation";
  if (!std::filesystem::exists(root)) GTEST_SKIP() << "../shared/data/real is absent: " << root;
  // The surface as the scene reads it (closed: its caps removed at the centerline ends).
  vessels::ReadOptions read;
  read.length_unit = "mm";
  const vessels::Network net = vessels::read_network((root / "aorta-centerline.vtp").string(), read);
  vessels::SurfaceMesh raw = vessels::read_surface((root / "aorta-surface.vtp").string(), 1e-3);
  std::vector<vessels::VesselEnd> ends;
  for (int e : net.ends()) {
    const auto& seg = net.segment(*net.node_segments(e).first);
    const int other = seg.node_from == e ? seg.node_to : seg.node_from;
    ends.push_back({net.node(e), (net.node(e) - net.node(other)).normalized(), seg.radius});
  }
  ASSERT_EQ(vessels::remove_end_caps(raw, ends) > 0, true);
  std::vector<Vec3> inside;
  for (int k = 0; k < net.num_nodes(); ++k) inside.push_back(net.node(k));
  const vessels::LumenSurface lumen(std::move(raw), inside);
  SurfaceWallStats stats;
  const mesh::TetMesh m = mesh_surface_wall(lumen, net, wall_of(0.0, 0.15, 0.0), &stats);
  std::printf("%d lumen vertices, %d thinned, thickness %.3g-%.3g mm; %d tets, %d nodes, %.2f s\n",
              stats.lumen_vertices, stats.thinned_vertices, stats.min_thickness * 1e3, stats.max_thickness * 1e3,
              m.num_tets(), m.num_nodes(), m.mesh_seconds);
  EXPECT_GT(stats.thinned_vertices, 0);  // the carina
  for (int e : net.ends()) EXPECT_GE(m.group_named(end_name(e)), 0) << e;
  // Every outer node lies outside the lumen, no nearer to it than a fifth of the thinnest wall.
  const int outer = m.group_named("outer"), lumen_group = m.group_named("lumen");
  double nearest = 1.0, worst_lumen = 0.0;
  for (size_t f = 0; f < m.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Vec3& x = m.nodes[static_cast<size_t>(m.faces[f][static_cast<size_t>(k)])];
      const double d = lumen.distance(x).distance;
      if (m.face_group[f] == outer) nearest = std::min(nearest, d);
      if (m.face_group[f] == lumen_group) worst_lumen = std::max(worst_lumen, std::abs(d));
    }
  EXPECT_GT(nearest, 0.2 * stats.min_thickness);
  EXPECT_LT(worst_lumen, 0.1 * stats.min_thickness);
  // The solid is whole: its volume that of the lumen's area times the thickness, roughly.
  EXPECT_GT(m.volume(), 0.0);
}

TEST(SurfaceWall, TheSameSurfaceGivesTheSameWallWhateverWasMeshedBefore) {
  // gmsh keeps its options from one model to the next within a process (a study, a fit, the
  // Python module): a wall must not depend on what was meshed before it. (The kept walls are
  // forgotten before the second, so that it is built again rather than given back.)
  const vessels::LumenSurface lumen = faceted_tube(32, 12);
  const vessels::Network net = tube_network();
  const mesh::TetMesh first = mesh_surface_wall(lumen, net, wall_of(kT, 0.0, 0.0));
  (void)mesh_tube_wall({kR, kR + kT, kL, 1.5e-3, true});  // another build between
  forget_kept_walls();
  const mesh::TetMesh again = mesh_surface_wall(lumen, net, wall_of(kT, 0.0, 0.0));
  EXPECT_GT(again.mesh_seconds, 0.0);  // built, not kept
  ASSERT_EQ(first.num_nodes(), again.num_nodes());
  ASSERT_EQ(first.num_tets(), again.num_tets());
  for (size_t k = 0; k < first.nodes.size(); ++k) EXPECT_EQ(first.nodes[k], again.nodes[k]) << k;
  // The same inputs again: the kept wall, at no cost.
  SurfaceWallStats stats;
  const mesh::TetMesh kept = mesh_surface_wall(lumen, net, wall_of(kT, 0.0, 0.0), &stats);
  EXPECT_EQ(kept.mesh_seconds, 0.0);
  EXPECT_EQ(kept.num_tets(), again.num_tets());
  EXPECT_GT(stats.lumen_vertices, 0);
}

TEST(SurfaceWall, RefusesWhatNoWallCanBeGrownAround) {
  const vessels::Network net = tube_network();
  const vessels::LumenSurface lumen = faceted_tube(32, 10);
  EXPECT_THROW((void)mesh_surface_wall(lumen, net, {}), flowire::Error);  // no thickness
  // A tube whose open ends lie 2 cm from the network's ends.
  vessels::Centerlines c;
  c.branches.push_back({"far", {Vec3(0.02, 0, -0.5 * kL), Vec3(0.02, 0, 0.5 * kL)}, {kR, kR}});
  const vessels::Network far = vessels::Network::build(c, {.max_segment_length = 5e-3});
  try {
    (void)mesh_surface_wall(lumen, far, wall_of(kT, 0.0, 1e-3));
    FAIL() << "no error";
  } catch (const flowire::Error& e) {
    EXPECT_EQ(e.kind(), flowire::ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("faceted tube: open end at"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace flowire::solid
