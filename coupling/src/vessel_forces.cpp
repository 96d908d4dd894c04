#include "flowire/coupling/vessel_forces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "flowire/common/error.hpp"

namespace flowire::coupling {

namespace {
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
}  // namespace

VesselForces::VesselForces(const vessels::SpatialIndex& index, double wire_radius, ContactParams contact,
                           DragModel drag, VelocityField velocity)
    : index_(index), wire_radius_(wire_radius), contact_(contact), drag_(drag), velocity_(std::move(velocity)) {
  drag_.wire_radius = wire_radius;
  // Checks the slender-body length once, at set-up, not in the first step.
  if (drag_.law == DragLaw::SlenderBody)
    (void)slender_body_normal_coefficient(drag_.viscosity, drag_.wire_length, wire_radius);
}

Vec3 VesselForces::total_drag() const {
  Vec3 sum = Vec3::Zero();
  for (int i = 0; i < free_ && i < static_cast<int>(drag_force_.size()); ++i)
    sum += drag_force_[static_cast<size_t>(i)];
  return sum;
}

void VesselForces::ensure_size(int n) {
  if (static_cast<int>(segment_.size()) < n) {
    segment_.resize(static_cast<size_t>(n), -1);
    location_.resize(static_cast<size_t>(n));
    near_.resize(static_cast<size_t>(n));
    fluid_.resize(static_cast<size_t>(n), Vec3::Zero());
    force_.resize(static_cast<size_t>(n), Vec3::Zero());
    drag_force_.resize(static_cast<size_t>(n), Vec3::Zero());
    contact_force_.resize(static_cast<size_t>(n), Vec3::Zero());
    reynolds_.resize(static_cast<size_t>(n), 0.0);
    drag_lin_.resize(static_cast<size_t>(n));
    cur_normal_force_.resize(static_cast<size_t>(n), 0.0);
    cur_normal_.resize(static_cast<size_t>(n), Vec3::UnitX());
    lag_normal_force_.resize(static_cast<size_t>(n), 0.0);
    lag_normal_.resize(static_cast<size_t>(n), Vec3::UnitX());
    surf_near_.resize(static_cast<size_t>(n));
  }
}

bool VesselForces::surface_wall(int i, const Vec3& x, double* d, Vec3* n, Mat3* H) {
  auto& near = surf_near_[static_cast<size_t>(i)];
  const auto q = surface_->smooth_distance(x, smoothing_, near, surf_margin_, H, surf_skip_);
  if (q.skipped) return false;
  *d = q.distance;
  *n = q.gradient;
  return true;
}

bool VesselForces::wall_at(int i, const Vec3& x, double a, double* d, Vec3* n, Mat3* H) {
  ++stats_.wall_queries;
  if (surface_) return surface_wall(i, x, d, n, H);
  const auto k = static_cast<size_t>(i);
  const auto& net = index_.network();
  const auto& seg = net.segment(segment_[k]);
  // The union's distance is at most the located capsule's: deep inside it, no wall is near.
  if (capsule_distance(x, net.node(seg.node_from), net.node(seg.node_to), seg.radius, nullptr, nullptr) + a +
          0.5 * contact_.onset <
      0.0)
    return false;
  *d = index_.wall_distance(x, location_[k], near_[k], n, H);
  return true;
}

void VesselForces::evaluate(const rod::RodView& rod, rod::ForceAccumulator& out) {
  const int n = rod.vertex_count();
  const int free = std::min(rod.first_clamped_vertex, n);
  ensure_size(n);
  free_ = free;
  ++stats_.evaluations;
  const auto& net = index_.network();

  // 1) Lookup: hint = the same vertex's segment at the previous evaluation, else the
  //    neighbour towards the base (vertices are found from the base towards the tip).
  //    Beyond the hint's window, the vertex's neighbourhood answers instead of the tree.
  auto t0 = Clock::now();
  for (int i = free - 1; i >= 0; --i) {
    const auto k = static_cast<size_t>(i);
    int hint = segment_[k];
    if (hint < 0 && i + 1 < n) hint = segment_[k + 1];
    location_[k] = index_.locate(rod.position(i), hint, near_[k]);
    segment_[k] = location_[k].segment;
    ++stats_.lookups;
  }
  stats_.seconds_lookup += since(t0);

  // 2) Wall contact and friction.
  t0 = Clock::now();
  const double tip_s = rod.arc_length.empty() ? 0.0 : rod.arc_length[0];
  for (int i = 0; i < free; ++i) {
    force_[static_cast<size_t>(i)].setZero();
    drag_force_[static_cast<size_t>(i)].setZero();
    contact_force_[static_cast<size_t>(i)].setZero();
    cur_normal_force_[static_cast<size_t>(i)] = 0.0;
    if (!contact_.enabled) continue;
    const Vec3& x = rod.position(i);
    const double a = rod.vertex_radius(i, wire_radius_);
    // Stiffness per vertex of the feeding grid, scaled with the vertex's edges where the
    // rod is resampled (so the wall stays equally stiff per unit length).
    const double k_wall = contact_.stiffness * rod.cell_weight(i);
    if (intro_reach_ > 0.0) {
      // The introducer: no way back out behind the entry plane near the entry axis.
      const Vec3 r = x - intro_point_;
      const double along = r.dot(intro_dir_);
      if ((r - along * intro_dir_).norm() < intro_reach_) {
        // The plane lies one wire radius behind the entry, so that vertices fed in at the
        // entry itself are free: δ = −along − a + a > 0 once a vertex is behind it.
        const auto pen = wall_penalty(-along - 2.0 * a, -intro_dir_, Mat3::Zero(), a, k_wall, contact_.onset);
        if (pen.energy > 0.0) {
          ++intro_contacts_;
          out.add_conservative_force(i, -pen.gradient);
          out.add_energy(pen.energy);
          out.add_position_jacobian(i, -pen.hessian);
          force_[static_cast<size_t>(i)] -= pen.gradient;
          contact_force_[static_cast<size_t>(i)] -= pen.gradient;
        }
      }
    }
    double d = 0.0;
    Vec3 n_wall;
    Mat3 H_wall;  // exact, blends included: Newton stays quadratic near junctions and bends
    if (!wall_at(i, x, a, &d, &n_wall, &H_wall)) continue;
    const auto pen = wall_penalty(d, n_wall, H_wall, a, k_wall, contact_.onset);
    if (!(pen.energy > 0.0)) continue;
    ++stats_.contacts;
    // The penalty has a potential (k/2 δ₊²): reported, the rod's line search measures the
    // contact exactly instead of by the work along its search ray.
    Vec3 f = -pen.gradient;
    out.add_conservative_force(i, f);
    out.add_energy(pen.energy);
    out.add_position_jacobian(i, -pen.hessian);
    cur_normal_force_[static_cast<size_t>(i)] = pen.normal_force;
    cur_normal_[static_cast<size_t>(i)] = n_wall;
    force_[static_cast<size_t>(i)] += f;
    contact_force_[static_cast<size_t>(i)] += f;
  }
  // Friction with the normal force and normal of the step's start (lagged, as in IPC):
  // the friction force is then a function of the velocity alone and its Jacobian is
  // exact, which keeps Newton quadratic at high μ. The first step uses the current ones.
  if (contact_.enabled) {
    for (int i = 0; i < free; ++i) {
      const auto k = static_cast<size_t>(i);
      const bool lag = lagged_ && k < lag_normal_force_.size();
      const double normal_force = lag ? lag_normal_force_[k] : cur_normal_force_[k];
      if (normal_force <= 0.0) continue;
      const Vec3& nrm = lag ? lag_normal_[k] : cur_normal_[k];
      const double mu = (tip_s - rod.arc_length[k] <= contact_.tip_length) ? contact_.tip_friction : contact_.friction;
      const auto fr = coulomb_friction(rod.velocity(i), nrm, normal_force, mu, contact_.slip_speed);
      if (lag && rod.dt > 0.0) {
        // With the normal force fixed over the step, friction is −∇_v D(v) with v = (x − x₀)/Δt:
        // the gradient in x of Δt·D, an exact incremental potential (as in IPC). Reported as
        // one, the line search measures friction exactly instead of by the work along its ray,
        // which across the stick/slip band of width ε is far off.
        out.add_conservative_force(i, fr.force);
        out.add_energy(rod.dt * fr.dissipation);
      } else {
        out.add_force(i, fr.force);
      }
      out.add_velocity_jacobian(i, fr.dfdv);
      force_[k] += fr.force;
      contact_force_[k] += fr.force;
      if (contact_.viscous_friction > 0.0) {
        const Vec3& x = rod.position(i);
        const double ell = 0.5 * ((i > 0 ? (x - rod.position(i - 1)).norm() : 0.0) +
                                  (i + 1 < n ? (rod.position(i + 1) - x).norm() : 0.0));
        const Mat3 C = contact_.viscous_friction * ell * (Mat3::Identity() - nrm * nrm.transpose());
        out.add_force(i, -C * rod.velocity(i));
        out.add_velocity_jacobian(i, -C);
        force_[k] -= C * rod.velocity(i);
        contact_force_[k] -= C * rod.velocity(i);
      }
    }
  }
  stats_.seconds_contact += since(t0);

  // 3) Blood drag from the local velocity profile (drag.hpp), implicit in the wire velocity.
  t0 = Clock::now();
  if (drag_.law != DragLaw::None && velocity_) {
    DragInput in;
    in.dt = rod.dt;
    // Once a step (DragModel::once_per_step): the first evaluation of a step, at Newton's
    // initial guess, evaluates the law and keeps it; the step's later iterates and trials
    // take it linearized in the wire velocity. The blood velocity, the vessel geometry and
    // the drag coefficient are then those of the guess (the flow frame is the step's anyway),
    // and the velocity Jacobian is exact for the force the step uses.
    const bool per_step = drag_.once_per_step && rod.dt > 0.0;
    if (per_step &&
        !(rod.time == drag_step_time_ && rod.dt == drag_step_dt_ && rod.solve_serial == drag_step_serial_)) {
      for (auto& l : drag_lin_) l.valid = false;
      drag_step_time_ = rod.time;
      drag_step_dt_ = rod.dt;
      drag_step_serial_ = rod.solve_serial;
    }
    for (int i = 0; i < free; ++i) {
      const auto k = static_cast<size_t>(i);
      if (k < shielded_.size() && shielded_[k]) {
        fluid_[k].setZero(), reynolds_[k] = 0.0;
        continue;
      }
      auto& lin = drag_lin_[k];
      if (per_step && lin.valid) {
        const Vec3 f = lin.force + lin.dfdv * (rod.velocity(i) - lin.v);
        // The normal Reynolds number of this iterate (what end_step records of the accepted one).
        if (drag_.law == DragLaw::Cylinder) {
          const Vec3 w = fluid_[k] - rod.velocity(i);
          reynolds_[k] = drag_.density * (w - w.dot(lin.t) * lin.t).norm() * 2.0 * rod.vertex_radius(i, wire_radius_) /
                         drag_.viscosity;
        }
        out.add_force(i, f);
        out.add_velocity_jacobian(i, lin.dfdv);
        force_[k] += f;
        drag_force_[k] = f;
        continue;
      }
      const Vec3& x = rod.position(i);
      const int s = segment_[k];
      in.u = velocity_(s, x);
      fluid_[k] = in.u;
      if (!in.u.allFinite())
        throw_numerical_error(fmt::format("the blood velocity at wire vertex {} (segment {}) is not finite", i, s));
      const Vec3 prev = i > 0 ? rod.position(i - 1) : x;
      const Vec3 next = i + 1 < n ? rod.position(i + 1) : x;
      in.ell = 0.5 * ((x - prev).norm() + (next - x).norm());
      const Vec3 t = prev - next;
      const double tn = t.norm();
      in.t = tn > 0.0 ? Vec3(t / tn) : Vec3::UnitX();
      in.v = rod.velocity(i);
      in.wire_radius = rod.vertex_radius(i, wire_radius_);
      in.vessel_radius = s >= 0 ? net.segment(s).radius : 0.0;
      // Where the wire crosses the vessel the walls confine it as a channel (drag.hpp): the
      // law needs the vessel's axis and the vertex's offset from it.
      in.axis.setZero();
      in.axis_offset.setZero();
      if (s >= 0) {
        const auto& seg = net.segment(s);
        const Vec3 p0 = net.node(seg.node_from);
        const Vec3 axis = (net.node(seg.node_to) - p0).normalized();
        in.axis = axis;
        in.axis_offset = (x - p0) - (x - p0).dot(axis) * axis;
      }
      const auto d = blood_drag(drag_, in);
      ++stats_.drag_evaluations;
      if (per_step) lin = {d.force, in.v, in.t, d.dfdv, true};
      reynolds_[k] = d.reynolds_normal;
      out.add_force(i, d.force);
      out.add_velocity_jacobian(i, d.dfdv);
      force_[k] += d.force;
      drag_force_[k] = d.force;
    }
  }
  stats_.seconds_drag += since(t0);
}

double VesselForces::wall_normal_force(double d, double a, double cell_weight) const {
  double d1 = 0.0;
  (void)onset_quadratic(d + a, contact_.onset, &d1);
  return contact_.stiffness * cell_weight * d1;
}

void VesselForces::end_step(const rod::RodView& rod) {
  const auto t0 = Clock::now();
  drag_step_time_ = std::numeric_limits<double>::quiet_NaN();  // the next step linearizes anew
  const int free = std::min(rod.first_clamped_vertex, rod.vertex_count());
  ensure_size(rod.vertex_count());
  lagged_ = contact_.enabled;
  // The drag's Reynolds number of the accepted state (the last evaluation), not of the
  // Newton and line-search trials on the way.
  for (int i = 0; i < free && i < static_cast<int>(reynolds_.size()); ++i)
    stats_.max_reynolds = std::max(stats_.max_reynolds, reynolds_[static_cast<size_t>(i)]);
  for (int i = 0; i < rod.vertex_count(); ++i) lag_normal_force_[static_cast<size_t>(i)] = 0.0;
  for (int i = 0; i < free; ++i) {
    const auto k = static_cast<size_t>(i);
    const double a = rod.vertex_radius(i, wire_radius_);
    Vec3 nrm;
    double d = 0.0;
    if (surface_) {
      // The friction's normal force from the contact's own (smooth) distance; the exact
      // distance measures how far outside the wire is. A vertex deeper than surf_skip_ has
      // no normal force, and its distance, below −a, cannot raise the maxima recorded below
      // (both ≥ 0).
      const auto q =
          surface_->smooth_distance(rod.position(i), smoothing_, surf_near_[k], surf_margin_, nullptr, surf_skip_);
      if (q.skipped) continue;
      nrm = q.gradient;
      const double fn = wall_normal_force(q.distance, a, rod.cell_weight(i));
      if (fn > 0.0) {
        lag_normal_force_[k] = fn;
        lag_normal_[k] = nrm;
      }
      d = surface_->distance(rod.position(i), surf_near_[k]).distance;
      // The wire passes the open inlet near the entry: measured from entry_margin on.
      if (!rod.arc_length.empty() && rod.arc_length[k] < entry_margin_) continue;
    } else {
      const int s = segment_[static_cast<size_t>(i)];
      if (s < 0) continue;
      const auto& seg = index_.network().segment(s);
      const auto& net = index_.network();
      // Deep inside the located capsule the union's wall is farther still: nothing to record.
      if (capsule_distance(rod.position(i), net.node(seg.node_from), net.node(seg.node_to), seg.radius, nullptr,
                           nullptr) +
              a + 0.5 * contact_.onset <
          0.0)
        continue;
      const auto loc = index_.locate(rod.position(i), s, near_[k]);
      d = index_.wall_distance(rod.position(i), loc, near_[k], &nrm);
      const double fn = wall_normal_force(d, a, rod.cell_weight(i));
      if (fn > 0.0) {
        lag_normal_force_[static_cast<size_t>(i)] = fn;
        lag_normal_[static_cast<size_t>(i)] = nrm;
      }
    }
    stats_.max_outside = std::max(stats_.max_outside, d);
    if (d > a && stats_.outside_time < 0.0) {
      stats_.outside_time = rod.time;
      stats_.outside_arc_length = rod.arc_length.empty() ? 0.0 : rod.arc_length[k];
      stats_.outside_distance = d;
      stats_.outside_position = rod.position(i);
    }
    stats_.max_penetration = std::max(stats_.max_penetration, d + a);
  }
  // The step's wall distances for friction and for the outside check are contact work too.
  stats_.seconds_contact += since(t0);
}

void VesselForces::remap(const rod::RodView& rod, std::span<const int> source) {
  const int n = rod.vertex_count();
  drag_step_time_ = std::numeric_limits<double>::quiet_NaN();  // another vertex set
  remap_segments_.assign(segment_.begin(), segment_.end());
  remap_surf_near_.swap(surf_near_);
  surf_near_.resize(remap_surf_near_.size());
  remap_near_.swap(near_);
  near_.resize(remap_near_.size());
  ensure_size(n);
  for (int i = 0; i < n; ++i) {
    const int k = source[static_cast<size_t>(i)];
    const bool kept = k >= 0 && k < static_cast<int>(remap_segments_.size());
    segment_[static_cast<size_t>(i)] = kept ? remap_segments_[static_cast<size_t>(k)] : -1;
    // A neighbourhood is valid for any point within its margin, whichever vertex made it.
    auto& sn = surf_near_[static_cast<size_t>(i)];
    if (kept && k < static_cast<int>(remap_surf_near_.size()))
      sn = remap_surf_near_[static_cast<size_t>(k)];  // within capacity after the first remaps
    else
      sn.clear();
    auto& nb = near_[static_cast<size_t>(i)];
    if (kept && k < static_cast<int>(remap_near_.size()))
      nb = remap_near_[static_cast<size_t>(k)];  // within capacity after the first remaps
    else
      nb.clear();
  }
  // New vertices: located from the neighbour towards the base, as in evaluate().
  const int free = std::min(rod.first_clamped_vertex, n);
  for (int i = free - 1; i >= 0; --i) {
    if (segment_[static_cast<size_t>(i)] >= 0) continue;
    const int hint = i + 1 < n ? segment_[static_cast<size_t>(i + 1)] : -1;
    location_[static_cast<size_t>(i)] = index_.locate(rod.position(i), hint, near_[static_cast<size_t>(i)]);
    segment_[static_cast<size_t>(i)] = location_[static_cast<size_t>(i)].segment;
    ++stats_.lookups;
  }
  if (lagged_) end_step(rod);
}

}  // namespace flowire::coupling
