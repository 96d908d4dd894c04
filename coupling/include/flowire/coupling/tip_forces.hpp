#pragma once
/// @file tip_forces.hpp
/// @brief Forces on the wire's distal tip: resistance inside marked obstacle regions (a
/// clot, a tight lesion) and an optional steering force towards a chosen branch, after the
/// elastic-rod guidewire simulator of Tang, Lagadec, Gould, Wan, Zhai & How 2010 (Vis.
/// Comput. 26, 1157–1165, §3.3–3.4: a clot's resistance f = βT/|T| along the tip's tangent,
/// a steering force of constant magnitude at the tip). Their steering pulls along the
/// target branch's centerline; here it pulls the tip sideways towards a target point.
///
/// - Obstacle: while the tip vertex is inside a sphere (centre, radius), a force of
///   magnitude F opposes its motion along the tip tangent t (t points distally):
///   f = −F·t. Released as soon as the tip leaves the region.
/// - Steering: while the tip is within `range` of the target point, a force of magnitude
///   F perpendicular to t pulls the tip towards the target: f = F·P⊥(p − x)/|P⊥(p − x)|,
///   P⊥ = I − t tᵀ.
/// Both act on vertex 0 (the tip). Their direction and whether they act are taken at the
/// start of each step (lagged, like the friction's normal force): within a step they are a
/// dead load f with the exact potential −f·x₀, so the rod's line search measures them
/// exactly. Follower forces re-evaluated at every iterate have no potential and stalled
/// Newton near convergence.
#include <vector>

#include <Eigen/Core>

#include "flowire/rod/external.hpp"

namespace flowire::coupling {

struct Obstacle {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 0.0;  ///< m
  double force = 0.0;   ///< N
};

struct Steering {
  bool enabled = false;
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  double force = 0.0;  ///< N
  double range = 0.0;  ///< m
};

class TipForces : public rod::ExternalForce {
 public:
  TipForces(std::vector<Obstacle> obstacles, Steering steering)
      : obstacles_(std::move(obstacles)), steering_(steering) {}
  void evaluate(const rod::RodView& rod, rod::ForceAccumulator& out) override;
  /// @brief Steps in which the tip was held back by an obstacle / steered.
  [[nodiscard]] long obstacle_steps() const { return obstacle_steps_; }
  [[nodiscard]] long steering_steps() const { return steering_steps_; }
  void end_step(const rod::RodView& rod) override;
  void start(const rod::RodView& rod) override { lag_ = force_at(rod); }

 private:
  [[nodiscard]] Eigen::Vector3d tip_tangent(const rod::RodView& rod) const;
  /// The obstacle and steering force on the tip in configuration @p rod.
  [[nodiscard]] Eigen::Vector3d force_at(const rod::RodView& rod) const;
  Eigen::Vector3d lag_ = Eigen::Vector3d::Zero();  ///< at the step start
  std::vector<Obstacle> obstacles_;
  Steering steering_;
  long obstacle_steps_ = 0, steering_steps_ = 0;
};

}  // namespace flowire::coupling
