// Rod energies: gradients and Hessians against finite differences of the energy values,
// over generic and near-degenerate stencils (straight rod, short edge, sharp bend).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <string>

#include "flowire/rod/energies.hpp"
#include "flowire_test.hpp"

namespace flowire::rod {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

/// Unpack the 11 stencil unknowns (x0, θe, x1, θf, x2) into a copy of `base`.
VertexStencil with_unknowns(const VertexStencil& base, const Vec11& q) {
  VertexStencil s = base;
  s.x0 = q.segment<3>(0);
  s.theta_e = q(3);
  s.x1 = q.segment<3>(4);
  s.theta_f = q(7);
  s.x2 = q.segment<3>(8);
  return s;
}

Vec11 unknowns(const VertexStencil& s) {
  Vec11 q;
  q << s.x0, s.theta_e, s.x1, s.theta_f, s.x2;
  return q;
}

/// Reference frame with tangent t, rotated by `angle` from an arbitrary perpendicular.
EdgeFrame frame_for(const Vec3& t, double angle) {
  const Vec3 trial = std::abs(t.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 a = (trial - t * t.dot(trial)).normalized();
  const Vec3 b = t.cross(a);
  EdgeFrame f;
  f.d1 = std::cos(angle) * a + std::sin(angle) * b;
  f.d2 = t.cross(f.d1);
  return f;
}

/// A stencil whose frames are up to date (base point), with random angles.
VertexStencil make_stencil(const Vec3& x0, const Vec3& x1, const Vec3& x2, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  VertexStencil s;
  s.x0 = x0;
  s.x1 = x1;
  s.x2 = x2;
  s.theta_e = u(rng);
  s.theta_f = u(rng);
  s.frame_e = frame_for((x1 - x0).normalized(), u(rng));
  s.frame_f = frame_for((x2 - x1).normalized(), u(rng));
  const double k = std::round(u(rng));  // a few full turns of accumulated reference twist
  s.ref_twist = reference_twist(s.frame_e.d1, (x1 - x0).normalized(), s.frame_f.d1, (x2 - x1).normalized(),
                                2.0 * std::numbers::pi * k);
  return s;
}

VertexParams make_params(std::mt19937& rng, double voronoi) {
  std::uniform_real_distribution<double> u(0.5, 2.0);
  std::uniform_real_distribution<double> k(-0.5, 0.5);
  VertexParams p;
  p.bend_stiffness1 = u(rng);
  p.bend_stiffness2 = u(rng);  // anisotropic on purpose
  p.rest_kappa1 = k(rng);
  p.rest_kappa2 = k(rng);
  p.twist_stiffness = u(rng);
  p.rest_twist = k(rng);
  p.voronoi_length = voronoi;
  return p;
}

Vec11 fd_gradient(const std::function<double(const Vec11&)>& E, const Vec11& q, double h) {
  Vec11 g;
  for (int i = 0; i < 11; ++i) {
    Vec11 a = q, b = q;
    a(i) += h;
    b(i) -= h;
    g(i) = (E(a) - E(b)) / (2.0 * h);
  }
  return g;
}

Mat11 fd_hessian(const std::function<double(const Vec11&)>& E, const Vec11& q, double h) {
  Mat11 H;
  for (int i = 0; i < 11; ++i) {
    for (int j = i; j < 11; ++j) {
      auto at = [&](double si, double sj) {
        Vec11 a = q;
        a(i) += si * h;
        a(j) += sj * h;
        return E(a);
      };
      H(i, j) = (at(1, 1) - at(1, -1) - at(-1, 1) + at(-1, -1)) / (4.0 * h * h);
      H(j, i) = H(i, j);
    }
  }
  return H;
}

void check_stencil(const VertexStencil& s, const VertexParams& p, double h, double rtol, const std::string& name) {
  SCOPED_TRACE(name);
  const Vec11 q = unknowns(s);
  auto Eb = [&](const Vec11& y) { return bend_energy(with_unknowns(s, y), p); };
  auto Et = [&](const Vec11& y) { return twist_energy(with_unknowns(s, y), p); };

  const Vec11 gb = bend_gradient(s, p);
  const Vec11 gb_fd = fd_gradient(Eb, q, h);
  EXPECT_LE((gb - gb_fd).norm(), rtol * (1.0 + gb_fd.norm())) << "bend gradient\n"
                                                              << gb.transpose() << "\n"
                                                              << gb_fd.transpose();
  const Mat11 Hb = bend_hessian(s, p);
  const Mat11 Hb_fd = fd_hessian(Eb, q, h);
  EXPECT_LE((Hb - Hb_fd).norm(), rtol * (1.0 + Hb_fd.norm())) << "bend Hessian\n" << Hb << "\n---\n" << Hb_fd;

  const Vec11 gt = twist_gradient(s, p);
  const Vec11 gt_fd = fd_gradient(Et, q, h);
  EXPECT_LE((gt - gt_fd).norm(), rtol * (1.0 + gt_fd.norm())) << "twist gradient\n"
                                                              << gt.transpose() << "\n"
                                                              << gt_fd.transpose();
  const Mat11 Ht = twist_hessian(s, p);
  const Mat11 Ht_fd = fd_hessian(Et, q, h);
  EXPECT_LE((Ht - Ht_fd).norm(), rtol * (1.0 + Ht_fd.norm())) << "twist Hessian\n" << Ht << "\n---\n" << Ht_fd;

  // The combined kernel agrees with the separate ones.
  Vec11 g;
  Mat11 H;
  const double e = bend_twist(s, p, &g, &H);
  EXPECT_NEAR(e, bend_energy(s, p) + twist_energy(s, p), 1e-12 * (1.0 + std::abs(e)));
  EXPECT_LE((g - gb - gt).norm(), 1e-10 * (1.0 + g.norm()));
  EXPECT_LE((H - Hb - Ht).norm(), 1e-10 * (1.0 + H.norm()));
  // The simulator's path from precomputed edge geometry gives the same results.
  const EdgeGeometry ge = edge_geometry(s.x0, s.x1, s.frame_e, s.theta_e);
  const EdgeGeometry gf = edge_geometry(s.x1, s.x2, s.frame_f, s.theta_f);
  Vec11 g2;
  Mat11 H2;
  const double e2 = bend_twist(ge, gf, s.theta_e, s.theta_f, s.ref_twist, p, &g2, &H2);
  EXPECT_NEAR(e2, e, 1e-12 * (1.0 + std::abs(e)));
  EXPECT_LE((g2 - g).norm(), 1e-10 * (1.0 + g.norm()));
  EXPECT_LE((H2 - H).norm(), 1e-10 * (1.0 + H.norm()));
  // Hessians are symmetric.
  EXPECT_LE((H - H.transpose()).norm(), 1e-10 * (1.0 + H.norm()));
}

TEST(RodEnergies, StretchMatchesFiniteDifferences) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec3 x0(n(rng), n(rng), n(rng));
    const Vec3 x1 = x0 + Vec3(n(rng), n(rng), n(rng));
    const double ks = 3.0, rest = 0.5 + 0.1 * trial;  // both stretched and compressed
    Vec6 q;
    q << x0, x1;
    auto E = [&](const Vec6& y) { return stretch_energy(y.head<3>(), y.tail<3>(), ks, rest); };
    const double h = 1e-6;
    Vec6 g_fd;
    Mat6 H_fd;
    for (int i = 0; i < 6; ++i) {
      Vec6 a = q, b = q;
      a(i) += h;
      b(i) -= h;
      g_fd(i) = (E(a) - E(b)) / (2 * h);
      const Vec6 ga = stretch_gradient(a.head<3>(), a.tail<3>(), ks, rest);
      const Vec6 gb = stretch_gradient(b.head<3>(), b.tail<3>(), ks, rest);
      H_fd.col(i) = (ga - gb) / (2 * h);
    }
    EXPECT_LE((stretch_gradient(x0, x1, ks, rest) - g_fd).norm(), 1e-7 * (1 + g_fd.norm()));
    EXPECT_LE((stretch_hessian(x0, x1, ks, rest) - H_fd).norm(), 1e-6 * (1 + H_fd.norm()));
  }
}

TEST(RodEnergies, ParallelTransportIsMinimalRotation) {
  const Vec3 a = Vec3(1, 2, 3).normalized();
  const Vec3 b = Vec3(-2, 0.5, 1).normalized();
  const Vec3 u = a.cross(Vec3::UnitZ()).normalized();
  const Vec3 v = parallel_transport(u, a, b);
  EXPECT_NEAR(v.norm(), 1.0, 1e-14);
  EXPECT_NEAR(v.dot(b), 0.0, 1e-14);
  EXPECT_NEAR((parallel_transport(a, a, b) - b).norm(), 0.0, 1e-14);
  // The axis a × b is left unchanged.
  const Vec3 axis = a.cross(b);
  EXPECT_NEAR((parallel_transport(axis, a, b) - axis).norm(), 0.0, 1e-14);
  // Antiparallel: still a rotation taking a to −a.
  EXPECT_NEAR((parallel_transport(a, a, -a) + a).norm(), 0.0, 1e-12);
}

TEST(RodEnergies, CurvatureOfAnArcIsTwoTanHalfAngle) {
  const double phi = 0.7;
  const Vec3 te = Vec3::UnitX();
  const Vec3 tf(std::cos(phi), std::sin(phi), 0.0);
  EXPECT_NEAR(curvature_binormal(te, tf).z(), 2.0 * std::tan(phi / 2.0), 1e-14);
}

TEST(RodEnergies, BendTwistGenericStencils) {
  std::mt19937 rng(42);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec3 x0(n(rng), n(rng), n(rng));
    const Vec3 x1 = x0 + Vec3(1.0 + 0.2 * n(rng), 0.3 * n(rng), 0.3 * n(rng));
    const Vec3 x2 = x1 + Vec3(1.0 + 0.2 * n(rng), 0.6 * n(rng), 0.6 * n(rng));
    const VertexStencil s = make_stencil(x0, x1, x2, rng);
    check_stencil(s, make_params(rng, 1.1), 1e-4, 2e-6, "generic " + std::to_string(trial));
  }
}

TEST(RodEnergies, BendTwistStraightRod) {
  std::mt19937 rng(3);
  const Vec3 d = Vec3(1, -2, 0.5).normalized();
  const VertexStencil s = make_stencil(Vec3::Zero(), d, 2.0 * d, rng);
  check_stencil(s, make_params(rng, 1.0), 1e-4, 2e-6, "straight");
  VertexParams p = make_params(rng, 1.0);
  p.rest_kappa1 = p.rest_kappa2 = 0.0;
  p.rest_twist = 0.0;
  VertexStencil s0 = s;
  s0.theta_f = s0.theta_e - s0.ref_twist;  // untwisted
  check_stencil(s0, p, 1e-4, 2e-6, "straight at rest");
}

TEST(RodEnergies, BendTwistShortEdge) {
  std::mt19937 rng(5);
  const Vec3 x0(0, 0, 0), x1(1e-3, 2e-4, -1e-4), x2(1.5, 0.7, 0.2);
  const VertexStencil s = make_stencil(x0, x1, x2, rng);
  check_stencil(s, make_params(rng, 0.75), 1e-7, 2e-5, "short edge");
}

TEST(RodEnergies, BendTwistSharpBend) {
  std::mt19937 rng(11);
  for (double deg : {150.0, 170.0, 178.0}) {
    const double phi = deg * std::numbers::pi / 180.0;  // turning angle
    const Vec3 x0(-1, 0, 0), x1(0, 0, 0);
    const Vec3 x2 = x1 + Vec3(std::cos(phi), std::sin(phi), 0.1);
    const VertexStencil s = make_stencil(x0, x1, x2, rng);
    const double h = 1e-4 * (std::numbers::pi - phi);
    check_stencil(s, make_params(rng, 1.0), h, 5e-5, "sharp bend " + std::to_string(deg));
  }
}

}  // namespace
}  // namespace flowire::rod
