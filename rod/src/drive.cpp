// The clamp's drive (drive.hpp): the force limit of a kinematic feed and the secant
// iteration of a force-driven one.
#include "flowire/rod/drive.hpp"

#include <algorithm>
#include <cmath>

namespace flowire::rod {

double Drive::kinematic_speed(double axial_force) {
  if (insertion_speed_ > 0.0 && max_insertion_force_ > 0.0 && axial_force > max_insertion_force_) {
    ++held_steps_;
    return 0.0;
  }
  return insertion_speed_;
}

double Drive::force_feed_begin(double vmax, double slope_guess) {
  // g grows with v (the step's inertia m/dt, damping, drag and friction, and the axial
  // stiffness times dt against an obstacle): a secant from the last step's speed and slope.
  if (!(slope_ > 0.0)) slope_ = slope_guess;
  vmax_ = vmax;
  speed_ = std::clamp(committed_, -vmax, vmax);
  step_iterations_ = 0;
  first_ = true;
  return speed_;
}

std::optional<double> Drive::force_feed_next(double axial_force) {
  const double g = axial_force - push_force_;
  if (!first_) {
    const double slope = (g - g_) / (speed_ - last_speed_);
    if (slope > 0.0 && std::isfinite(slope)) slope_ = slope;
  }
  first_ = false;
  g_ = g;
  const bool balanced = std::abs(g) <= kForceFeedTolerance * push_force_;
  if (!balanced && step_iterations_ < kMaxForceFeedIterations) {
    const double v_new = std::clamp(speed_ - g / slope_, -vmax_, vmax_);
    if (v_new != speed_) {  // else at the per-step limit
      ++step_iterations_;
      last_speed_ = speed_;
      speed_ = v_new;
      return v_new;
    }
  }
  // The step's feed is decided (a step whose solve failed on the way decides nothing).
  iterations_ += step_iterations_;
  if (!balanced) ++unbalanced_;
  committed_ = speed_;
  return std::nullopt;
}

}  // namespace flowire::rod
