// WallFriction: pressed by the contact's lagged record, its incremental potential Δt·D(v) has
// the friction force as its negative gradient in the positions (v = (x − x₀)/Δt) and its
// velocity Jacobian is the force's derivative (central differences); the tip's coefficient
// within tip_length; before any step ends, a plain (non-conservative) force; the viscous part
// is tangential and linear.
#include "flowire/coupling/wall_friction.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "flowire/vessels/generators.hpp"
#include "flowire_test.hpp"

using namespace flowire;
using namespace flowire::coupling;
using vessels::Vec3;

namespace {

/// Vertices x0 pressed into the wall of a network (by default: a wire of n vertices lying
/// 0.1 mm deep in the bottom wall of a straight tube along x).
struct TubeFloor {
  static constexpr double R = 3e-3, a = 0.45e-3, dt = 1e-2;
  vessels::Network net;
  vessels::SpatialIndex index{net};
  WireLocation where{index};
  NetworkWall wall{where};
  std::vector<Vec3> x0;
  std::vector<double> arc;
  explicit TubeFloor(int n)
      : net(vessels::Network::build(vessels::straight_tube({.length = 0.1, .radius = R}),
                                    {.max_segment_length = 5e-3})) {
    for (int i = 0; i < n; ++i) x0.emplace_back(0.03 + 1e-3 * i, 0.0, -(R - a) - 1e-4);
    for (int i = 0; i < n; ++i) arc.push_back(1e-3 * (n - i));
  }
  TubeFloor(vessels::Network network, std::vector<Vec3> points) : net(std::move(network)), x0(std::move(points)) {
    for (size_t i = 0; i < x0.size(); ++i) arc.push_back(1e-3 * static_cast<double>(x0.size() - i));
  }
  rod::RodView view(const std::vector<Vec3>& x, const std::vector<Vec3>& v, double step) {
    rod::RodView r;
    r.positions = x;
    r.velocities = v;
    r.arc_length = arc;
    r.first_clamped_vertex = static_cast<int>(x.size());
    r.dt = step;
    return r;
  }
  /// The contact pressed at x0 and, with @p lag, recorded as a step's start.
  void press(WallContact& contact, bool lag) {
    std::vector<Vec3> v(x0.size(), Vec3::Zero());
    const auto r = view(x0, v, dt);
    InteractionStats s;
    where.locate(r, r.vertex_count(), s);
    rod::ForceAccumulator acc;
    acc.reset(r.vertex_count());
    std::vector<Vec3> tally(x0.size(), Vec3::Zero());
    contact.evaluate(r, r.vertex_count(), wall, acc, tally, s);
    if (lag) contact.end_step(r, wall, s);
  }
  rod::ForceAccumulator friction(const WallFriction& f, const WallContact& c, const std::vector<Vec3>& x, double step) {
    std::vector<Vec3> v(x.size());
    for (size_t i = 0; i < x.size(); ++i) v[i] = (x[i] - x0[i]) / step;
    rod::ForceAccumulator acc;
    acc.reset(static_cast<int>(x.size()));
    std::vector<Vec3> tally(x.size(), Vec3::Zero());
    f.evaluate(view(x, v, step), static_cast<int>(x.size()), c, acc, tally);
    for (size_t i = 0; i < x.size(); ++i) EXPECT_LT((tally[i] - acc.forces()[i]).norm(), 1e-15);
    return acc;
  }
  /// Central differences in vertex @p i's coordinate @p c (step @p h): −∂E/∂x_ic of the
  /// friction's incremental potential, and ∂f_i/∂x_ic.
  std::pair<double, Vec3> differences(const WallFriction& f, const WallContact& c, const std::vector<Vec3>& x, size_t i,
                                      int coord, double h) {
    auto xp = x, xm = x;
    xp[i][coord] += h;
    xm[i][coord] -= h;
    const auto ap = friction(f, c, xp, dt);
    const auto am = friction(f, c, xm, dt);
    return {-(ap.energy() - am.energy()) / (2 * h), Vec3((ap.forces()[i] - am.forces()[i]) / (2 * h))};
  }
};

}  // namespace

TEST(WallFriction, ItsIncrementalPotentialsGradientIsTheForceAndItsVelocityJacobianTheForcesDerivative) {
  TubeFloor floor(12);
  ContactParams p{.stiffness = 3e4, .friction = 0.3, .tip_friction = 0.3, .slip_speed = 1e-4};
  WallContact contact(p, TubeFloor::a);
  floor.press(contact, true);
  WallFriction friction(p);
  std::mt19937 rng(1);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Vec3> x = floor.x0;
  // Velocities from sticking (|v| ≪ ε) to sliding (|v| ≫ ε).
  for (size_t i = 0; i < x.size(); ++i)
    x[i] += TubeFloor::dt * std::pow(10.0, -6.0 + 0.4 * static_cast<double>(i)) * Vec3(g(rng), g(rng), g(rng));
  const auto acc = floor.friction(friction, contact, x, TubeFloor::dt);
  for (size_t i = 0; i < x.size(); ++i) {
    const double f = acc.forces()[i].norm();
    ASSERT_GT(f, 0.0);
    EXPECT_EQ(acc.forces()[i], acc.conservative_forces()[i]);
    const double speed = ((x[i] - floor.x0[i]) / TubeFloor::dt).norm();
    for (int c = 0; c < 3; ++c) {
      const auto [force, dfdx] =
          floor.differences(friction, contact, x, i, c, 1e-3 * std::min(speed, p.slip_speed) * TubeFloor::dt);
      EXPECT_NEAR(force, acc.forces()[i][c], 1e-5 * f) << "vertex " << i;
      // ∂f/∂v = Δt ∂f/∂x.
      const Vec3 col = dfdx * TubeFloor::dt;
      EXPECT_LT((col - acc.velocity_jacobians()[i].col(c)).norm(), 1e-5 * acc.velocity_jacobians()[i].norm() + 1e-12)
          << "vertex " << i << " column " << c;
    }
  }
}

TEST(WallFriction, WhereCapsulesBlendItIsPressedAlongTheUnitNormalAndStillTheGradientOfItsPotential) {
  // Where the capsules of a junction blend, the wall distance's gradient is shorter than 1.
  // The contact records the normal force as the penalty's multiplier times that length and
  // the direction normalized; with the gradient itself, I − n nᵀ was no projector, the
  // friction force not the gradient of its potential (by a factor up to 2 on the arch's
  // aortic bifurcation), and the line search stalled where Newton had converged.
  auto net = vessels::Network::build(vessels::y_bifurcation({}), {.max_segment_length = 5e-3});
  std::vector<Vec3> points;
  {
    const vessels::SpatialIndex index(net);
    for (int i = 0; i <= 4000 && points.size() < 8; ++i) {  // across the crease between the daughters
      const Vec3 p(0.035 + 0.02 * i / 4000.0, -0.01 + 0.02 * i / 4000.0, 0.002);
      Vec3 grad;
      const double d = index.wall_distance(p, -1, &grad);
      if (d + TubeFloor::a > 1e-5 && d + TubeFloor::a < 2e-4 && grad.norm() < 0.98 &&
          (points.empty() || (p - points.back()).norm() > 2e-5))
        points.push_back(p);
    }
  }
  ASSERT_GE(points.size(), 3u) << "no blended wall points found";
  TubeFloor crease(std::move(net), points);
  ContactParams p{.stiffness = 3e4, .friction = 0.3, .tip_friction = 0.3, .slip_speed = 1e-4};
  WallContact contact(p, TubeFloor::a);
  crease.press(contact, true);
  WallFriction friction(p);
  std::vector<Vec3> x = crease.x0;
  std::mt19937 rng(2);
  std::normal_distribution<double> g(0.0, 1.0);
  for (size_t i = 0; i < x.size(); ++i)  // sliding, from 0.1 to 2 cm/s
    x[i] += TubeFloor::dt * (1e-3 + 2e-3 * static_cast<double>(i)) * Vec3(g(rng), g(rng), g(rng));
  const auto acc = crease.friction(friction, contact, x, TubeFloor::dt);
  for (size_t i = 0; i < x.size(); ++i) {
    const int k = static_cast<int>(i);
    ASSERT_GT(contact.normal_force(k), 0.0) << i;
    EXPECT_NEAR(contact.normal(k).norm(), 1.0, 1e-12) << i;
    const double f = acc.forces()[i].norm();
    EXPECT_LT(f, p.friction * contact.normal_force(k) * (1.0 + 1e-12)) << i;
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(crease.differences(friction, contact, x, i, c, 1e-3 * p.slip_speed * TubeFloor::dt).first,
                  acc.forces()[i][c], 1e-6 * f)
          << "vertex " << i;
  }
}

TEST(WallFriction, ASlidingVertexFeelsMuTimesNWithTheTipsOwnCoefficientNearTheTip) {
  TubeFloor floor(10);
  ContactParams p{.stiffness = 3e4, .friction = 0.4, .tip_friction = 0.05, .tip_length = 2.5e-3, .slip_speed = 1e-5};
  WallContact contact(p, TubeFloor::a);
  floor.press(contact, true);
  WallFriction friction(p);
  std::vector<Vec3> x = floor.x0;
  for (auto& xi : x) xi += TubeFloor::dt * Vec3(0.01, 0, 0);  // sliding at 1 cm/s along the tube
  const auto acc = floor.friction(friction, contact, x, TubeFloor::dt);
  for (size_t i = 0; i < x.size(); ++i) {
    const int k = static_cast<int>(i);
    const double mu = floor.arc[0] - floor.arc[i] <= p.tip_length ? p.tip_friction : p.friction;
    // μN (1 − O(ε²/v²)), against the motion.
    EXPECT_NEAR(acc.forces()[i].x(), -mu * contact.normal_force(k), 1e-6 * mu * contact.normal_force(k)) << i;
    EXPECT_NEAR(acc.forces()[i].tail<2>().norm(), 0.0, 1e-12);
  }
}

TEST(WallFriction, BeforeAnyStepEndsItIsAPlainForceAndTheViscousPartIsTangential) {
  TubeFloor floor(6);
  ContactParams p{.stiffness = 3e4, .friction = 0.2, .tip_friction = 0.2, .slip_speed = 1e-4, .viscous_friction = 0.5};
  WallContact contact(p, TubeFloor::a);
  floor.press(contact, false);
  WallFriction friction(p);
  std::vector<Vec3> x = floor.x0;
  const Vec3 v(0.01, 0.0, -0.002);  // along the wall and into it
  for (auto& xi : x) xi += TubeFloor::dt * v;
  const auto acc = floor.friction(friction, contact, x, TubeFloor::dt);
  EXPECT_EQ(acc.energy(), 0.0);
  WallContact off({.stiffness = 3e4, .friction = 0.0, .tip_friction = 0.0, .slip_speed = 1e-4, .viscous_friction = 0.5},
                  TubeFloor::a);
  floor.press(off, false);
  const auto viscous = floor.friction(WallFriction({.friction = 0.0, .tip_friction = 0.0, .viscous_friction = 0.5}),
                                      off, x, TubeFloor::dt);
  for (size_t i = 1; i + 1 < x.size(); ++i) {
    EXPECT_EQ(acc.conservative_forces()[i], Vec3::Zero());
    // −c ℓ (I − n nᵀ) v with n = −e_z and ℓ = 1 mm: only the sliding component.
    EXPECT_LT((viscous.forces()[i] - Vec3(-0.5 * 1e-3 * 0.01, 0, 0)).norm(), 1e-12) << i;
  }
}
