// The two walls the contact law presses against: the network's capsules (NetworkWall) and a
// triangulated lumen surface (SurfaceWall). Checked: both give the cylinder's distance and
// normal on a straight tube (the surface to its faceting and smoothing error); a vertex the
// network wall skips is deeper inside than its radius plus the reach by the exact union
// distance; the accepted-state answer is the solve's answer; the surface's entry margin; a
// resampling keeps every answer.
#include "flowire/coupling/wall.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "faceted_tube.hpp"
#include "flowire/vessels/generators.hpp"
#include "flowire_test.hpp"

using namespace flowire;
using namespace flowire::coupling;
using vessels::Vec3;

namespace {

rod::RodView view_of(const std::vector<Vec3>& x) {
  rod::RodView v;
  v.positions = x;
  v.first_clamped_vertex = static_cast<int>(x.size());
  return v;
}

}  // namespace

TEST(Wall, BothWallsGiveTheCylindersDistanceAndNormalOnAStraightTube) {
  const double R = 3e-3, L = 0.06, a = 0.45e-3;
  const auto net = vessels::Network::build(
      vessels::straight_tube({.length = L, .radius = R, .origin = Vec3(0, 0, -0.5 * L), .direction = Vec3::UnitZ()}),
      {.max_segment_length = 5e-3});
  const vessels::SpatialIndex index(net);
  WireLocation where(index);
  NetworkWall capsules(where);
  const auto surface = test::faceted_tube(128, 120, R, L);
  const double sigma = 0.5 * surface.counts().mean_edge;
  SurfaceWall lumen(surface, sigma, a, 0.0, 0.0);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ang(0, 2 * std::numbers::pi), rho(R - 0.9 * a, R + 0.2 * a), zs(-0.01, 0.01);
  std::vector<Vec3> x(50);
  for (auto& p : x) {
    const double t = ang(rng), r = rho(rng);
    p = Vec3(r * std::cos(t), r * std::sin(t), zs(rng));
  }
  InteractionStats stats;
  const int n = static_cast<int>(x.size());
  where.locate(view_of(x), n, stats);
  capsules.ensure_size(n);
  lumen.ensure_size(n);
  double worst_capsule = 0.0, worst_surface = 0.0, worst_normal = 0.0;
  for (int i = 0; i < n; ++i) {
    const Vec3& p = x[static_cast<size_t>(i)];
    const double exact = std::hypot(p.x(), p.y()) - R;
    const Vec3 radial = Vec3(p.x(), p.y(), 0).normalized();
    double d = 0.0, ds = 0.0;
    Vec3 nrm, ns;
    Eigen::Matrix3d H, Hs;
    ASSERT_TRUE(capsules.at(i, p, a, 0.0, &d, &nrm, &H)) << i;
    ASSERT_TRUE(lumen.at(i, p, a, 0.0, &ds, &ns, &Hs)) << i;
    worst_capsule = std::max(worst_capsule, std::abs(d - exact));
    worst_surface = std::max(worst_surface, std::abs(ds - exact));
    worst_normal = std::max({worst_normal, (nrm - radial).norm(), (ns - radial).norm()});
  }
  EXPECT_LT(worst_capsule, 1e-12);
  // The 128-gon's sagitta R(1 − cos(π/128)) = 0.9 µm and the smoothing's O(σ²/R) bound the surface.
  EXPECT_LT(worst_surface, 0.01 * a);
  EXPECT_LT(worst_normal, 0.05);
}

TEST(Wall, AVertexTheNetworkWallSkipsIsDeeperInsideThanItsRadiusAndReach) {
  const auto net = vessels::Network::build(vessels::aortic_arch(), {.max_segment_length = 2e-3});
  const vessels::SpatialIndex index(net);
  WireLocation where(index);
  NetworkWall wall(where);
  const double a = 0.45e-3, reach = 0.1e-3;
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> seg(0, net.num_segments() - 1);
  std::uniform_real_distribution<double> u(0.0, 1.0), r(0.5, 1.05);
  std::vector<Vec3> x;
  while (x.size() < 400) {
    const auto& s = net.segment(seg(rng));
    const Vec3 a0 = net.node(s.node_from), a1 = net.node(s.node_to);
    const Vec3 axis = (a1 - a0).normalized();
    const Vec3 side = axis.unitOrthogonal();
    const Vec3 q = a0 + u(rng) * (a1 - a0) + s.radius * r(rng) * (Eigen::AngleAxisd(6.283 * u(rng), axis) * side);
    x.push_back(q);
  }
  InteractionStats stats;
  const int n = static_cast<int>(x.size());
  where.locate(view_of(x), n, stats);
  wall.ensure_size(n);
  int skipped = 0, answered = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3& p = x[static_cast<size_t>(i)];
    double d = 0.0;
    Vec3 nrm;
    const double exact = index.wall_distance(p);
    if (!wall.at(i, p, a, reach, &d, &nrm, nullptr)) {
      ++skipped;
      EXPECT_LT(exact + a + reach, 0.0) << "vertex " << i << " skipped at wall distance " << exact;
      AcceptedWall w;
      EXPECT_FALSE(wall.accepted(i, p, a, reach, 0.0, &w));
    } else {
      ++answered;
      EXPECT_NEAR(d, exact, 1e-12);
      AcceptedWall w;
      ASSERT_TRUE(wall.accepted(i, p, a, reach, 0.0, &w));
      EXPECT_NEAR(w.distance, d, 1e-12);
      EXPECT_EQ(w.contact_distance, w.distance);
      EXPECT_LT((w.normal - nrm).norm(), 1e-12);
      EXPECT_TRUE(w.measured);
    }
  }
  EXPECT_GT(skipped, 50);
  EXPECT_GT(answered, 50);
}

TEST(Wall, TheSurfaceWallMeasuresOutsideFromTheEntryMarginOnAndKeepsItsAnswersOverAResampling) {
  const double R = 3e-3, L = 0.06, a = 0.45e-3, margin = 3e-3;
  const auto surface = test::faceted_tube(32, 30, R, L);
  const double sigma = 0.5 * surface.counts().mean_edge;
  SurfaceWall wall(surface, sigma, a, 0.0, margin);
  std::vector<Vec3> x;
  for (int i = 0; i < 10; ++i) x.emplace_back(R - 0.5 * a, 0.0, -0.02 + 2e-3 * i);
  const int n = static_cast<int>(x.size());
  wall.ensure_size(n);
  std::vector<double> d0(x.size());
  for (int i = 0; i < n; ++i) {
    double d = 0.0;
    Vec3 nrm;
    ASSERT_TRUE(wall.at(i, x[static_cast<size_t>(i)], a, 0.0, &d, &nrm, nullptr));
    d0[static_cast<size_t>(i)] = d;
    AcceptedWall w;
    ASSERT_TRUE(wall.accepted(i, x[static_cast<size_t>(i)], a, 0.0, 1e-3 * i, &w));
    EXPECT_EQ(w.contact_distance, d);
    EXPECT_NEAR(w.distance, surface.distance(x[static_cast<size_t>(i)]).distance, 1e-15);
    EXPECT_EQ(w.measured, 1e-3 * i >= margin) << i;
  }
  // Reversed order, one vertex new: every kept vertex answers as before.
  std::vector<int> source;
  std::vector<Vec3> y;
  for (int i = n - 1; i >= 0; --i) y.push_back(x[static_cast<size_t>(i)]), source.push_back(i);
  y.emplace_back(0.0, R - 0.2 * a, 0.0);
  source.push_back(-1);
  wall.remap(source, n + 1);
  for (int j = 0; j <= n; ++j) {
    double d = 0.0;
    Vec3 nrm;
    ASSERT_TRUE(wall.at(j, y[static_cast<size_t>(j)], a, 0.0, &d, &nrm, nullptr));
    if (j < n) {
      EXPECT_EQ(d, d0[static_cast<size_t>(n - 1 - j)]) << j;
    } else {
      EXPECT_NEAR(d, surface.smooth_distance(y.back(), sigma).distance, 1e-15);
    }
  }
}
