// The clamp's drive (rod/drive.hpp) on its own: the force limit of a kinematic feed, and the
// secant of a force-driven one on force laws g(v) whose root is known in closed form.
#include "flowire/rod/drive.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

using flowire::rod::Drive;

namespace {

/// One force-driven step on the axial-force law @p axial (the clamp's force at the step's end
/// when the step feeds at speed v): the speeds the drive tries, to the one it decides.
struct Step {
  double speed = 0.0;
  int tries = 0;
};
Step force_step(Drive& d, const std::function<double(double)>& axial, double vmax, double slope_guess) {
  Step s;
  double v = d.force_feed_begin(vmax, slope_guess);
  for (s.tries = 1;; ++s.tries) {
    const auto next = d.force_feed_next(axial(v));
    if (!next) break;
    v = *next;
  }
  s.speed = v;
  return s;
}

}  // namespace

TEST(Drive, AForceLimitHoldsAPushButNeverAPullBack) {
  Drive d;
  d.set_insertion_speed(0.02);
  EXPECT_EQ(d.kinematic_speed(5.0), 0.02);  // no limit set
  d.set_max_insertion_force(0.5);
  EXPECT_EQ(d.kinematic_speed(0.49), 0.02);
  EXPECT_EQ(d.kinematic_speed(0.51), 0.0);
  EXPECT_EQ(d.held_steps(), 1);
  d.set_insertion_speed(-0.02);  // pulling back against any force
  EXPECT_EQ(d.kinematic_speed(3.0), -0.02);
  EXPECT_EQ(d.held_steps(), 1);
  d.set_rotation_speed(2.0);
  d.set_base_angle(0.5);
  EXPECT_DOUBLE_EQ(d.angle_after(0.25), 1.0);
}

TEST(Drive, TheSecantFindsTheFeedWhoseClampForceIsThePushAndKeepsItsSlope) {
  // A linear law, g(v) = c v + f₀ (a damper c against a preload f₀): the feed balancing F is
  // (F − f₀)/c. From a wrong slope guess the first retake lands on the secant's root, which
  // for a line is exact; the next step, starting from that speed and slope, needs no retake.
  const double c = 3.0, f0 = 0.01, F = 0.07;
  Drive d;
  d.set_push_force(F);
  const auto line = [&](double v) { return c * v + f0; };
  const Step first = force_step(d, line, 1.0, 10.0 * c);
  EXPECT_NEAR(first.speed, (F - f0) / c, Drive::kForceFeedTolerance * F / c);
  EXPECT_NEAR(d.force_feed_speed(), first.speed, 0.0);
  const Step second = force_step(d, line, 1.0, 10.0 * c);
  EXPECT_EQ(second.tries, 1);
  EXPECT_EQ(d.force_feed_unbalanced(), 0);
  // A stiffening law, g = c v + k v³: the secant converges to its root within the tolerance.
  Drive n;
  n.set_push_force(F);
  const double k = 400.0;
  const auto cubic = [&](double v) { return c * v + k * v * v * v; };
  const Step s = force_step(n, cubic, 1.0, c);
  EXPECT_LE(std::abs(cubic(s.speed) - F), Drive::kForceFeedTolerance * F);
  EXPECT_LT(s.tries, Drive::kMaxForceFeedIterations);
  EXPECT_EQ(n.force_feed_iterations(), s.tries - 1);
}

TEST(Drive, AFeedBeyondTheStepsLimitIsCountedUnbalanced) {
  // The push needs v = 2 but one step may feed at most 0.5: the drive feeds at the limit and
  // says the force was not balanced.
  Drive d;
  d.set_push_force(2.0);
  const Step s = force_step(
      d, [](double v) { return v; }, 0.5, 1.0);
  EXPECT_DOUBLE_EQ(s.speed, 0.5);
  EXPECT_EQ(d.force_feed_unbalanced(), 1);
  // Setting the force again forgets the slope and starts from the last decided speed.
  d.set_push_force(0.2);
  const Step back = force_step(
      d, [](double v) { return v; }, 0.5, 1.0);
  EXPECT_NEAR(back.speed, 0.2, Drive::kForceFeedTolerance * 0.2);
}
