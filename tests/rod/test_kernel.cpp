// The bend/twist stencil kernel the simulator assembles with (bend_twist) against the
// straightforward evaluations of the same energy: the dense y-space reference
// (detail::bend_twist_reference) and the separate bend_* / twist_* functions, to round-off,
// on random stencils from nearly straight to sharply bent, for the exact and the
// Gauss–Newton Hessian.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "flowire/rod/energies.hpp"

namespace flowire::rod {
namespace {

/// A unit vector perpendicular to t, rotated by `angle` about t.
Vec3 perpendicular(const Vec3& t, double angle) {
  const Vec3 trial = std::abs(t.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 a = (trial - t * t.dot(trial)).normalized();
  return std::cos(angle) * a + std::sin(angle) * t.cross(a);
}

EdgeFrame frame_for(const Vec3& t, double angle) {
  EdgeFrame f;
  f.d1 = perpendicular(t, angle);
  f.d2 = t.cross(f.d1);
  return f;
}

struct Case {
  VertexStencil s;
  VertexParams p;
};

/// A stencil with edges of length ~`h` turning by `turn` radians, at the base point,
/// with random twist angles, rest curvatures and stiffnesses of a guidewire's magnitude.
Case random_case(std::mt19937& rng, double turn, double h) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Case c;
  const Vec3 te = Vec3(u(rng), u(rng), u(rng)).normalized();
  const Vec3 axis = perpendicular(te, 3.0 * u(rng));
  const Vec3 tf = Eigen::AngleAxisd(turn, axis) * te;
  c.s.x0 = Vec3(u(rng), u(rng), u(rng));
  c.s.x1 = c.s.x0 + h * (1.0 + 0.3 * u(rng)) * te;
  c.s.x2 = c.s.x1 + h * (1.0 + 0.3 * u(rng)) * tf;
  c.s.theta_e = 3.0 * u(rng);
  c.s.theta_f = 3.0 * u(rng);
  c.s.frame_e = frame_for((c.s.x1 - c.s.x0).normalized(), 3.0 * u(rng));
  c.s.frame_f = frame_for((c.s.x2 - c.s.x1).normalized(), 3.0 * u(rng));
  c.s.ref_twist = reference_twist(c.s.frame_e.d1, (c.s.x1 - c.s.x0).normalized(), c.s.frame_f.d1,
                                  (c.s.x2 - c.s.x1).normalized(), 2.0 * std::numbers::pi * std::round(2.0 * u(rng)));
  const double ei = 1e-3 * (1.0 + 0.5 * u(rng));
  c.p.bend_stiffness1 = ei;
  c.p.bend_stiffness2 = ei * (1.0 + 0.5 * u(rng));  // anisotropic on purpose
  c.p.rest_kappa1 = 0.5 * u(rng) * turn;
  c.p.rest_kappa2 = 0.5 * u(rng) * turn;
  c.p.twist_stiffness = 0.8 * ei;
  c.p.rest_twist = 0.2 * u(rng);
  c.p.voronoi_length = h;
  return c;
}

double rel(const auto& a, const auto& b) { return (a - b).norm() / std::max(b.norm(), 1e-300); }

void check(const Case& c, const std::string& name) {
  SCOPED_TRACE(name);
  const VertexStencil& s = c.s;
  const VertexParams& p = c.p;
  const EdgeGeometry ge = edge_geometry(s.x0, s.x1, s.frame_e, s.theta_e);
  const EdgeGeometry gf = edge_geometry(s.x1, s.x2, s.frame_f, s.theta_f);
  constexpr double tol = 1e-12;
  for (const bool gn : {false, true}) {
    SCOPED_TRACE(gn ? "Gauss-Newton" : "exact");
    Vec11 g, g_ref;
    Mat11 H, H_ref;
    const double e = bend_twist(ge, gf, s.theta_e, s.theta_f, s.ref_twist, p, &g, &H, gn);
    const double e_ref = detail::bend_twist_reference(ge, gf, s.theta_e, s.theta_f, s.ref_twist, p, &g_ref, &H_ref, gn);
    EXPECT_LE(std::abs(e - e_ref), tol * std::abs(e_ref));
    EXPECT_LE(rel(g, g_ref), tol);
    EXPECT_LE(rel(H, H_ref), tol);
    EXPECT_EQ((H - H.transpose()).norm(), 0.0);  // written symmetric by construction
    // Gradient only, and value only, give the same numbers as with the Hessian.
    Vec11 g_only;
    EXPECT_EQ(bend_twist(ge, gf, s.theta_e, s.theta_f, s.ref_twist, p, &g_only, nullptr, gn), e);
    EXPECT_EQ((g_only - g).norm(), 0.0);
    EXPECT_EQ(bend_twist(ge, gf, s.theta_e, s.theta_f, s.ref_twist, p, nullptr, nullptr, gn), e);
    // The stencil overload is the same kernel.
    Vec11 g_s;
    Mat11 H_s;
    EXPECT_LE(std::abs(bend_twist(s, p, &g_s, &H_s, gn) - e), tol * std::abs(e));
    EXPECT_LE(rel(g_s, g), tol);
    EXPECT_LE(rel(H_s, H), tol);
  }
  // The separate functions (exact Hessian).
  Vec11 g;
  Mat11 H;
  const double e = bend_twist(ge, gf, s.theta_e, s.theta_f, s.ref_twist, p, &g, &H);
  EXPECT_LE(std::abs(e - bend_energy(s, p) - twist_energy(s, p)), tol * std::abs(e));
  EXPECT_LE(rel(g, Vec11(bend_gradient(s, p) + twist_gradient(s, p))), tol);
  EXPECT_LE(rel(H, Mat11(bend_hessian(s, p) + twist_hessian(s, p))), tol);
}

TEST(RodKernel, MatchesReferenceOnRandomStencils) {
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> turn(0.0, 2.5);
  for (int i = 0; i < 200; ++i) {
    check(random_case(rng, turn(rng), 1e-3), "guidewire scale " + std::to_string(i));
    check(random_case(rng, turn(rng), 1.0), "unit scale " + std::to_string(i));
  }
}

TEST(RodKernel, MatchesReferenceNearlyStraight) {
  std::mt19937 rng(7);
  for (const double turn : {0.0, 1e-12, 1e-9, 1e-6, 1e-3}) {
    for (int i = 0; i < 20; ++i)
      check(random_case(rng, turn, 1e-3), "turn " + std::to_string(turn) + " #" + std::to_string(i));
  }
}

TEST(RodKernel, MatchesReferenceSharplyBent) {
  std::mt19937 rng(11);
  for (const double deg : {150.0, 170.0, 175.0, 178.0}) {
    for (int i = 0; i < 20; ++i)
      check(random_case(rng, deg * std::numbers::pi / 180.0, 1e-3), std::to_string(deg) + " deg #" + std::to_string(i));
  }
}

}  // namespace
}  // namespace flowire::rod
