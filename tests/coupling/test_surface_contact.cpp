// The wall penalty on a triangulated surface's smooth signed distance d_σ (the implicit
// surface of the triangles' planes, LumenSurface::smooth_distance): energy, force and Jacobian
// against finite differences, on a faceted tube (where the exact distance's gradient jumps
// between faces) and on the real anatomies; d_σ against the analytic distance to a cylinder
// (second order in the mesh size); the kept neighbourhoods against fresh queries; and the
// band within which the contact skips deep vertices, measured on the real lumens.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "faceted_tube.hpp"
#include "flowire/coupling/interaction.hpp"
#include "flowire/coupling/lumen.hpp"
#include "flowire/coupling/vessel_forces.hpp"
#include "flowire/vessels/io.hpp"
#include "flowire/vessels/surface.hpp"
#include "flowire_test.hpp"

using namespace flowire;
using vessels::Vec3;

namespace {

using test::faceted_tube;

/// The triangles' mean edge length.
double mean_edge(const vessels::LumenSurface& s) { return s.counts().mean_edge; }

}  // namespace

TEST(SurfaceContact, PenaltyEnergyForceAndJacobianMatchFiniteDifferences) {
  const double R = 3e-3, a = 0.445e-3, k = 3e4;
  const auto s = faceted_tube(16, 20, R, 40e-3);
  const double sigma = 0.5 * mean_edge(s);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> ang(0.0, 2.0 * M_PI), rho(R - 1.2 * a, R - 0.2 * a), z(-10e-3, 10e-3);
  auto energy = [&](const Vec3& x) {
    Eigen::Matrix3d H;
    const auto q = s.smooth_distance(x, sigma, &H);
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
  }
  EXPECT_GT(active, 100);
}

TEST(SurfaceContact, SmoothDistanceGradientAndHessianMatchFiniteDifferences) {
  // d_σ itself, inside and outside, near faces, edges and vertices, and beyond the open ends.
  const double R = 3e-3;
  const auto s = faceted_tube(16, 20, R, 40e-3);
  const double sigma = 0.5 * mean_edge(s);
  std::mt19937 rng(5);
  // Within the depth the contact evaluates (deeper, weights below e⁻¹⁰ of the largest are
  // dropped: jumps of ~1e-11 m, which finite differences over 1e-8 m would see).
  std::uniform_real_distribution<double> ang(0.0, 2.0 * M_PI), rho(0.5 * R, 1.3 * R), z(-24e-3, 24e-3);
  for (int t = 0; t < 200; ++t) {
    const double th = ang(rng), r = rho(rng);
    const Vec3 x(r * std::cos(th), r * std::sin(th), z(rng));
    Eigen::Matrix3d H;
    const auto q = s.smooth_distance(x, sigma, &H);
    EXPECT_LT((H - H.transpose()).norm(), 1e-9 * (1.0 + H.norm()));
    const double h = 1e-8;
    for (int c = 0; c < 3; ++c) {
      const Vec3 e = Vec3::Unit(c);
      const auto qp = s.smooth_distance(x + h * e, sigma), qm = s.smooth_distance(x - h * e, sigma);
      EXPECT_NEAR((qp.distance - qm.distance) / (2 * h), q.gradient[c], 1e-6) << "at " << x.transpose();
      EXPECT_LT(((qp.gradient - qm.gradient) / (2 * h) - H.col(c)).norm(), 1e-4 * (1.0 + H.norm())) << "column " << c;
    }
  }
}

TEST(SurfaceContact, SmoothDistanceIsContinuousWhereTheExactGradientJumps) {
  const double R = 3e-3;
  const auto s = faceted_tube(16, 20, R, 40e-3);
  const double sigma = 0.5 * mean_edge(s);
  // Across the bisector of two faces, at depth 0.5 mm: the exact gradient jumps by the facet
  // angle 2π/16; the smooth one turns continuously.
  double max_jump_exact = 0.0, max_jump_smooth = 0.0;
  const double r = R - 0.5e-3;
  Vec3 g0e = Vec3::Zero(), g0s = Vec3::Zero();
  for (int i = 0; i <= 2000; ++i) {
    const double th = 2.0 * M_PI / 16 * (i / 2000.0);
    const Vec3 x(r * std::cos(th), r * std::sin(th), 0.3e-3);
    const auto e = s.distance(x);
    const auto m = s.smooth_distance(x, sigma);
    if (i > 0) {
      max_jump_exact = std::max(max_jump_exact, (e.gradient - g0e).norm());
      max_jump_smooth = std::max(max_jump_smooth, (m.gradient - g0s).norm());
    }
    g0e = e.gradient, g0s = m.gradient;
  }
  EXPECT_GT(max_jump_exact, 0.15);   // one face normal to the next (the rings are staggered)
  EXPECT_LT(max_jump_smooth, 0.02);  // over a step of 2π/16/2000 rad
}

TEST(SurfaceContact, SmoothDistanceIsExactAboveAPlaneAtAnyHeight) {
  // A soft minimum over triangles sees a plane earlier the farther the point is (more
  // triangles lie nearly as near); the plane's implicit surface is the plane itself.
  vessels::SurfaceMesh mesh;
  const int n = 30;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.3e-3, 0.3e-3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      mesh.vertices.emplace_back(1e-3 * i + (i % n ? jitter(rng) : 0.0), 1e-3 * j + (j % n ? jitter(rng) : 0.0), 0.0);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      mesh.triangles.push_back({a, c, b});
      mesh.triangles.push_back({b, c, d});
    }
  mesh.source = "plane";
  const vessels::LumenSurface s(std::move(mesh), {Vec3(15e-3, 15e-3, 1e-3)});
  for (const double h : {0.1e-3, 0.5e-3, 2e-3, 5e-3}) {
    const auto q = s.smooth_distance(Vec3(14.3e-3, 15.2e-3, h), 0.5e-3);
    EXPECT_NEAR(q.distance, -h, 1e-15) << h;
    EXPECT_LT((q.gradient - Vec3(0, 0, -1)).norm(), 1e-12);
  }
}

TEST(SurfaceContact, SmoothDistanceConvergesToTheCylinderAtSecondOrder) {
  // Tubes of radius R with n facets around and rings as far apart as the facets are wide,
  // σ half the mean edge: d_σ against the analytic distance r − R of the smooth cylinder the
  // vertices lie on. Facets (sagitta R(1 − cos π/n)) and smoothing (σ²/R) are both O(ℓ²).
  const double R = 3e-3;
  std::vector<double> h, err;
  for (const int n : {12, 24, 48, 96}) {
    const double width = 2.0 * M_PI * R / n, L = 12e-3;
    const int rings = static_cast<int>(std::lround(L / width));
    const auto s = faceted_tube(n, rings, R, L);
    const double sigma = 0.5 * mean_edge(s);
    double worst = 0.0;
    for (int i = 0; i < 400; ++i) {
      const double th = 2.0 * M_PI * i / 400.0 * 1.013, z = -2e-3 + 4e-3 * i / 400.0;
      for (const double depth : {0.2e-3, 0.5e-3, 1e-3}) {
        const double r = R - depth;
        worst = std::max(
            worst, std::abs(s.smooth_distance(Vec3(r * std::cos(th), r * std::sin(th), z), sigma).distance + depth));
      }
    }
    h.push_back(mean_edge(s));
    err.push_back(worst);
  }
  const double slope = flowire::testing::loglog_slope(h, err);
  EXPECT_GT(slope, 1.8) << "errors " << err[0] << " " << err[1] << " " << err[2] << " " << err[3];
  EXPECT_LT(slope, 2.3);
  EXPECT_LT(err.back(), 0.02 * err.front());
}

TEST(SurfaceContact, KeptNeighbourhoodAnswersAsAFreshQueryAlongAWanderingPath) {
  // A vertex's kept triangles (SurfaceNeighbourhood) must give the answer of a fresh query,
  // whether the point barely moves (Newton iterates), moves within the margin, or jumps
  // beyond it (rebuild) — on the faceted tube and beyond the open ends.
  const double R = 3e-3, margin = 0.3e-3;
  const auto s = faceted_tube(16, 20, R, 40e-3);
  const double sigma = 0.5 * mean_edge(s);
  std::mt19937 rng(7);
  std::normal_distribution<double> step(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  vessels::SurfaceNeighbourhood near[2];  // one per smoothing width
  Vec3 x(R - 0.4e-3, 0.0, 0.0);
  int rebuilt = 0, reused = 0;
  Vec3 last_centre = Vec3::Constant(1e9);
  for (int t = 0; t < 3000; ++t) {
    const double scale = unit(rng) < 0.1 ? 1.5e-3 : (unit(rng) < 0.5 ? 1e-6 : 0.1e-3);
    x += scale * Vec3(step(rng), step(rng), step(rng));
    const double rho = std::hypot(x.x(), x.y());
    if (rho > R + 0.3e-3) x.head<2>() *= (R + 0.3e-3) / rho;
    x.z() = std::clamp(x.z(), -22e-3, 22e-3);
    for (int k = 0; k < 2; ++k) {
      const double w = k == 0 ? sigma : 0.0;
      Eigen::Matrix3d H_kept, H_fresh;
      const auto kept = s.smooth_distance(x, w, near[k], margin, &H_kept);
      const auto fresh = s.smooth_distance(x, w, &H_fresh);
      EXPECT_NEAR(kept.distance, fresh.distance, 1e-15) << "step " << t;
      EXPECT_LT((kept.gradient - fresh.gradient).norm(), 1e-12);
      EXPECT_LT((H_kept - H_fresh).norm(), 1e-9 * (1.0 + H_fresh.norm()));
      const auto brute = s.distance_brute_force(x);
      if (k == 1) {
        EXPECT_NEAR(kept.distance, brute.distance, 1e-15);  // σ = 0: exact
      }
      // The exact distance from the kept triangles (or the hierarchy where they may not hold
      // the nearest) is every triangle's.
      const auto listed = s.distance(x, near[k]);
      EXPECT_EQ(listed.triangle, brute.triangle) << "step " << t;
      EXPECT_NEAR(listed.distance, brute.distance, 1e-15);
    }
    ((near[0].centre - last_centre).norm() > 0.0 ? rebuilt : reused) += 1;
    last_centre = near[0].centre;
  }
  EXPECT_GT(rebuilt, 100) << reused;
  EXPECT_GT(reused, 100);
}

TEST(SurfaceContact, SkippedDeepVerticesHaveNoContactOnTheRealLumens) {
  // The contact evaluates d_σ only for vertices within surface_skip_depth of the wall by the
  // exact distance. That is exact only if d_σ < −a wherever d < −skip: checked on points at
  // every depth below each real surface's triangles (inwards along their normals), with the
  // default σ. Also reported: how far d_σ lies from d within a wire radius of the wall.
  FLOWIRE_REQUIRE_SHARED("data/real/feelpp-aortic-arch/aorta2.stl");
  const auto shared = flowire::testing::shared_dir() / "data/real";
  struct Mesh {
    const char* file;
    double factor;
    double a;  // the example scene's wire radius
  };
  for (const Mesh& m : {Mesh{"feelpp-aortic-arch/aorta2.stl", 1e-2, 0.445e-3},
                        Mesh{"vmtk-abdominal-aorta-bifurcation/aorta-surface.vtp", 1e-3, 0.445e-3},
                        Mesh{"simvascular-demo-aorta-iliac/model_surface.vtp", 1e-2, 0.445e-3},
                        Mesh{"aneurisk-c0015-ica-vampy/artery.vtp", 1e-3, 0.178e-3}}) {
    if (!std::filesystem::exists(shared / m.file)) continue;
    auto mesh = vessels::read_surface((shared / m.file).string(), m.factor);
    // Orientation from a point inside: the surface's own enclosed-volume rule.
    const vessels::LumenSurface s(std::move(mesh));
    const double sigma = coupling::default_surface_smoothing(s);
    const double skip = coupling::surface_skip_depth(m.a, sigma);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const auto& tri = s.triangles();
    const auto& v = s.vertices();
    // Folds: a triangle at more than 45° to the mean of its vertices' (area-weighted) normals
    // (10 of 7,485 on the AneuRisk carotid, 14 of 18,584 on the SimVascular aorta, none on
    // the others). Above one, the exact distance's sign is that one triangle's: a point
    // "inside" by it lies outside its neighbours' planes. Not sampled.
    std::vector<Vec3> vertex_normal(v.size(), Vec3::Zero());
    for (const auto& t : tri) {
      const Vec3 area = (v[static_cast<size_t>(t[1])] - v[static_cast<size_t>(t[0])])
                            .cross(v[static_cast<size_t>(t[2])] - v[static_cast<size_t>(t[0])]);
      for (int k : t) vertex_normal[static_cast<size_t>(k)] += area;
    }
    int checked = 0, near_wall = 0;
    double worst_band = 0.0, worst_deep = -1.0;
    for (size_t f = 0; f < tri.size(); f += 7) {
      const Vec3 A = v[static_cast<size_t>(tri[f][0])], B = v[static_cast<size_t>(tri[f][1])],
                 C = v[static_cast<size_t>(tri[f][2])];
      double b1 = unit(rng), b2 = unit(rng);
      if (b1 + b2 > 1.0) b1 = 1.0 - b1, b2 = 1.0 - b2;
      const Vec3 p = A + b1 * (B - A) + b2 * (C - A);
      const Vec3 nrm = (B - A).cross(C - A).normalized();
      Vec3 around = Vec3::Zero();
      for (int k : tri[f]) around += vertex_normal[static_cast<size_t>(k)].normalized();
      if (nrm.dot(around.normalized()) < std::cos(M_PI / 4)) continue;
      const double depth = (2.0 * skip) * unit(rng);
      const Vec3 x = p - depth * nrm;
      const auto e = s.distance(x);
      if (e.open || e.distance > 0.0) continue;  // beyond an open end, or through a thin wall
      const double ds = s.smooth_distance(x, sigma).distance;
      ++checked;
      if (e.distance < -skip) worst_deep = std::max(worst_deep, ds + m.a);  // must stay < 0
      if (e.distance > -m.a) ++near_wall, worst_band = std::max(worst_band, std::abs(ds - e.distance));
    }
    EXPECT_GT(checked, 200) << m.file;
    EXPECT_LT(worst_deep, 0.0) << m.file << ": a skipped vertex would touch the wall (d_σ + a = " << worst_deep
                               << " m)";
    std::printf(
        "%s: σ %.3f mm, skip band %.3f mm; max |d_σ − d| within a wire radius of the wall %.4f mm (%d points); "
        "deepest skipped d_σ + a = %.3f mm\n",
        m.file, 1e3 * sigma, 1e3 * skip, 1e3 * worst_band, near_wall, 1e3 * worst_deep);
  }
}
