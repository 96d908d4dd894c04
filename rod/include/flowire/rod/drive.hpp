#pragma once
/// @file drive.hpp
/// @brief The clamp's drive at the entry: how the wire is fed and turned, by which rule.
///
/// A speed (> 0 pushes in, < 0 pulls back), held to zero for a step that starts with the clamp
/// pushing harder than a force limit; or a push force, for which each step's feed is the one
/// whose clamp axial force at the step's end equals it, found by a secant iteration over
/// retakes of the step. The clamp also turns at a rotation speed from a base angle. The drive
/// knows nothing of the rod but the clamp's axial force it is told: RodSimulator takes the
/// steps, the drive decides their feed (a new feeding rule is a change here).
#include <optional>

namespace flowire::rod {

class Drive {
 public:
  // --- settings -------------------------------------------------------------------------
  /// @brief Feeding speed [m/s], > 0 pushes in, < 0 pulls back.
  void set_insertion_speed(double speed) { insertion_speed_ = speed; }
  [[nodiscard]] double insertion_speed() const { return insertion_speed_; }
  /// @brief A step that starts with the clamp pushing in harder than @p force [N] feeds
  /// nothing; 0: no limit.
  void set_max_insertion_force(double force) { max_insertion_force_ = force; }
  /// @brief Push with a constant force [N] (> 0) instead of at a speed; 0: back to the speed.
  void set_push_force(double force) {
    push_force_ = force;
    slope_ = 0.0;
  }
  [[nodiscard]] double push_force() const { return push_force_; }
  [[nodiscard]] bool force_driven() const { return push_force_ > 0.0; }
  /// @brief Clamp rotation speed, right-handed about the insertion direction [rad/s].
  void set_rotation_speed(double omega) { rotation_speed_ = omega; }
  [[nodiscard]] double rotation_speed() const { return rotation_speed_; }
  /// @brief The clamp's angle at the start of the next step [rad].
  void set_base_angle(double angle) { angle_ = angle; }
  [[nodiscard]] double base_angle() const { return angle_; }
  /// @brief The clamp's angle at the end of a step of @p dt from the current one.
  [[nodiscard]] double angle_after(double dt) const { return angle_ + rotation_speed_ * dt; }

  // --- a kinematic step -----------------------------------------------------------------
  /// @brief The feed speed of a step that starts with the clamp pushing the wire in with
  /// axial force @p axial_force [N]: the insertion speed, or 0 when it pushes in and the
  /// force exceeds the limit (counted in held_steps()).
  double kinematic_speed(double axial_force);

  // --- a force-driven step: g(v) = axial force at the step's end − push force = 0 --------
  /// @brief The first feed speed to try: the last decided step's, within ±@p vmax; @p slope_guess
  /// (dg/dv, > 0) starts the secant where no step has measured it yet.
  double force_feed_begin(double vmax, double slope_guess);
  /// @brief The step at the speed last tried ended with clamp axial force @p axial_force: the
  /// next speed to try (secant on g, the slope kept from step to step), or nothing when g is
  /// within the tolerance, at the per-step limit, or after the iteration limit (the step's
  /// feed is then the last speed tried, counted in force_feed_unbalanced() unless balanced).
  std::optional<double> force_feed_next(double axial_force);

  // --- what the drive did ----------------------------------------------------------------
  /// @brief Feed speed of the last force-driven step [m/s].
  [[nodiscard]] double force_feed_speed() const { return committed_; }
  /// @brief Secant iterations (extra step solves) spent by force-driven feeding so far.
  [[nodiscard]] long force_feed_iterations() const { return iterations_; }
  /// @brief Force-driven steps whose axial force stayed off by more than the tolerance.
  [[nodiscard]] long force_feed_unbalanced() const { return unbalanced_; }
  /// @brief Steps in which feeding was held by the force limit.
  [[nodiscard]] long held_steps() const { return held_steps_; }

  static constexpr int kMaxForceFeedIterations = 12;
  static constexpr double kForceFeedTolerance = 1e-4;  ///< relative to the push force

 private:
  double insertion_speed_ = 0.0, max_insertion_force_ = 0.0, push_force_ = 0.0;
  double rotation_speed_ = 0.0, angle_ = 0.0;
  // The secant: the speed and g last tried this step, the slope dg/dv kept across steps.
  double committed_ = 0.0;  // the last decided step's speed
  double speed_ = 0.0, last_speed_ = 0.0, g_ = 0.0, slope_ = 0.0, vmax_ = 0.0;
  int step_iterations_ = 0;
  bool first_ = true;
  long iterations_ = 0, unbalanced_ = 0, held_steps_ = 0;
};

}  // namespace flowire::rod
