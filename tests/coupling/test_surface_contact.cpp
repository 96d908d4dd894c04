// The wall penalty on a triangulated surface's smoothed signed distance: energy, force and
// Jacobian against finite differences, on a faceted tube (where the exact distance's gradient
// jumps between faces), and the smoothing's bound d ≤ d_τ ≤ d + τ log k.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "flowire/coupling/interaction.hpp"
#include "flowire/vessels/surface.hpp"
#include "flowire_test.hpp"

using namespace flowire;
using vessels::Vec3;

namespace {

/// A tube of radius R along z, n facets around, m rings over length L, open at both ends.
vessels::LumenSurface faceted_tube(int n, int m, double R, double L) {
  vessels::SurfaceMesh mesh;
  for (int j = 0; j <= m; ++j)
    for (int i = 0; i < n; ++i) {
      const double a = 2.0 * M_PI * i / n + (j % 2) * M_PI / n;
      mesh.vertices.emplace_back(R * std::cos(a), R * std::sin(a), L * j / m - 0.5 * L);
    }
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * n + i, b = j * n + (i + 1) % n, c = (j + 1) * n + i, d = (j + 1) * n + (i + 1) % n;
      mesh.triangles.push_back({a, b, c});
      mesh.triangles.push_back({b, d, c});
    }
  mesh.source = "faceted tube";
  return vessels::LumenSurface(std::move(mesh), {Vec3::Zero()});
}

}  // namespace

TEST(SurfaceContact, PenaltyEnergyForceAndJacobianMatchFiniteDifferences) {
  const double R = 3e-3, a = 0.445e-3, k = 3e4, tau = 0.1e-3;
  const auto s = faceted_tube(16, 20, R, 40e-3);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> ang(0.0, 2.0 * M_PI), rho(R - 1.2 * a, R - 0.2 * a), z(-10e-3, 10e-3);
  auto energy = [&](const Vec3& x) {
    Eigen::Matrix3d H;
    const auto q = s.smooth_distance(x, tau, -1, &H);
    return coupling::wall_penalty(q.distance, q.gradient, H, a, k);
  };
  int active = 0;
  for (int t = 0; t < 300; ++t) {
    const double th = ang(rng), r = rho(rng);
    const Vec3 x(r * std::cos(th), r * std::sin(th), z(rng));
    const auto p = energy(x);
    if (p.penetration <= 0.0) continue;
    ++active;
    const double h = 1e-9;
    for (int c = 0; c < 3; ++c) {
      const Vec3 e = Vec3::Unit(c);
      const auto pp = energy(x + h * e), pm = energy(x - h * e);
      EXPECT_NEAR((pp.energy - pm.energy) / (2 * h), p.gradient[c], 1e-6 * (1.0 + p.gradient.norm()));
      const Vec3 col = (pp.gradient - pm.gradient) / (2 * h);
      EXPECT_LT((col - p.hessian.col(c)).norm(), 2e-4 * (k + p.hessian.norm())) << "column " << c;
    }
    // The force is continuous where the exact distance's gradient jumps (between faces).
  }
  EXPECT_GT(active, 100);
}

TEST(SurfaceContact, SmoothedDistanceIsBoundedByTheExactOneAndContinuousAcrossFaces) {
  const double R = 3e-3, tau = 0.1e-3;
  const auto s = faceted_tube(16, 20, R, 40e-3);
  // Across the bisector of two faces, at depth 0.5 mm: the exact gradient jumps by the facet
  // angle 2π/16; the smoothed one turns continuously.
  double max_jump_exact = 0.0, max_jump_smooth = 0.0;
  const double r = R - 0.5e-3;
  Vec3 g0e = Vec3::Zero(), g0s = Vec3::Zero();
  for (int i = 0; i <= 2000; ++i) {
    const double th = 2.0 * M_PI / 16 * (i / 2000.0);
    const Vec3 x(r * std::cos(th), r * std::sin(th), 0.3e-3);
    const auto e = s.distance(x), m = s.smooth_distance(x, tau);
    EXPECT_LE(e.distance, m.distance + 1e-15);
    EXPECT_LE(m.distance, e.distance + tau * std::log(8.0));
    if (i > 0) {
      max_jump_exact = std::max(max_jump_exact, (e.gradient - g0e).norm());
      max_jump_smooth = std::max(max_jump_smooth, (m.gradient - g0s).norm());
    }
    g0e = e.gradient, g0s = m.gradient;
  }
  EXPECT_GT(max_jump_exact, 0.15);   // one face normal to the next (the rings are staggered)
  EXPECT_LT(max_jump_smooth, 0.02);  // over a step of 2π/16/2000 rad
}

TEST(SurfaceContact, KeptNeighbourhoodAnswersAsAFreshQueryAlongAWanderingPath) {
  // A vertex's kept triangles (SurfaceNeighbourhood) must give the answer of a query that
  // walks the whole hierarchy, whether the point barely moves (Newton iterates), moves within
  // the margin, or jumps beyond it (rebuild) — on the faceted tube and at the open ends.
  const double R = 3e-3, tau = 0.1e-3, margin = 0.3e-3;
  const auto s = faceted_tube(16, 20, R, 40e-3);
  std::mt19937 rng(7);
  std::normal_distribution<double> step(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  vessels::SurfaceNeighbourhood near[2];  // one per smoothing width
  Vec3 x(R - 0.4e-3, 0.0, 0.0);
  int rebuilt = 0, reused = 0;
  Vec3 last_centre = Vec3::Constant(1e9);
  for (int t = 0; t < 3000; ++t) {
    // Mostly small moves, sometimes one past the margin; kept inside radius ≈ R and |z| < 22 mm
    // (beyond the open ends at ±20 mm too).
    const double scale = unit(rng) < 0.1 ? 1.5e-3 : (unit(rng) < 0.5 ? 1e-6 : 0.1e-3);
    x += scale * Vec3(step(rng), step(rng), step(rng));
    const double rho = std::hypot(x.x(), x.y());
    if (rho > R + 0.3e-3) x.head<2>() *= (R + 0.3e-3) / rho;
    x.z() = std::clamp(x.z(), -22e-3, 22e-3);
    for (int k = 0; k < 2; ++k) {
      const double w = k == 0 ? tau : 0.0;
      Eigen::Matrix3d H_kept, H_fresh;
      const auto kept = s.smooth_distance(x, w, near[k], margin, &H_kept);
      const auto fresh = s.smooth_distance(x, w, -1, &H_fresh);
      ASSERT_EQ(kept.triangle, fresh.triangle) << "step " << t;
      EXPECT_NEAR(kept.distance, fresh.distance, 1e-15) << "step " << t;
      EXPECT_NEAR(kept.exact, fresh.exact, 1e-15);
      EXPECT_EQ(kept.open, fresh.open);
      EXPECT_LT((kept.gradient - fresh.gradient).norm(), 1e-12);
      EXPECT_LT((H_kept - H_fresh).norm(), 1e-9 * (1.0 + H_fresh.norm()));
      // The exact part agrees with checking every triangle.
      EXPECT_NEAR(kept.exact, s.distance_brute_force(x).distance, 1e-15);
    }
    ((near[0].centre - last_centre).norm() > 0.0 ? rebuilt : reused) += 1;
    last_centre = near[0].centre;
  }
  // Both paths were taken.
  EXPECT_GT(rebuilt, 100) << reused;
  EXPECT_GT(reused, 100);
}
