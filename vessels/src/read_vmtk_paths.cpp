// VMTK vmtkcenterlines output: one polyline per inlet→outlet path, every path repeating the
// trunk it shares with the others under point ids of its own (coordinates equal or nearly so),
// with the point array MaximumInscribedSphereRadius. The paths are merged into one tree from
// their common inlet (the path end shared by most paths): a path stays on the tree while its
// points lie within `merge_tolerance` × the local radius of it, and the last such point becomes
// a junction (splitting the branch there); what follows is a new branch. Branches are named
// branch_0, branch_1, ... in the order they are made. File units throughout.
#include <fmt/format.h>

#include <algorithm>
#include <cstddef>
#include <limits>
#include <utility>

#include "flowire/common/error.hpp"
#include "polydata_internal.hpp"

namespace flowire::vessels::detail {
namespace {

struct Location {
  size_t branch = 0;
  size_t seg = 0;  // segment index within the branch
  double t = 0.0;  // parameter on the segment
  double dist = std::numeric_limits<double>::infinity();
};

/// Closest point to x on segments [s0, s1) of branch b, if closer than `best`.
void scan(const std::vector<Polyline>& tree, size_t b, size_t s0, size_t s1, const Vec3& x, Location& best) {
  const auto& pts = tree[b].points;
  s1 = std::min(s1, pts.size() - 1);
  for (size_t s = s0; s < s1; ++s) {
    const Vec3 d = pts[s + 1] - pts[s];
    const double dd = d.squaredNorm();
    const double t = std::clamp(dd > 0.0 ? (x - pts[s]).dot(d) / dd : 0.0, 0.0, 1.0);
    const double dist = (pts[s] + t * d - x).norm();
    if (dist < best.dist) best = {b, s, t, dist};
  }
}

Location closest_on(const std::vector<Polyline>& tree, const Vec3& x) {
  Location best;
  for (size_t b = 0; b < tree.size(); ++b) scan(tree, b, 0, tree[b].points.size(), x, best);
  return best;
}

/// Closest point near the previous location: a few segments either side on its branch and,
/// close to a branch end, on the branches that meet there.
Location closest_near(const std::vector<Polyline>& tree, const Location& hint, const Vec3& x) {
  constexpr size_t window = 4;
  Location best;
  const auto& own = tree[hint.branch].points;
  const size_t nseg = own.size() - 1;
  scan(tree, hint.branch, hint.seg > window ? hint.seg - window : 0, hint.seg + window + 1, x, best);
  if (hint.seg + window >= nseg || hint.seg < window) {
    for (size_t b = 0; b < tree.size(); ++b) {
      if (b == hint.branch) continue;
      const auto& p = tree[b].points;
      if (hint.seg + window >= nseg && (p.front() == own.back() || p.back() == own.back())) {
        scan(tree, b, 0, window, x, best);
        scan(tree, b, p.size() > window + 1 ? p.size() - 1 - window : 0, p.size(), x, best);
      }
      if (hint.seg < window && (p.back() == own.front() || p.front() == own.front())) {
        scan(tree, b, 0, window, x, best);
        scan(tree, b, p.size() > window + 1 ? p.size() - 1 - window : 0, p.size(), x, best);
      }
    }
  }
  return best;
}

double radius_at(const std::vector<Polyline>& tree, const Location& l) {
  const auto& r = tree[l.branch].radii;
  return (1.0 - l.t) * r[l.seg] + l.t * r[l.seg + 1];
}

/// Index of the point of `tree[l.branch]` at location l, inserting one if needed.
size_t point_at(std::vector<Polyline>& tree, const Location& l) {
  auto& p = tree[l.branch];
  const Vec3 x = (1.0 - l.t) * p.points[l.seg] + l.t * p.points[l.seg + 1];
  const double eps = 1e-9 * std::max(1.0, x.norm());
  if ((x - p.points[l.seg]).norm() <= eps) return l.seg;
  if ((x - p.points[l.seg + 1]).norm() <= eps) return l.seg + 1;
  const double r = radius_at(tree, l);
  p.points.insert(p.points.begin() + static_cast<std::ptrdiff_t>(l.seg + 1), x);
  p.radii.insert(p.radii.begin() + static_cast<std::ptrdiff_t>(l.seg + 1), r);
  return l.seg + 1;
}

bool is_branch_end(const std::vector<Polyline>& tree, const Vec3& x, size_t except) {
  for (size_t b = 0; b < tree.size(); ++b) {
    if (b == except) continue;
    if (tree[b].points.front() == x || tree[b].points.back() == x) return true;
  }
  return false;
}

/// Orients every path so that it starts at the end shared by most paths (the inlet).
void orient_paths(std::vector<Polyline>& paths, double tol) {
  std::vector<std::pair<Vec3, double>> ends;
  for (const auto& p : paths) {
    ends.emplace_back(p.points.front(), p.radii.front());
    ends.emplace_back(p.points.back(), p.radii.back());
  }
  size_t best = 0;
  int best_count = -1;
  for (size_t e = 0; e < ends.size(); ++e) {
    int count = 0;
    for (size_t f = 0; f < ends.size(); ++f)
      if ((ends[f].first - ends[e].first).norm() <= tol * std::max(ends[e].second, ends[f].second) + 1e-300) ++count;
    if (count > best_count) best_count = count, best = e;
  }
  const Vec3 inlet = ends[best].first;
  for (auto& p : paths) {
    if ((p.points.back() - inlet).norm() < (p.points.front() - inlet).norm()) {
      std::reverse(p.points.begin(), p.points.end());
      std::reverse(p.radii.begin(), p.radii.end());
    }
  }
}

/// Overlapping inlet→outlet paths (file units) merged into one tree of branches.
std::vector<Polyline> merge_paths(std::vector<Polyline> paths, double merge_tolerance, const std::string& source) {
  const double tol = std::max(merge_tolerance, 0.0);
  orient_paths(paths, std::max(tol, 1e-6));
  std::vector<Polyline> tree;
  for (size_t j = 0; j < paths.size(); ++j) {
    Polyline& p = paths[j];
    if (tree.empty()) {
      tree.push_back(std::move(p));
      continue;
    }
    // Walk from the inlet while the path stays on the tree.
    size_t d = 0;
    Location last;
    for (; d < p.points.size(); ++d) {
      Location loc;
      if (d > 0) loc = closest_near(tree, last, p.points[d]);
      if (d == 0 || loc.dist > tol * radius_at(tree, loc)) loc = closest_on(tree, p.points[d]);
      if (loc.dist > tol * radius_at(tree, loc)) break;
      last = loc;
    }
    if (d == p.points.size()) continue;  // entirely on the tree already
    if (d == 0) {                        // does not start on the tree: a piece of its own
      tree.push_back(std::move(p));
      continue;
    }
    const size_t b = last.branch;
    const size_t k = point_at(tree, last);
    const Vec3 x = tree[b].points[k];
    const double r = tree[b].radii[k];
    Polyline tail;
    tail.points.push_back(x);
    tail.radii.push_back(r);
    for (size_t i = d; i < p.points.size(); ++i) {
      // Points closer than rounding to the junction would make a zero-length piece.
      if ((p.points[i] - tail.points.back()).norm() <= 1e-9 * std::max(1.0, p.points[i].norm())) continue;
      tail.points.push_back(p.points[i]);
      tail.radii.push_back(p.radii[i]);
    }
    if (tail.points.size() < 2) continue;
    const bool at_end = k + 1 == tree[b].points.size();
    if (at_end && !is_branch_end(tree, x, b)) {  // the path goes on past an outlet: extend it
      append_points(tree[b], tail, 1);
      continue;
    }
    if (k > 0 && !at_end) {  // split the branch at the junction
      Polyline rest;
      rest.points.assign(tree[b].points.begin() + static_cast<std::ptrdiff_t>(k), tree[b].points.end());
      rest.radii.assign(tree[b].radii.begin() + static_cast<std::ptrdiff_t>(k), tree[b].radii.end());
      tree[b].points.resize(k + 1);
      tree[b].radii.resize(k + 1);
      tree.push_back(std::move(rest));
    }
    tree.push_back(std::move(tail));
  }
  if (tree.empty()) throw_input_error(source, "no centerline paths");
  for (size_t b = 0; b < tree.size(); ++b) tree[b].name = fmt::format("branch_{}", b);
  return tree;
}

}  // namespace

bool paths_overlap(std::vector<Polyline> paths, double tol) {
  if (paths.size() < 2) return false;
  orient_paths(paths, tol);
  for (size_t j = 1; j < paths.size(); ++j) {
    for (size_t i = 0; i < j; ++i) {
      const std::vector<Polyline> tree{paths[i]};
      const auto& pj = paths[j];
      const size_t k_max = std::min<size_t>(4, pj.points.size() - 1);
      bool all_in = k_max >= 2;
      for (size_t k = 0; k <= k_max && all_in; ++k) {
        const auto loc = closest_on(tree, pj.points[k]);
        all_in = loc.dist <= tol * radius_at(tree, loc);
      }
      if (all_in) return true;
    }
  }
  return false;
}

std::vector<Polyline> vmtk_paths(const PolyData& pd, const std::vector<double>& radii, double merge_tolerance) {
  std::vector<Polyline> paths;
  for (size_t k = 0; k < pd.lines.size(); ++k) paths.push_back(make_polyline(pd, radii, cell_ids(pd, k, true), {}));
  return merge_paths(std::move(paths), merge_tolerance, pd.source);
}

}  // namespace flowire::vessels::detail
