#include "flowire/coupling/wall.hpp"

#include <algorithm>

namespace flowire::coupling {

bool NetworkWall::deep_inside(int segment, const Vec3& x, double a, double reach) const {
  const auto& net = where_.index().network();
  const auto& seg = net.segment(segment);
  // The union's distance is at most the located capsule's: deep inside it, no wall is near.
  return capsule_distance(x, net.node(seg.node_from), net.node(seg.node_to), seg.radius, nullptr, nullptr) + a + reach <
         0.0;
}

bool NetworkWall::at(int i, const Vec3& x, double a, double reach, double* d, Vec3* n, Mat3* H) {
  if (deep_inside(where_.segment(i), x, a, reach)) return false;
  *d = where_.index().wall_distance(x, where_.location(i), where_.near(i), n, H);
  return true;
}

bool NetworkWall::accepted(int i, const Vec3& x, double a, double reach, double /*s*/, AcceptedWall* out) {
  const int s = where_.segment(i);
  if (s < 0 || deep_inside(s, x, a, reach)) return false;  // nothing to record
  const auto loc = where_.index().locate(x, s, where_.near(i));
  out->distance = where_.index().wall_distance(x, loc, where_.near(i), &out->normal);
  out->contact_distance = out->distance;
  out->measured = true;
  return true;
}

SurfaceWall::SurfaceWall(const vessels::LumenSurface& surface, double smoothing, double wire_radius, double reach,
                         double entry_margin)
    : surface_(surface),
      smoothing_(smoothing),
      margin_(std::max(wire_radius, smoothing)),
      skip_(surface_skip_depth(wire_radius, smoothing) + reach),  // (the onset starts earlier)
      entry_margin_(entry_margin) {}

void SurfaceWall::ensure_size(int n) {
  if (static_cast<int>(near_.size()) < n) near_.resize(static_cast<size_t>(n));
}

bool SurfaceWall::at(int i, const Vec3& x, double /*a*/, double /*reach*/, double* d, Vec3* n, Mat3* H) {
  const auto q = surface_.smooth_distance(x, smoothing_, near_[static_cast<size_t>(i)], margin_, H, skip_);
  if (q.skipped) return false;
  *d = q.distance;
  *n = q.gradient;
  return true;
}

bool SurfaceWall::accepted(int i, const Vec3& x, double /*a*/, double /*reach*/, double s, AcceptedWall* out) {
  // The friction's normal force from the contact's own (smooth) distance; the exact distance
  // measures how far outside the wire is. A vertex deeper than the skip depth has no normal
  // force, and its distance, below −a, could not raise an "outside" record.
  auto& near = near_[static_cast<size_t>(i)];
  const auto q = surface_.smooth_distance(x, smoothing_, near, margin_, nullptr, skip_);
  if (q.skipped) return false;
  out->contact_distance = q.distance;
  out->normal = q.gradient;
  out->distance = surface_.distance(x, near).distance;
  // The wire passes the open inlet near the entry: measured from entry_margin on.
  out->measured = s >= entry_margin_;
  return true;
}

void SurfaceWall::remap(std::span<const int> source, int n) {
  remap_near_.swap(near_);
  near_.resize(remap_near_.size());
  ensure_size(n);
  for (int i = 0; i < n; ++i) {
    const int k = source[static_cast<size_t>(i)];
    // A neighbourhood is valid for any point within its margin, whichever vertex made it.
    auto& sn = near_[static_cast<size_t>(i)];
    if (k >= 0 && k < static_cast<int>(remap_near_.size()))
      sn = remap_near_[static_cast<size_t>(k)];  // within capacity after the first remaps
    else
      sn.clear();
  }
}

}  // namespace flowire::coupling
