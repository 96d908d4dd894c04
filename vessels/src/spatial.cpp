#include "flowire/vessels/spatial.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace flowire::vessels {

AxisProjection project_on_axis(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double L2 = ab.squaredNorm();
  double t = L2 > 0.0 ? (p - a).dot(ab) / L2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return {t, (p - (a + t * ab)).norm()};
}

SpatialIndex::SpatialIndex(const Network& net, int window) : net_(net), window_(std::max(0, window)) {
  const int ns = net.num_segments();
  seg_boxes_.resize(static_cast<size_t>(ns));
  order_.resize(static_cast<size_t>(ns));
  for (int s = 0; s < ns; ++s) {
    const auto& seg = net.segment(s);
    Eigen::AlignedBox3d box(net.node(seg.node_from));
    box.extend(net.node(seg.node_to));
    box.min().array() -= seg.radius;
    box.max().array() += seg.radius;
    seg_boxes_[static_cast<size_t>(s)] = box;
    order_[static_cast<size_t>(s)] = s;
  }
  bvh_.reserve(static_cast<size_t>(2 * ns / 4 + 2));
  build_bvh(0, ns, 0);
}

int SpatialIndex::build_bvh(int first, int count, int depth) {
  const int id = static_cast<int>(bvh_.size());
  bvh_.emplace_back();
  Eigen::AlignedBox3d box;
  box.setEmpty();
  for (int i = first; i < first + count; ++i) box.extend(seg_boxes_[static_cast<size_t>(order_[static_cast<size_t>(i)])]);
  bvh_[static_cast<size_t>(id)].box = box;
  constexpr int kLeaf = 4;
  if (count <= kLeaf || depth > 60) {
    bvh_[static_cast<size_t>(id)].first = first;
    bvh_[static_cast<size_t>(id)].count = count;
    return id;
  }
  int axis = 0;
  box.sizes().maxCoeff(&axis);
  const int mid = first + count / 2;
  auto centre = [&](int s) { return seg_boxes_[static_cast<size_t>(s)].center()[axis]; };
  std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + first + count,
                   [&](int a, int b) { return centre(a) < centre(b); });
  const int left = build_bvh(first, mid - first, depth + 1);
  const int right = build_bvh(mid, first + count - mid, depth + 1);
  bvh_[static_cast<size_t>(id)].left = left;
  bvh_[static_cast<size_t>(id)].right = right;
  return id;
}

bool SpatialIndex::test_segment(const Vec3& p, int s, Location& best) const {
  const auto& seg = net_.segment(s);
  const auto pr = project_on_axis(p, net_.node(seg.node_from), net_.node(seg.node_to));
  if (pr.distance > seg.radius) return false;
  // Among several holding segments prefer the one whose axis is nearest, relative to radius.
  if (!best.inside || pr.distance / seg.radius < best.axis_distance / net_.segment(best.segment).radius) {
    best.segment = s;
    best.inside = true;
    best.t = pr.t;
    best.axis_distance = pr.distance;
  }
  return true;
}

Location SpatialIndex::locate(const Vec3& p, int hint) const {
  const int ns = net_.num_segments();
  if (hint >= 0 && hint < ns) {
    Location best;
    if (test_segment(p, hint, best)) {  // the wire moves little between queries: try the hint alone first
      best.from_window = true;
      ++stats_.window_hits;
      return best;
    }
    const int lo = std::max(0, hint - window_), hi = std::min(ns - 1, hint + window_);
    for (int s = lo; s <= hi; ++s) test_segment(p, s, best);
    const auto& h = net_.segment(hint);
    for (int n : {h.node_from, h.node_to}) {
      auto [b, e] = net_.node_segments(n);
      for (const int* it = b; it != e; ++it) test_segment(p, *it, best);
    }
    if (best.inside) {
      best.from_window = true;
      ++stats_.window_hits;
      return best;
    }
  }
  ++stats_.fallbacks;
  return fallback(p);
}

Location SpatialIndex::fallback(const Vec3& p) const {
  Location best;
  // 1) every segment whose box holds p.
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const auto& node = bvh_[static_cast<size_t>(stack[--top])];
    if (!node.box.contains(p)) continue;
    if (node.left < 0) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        const int s = order_[static_cast<size_t>(i)];
        if (seg_boxes_[static_cast<size_t>(s)].contains(p)) test_segment(p, s, best);
      }
    } else {
      assert(top + 2 <= 128);
      stack[top++] = node.left;
      stack[top++] = node.right;
    }
  }
  if (best.inside) return best;
  // 2) outside the lumen: the segment whose wall is nearest (branch and bound; a box's
  // distance is a lower bound of its capsules' wall distances).
  double best_d = std::numeric_limits<double>::infinity();
  top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const auto& node = bvh_[static_cast<size_t>(stack[--top])];
    if (node.box.exteriorDistance(p) >= best_d) continue;
    if (node.left < 0) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        const int s = order_[static_cast<size_t>(i)];
        const auto& seg = net_.segment(s);
        const auto pr = project_on_axis(p, net_.node(seg.node_from), net_.node(seg.node_to));
        const double d = pr.distance - seg.radius;
        if (d < best_d) {
          best_d = d;
          best.segment = s;
          best.t = pr.t;
          best.axis_distance = pr.distance;
        }
      }
    } else {
      const double dl = bvh_[static_cast<size_t>(node.left)].box.exteriorDistance(p);
      const double dr = bvh_[static_cast<size_t>(node.right)].box.exteriorDistance(p);
      if (dl < dr) {  // visit the nearer child first
        stack[top++] = node.right;
        stack[top++] = node.left;
      } else {
        stack[top++] = node.left;
        stack[top++] = node.right;
      }
    }
  }
  best.inside = false;
  return best;
}

Location SpatialIndex::locate_brute_force(const Vec3& p) const {
  Location best;
  for (int s = 0; s < net_.num_segments(); ++s) test_segment(p, s, best);
  if (best.inside) return best;
  double best_d = std::numeric_limits<double>::infinity();
  for (int s = 0; s < net_.num_segments(); ++s) {
    const auto& seg = net_.segment(s);
    const auto pr = project_on_axis(p, net_.node(seg.node_from), net_.node(seg.node_to));
    if (pr.distance - seg.radius < best_d) {
      best_d = pr.distance - seg.radius;
      best.segment = s;
      best.t = pr.t;
      best.axis_distance = pr.distance;
    }
  }
  return best;
}

void SpatialIndex::nearby_segments(const Vec3& p, double radius, std::vector<int>& out) const {
  out.clear();
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const auto& node = bvh_[static_cast<size_t>(stack[--top])];
    if (node.box.exteriorDistance(p) > radius) continue;
    if (node.left < 0) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        const int s = order_[static_cast<size_t>(i)];
        if (seg_boxes_[static_cast<size_t>(s)].exteriorDistance(p) <= radius) out.push_back(s);
      }
    } else {
      stack[top++] = node.left;
      stack[top++] = node.right;
    }
  }
}

double SpatialIndex::wall_distance(const Vec3& p, int hint, Vec3* gradient, Eigen::Matrix3d* hessian) const {
  // Union of capsules: d(p) = min_i (|p − proj_i(p)| − r_i). Segments meeting at an angle
  // are blended with a quadratic smooth minimum of width k_ij = 0.2·min(r)·(1 − t_i·t_j),
  // which is zero for collinear segments (a straight tube stays exact) and rounds the
  // crease where branches meet.
  const Location loc = locate(p, hint);
  const auto& s0 = net_.segment(loc.segment);
  const double d0 = loc.axis_distance - s0.radius;
  thread_local std::vector<int> cand;
  constexpr double kBlend = 0.2;
  nearby_segments(p, std::max(d0, 0.0) + kBlend * s0.radius + 1e-12, cand);

  using Mat3 = Eigen::Matrix3d;
  struct Term {
    double d;
    Vec3 g;
    Vec3 t;
    double r;
    Mat3 H;
  };
  auto term = [&](int s) {
    const auto& seg = net_.segment(s);
    const Vec3& a = net_.node(seg.node_from);
    const Vec3& b = net_.node(seg.node_to);
    const Vec3 ab = b - a;
    const double L2 = ab.squaredNorm();
    const double t_raw = L2 > 0.0 ? (p - a).dot(ab) / L2 : 0.0;
    const Vec3 q = a + std::clamp(t_raw, 0.0, 1.0) * ab;
    Vec3 g = p - q;
    const double n = g.norm();
    const Vec3 t = ab.normalized();
    if (n > 1e-300) g /= n;
    else g = t.unitOrthogonal();
    Mat3 H = Mat3::Zero();
    if (hessian && n > 1e-300) {
      // Distance to a segment: to its axis inside the span, to an end point beyond it.
      H = Mat3::Identity() - g * g.transpose();
      if (t_raw > 0.0 && t_raw < 1.0) H -= t * t.transpose();
      H /= n;
    }
    return Term{n - seg.radius, g, t, seg.radius, H};
  };
  // The plain minimum first, then blend the others in.
  int best_i = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < cand.size(); ++i) {
    const Term tm = term(cand[i]);
    if (tm.d < best_d) best_d = tm.d, best_i = static_cast<int>(i);
  }
  if (best_i < 0) {  // cannot happen (the located segment is a candidate), but stay defined
    if (gradient) *gradient = Vec3::UnitX();
    if (hessian) hessian->setZero();
    return d0;
  }
  const Term tb = term(cand[static_cast<size_t>(best_i)]);
  double d = tb.d;
  Vec3 g = tb.g;
  Mat3 H = tb.H;
  for (size_t i = 0; i < cand.size(); ++i) {
    if (static_cast<int>(i) == best_i) continue;
    const Term ti = term(cand[i]);
    const double k = kBlend * std::min(tb.r, ti.r) * (1.0 - std::abs(tb.t.dot(ti.t)));
    const double diff = std::abs(d - ti.d);
    if (k <= 0.0 || diff >= k) {
      if (ti.d < d) d = ti.d, g = ti.g, H = ti.H;
      continue;
    }
    // Quadratic smooth minimum: d' = min − h²k/4, h = (k − |d − d_i|)/k, so
    // ∇d' = (1 − h/2)∇min + (h/2)∇max and ∇²d' adds −(g − g_i)(g − g_i)ᵀ/(2k).
    const double h = (k - diff) / k;
    const double w = d <= ti.d ? 1.0 - 0.5 * h : 0.5 * h;  // weight of the current (d, g, H)
    if (hessian) {
      const Vec3 dg = g - ti.g;
      H = w * H + (1.0 - w) * ti.H - dg * dg.transpose() / (2.0 * k);
    }
    g = w * g + (1.0 - w) * ti.g;
    d = std::min(d, ti.d) - 0.25 * h * h * k;
  }
  if (gradient) *gradient = g;
  if (hessian) *hessian = H;
  return d;
}

}  // namespace flowire::vessels
