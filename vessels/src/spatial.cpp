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
  for (int i = first; i < first + count; ++i)
    box.extend(seg_boxes_[static_cast<size_t>(order_[static_cast<size_t>(i)])]);
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

bool SpatialIndex::holds_in_window(const Vec3& p, int hint, Location& best) const {
  const int ns = net_.num_segments();
  if (hint < 0 || hint >= ns) return false;
  if (test_segment(p, hint, best)) return true;  // the wire moves little between queries: the hint alone first
  const int lo = std::max(0, hint - window_), hi = std::min(ns - 1, hint + window_);
  for (int s = lo; s <= hi; ++s) test_segment(p, s, best);
  const auto& h = net_.segment(hint);
  for (int n : {h.node_from, h.node_to}) {
    auto [b, e] = net_.node_segments(n);
    for (const int* it = b; it != e; ++it) test_segment(p, *it, best);
  }
  return best.inside;
}

bool SpatialIndex::locate_in_window(const Vec3& p, int hint, Location& best) const {
  if (holds_in_window(p, hint, best)) {
    best.from_window = true;
    ++stats_.window_hits;
    return true;
  }
  ++stats_.fallbacks;
  return false;
}

Location SpatialIndex::locate(const Vec3& p, int hint) const {
  Location best;
  if (locate_in_window(p, hint, best)) return best;
  return fallback(p);
}

Location SpatialIndex::locate(const Vec3& p, int hint, Neighbourhood& nb) const {
  Location best;
  if (locate_in_window(p, hint, best)) return best;
  const double delta = nb.reach >= 0.0 ? (p - nb.centre).norm() : std::numeric_limits<double>::infinity();
  if (delta <= nb.reach) {
    // The fallback's two passes over the neighbourhood. A segment left out has its box
    // farther than reach − δ from p, and a box is never farther than its capsule's wall.
    Location loc;
    for (int s : nb.segments)
      if (seg_boxes_[static_cast<size_t>(s)].contains(p)) test_segment(p, s, loc);
    if (loc.inside) return loc;
    double best_d = std::numeric_limits<double>::infinity();
    for (int s : nb.segments) nearest_wall_candidate(p, s, best_d, loc);
    if (best_d <= nb.reach - delta) return loc;
  }
  const Location loc = fallback(p);
  gather(p, gather_reach(loc), nb);
  return loc;
}

void SpatialIndex::nearest_wall_candidate(const Vec3& p, int s, double& best_d, Location& best) const {
  const auto& seg = net_.segment(s);
  const auto pr = project_on_axis(p, net_.node(seg.node_from), net_.node(seg.node_to));
  const double d = pr.distance - seg.radius;
  // Ties (a point beyond a node shared by two equal tubes) go to the lower index, so the
  // answer does not depend on the order segments are visited in.
  if (d < best_d || (d == best_d && s < best.segment)) {
    best_d = d;
    best.segment = s;
    best.t = pr.t;
    best.axis_distance = pr.distance;
  }
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
    if (node.box.exteriorDistance(p) > best_d) continue;  // (equal: a tie may go to a lower index)
    if (node.left < 0) {
      for (int i = node.first; i < node.first + node.count; ++i)
        nearest_wall_candidate(p, order_[static_cast<size_t>(i)], best_d, best);
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
  for (int s = 0; s < net_.num_segments(); ++s) nearest_wall_candidate(p, s, best_d, best);
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

void SpatialIndex::gather(const Vec3& centre, double reach, Neighbourhood& nb) const {
  ++stats_.gathers;
  nb.centre = centre;
  nb.reach = reach;
  nearby_segments(centre, reach, nb.segments);
}

namespace {
constexpr double kBlend = 0.2;  // blend width k_ij = kBlend·min(r)·(1 − |t_i·t_j|)
}  // namespace

double SpatialIndex::wall_search_radius(const Location& loc) const {
  const auto& s0 = net_.segment(loc.segment);
  const double d0 = loc.axis_distance - s0.radius;
  return std::max(d0, 0.0) + kBlend * s0.radius + 1e-12;
}

double SpatialIndex::gather_reach(const Location& loc) const {
  // Room for the point to move by half its vessel's radius before the next gathering.
  return wall_search_radius(loc) + 0.5 * net_.segment(loc.segment).radius;
}

double SpatialIndex::wall_distance(const Vec3& p, int hint, Vec3* gradient, Eigen::Matrix3d* hessian) const {
  // Union of capsules: d(p) = min_i (|p − proj_i(p)| − r_i). Segments meeting at an angle
  // are blended with a quadratic smooth minimum of width k_ij = 0.2·min(r)·(1 − t_i·t_j),
  // which is zero for collinear segments (a straight tube stays exact) and rounds the
  // crease where branches meet.
  const Location loc = locate(p, hint);
  thread_local std::vector<int> cand;
  nearby_segments(p, wall_search_radius(loc), cand);
  return blended_distance(p, cand, loc, gradient, hessian);
}

double SpatialIndex::wall_distance(const Vec3& p, const Location& loc, Neighbourhood& nb, Vec3* gradient,
                                   Eigen::Matrix3d* hessian) const {
  const double radius = wall_search_radius(loc);
  const double delta = nb.reach >= 0.0 ? (p - nb.centre).norm() : std::numeric_limits<double>::infinity();
  if (!(radius + delta <= nb.reach)) gather(p, gather_reach(loc), nb);
  // The segments nearby_segments(p, radius) would find, in its order: every one is in nb
  // (its box is within radius + δ ≤ reach of the centre) and nb keeps the tree's order.
  thread_local std::vector<int> cand;
  cand.clear();
  for (int s : nb.segments)
    if (seg_boxes_[static_cast<size_t>(s)].exteriorDistance(p) <= radius) cand.push_back(s);
  return blended_distance(p, cand, loc, gradient, hessian);
}

double SpatialIndex::blended_distance(const Vec3& p, const std::vector<int>& cand, const Location& loc, Vec3* gradient,
                                      Eigen::Matrix3d* hessian) const {
  using Mat3 = Eigen::Matrix3d;
  // Per candidate: the distance and axis first (cheap); the normal and curvature only for
  // the terms that enter the result (the minimum and those within the blend width of it).
  struct Term {
    double d;
    double n;      // distance to the axis point
    double t_raw;  // unclamped axial parameter
    Vec3 g;
    Vec3 t;
    double r;
    Vec3 diff;  // p − axis point
  };
  thread_local std::vector<Term> terms;
  terms.resize(cand.size());
  int best_i = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < cand.size(); ++i) {
    const auto& seg = net_.segment(cand[i]);
    const Vec3& a = net_.node(seg.node_from);
    const Vec3& b = net_.node(seg.node_to);
    const Vec3 ab = b - a;
    const double L2 = ab.squaredNorm();
    Term& tm = terms[i];
    tm.t_raw = L2 > 0.0 ? (p - a).dot(ab) / L2 : 0.0;
    const Vec3 q = a + std::clamp(tm.t_raw, 0.0, 1.0) * ab;
    tm.diff = p - q;
    tm.n = tm.diff.norm();
    tm.t = ab.normalized();
    tm.r = seg.radius;
    tm.d = tm.n - seg.radius;
    if (tm.d < best_d) best_d = tm.d, best_i = static_cast<int>(i);
  }
  if (best_i < 0) {  // cannot happen (the located segment is a candidate), but stay defined
    if (gradient) *gradient = Vec3::UnitX();
    if (hessian) hessian->setZero();
    return loc.axis_distance - net_.segment(loc.segment).radius;
  }
  auto finish = [&](const Term& tm, Vec3& g, Mat3* H) {
    g = tm.diff;
    if (tm.n > 1e-300)
      g /= tm.n;
    else
      g = tm.t.unitOrthogonal();
    if (!H) return;
    H->setZero();
    if (tm.n > 1e-300) {
      // Distance to a segment: to its axis inside the span, to an end point beyond it.
      *H = Mat3::Identity() - g * g.transpose();
      if (tm.t_raw > 0.0 && tm.t_raw < 1.0) *H -= tm.t * tm.t.transpose();
      *H /= tm.n;
    }
  };
  const Term& tb = terms[static_cast<size_t>(best_i)];
  double d = tb.d;
  Vec3 g;
  Mat3 H = Mat3::Zero();
  finish(tb, g, hessian ? &H : nullptr);
  Vec3 gi;
  Mat3 Hi = Mat3::Zero();
  for (size_t i = 0; i < cand.size(); ++i) {
    if (static_cast<int>(i) == best_i) continue;
    const Term& ti = terms[i];
    const double k = kBlend * std::min(tb.r, ti.r) * (1.0 - std::abs(tb.t.dot(ti.t)));
    const double diff = std::abs(d - ti.d);
    if (k <= 0.0 || diff >= k) {
      if (ti.d < d) {
        d = ti.d;
        finish(ti, g, hessian ? &H : nullptr);
      }
      continue;
    }
    finish(ti, gi, hessian ? &Hi : nullptr);
    // Quadratic smooth minimum: d' = min − h²k/4, h = (k − |d − d_i|)/k, so
    // ∇d' = (1 − h/2)∇min + (h/2)∇max and ∇²d' adds −(g − g_i)(g − g_i)ᵀ/(2k).
    const double h = (k - diff) / k;
    const double w = d <= ti.d ? 1.0 - 0.5 * h : 0.5 * h;  // weight of the current (d, g, H)
    if (hessian) {
      const Vec3 dg = g - gi;
      H = w * H + (1.0 - w) * Hi - dg * dg.transpose() / (2.0 * k);
    }
    g = w * g + (1.0 - w) * gi;
    d = std::min(d, ti.d) - 0.25 * h * h * k;
  }
  if (gradient) *gradient = g;
  if (hessian) *hessian = H;
  return d;
}

}  // namespace flowire::vessels
