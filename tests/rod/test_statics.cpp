// Static solves against analytic references (../shared/reference/README.md, "Rods"):
// elastica cantilever (Bisshopp–Drucker), end moment closing a circle, uniform torsion,
// Euler buckling of a clamped–free column, small-deflection Euler–Bernoulli.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "flowire/rod/simulator.hpp"
#include "flowire_test.hpp"
#include "rod_test_util.hpp"

namespace flowire::rod {
namespace {

using testing::tol;

struct ElasticaRef {
  double alpha, deflection, shortening;
};
// Bisshopp–Drucker, from the shared reference table: δ/L and (L − x)/L.
constexpr ElasticaRef kElastica[] = {{1.0, 0.30172, 0.05643}, {5.0, 0.71379, 0.38763}, {10.0, 0.81061, 0.55500}};

/// Tip (x along the rod, y along the load) of a unit cantilever with EI = 1 under PL²/EI = α.
Eigen::Vector2d cantilever_tip(double alpha, int segments) {
  WireSpec spec = unit_rod_spec(segments);
  RodSimulator sim(spec);
  sim.set_tip_force({0.0, alpha, 0.0});
  sim.settings().static_load_steps = alpha > 5 ? 2 : 1;
  const StepReport r = sim.solve_static();
  EXPECT_TRUE(r.converged()) << to_string(r.status);
  const Eigen::Vector3d tip = sim.tip_position();
  return {tip.x(), tip.y()};
}

TEST(RodStatics, ElasticaCantileverWithinHalfPercentAt50Segments) {
  for (const auto& ref : kElastica) {
    SCOPED_TRACE(ref.alpha);
    const Eigen::Vector2d tip = cantilever_tip(ref.alpha, 50);
    EXPECT_NEAR(tip.y(), ref.deflection, tol(0.005));
    EXPECT_NEAR(1.0 - tip.x(), ref.shortening, tol(0.005));
  }
}

TEST(RodStatics, ElasticaErrorFallsAsHSquared) {
  for (const auto& ref : kElastica) {
    SCOPED_TRACE(ref.alpha);
    std::vector<double> hs, errs;
    for (int n : {20, 40, 80}) {
      const Eigen::Vector2d tip = cantilever_tip(ref.alpha, n);
      const double err = std::hypot(tip.y() - ref.deflection, 1.0 - tip.x() - ref.shortening);
      hs.push_back(1.0 / n);
      errs.push_back(err);
    }
    const double slope = loglog_slope(hs, errs);
    EXPECT_GT(slope, 1.8) << "errors " << errs[0] << " " << errs[1] << " " << errs[2];
    EXPECT_LT(slope, 2.3);
  }
}

TEST(RodStatics, ClampReactionBalancesTipLoad) {
  RodSimulator sim(unit_rod_spec(40));
  sim.set_tip_force({0.0, 5.0, 0.0});
  ASSERT_TRUE(sim.solve_static().converged());
  EXPECT_NEAR(sim.base_force().y(), -5.0, 1e-6);
  EXPECT_NEAR(sim.base_force().x(), 0.0, 1e-6);
  // Moment about the entry point: the clamp balances r_tip × P.
  const Eigen::Vector3d m = sim.tip_position().cross(Eigen::Vector3d(0, 5, 0));
  EXPECT_NEAR(sim.base_torque().z(), -m.z(), 1e-6);
}

TEST(RodStatics, SmallDeflectionMatchesEulerBernoulli) {
  // Reference README: L = 3, r = 0.25, E = 1e6, F = 15 → F L³/(3EI) = 0.044003.
  WireSpec spec;
  spec.length = 3.0;
  spec.radius = 0.25;
  spec.youngs_modulus = 1e6;
  spec.density = 1000.0;
  spec.segments = 100;
  spec.tip.length = 0.0;
  spec.stretch_stiffness = 1e12;
  RodSimulator sim(spec);
  sim.set_tip_force({0.0, -15.0, 0.0});
  ASSERT_TRUE(sim.solve_static().converged());
  // Geometric nonlinearity shortens the deflection by O((δ/L)²) ≈ 1e-4 relative.
  EXPECT_NEAR(-sim.tip_position().y(), 0.044003, tol(0.044003 * 0.005));
}

TEST(RodStatics, TheCantileverIsAsLongAsTheInsertedLengthBetweenGridPoints) {
  // The clamp holds the wire at the entry whatever the inserted length: a cantilever inserted a
  // fraction of a segment past a grid point bends as F L³/(3EI) of its own length L, to the
  // scheme's O(h²) (a clamp vertex on the grid would hold it up to a segment behind the entry:
  // (1 + h/L)³ − 1, up to 30% at 5 cm segments, an O(h) sawtooth in L). Unit rod, L from 0.50
  // to 0.60 m in 5 mm steps, a load small enough for Euler–Bernoulli (δ/L ≈ 3·10⁻⁵); the worst
  // error over L at 5, 2.5 and 1.25 cm segments.
  std::vector<double> h, worst;
  for (const int segments : {20, 40, 80}) {
    double w = 0.0;
    for (int i = 0; i <= 20; ++i) {
      const double L = 0.5 + 0.005 * i;
      WireSpec spec = unit_rod_spec(segments);
      spec.inserted_length = L;
      RodSimulator sim(spec);
      const double force = 1e-4;
      sim.set_tip_force({0.0, force, 0.0});
      ASSERT_TRUE(sim.solve_static().converged()) << L;
      w = std::max(w, std::abs(sim.tip_position().y() / (force * L * L * L / 3.0) - 1.0));
    }
    h.push_back(1.0 / segments);
    worst.push_back(w);
  }
  const double slope = loglog_slope(h, worst);
  std::printf("worst |δ/δ_EB − 1| over L: %.2e, %.2e, %.2e (slope %.2f)\n", worst[0], worst[1], worst[2], slope);
  RecordProperty("slope", std::to_string(slope));
  EXPECT_LT(worst[0], 6e-3);
  EXPECT_GT(slope, 1.9);
}

TEST(RodStatics, GravityAndPointForceMatchBeamTheory) {
  // Small deflections of the unit cantilever (EI = ρA = L = 1): a uniform load q gives a
  // tip deflection qL⁴/(8EI); a point load P at distance a from the clamp gives
  // P a² (3L − a)/(6EI) at the tip.
  {
    RodSimulator sim(unit_rod_spec(100));
    const double g = 1e-3;
    sim.set_gravity({0.0, -g, 0.0});
    ASSERT_TRUE(sim.solve_static().converged());
    EXPECT_NEAR(-sim.tip_position().y(), g / 8.0, tol(0.002 * g / 8.0));
    // The clamp carries the weight of every simulated vertex (the free wire and the stub).
    double mass = 0.0;
    for (int k = 0; k < sim.vertex_count(); ++k) mass += sim.discretization().mass[k];
    EXPECT_NEAR(sim.base_force().y(), g * mass, 1e-6 * g);
  }
  {
    RodSimulator sim(unit_rod_spec(100));
    const double P = 1e-3, a = 0.4;
    sim.add_point_force(a, {0.0, P, 0.0});  // s measured from the entry
    ASSERT_TRUE(sim.solve_static().converged());
    EXPECT_NEAR(sim.tip_position().y(), P * a * a * (3.0 - a) / 6.0, tol(0.002 * P * a * a * (3.0 - a) / 6.0));
  }
}

TEST(RodStatics, EndMomentClosesACircle) {
  const int n = 100;
  RodSimulator sim(unit_rod_spec(n));
  const double M = 2.0 * std::numbers::pi;  // 2π EI / L with EI = L = 1
  sim.set_tip_moment({0.0, 0.0, M});
  sim.settings().static_load_steps = 8;
  const StepReport r = sim.solve_static();
  ASSERT_TRUE(r.converged()) << to_string(r.status);
  // The tip returns to the clamp; every vertex lies on a circle of radius L/(2π).
  EXPECT_LT(sim.tip_position().norm(), tol(0.005));
  const double R = 1.0 / (2.0 * std::numbers::pi);
  const Eigen::Vector3d center(0.0, R, 0.0);
  double worst = 0.0;
  for (int k = 0; k <= sim.first_clamped_vertex(); ++k)
    worst = std::max(worst, std::abs((sim.positions()[k] - center).norm() - R));
  EXPECT_LT(worst / R, tol(0.005));
}

TEST(RodStatics, TorsionAngleIsTLOverGJ) {
  WireSpec spec = unit_rod_spec(30);
  spec.twist_stiffness = 0.7;
  RodSimulator sim(spec);
  const double T = 0.3;
  sim.set_tip_moment({T, 0.0, 0.0});  // along the rod (base direction +x)
  ASSERT_TRUE(sim.solve_static().converged());
  // Rotation of each edge's material frame relative to the clamp frame grows linearly
  // with the arc length of the edge midpoint, φ(s) = T s / GJ; at the free end, TL/GJ.
  const auto [m1_base, m2_base] = sim.material_frame(sim.first_clamped_vertex());
  auto rotation = [&](int edge) {
    const auto [m1, m2] = sim.material_frame(edge);
    return std::atan2(m1_base.cross(m1).dot(Eigen::Vector3d::UnitX()), m1_base.dot(m1));
  };
  const double h = 1.0 / 30.0;
  for (int j = 0; j < sim.first_clamped_vertex(); ++j)
    EXPECT_NEAR(rotation(j), T * (1.0 - (j + 0.5) * h) / 0.7, 1e-6) << "edge " << j;
  const double phi_end = rotation(0) + 0.5 * (rotation(0) - rotation(1));
  EXPECT_NEAR(phi_end, T * 1.0 / 0.7, 1e-6);
  EXPECT_NEAR(sim.base_torque().x(), -T, 1e-9);
}

TEST(RodStatics, EulerBucklingLoadClampedFree) {
  // P_cr = π² EI / (2L)²: the straight equilibrium under an axial load P loses stability.
  const int n = 20;
  const double P_cr = std::numbers::pi * std::numbers::pi / 4.0;
  auto unstable = [&](double P) {
    RodSimulator sim(unit_rod_spec(n));
    sim.set_tip_force({-P, 0.0, 0.0});  // pushes the tip toward the clamp
    EXPECT_TRUE(sim.solve_static().converged());
    return sim.static_hessian_negative_eigenvalues() > 0;
  };
  double lo = 0.5 * P_cr, hi = 1.5 * P_cr;
  ASSERT_FALSE(unstable(lo));
  ASSERT_TRUE(unstable(hi));
  for (int i = 0; i < 30; ++i) {
    const double mid = 0.5 * (lo + hi);
    (unstable(mid) ? hi : lo) = mid;
  }
  EXPECT_NEAR(0.5 * (lo + hi), P_cr, tol(0.01 * P_cr));
}

TEST(RodStatics, EulerBucklingClampedClampedWithTipClamp) {
  // Both ends clamped, the tip clamp moved toward the base by δ: the axial force
  // N = EA δ / L reaches P_cr = 4π² EI / ℓ² (K = 0.5) when the straight state turns
  // unstable; ℓ = L − h is the span between the clamp vertices (the tip clamp holds the
  // distal edge).
  const int n = 40;
  const double EA = 1e7;
  const double span = 1.0 - 1.0 / n;
  const double P_cr = 4.0 * std::numbers::pi * std::numbers::pi / (span * span);
  auto unstable = [&](double N) {
    RodSimulator sim(unit_rod_spec(n));
    const double delta = N / EA;
    const double h = 1.0 / n;
    sim.clamp_tip({1.0 - delta, 0.0, 0.0}, {1.0 - delta - h * (1.0 - delta), 0.0, 0.0});
    EXPECT_TRUE(sim.solve_static().converged());
    EXPECT_NEAR(sim.base_force().x(), N, 1e-6 * N);  // the clamp pushes back with N
    return sim.static_hessian_negative_eigenvalues() > 0;
  };
  double lo = 0.5 * P_cr, hi = 1.5 * P_cr;
  ASSERT_FALSE(unstable(lo));
  ASSERT_TRUE(unstable(hi));
  for (int i = 0; i < 25; ++i) {
    const double mid = 0.5 * (lo + hi);
    (unstable(mid) ? hi : lo) = mid;
  }
  EXPECT_NEAR(0.5 * (lo + hi), P_cr, tol(0.01 * P_cr));
}

TEST(RodStatics, TorsionalBucklingClampedClamped) {
  // A straight rod clamped at both ends and twisted by Φ carries the torque M = GJ Φ / ℓ;
  // it buckles when M reaches 8.9868 B / ℓ (both ends clamped; Greenhill's hinged value
  // is 2π B / ℓ). Couples twist and bending through the reference twist and frames.
  const int n = 100;
  const double span = 1.0 - 1.0 / n;  // the tip clamp holds the distal edge
  auto unstable = [&](double phi) {
    RodSimulator sim(unit_rod_spec(n));
    sim.clamp_tip({1.0, 0.0, 0.0}, {1.0 - 1.0 / n, 0.0, 0.0});
    sim.set_base_angle(phi);
    EXPECT_TRUE(sim.solve_static().converged());
    return sim.static_hessian_negative_eigenvalues() > 0;
  };
  double lo = 1.0, hi = 20.0;
  ASSERT_FALSE(unstable(lo));
  ASSERT_TRUE(unstable(hi));
  for (int i = 0; i < 30; ++i) {
    const double mid = 0.5 * (lo + hi);
    (unstable(mid) ? hi : lo) = mid;
  }
  const double M_cr = 0.5 * (lo + hi) / span;  // GJ = 1
  EXPECT_NEAR(M_cr * span, 8.9868, tol(0.01 * 8.9868));
}

}  // namespace
}  // namespace flowire::rod
