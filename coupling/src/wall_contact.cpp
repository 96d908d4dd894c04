#include "flowire/coupling/wall_contact.hpp"

#include <algorithm>

namespace flowire::coupling {

void WallContact::set_introducer(const Vec3& p, const Vec3& t, double reach) {
  intro_point_ = p;
  intro_dir_ = t.normalized();
  intro_reach_ = reach;
}

void WallContact::ensure_size(int n) {
  if (static_cast<int>(normal_force_.size()) >= n) return;
  normal_force_.resize(static_cast<size_t>(n), 0.0);
  normal_.resize(static_cast<size_t>(n), Vec3::UnitX());
  lag_normal_force_.resize(static_cast<size_t>(n), 0.0);
  lag_normal_.resize(static_cast<size_t>(n), Vec3::UnitX());
}

double WallContact::normal_force_at(double d, double a, double cell_weight) const {
  double d1 = 0.0;
  (void)onset_quadratic(d + a, params_.onset, &d1);
  return params_.stiffness * cell_weight * d1;
}

void WallContact::evaluate(const rod::RodView& rod, int free, Wall& wall, rod::ForceAccumulator& out,
                           std::span<Vec3> tally, InteractionStats& stats) {
  ensure_size(rod.vertex_count());
  wall.ensure_size(rod.vertex_count());
  for (int i = 0; i < free; ++i) {
    const auto k = static_cast<size_t>(i);
    normal_force_[k] = 0.0;
    const Vec3& x = rod.position(i);
    const double a = rod.vertex_radius(i, wire_radius_);
    // Stiffness per vertex of the feeding grid, scaled with the vertex's edges where the
    // rod is resampled (so the wall stays equally stiff per unit length).
    const double k_wall = params_.stiffness * rod.cell_weight(i);
    if (intro_reach_ > 0.0) {
      // The introducer: no way back out behind the entry plane near the entry axis.
      const Vec3 r = x - intro_point_;
      const double along = r.dot(intro_dir_);
      if ((r - along * intro_dir_).norm() < intro_reach_) {
        // The plane lies one wire radius behind the entry, so that vertices fed in at the
        // entry itself are free: δ = −along − a + a > 0 once a vertex is behind it.
        const auto pen = wall_penalty(-along - 2.0 * a, -intro_dir_, Mat3::Zero(), a, k_wall, params_.onset);
        if (pen.energy > 0.0) {
          ++intro_contacts_;
          out.add_conservative_force(i, -pen.gradient);
          out.add_energy(pen.energy);
          out.add_position_jacobian(i, -pen.hessian);
          tally[k] -= pen.gradient;
        }
      }
    }
    ++stats.wall_queries;
    double d = 0.0;
    Vec3 n_wall;
    Mat3 H_wall;  // exact, blends included: Newton stays quadratic near junctions and bends
    if (!wall.at(i, x, a, 0.5 * params_.onset, &d, &n_wall, &H_wall)) continue;
    const auto pen = wall_penalty(d, n_wall, H_wall, a, k_wall, params_.onset);
    if (!(pen.energy > 0.0)) continue;
    ++stats.contacts;
    // The penalty has a potential (k φ(δ)): reported, the rod's line search measures the
    // contact exactly instead of by the work along its search ray.
    const Vec3 f = -pen.gradient;
    out.add_conservative_force(i, f);
    out.add_energy(pen.energy);
    out.add_position_jacobian(i, -pen.hessian);
    normal_force_[k] = pen.normal_force;
    normal_[k] = n_wall;
    tally[k] += f;
  }
}

void WallContact::end_step(const rod::RodView& rod, Wall& wall, InteractionStats& stats) {
  const int n = rod.vertex_count();
  const int free = std::min(rod.first_clamped_vertex, n);
  ensure_size(n);
  wall.ensure_size(n);
  lagged_ = params_.enabled;
  for (int i = 0; i < n; ++i) lag_normal_force_[static_cast<size_t>(i)] = 0.0;
  for (int i = 0; i < free; ++i) {
    const auto k = static_cast<size_t>(i);
    const double a = rod.vertex_radius(i, wire_radius_);
    const double s = rod.arc_length.empty() ? std::numeric_limits<double>::infinity() : rod.arc_length[k];
    AcceptedWall w;
    if (!wall.accepted(i, rod.position(i), a, 0.5 * params_.onset, s, &w)) continue;
    const double fn = normal_force_at(w.contact_distance, a, rod.cell_weight(i));
    if (fn > 0.0) {
      lag_normal_force_[k] = fn;
      lag_normal_[k] = w.normal;
    }
    if (!w.measured) continue;
    const double d = w.distance;
    stats.max_outside = std::max(stats.max_outside, d);
    if (d > a && stats.outside_time < 0.0) {
      stats.outside_time = rod.time;
      stats.outside_arc_length = rod.arc_length.empty() ? 0.0 : rod.arc_length[k];
      stats.outside_distance = d;
      stats.outside_position = rod.position(i);
    }
    stats.max_penetration = std::max(stats.max_penetration, d + a);
  }
}

}  // namespace flowire::coupling
