#include "flowire/coupling/vessel_path.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace flowire::coupling {

using vessels::Vec3;

VesselPath::VesselPath(const vessels::Network& net, int entry) {
  std::vector<char> seen(static_cast<size_t>(net.num_nodes()), 0);
  int node = entry, came_by = -1;
  points_.push_back(net.node(node));
  s_.push_back(0.0);
  seen[static_cast<size_t>(node)] = 1;
  for (;;) {
    int next_seg = -1;
    auto [b, e] = net.node_segments(node);
    for (const int* it = b; it != e; ++it) {
      if (*it == came_by) continue;
      if (next_seg < 0 || net.segment(*it).radius > net.segment(next_seg).radius) next_seg = *it;
    }
    if (next_seg < 0) break;
    const auto& seg = net.segment(next_seg);
    const int other = seg.node_from == node ? seg.node_to : seg.node_from;
    if (seen[static_cast<size_t>(other)]) break;
    seen[static_cast<size_t>(other)] = 1;
    const double len = (net.node(other) - net.node(node)).norm();
    if (len > 0.0) {
      points_.push_back(net.node(other));
      s_.push_back(s_.back() + len);
      radius_.push_back(seg.radius);
    }
    node = other;
    came_by = next_seg;
  }
  if (points_.size() < 2) throw std::invalid_argument("VesselPath: the entry node has no segment");
  // The turn: a half circle of radius 0.3·r whose far side stays 0.4·r inside the wall.
  const double r_end = radius_.back();
  turn_radius_ = 0.3 * r_end;
  turn_at_ = std::max(0.0, length() - 0.7 * r_end);
  turn_normal_ = tangent(turn_at_).unitOrthogonal();
  // The way back keeps the offset 0.6·r_end: it is laid only as far back as the vessel
  // stays at least 0.8·r_end wide, so it keeps 0.2·r_end off the wall.
  return_until_ = turn_at_;
  for (int i = static_cast<int>(radius_.size()) - 1; i >= 0; --i) {
    if (radius_[static_cast<size_t>(i)] < 0.8 * r_end) break;
    return_until_ = std::min(turn_at_, s_[static_cast<size_t>(i)]);
  }
}

int VesselPath::piece(double s) const {
  const auto it = std::upper_bound(s_.begin(), s_.end(), s);
  return std::clamp(static_cast<int>(it - s_.begin()) - 1, 0, static_cast<int>(s_.size()) - 2);
}

Vec3 VesselPath::at(double s) const {
  s = std::clamp(s, 0.0, length());
  const int i = piece(s);
  const double a = (s - s_[static_cast<size_t>(i)]) / (s_[static_cast<size_t>(i) + 1] - s_[static_cast<size_t>(i)]);
  return (1.0 - a) * points_[static_cast<size_t>(i)] + a * points_[static_cast<size_t>(i) + 1];
}

Vec3 VesselPath::tangent(double s) const {
  const int i = piece(std::clamp(s, 0.0, length()));
  return (points_[static_cast<size_t>(i) + 1] - points_[static_cast<size_t>(i)]).normalized();
}

double VesselPath::radius(double s) const { return radius_[static_cast<size_t>(piece(std::clamp(s, 0.0, length())))]; }

double VesselPath::max_wire_length() const {
  return turn_at_ + std::numbers::pi * turn_radius_ + (turn_at_ - return_until_);
}

Vec3 VesselPath::wire_point(double s) const {
  if (s <= turn_at_) return at(s);
  const double u = s - turn_at_;
  const double arc = std::numbers::pi * turn_radius_;
  const Vec3 p0 = at(turn_at_);
  const Vec3 t = tangent(turn_at_);
  if (u <= arc) {
    const double phi = u / turn_radius_;
    return p0 + turn_radius_ * ((1.0 - std::cos(phi)) * turn_normal_ + std::sin(phi) * t);
  }
  const double back = turn_at_ - (u - arc);
  if (back < return_until_ - 1e-12)
    throw std::invalid_argument("VesselPath: the wire is longer than the path there and back");
  return at(back) + 2.0 * turn_radius_ * turn_normal_;
}

}  // namespace flowire::coupling
