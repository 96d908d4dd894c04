// Forces on the distal tip (coupling/src/tip_forces.cpp): the obstacle resistance −F·t and
// the steering force F·P⊥(p − x)/|P⊥(p − x)| against hand-computed vectors, their lag over a
// step (a dead load whose potential −f·x₀ has f as its exact negative gradient), and when
// they act.
#include "flowire/coupling/tip_forces.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "flowire_test.hpp"

using namespace flowire;
using namespace flowire::coupling;
using Vec3 = Eigen::Vector3d;

namespace {

/// A three-vertex wire, tip (vertex 0) first, clamped from vertex 2.
struct Wire {
  std::vector<Vec3> x;
  std::vector<Vec3> v = std::vector<Vec3>(3, Vec3::Zero());
  rod::RodView view;
  explicit Wire(std::vector<Vec3> pts, int first_clamped = 2) : x(std::move(pts)) {
    view.positions = x;
    view.velocities = v;
    view.first_clamped_vertex = first_clamped;
    view.dt = 1e-3;
  }
  Wire(const Wire&) = delete;
  Wire& operator=(const Wire&) = delete;
  void move_tip(const Vec3& to) {
    x[0] = to;
    view.positions = x;
  }
};

struct Evaluated {
  std::vector<Vec3> force, conservative;
  double energy;
};

Evaluated evaluate(TipForces& tf, const rod::RodView& view) {
  rod::ForceAccumulator acc;
  acc.reset(view.vertex_count());
  tf.evaluate(view, acc);
  return {acc.forces(), acc.conservative_forces(), acc.energy()};
}

void expect_vec_near(const Vec3& a, const Vec3& b, double tol) {
  EXPECT_LT((a - b).norm(), tol) << "got " << a.transpose() << ", expected " << b.transpose();
}

TEST(TipForces, AnObstacleOpposesTheTipAlongItsTangent) {
  // Tip at (1, 1, 0) coming from (0, 0, 0): t = (1, 1, 0)/√2.
  Wire w({Vec3(1, 1, 0), Vec3(0, 0, 0), Vec3(-1, -1, 0)});
  TipForces tf({{Vec3(1.2, 1.0, 0.0), 0.5, 0.3}}, {});
  tf.start(w.view);
  const auto e = evaluate(tf, w.view);
  const Vec3 expected = -0.3 * Vec3(1, 1, 0) / std::sqrt(2.0);
  expect_vec_near(e.force[0], expected, 1e-15);
  expect_vec_near(e.conservative[0], expected, 1e-15);  // a dead load with its potential
  EXPECT_EQ(e.force[1], Vec3::Zero());
  EXPECT_EQ(e.force[2], Vec3::Zero());
  EXPECT_NEAR(e.energy, -expected.dot(w.x[0]), 1e-15);
}

TEST(TipForces, OverlappingObstaclesAddAndAFarOneDoesNothing) {
  Wire w({Vec3(0, 0, 2), Vec3(0, 0, 1), Vec3(0, 0, 0)});  // t = +z
  TipForces tf({{Vec3(0, 0, 2), 0.1, 0.2}, {Vec3(0, 0.05, 2), 0.1, 0.5}, {Vec3(5, 5, 5), 1.0, 7.0}}, {});
  tf.start(w.view);
  expect_vec_near(evaluate(tf, w.view).force[0], Vec3(0, 0, -0.7), 1e-15);
}

TEST(TipForces, SteeringPullsTheTipSidewaysTowardsTheTarget) {
  // Tip at the origin heading +x; target at (3, 4, 0): P⊥(p − x) = (0, 4, 0).
  Wire w({Vec3(0, 0, 0), Vec3(-1, 0, 0), Vec3(-2, 0, 0)});
  Steering st;
  st.enabled = true;
  st.target = Vec3(3, 4, 0);
  st.force = 0.02;
  st.range = 5.0 + 1e-12;  // |p − x| = 5
  TipForces tf({}, st);
  tf.start(w.view);
  expect_vec_near(evaluate(tf, w.view).force[0], Vec3(0, 0.02, 0), 1e-15);
  // Out of range, disabled, or a target straight ahead (no lateral direction): no force.
  st.range = 4.999;
  TipForces far({}, st);
  far.start(w.view);
  EXPECT_EQ(evaluate(far, w.view).force[0], Vec3::Zero());
  st.range = 10.0;
  st.enabled = false;
  TipForces off({}, st);
  off.start(w.view);
  EXPECT_EQ(evaluate(off, w.view).force[0], Vec3::Zero());
  st.enabled = true;
  st.target = Vec3(2, 0, 0);
  TipForces ahead({}, st);
  ahead.start(w.view);
  EXPECT_EQ(evaluate(ahead, w.view).force[0], Vec3::Zero());
}

TEST(TipForces, ObstacleAndSteeringAdd) {
  Wire w({Vec3(0, 0, 0), Vec3(0, -1, 0), Vec3(0, -2, 0)});  // t = +y
  Steering st{true, Vec3(0, 1, -1), 0.04, 2.0};             // lateral direction −z
  TipForces tf({{Vec3::Zero(), 0.1, 0.3}}, st);
  tf.start(w.view);
  expect_vec_near(evaluate(tf, w.view).force[0], Vec3(0, -0.3, -0.04), 1e-15);
}

TEST(TipForces, WithinAStepTheForceIsADeadLoadWithAnExactPotential) {
  Wire w({Vec3(1, 0, 0), Vec3(0, 0, 0), Vec3(-1, 0, 0)});
  TipForces tf({{Vec3(1, 0, 0), 0.2, 0.4}}, {true, Vec3(2, 1, 0), 0.1, 3.0});
  tf.start(w.view);
  const Vec3 f0 = evaluate(tf, w.view).force[0];
  // The iterate moves the tip out of the obstacle and turns it: the force stays the step
  // start's, and its energy's negative gradient (central differences) is that force.
  w.move_tip(Vec3(0.3, 0.9, 0.2));
  const auto e = evaluate(tf, w.view);
  EXPECT_EQ(e.force[0], f0);
  const double h = 1e-6;
  Vec3 grad;
  for (int k = 0; k < 3; ++k) {
    Vec3 p = w.x[0], m = w.x[0];
    p[k] += h;
    m[k] -= h;
    w.move_tip(p);
    const double ep = evaluate(tf, w.view).energy;
    w.move_tip(m);
    const double em = evaluate(tf, w.view).energy;
    grad[k] = (ep - em) / (2 * h);
  }
  expect_vec_near(-grad, f0, 1e-9 * f0.norm());
}

TEST(TipForces, EndStepCountsAndTakesTheNewStepsForce) {
  Wire w({Vec3(1, 0, 0), Vec3(0, 0, 0), Vec3(-1, 0, 0)});
  TipForces tf({{Vec3(1, 0, 0), 0.2, 0.4}}, {true, Vec3(1.5, 1.0, 0), 0.1, 1.2});
  tf.start(w.view);
  tf.end_step(w.view);  // inside both
  EXPECT_EQ(tf.obstacle_steps(), 1);
  EXPECT_EQ(tf.steering_steps(), 1);
  // Out of both regions: the next step carries no force, and nothing more is counted.
  w.move_tip(Vec3(1, -5, 0));
  tf.end_step(w.view);
  EXPECT_EQ(tf.obstacle_steps(), 1);
  EXPECT_EQ(tf.steering_steps(), 1);
  const auto e = evaluate(tf, w.view);
  EXPECT_EQ(e.force[0], Vec3::Zero());
  EXPECT_EQ(e.energy, 0.0);
}

TEST(TipForces, AClampedTipFeelsNothing) {
  // Every vertex held by the clamp (the wire not yet fed out): no force even inside.
  Wire w({Vec3(1, 0, 0), Vec3(0, 0, 0), Vec3(-1, 0, 0)}, 0);
  TipForces tf({{Vec3(1, 0, 0), 0.2, 0.4}}, {true, Vec3(1, 1, 0), 0.1, 3.0});
  tf.start(w.view);
  const auto e = evaluate(tf, w.view);
  EXPECT_EQ(e.force[0], Vec3::Zero());
  EXPECT_EQ(e.energy, 0.0);
}

}  // namespace
