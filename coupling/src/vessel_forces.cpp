#include "flowire/coupling/vessel_forces.hpp"

#include <algorithm>
#include <chrono>

namespace flowire::coupling {

namespace {
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
}  // namespace

VesselForces::VesselForces(const vessels::SpatialIndex& index, double wire_radius, ContactParams contact,
                           DragModel drag, VelocityField velocity)
    : wire_radius_(wire_radius),
      where_(index),
      wall_(std::make_unique<NetworkWall>(where_)),
      contact_law_(contact, wire_radius),
      friction_law_(contact),
      drag_law_(drag, wire_radius, std::move(velocity)) {}

void VesselForces::set_surface(const vessels::LumenSurface* surface, double smoothing, double entry_margin) {
  if (surface)
    wall_ = std::make_unique<SurfaceWall>(*surface, smoothing, wire_radius_, 0.5 * contact().onset, entry_margin);
  else
    wall_ = std::make_unique<NetworkWall>(where_);
}

Vec3 VesselForces::total_drag() const {
  Vec3 sum = Vec3::Zero();
  for (int i = 0; i < free_ && i < static_cast<int>(drag_force_.size()); ++i)
    sum += drag_force_[static_cast<size_t>(i)];
  return sum;
}

void VesselForces::ensure_size(int n) {
  where_.ensure_size(n);
  wall_->ensure_size(n);
  if (static_cast<int>(force_.size()) >= n) return;
  force_.resize(static_cast<size_t>(n), Vec3::Zero());
  drag_force_.resize(static_cast<size_t>(n), Vec3::Zero());
  contact_force_.resize(static_cast<size_t>(n), Vec3::Zero());
}

void VesselForces::evaluate(const rod::RodView& rod, rod::ForceAccumulator& out) {
  const int n = rod.vertex_count();
  const int free = std::min(rod.first_clamped_vertex, n);
  ensure_size(n);
  free_ = free;
  ++stats_.evaluations;

  auto t0 = Clock::now();
  where_.locate(rod, free, stats_);
  stats_.seconds_lookup += since(t0);

  t0 = Clock::now();
  for (int i = 0; i < free; ++i) {
    contact_force_[static_cast<size_t>(i)].setZero();
    drag_force_[static_cast<size_t>(i)].setZero();
  }
  if (contact().enabled) {
    contact_law_.evaluate(rod, free, *wall_, out, contact_force_, stats_);
    friction_law_.evaluate(rod, free, contact_law_, out, contact_force_);
  }
  stats_.seconds_contact += since(t0);

  t0 = Clock::now();
  if (drag_law_.active()) drag_law_.evaluate(rod, free, where_, out, drag_force_, stats_);
  stats_.seconds_drag += since(t0);

  // The wall's share and the blood's, summed per vertex in the order they act.
  for (int i = 0; i < free; ++i) {
    const auto k = static_cast<size_t>(i);
    force_[k] = contact_force_[k] + drag_force_[k];
  }
}

void VesselForces::end_step(const rod::RodView& rod) {
  const auto t0 = Clock::now();
  const int free = std::min(rod.first_clamped_vertex, rod.vertex_count());
  ensure_size(rod.vertex_count());
  drag_law_.end_step(free, stats_);
  contact_law_.end_step(rod, *wall_, stats_, contact_force_);
  // The step's wall distances for friction and for the outside check are contact work too.
  stats_.seconds_contact += since(t0);
}

void VesselForces::remap(const rod::RodView& rod, std::span<const int> source) {
  drag_law_.invalidate();  // another vertex set
  contact_law_.invalidate_anchors();
  wall_->remap(source, rod.vertex_count());
  where_.remap(rod, source, stats_);
  if (contact_law_.lagged()) end_step(rod);
}

}  // namespace flowire::coupling
