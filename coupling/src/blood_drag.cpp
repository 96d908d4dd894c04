#include "flowire/coupling/blood_drag.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "flowire/common/error.hpp"

namespace flowire::coupling {

BloodDrag::BloodDrag(DragModel model, double wire_radius, VelocityField velocity)
    : model_(model), wire_radius_(wire_radius), velocity_(std::move(velocity)) {
  model_.wire_radius = wire_radius;
  // Checks the slender-body length once, at set-up, not in the first step.
  if (model_.law == DragLaw::SlenderBody)
    (void)slender_body_normal_coefficient(model_.viscosity, model_.wire_length, wire_radius);
}

void BloodDrag::ensure_size(int n) {
  if (static_cast<int>(fluid_.size()) >= n) return;
  fluid_.resize(static_cast<size_t>(n), Vec3::Zero());
  reynolds_.resize(static_cast<size_t>(n), 0.0);
  lin_.resize(static_cast<size_t>(n));
}

void BloodDrag::evaluate(const rod::RodView& rod, int free, const WireLocation& where, rod::ForceAccumulator& out,
                         std::span<Vec3> tally, InteractionStats& stats) {
  const int n = rod.vertex_count();
  ensure_size(n);
  const auto& net = where.index().network();
  DragInput in;
  in.dt = rod.dt;
  // Once a step: the first evaluation of a step, at Newton's initial guess, evaluates the law
  // and keeps it; the step's later iterates and trials take it linearized in the wire velocity.
  // The blood velocity, the vessel geometry and the drag coefficient are then those of the guess
  // (the flow frame is the step's anyway), and the velocity Jacobian is exact for the force the
  // step uses.
  const bool per_step = model_.once_per_step && rod.dt > 0.0;
  if (per_step && !(rod.time == step_time_ && rod.dt == step_dt_ && rod.solve_serial == step_serial_)) {
    for (auto& l : lin_) l.valid = false;
    step_time_ = rod.time;
    step_dt_ = rod.dt;
    step_serial_ = rod.solve_serial;
  }
  for (int i = 0; i < free; ++i) {
    const auto k = static_cast<size_t>(i);
    if (k < shielded_.size() && shielded_[k]) {
      fluid_[k].setZero(), reynolds_[k] = 0.0;
      continue;
    }
    auto& lin = lin_[k];
    if (per_step && lin.valid) {
      const Vec3 f = lin.force + lin.dfdv * (rod.velocity(i) - lin.v);
      // The normal Reynolds number of this iterate (what end_step records of the accepted one).
      if (model_.law == DragLaw::Cylinder) {
        const Vec3 w = fluid_[k] - rod.velocity(i);
        reynolds_[k] = model_.density * (w - w.dot(lin.t) * lin.t).norm() * 2.0 * rod.vertex_radius(i, wire_radius_) /
                       model_.viscosity;
      }
      out.add_force(i, f);
      out.add_velocity_jacobian(i, lin.dfdv);
      tally[k] = f;
      continue;
    }
    const Vec3& x = rod.position(i);
    const int s = where.segment(i);
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
    const auto d = blood_drag(model_, in);
    ++stats.drag_evaluations;
    if (per_step) lin = {d.force, in.v, in.t, d.dfdv, true};
    reynolds_[k] = d.reynolds_normal;
    out.add_force(i, d.force);
    out.add_velocity_jacobian(i, d.dfdv);
    tally[k] = d.force;
  }
}

void BloodDrag::end_step(int free, InteractionStats& stats) {
  invalidate();  // the next step linearizes anew
  // The Reynolds number of the accepted state (the last evaluation), not of the Newton and
  // line-search trials on the way.
  for (int i = 0; i < free && i < static_cast<int>(reynolds_.size()); ++i)
    stats.max_reynolds = std::max(stats.max_reynolds, reynolds_[static_cast<size_t>(i)]);
}

}  // namespace flowire::coupling
