#include "flowire/coupling/occlusion.hpp"

#include <algorithm>
#include <cmath>

#include "flowire/flow/annulus.hpp"

namespace flowire::coupling {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

WireOcclusion::WireOcclusion(const flow::FlowSolver& flow) : flow_(flow) {
  const auto& net = flow.network();
  const auto ne = static_cast<size_t>(net.num_segments());
  axis_.resize(ne);
  inertance_.resize(ne);
  const double rho = flow.spec().density;
  for (size_t s = 0; s < ne; ++s) {
    const auto& seg = net.segment(static_cast<int>(s));
    axis_[s] = (net.node(seg.node_to) - net.node(seg.node_from)).normalized();
    inertance_[s] = rho * seg.length / (kPi * seg.radius_from * seg.radius_to);
  }
  sum_.assign(ne, Sum{});
  occ_.assign(ne, flow::SegmentOcclusion{});
  touched_.reserve(ne);
}

std::span<const flow::SegmentOcclusion> WireOcclusion::update(std::span<const Eigen::Vector3d> x, int free,
                                                              std::span<const int> segment,
                                                              std::span<const double> edge_radius) {
  return update({Body{x, free, segment, edge_radius}});
}

std::span<const flow::SegmentOcclusion> WireOcclusion::update(std::initializer_list<Body> bodies) {
  for (int s : touched_) {
    sum_[static_cast<size_t>(s)] = Sum{};
    occ_[static_cast<size_t>(s)] = flow::SegmentOcclusion{};
  }
  touched_.clear();
  for (const Body& b : bodies) add(b.x, b.free, b.segment, b.edge_radius);
  return finish();
}

void WireOcclusion::add(std::span<const Eigen::Vector3d> x, int free, std::span<const int> segment,
                        std::span<const double> edge_radius) {
  const auto& net = flow_.network();
  const double eta = flow_.spec().viscosity, rho = flow_.spec().density;
  const int n = static_cast<int>(x.size());
  free = std::min({free, n, static_cast<int>(segment.size())});
  for (int i = 0; i < free; ++i) {
    const int s = segment[static_cast<size_t>(i)];
    if (s < 0) continue;
    const auto k = static_cast<size_t>(s);
    const auto& seg = net.segment(s);
    const Eigen::Vector3d& e = axis_[k];
    // The vertex's share of its edges, along the axis, and its wire radius.
    double ell = 0.0, a_sum = 0.0, w_sum = 0.0;
    for (int j : {i - 1, i}) {  // edge j joins vertices j and j + 1
      if (j < 0 || j + 1 >= n) continue;
      const Eigen::Vector3d d = x[static_cast<size_t>(j + 1)] - x[static_cast<size_t>(j)];
      const double half = 0.5 * std::abs(d.dot(e));
      ell += half;
      const double a = static_cast<size_t>(j) < edge_radius.size() ? edge_radius[static_cast<size_t>(j)] : 0.0;
      a_sum += half * a;
      w_sum += half;
    }
    if (!(ell > 0.0)) continue;
    const double a = a_sum / w_sum;
    const Eigen::Vector3d rel = x[static_cast<size_t>(i)] - net.node(seg.node_from);
    const double along = std::clamp(rel.dot(e) / seg.length, 0.0, 1.0);
    const double offset = (rel - rel.dot(e) * e).norm();
    const double r = seg.radius_from + along * (seg.radius_to - seg.radius_from);
    const double r_eff = std::max(r, a / kMaxOcclusionRadiusRatio);  // the model's range
    Sum& acc = sum_[k];
    if (acc.length == 0.0) touched_.push_back(s);
    acc.length += ell;
    acc.offset += ell * offset;
    acc.wire += ell * a;
    acc.radius += ell * r;
    acc.resistance += 8.0 * eta * ell / (kPi * r * r * r * r);
    acc.inertance += rho * ell * (1.0 / (kPi * (r_eff * r_eff - a * a)) - 1.0 / (kPi * r_eff * r_eff));
  }
}

std::span<const flow::SegmentOcclusion> WireOcclusion::finish() {
  const auto& net = flow_.network();
  stats_.occupied_segments = static_cast<int>(touched_.size());
  for (int s : touched_) {
    const auto k = static_cast<size_t>(s);
    const Sum& acc = sum_[k];
    const auto& seg = net.segment(s);
    // A wire looping inside one segment occupies it once.
    const double scale = std::min(1.0, seg.length / acc.length);
    const double a = acc.wire / acc.length, r = acc.radius / acc.length, d = acc.offset / acc.length;
    double ratio = a / r;
    if (ratio > kMaxOcclusionRadiusRatio) {
      ratio = kMaxOcclusionRadiusRatio;
      ++stats_.radius_ratio_clamped;
    }
    const double gap = r * (1.0 - ratio);  // R − a at the ratio evaluated
    const double f = flow::annulus_resistance_factor(ratio, gap > 0.0 ? d / gap : 0.0);
    auto& o = occ_[k];
    o.occupied_fraction = std::min(1.0, acc.length / seg.length);
    o.gradient_factor = f;
    o.resistance_factor = 1.0 + (f - 1.0) * scale * acc.resistance / flow_.resistance(s);
    o.inertance_factor = 1.0 + scale * acc.inertance / inertance_[k];
    stats_.max_resistance_factor = std::max(stats_.max_resistance_factor, o.resistance_factor);
  }
  return occ_;
}

}  // namespace flowire::coupling
