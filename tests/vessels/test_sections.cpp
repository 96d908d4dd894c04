// Cross-sections of a lumen surface (vessels/sections.hpp) against the closed forms of prisms
// cut straight and obliquely, and the network's radii from them on an elliptic tube, whose
// equal-area circle is √(ab) where the centerline's inscribed radius is b.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "flowire/vessels/sections.hpp"

using namespace flowire::vessels;

namespace {

constexpr double kPi = std::numbers::pi;

/// An open tube along x from @p x0 to x0 + @p length whose section is the polygon of @p n vertices on the
/// ellipse of half-axes @p a (y) and @p b (z), with @p rings rings of vertices along x.
LumenSurface elliptic_prism(double a, double b, int n, double length, int rings, double x0 = 0.0) {
  SurfaceMesh m;
  m.source = "prism";
  for (int r = 0; r < rings; ++r)
    for (int k = 0; k < n; ++k) {
      const double phi = 2.0 * kPi * k / n;
      m.vertices.emplace_back(x0 + length * r / (rings - 1), a * std::cos(phi), b * std::sin(phi));
    }
  for (int r = 0; r + 1 < rings; ++r)
    for (int k = 0; k < n; ++k) {
      const int i0 = r * n + k, i1 = r * n + (k + 1) % n, j0 = i0 + n, j1 = i1 + n;
      m.triangles.push_back({i0, i1, j1});
      m.triangles.push_back({i0, j1, j0});
    }
  return LumenSurface(std::move(m), {Vec3(x0 + 0.5 * length, 0.0, 0.0)});
}

/// Area and perimeter of that polygon.
double polygon_area(double a, double b, int n) { return 0.5 * n * a * b * std::sin(2.0 * kPi / n); }

}  // namespace

TEST(Sections, APrismCutAcrossHasThePolygonsArea) {
  const double r = 2e-3;
  const int n = 12;
  const LumenSurface s = elliptic_prism(r, r, n, 0.02, 11);
  const auto sec = cut_section(s, Vec3(0.0103, 0.2e-3, -0.1e-3), Vec3::UnitX(), 8e-3);
  ASSERT_TRUE(sec.has_value());
  EXPECT_NEAR(sec->area, polygon_area(r, r, n), 1e-12 * polygon_area(r, r, n));
  EXPECT_NEAR(sec->perimeter, 2.0 * n * r * std::sin(kPi / n), 1e-12);
  EXPECT_EQ(sec->contours, 1);
  // From the polygon's centre, the apothem and the circumradius.
  const auto centred = cut_section(s, Vec3(0.0103, 0.0, 0.0), Vec3::UnitX(), 8e-3);
  ASSERT_TRUE(centred.has_value());
  EXPECT_NEAR(centred->min_distance, r * std::cos(kPi / n), 1e-12);
  EXPECT_NEAR(centred->max_distance, r, 1e-12);
}

TEST(Sections, AnObliqueCutOfAPrismIsItsSectionOverTheCosine) {
  // Each facet strip is planar, so a plane tilted by φ from the normal section cuts the prism in
  // the section stretched by 1/cos φ along the tilt, across rings of vertices or not.
  const double a = 3e-3, b = 2e-3;
  const int n = 16;
  const LumenSurface s = elliptic_prism(a, b, n, 0.04, 9);
  for (const double phi : {0.2, 0.5, 0.9}) {
    for (const Vec3& tilt : {Vec3(std::cos(phi), std::sin(phi), 0.0), Vec3(std::cos(phi), 0.0, std::sin(phi))}) {
      const auto sec = cut_section(s, Vec3(0.02, 0.0, 0.0), tilt, 20e-3);
      ASSERT_TRUE(sec.has_value()) << phi;
      EXPECT_NEAR(sec->area, polygon_area(a, b, n) / std::cos(phi), 1e-12 * polygon_area(a, b, n) / std::cos(phi))
          << "phi " << phi;
    }
  }
}

TEST(Sections, NoSectionOutsideTheLumenOrBeyondTheReach) {
  const LumenSurface s = elliptic_prism(2e-3, 2e-3, 12, 0.02, 11);
  // Outside the tube: the contour does not wind around the point.
  EXPECT_FALSE(cut_section(s, Vec3(0.01, 5e-3, 0.0), Vec3::UnitX(), 20e-3).has_value());
  // Past the open end: nothing to cut.
  EXPECT_FALSE(cut_section(s, Vec3(0.03, 0.0, 0.0), Vec3::UnitX(), 5e-3).has_value());
  // The reach does not gather the whole contour: it is open, so not taken.
  EXPECT_FALSE(cut_section(s, Vec3(0.01, 0.0, 0.0), Vec3(0.2, 1.0, 0.0), 1e-3).has_value());
}

TEST(Sections, AnEllipticTubesNetworkTakesTheCircleOfTheSameArea) {
  // The centerline of an elliptic tube (half-axes 3 and 2 mm) with its inscribed radius 2 mm:
  // from the sections every radius becomes √(A/π) of the 256-gon, √(ab) to 1e-4.
  const double a = 3e-3, b = 2e-3, length = 0.04;
  const int n = 256;
  const LumenSurface s = elliptic_prism(a, b, n, length + 2e-3, 21, -1e-3);
  std::vector<Vec3> nodes;
  std::vector<Segment> segs;
  const int m = 8;
  for (int i = 0; i <= m; ++i) nodes.emplace_back(length * i / m, 0.0, 0.0);
  for (int i = 0; i < m; ++i) segs.push_back({i, i + 1, b, length / m, 0, b, b});
  Branch br{"tube", {}, {}};
  for (int i = 0; i <= m; ++i) br.nodes.push_back(i);
  for (int i = 0; i < m; ++i) br.segments.push_back(i);
  const Network net = Network::from_graph(nodes, segs, {br}, "tube");
  const SectionRadii r = section_radii(net, s);
  EXPECT_EQ(r.points, m + 1);
  EXPECT_EQ(r.measured, m + 1);
  EXPECT_EQ(r.filled, 0);
  const double expected = std::sqrt(polygon_area(a, b, n) / kPi);
  EXPECT_NEAR(expected / std::sqrt(a * b), 1.0, 1e-4);
  EXPECT_NEAR(r.median_ratio, expected / b, 1e-12);
  for (int i = 0; i < m; ++i) {
    const Segment& g = r.network.segment(i);
    EXPECT_NEAR(g.radius_from, expected, 1e-12 * expected) << i;
    EXPECT_NEAR(g.radius_to, expected, 1e-12 * expected) << i;
    EXPECT_NEAR(g.radius, expected, 1e-12 * expected) << i;
    EXPECT_EQ(g.node_from, net.segment(i).node_from);
  }
  EXPECT_EQ(r.network.branch(0).name, "tube");
  // Each segment's shape factor is the ellipse's, (a² + b²)/(2ab), so that its resistance is
  // Boussinesq's exact one for the elliptic pipe, 4μL(a² + b²)/(πa³b³) (written out here).
  const double shape = (a * a + b * b) / (2.0 * a * b);
  EXPECT_NEAR(r.median_shape, shape, 1e-4);
  EXPECT_NEAR(r.max_shape, shape, 1e-4);
  const double mu = 3.5e-3;
  double resistance = 0.0;
  for (int i = 0; i < m; ++i) {  // the circle of the same area times the segment's shape factor
    const Segment& g = r.network.segment(i);
    resistance += g.shape * 8.0 * mu * g.length / (kPi * std::pow(g.radius, 4));
  }
  EXPECT_NEAR(resistance / (4.0 * mu * length * (a * a + b * b) / (kPi * std::pow(a * b, 3))), 1.0, 5e-4);
}

TEST(Sections, ACircularSectionHasNoShapeFactorAndAnEllipseItsOwnAtAnyOrientation) {
  const LumenSurface circle = elliptic_prism(2e-3, 2e-3, 128, 0.02, 11);
  const auto c = cut_section(circle, Vec3(0.01, 0.0, 0.0), Vec3(1.0, 0.0, 0.0), 8e-3);
  ASSERT_TRUE(c);
  EXPECT_NEAR(c->shape_factor, 1.0, 1e-12);
  for (const double ratio : {1.2, 1.5, 2.0}) {
    const LumenSurface e = elliptic_prism(2e-3 * ratio, 2e-3, 256, 0.02, 11);
    // The normal section, and one off the centre (the moments are taken about the contour's centroid).
    for (const Vec3& at : {Vec3(0.01, 0.0, 0.0), Vec3(0.01, 0.5e-3, -0.3e-3)}) {
      const auto sec = cut_section(e, at, Vec3(1.0, 0.0, 0.0), 8e-3);
      ASSERT_TRUE(sec);
      EXPECT_NEAR(sec->shape_factor, 0.5 * (ratio + 1.0 / ratio), 1e-4) << ratio;
    }
  }
}

TEST(Sections, ABranchBeyondTheSurfaceKeepsTheRatioOfItsNearestSection) {
  // The centerline runs 2 cm on past the tube's end (at 21 mm): those nodes have no section and take the
  // ratio of the last node measured (a surface shorter than its centerline, or a cut end).
  const double a = 2.5e-3, b = 2e-3;
  const LumenSurface s = elliptic_prism(a, b, 64, 0.022, 12, -1e-3);
  std::vector<Vec3> nodes;
  std::vector<Segment> segs;
  Branch br{"long", {}, {}};
  for (int i = 0; i <= 8; ++i) nodes.emplace_back(0.005 * i, 0.0, 0.0), br.nodes.push_back(i);
  for (int i = 0; i < 8; ++i) segs.push_back({i, i + 1, b, 0.005, 0, b, b}), br.segments.push_back(i);
  const SectionRadii r = section_radii(Network::from_graph(nodes, segs, {br}, "long"), s);
  EXPECT_EQ(r.measured, 5);  // x = 0 to 20 mm
  EXPECT_EQ(r.filled, 4);
  const double ratio = std::sqrt(polygon_area(a, b, 64) / kPi) / b;
  for (int i = 0; i < 8; ++i) EXPECT_NEAR(r.network.segment(i).radius / b, ratio, 1e-12) << i;
}
