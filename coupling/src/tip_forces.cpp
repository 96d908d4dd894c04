#include "flowire/coupling/tip_forces.hpp"

namespace flowire::coupling {

Eigen::Vector3d TipForces::tip_tangent(const rod::RodView& rod) const {
  Eigen::Vector3d t = rod.position(0) - rod.position(1);  // towards the distal end
  const double n = t.norm();
  return n > 0.0 ? Eigen::Vector3d(t / n) : Eigen::Vector3d::UnitX();
}

Eigen::Vector3d TipForces::force_at(const rod::RodView& rod) const {
  Eigen::Vector3d f = Eigen::Vector3d::Zero();
  if (rod.vertex_count() < 2 || rod.first_clamped_vertex < 1) return f;
  const Eigen::Vector3d& x = rod.position(0);
  const Eigen::Vector3d t = tip_tangent(rod);
  for (const auto& o : obstacles_)
    if ((x - o.center).norm() <= o.radius) f -= o.force * t;
  if (steering_.enabled && (steering_.target - x).norm() <= steering_.range) {
    const Eigen::Vector3d lateral = (Eigen::Matrix3d::Identity() - t * t.transpose()) * (steering_.target - x);
    const double n = lateral.norm();
    if (n > 0.0) f += steering_.force * lateral / n;
  }
  return f;
}

void TipForces::evaluate(const rod::RodView& rod, rod::ForceAccumulator& out) {
  if (rod.vertex_count() < 2 || rod.first_clamped_vertex < 1 || lag_.isZero(0.0)) return;
  out.add_conservative_force(0, lag_);
  out.add_energy(-lag_.dot(rod.position(0)));
}

void TipForces::end_step(const rod::RodView& rod) {
  if (rod.vertex_count() < 2) return;
  const Eigen::Vector3d& x = rod.position(0);
  for (const auto& o : obstacles_)
    if ((x - o.center).norm() <= o.radius) {
      ++obstacle_steps_;
      break;
    }
  if (steering_.enabled && (steering_.target - x).norm() <= steering_.range) ++steering_steps_;
  lag_ = force_at(rod);
}

}  // namespace flowire::coupling
