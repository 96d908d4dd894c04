#include "flowire/coupling/tip_forces.hpp"

namespace flowire::coupling {

Eigen::Vector3d TipForces::tip_tangent(const rod::RodView& rod) const {
  Eigen::Vector3d t = rod.position(0) - rod.position(1);  // towards the distal end
  const double n = t.norm();
  return n > 0.0 ? Eigen::Vector3d(t / n) : Eigen::Vector3d::UnitX();
}

void TipForces::evaluate(const rod::RodView& rod, rod::ForceAccumulator& out) {
  if (rod.vertex_count() < 2 || rod.first_clamped_vertex < 1) return;
  const Eigen::Vector3d& x = rod.position(0);
  const Eigen::Vector3d t = tip_tangent(rod);
  for (const auto& o : obstacles_)
    if ((x - o.center).norm() <= o.radius) out.add_force(0, -o.force * t);
  if (steering_.enabled && (steering_.target - x).norm() <= steering_.range) {
    Eigen::Vector3d lateral = (Eigen::Matrix3d::Identity() - t * t.transpose()) * (steering_.target - x);
    const double n = lateral.norm();
    if (n > 0.0) out.add_force(0, steering_.force * lateral / n);
  }
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
}

}  // namespace flowire::coupling
