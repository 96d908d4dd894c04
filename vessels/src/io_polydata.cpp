// Poly data (points, line cells, arrays) → centerline branches, for every kind of centerline
// file flowire reads: VMTK paths, VMTK branch-split, SimVascular ROM, plain polylines and
// flowire's own networks. Nothing here depends on VTK.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <unordered_map>

#include "flowire/common/error.hpp"
#include "polydata_internal.hpp"

namespace flowire::vessels::detail {
namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  for (auto& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

const StringArray* find_strings(const std::vector<StringArray>& arrays, std::string_view name) {
  const auto key = lower(name);
  for (const auto& a : arrays)
    if (lower(a.name) == key) return &a;
  return nullptr;
}

/// Integer value of tuple i, first component (arrays stored as double).
long long int_at(const NumericArray& a, size_t i) {
  const double v = a.values[i * static_cast<size_t>(a.components)];
  if (!std::isfinite(v) || std::abs(v) > 1e15) return std::numeric_limits<long long>::min();
  return std::llround(v);
}

std::string array_names(const std::vector<NumericArray>& arrays) {
  if (arrays.empty()) return "none";
  std::string out;
  for (const auto& a : arrays) out += (out.empty() ? "" : ", ") + a.name;
  return out;
}

void require_tuples(const PolyData& pd, const NumericArray& a, size_t n, const char* what) {
  if (a.components < 1 || a.tuples() != n || a.values.size() != n * static_cast<size_t>(a.components))
    throw_input_error(pd.source, fmt::format("{} array '{}' has {} values for {} {}", what, a.name, a.values.size(), n,
                                             what[0] == 'p' ? "points" : "cells"));
}

/// Radius at every point, from the first radius-like point array found.
std::vector<double> point_radii(const PolyData& pd) {
  for (const char* name : {"radius", "radii", "MaximumInscribedSphereRadius", "misr"}) {
    if (const auto* a = find_array(pd.point_data, name)) {
      require_tuples(pd, *a, pd.points.size(), "point");
      std::vector<double> r(pd.points.size());
      for (size_t i = 0; i < r.size(); ++i) r[i] = a->values[i * static_cast<size_t>(a->components)];
      return r;
    }
  }
  if (const auto* a = find_array(pd.point_data, "CenterlineSectionArea")) {
    require_tuples(pd, *a, pd.points.size(), "point");
    std::vector<double> r(pd.points.size());
    for (size_t i = 0; i < r.size(); ++i) {
      const double area = a->values[i * static_cast<size_t>(a->components)];
      r[i] = area >= 0.0 ? std::sqrt(area / std::numbers::pi) : area;
    }
    return r;
  }
  throw_input_error(pd.source, fmt::format("no radius array: expected a point array 'radius', 'radii' or "
                                           "'MaximumInscribedSphereRadius' (point arrays in the file: {})",
                                           array_names(pd.point_data)));
}

bool is_vmtk(const PolyData& pd) { return find_array(pd.point_data, "MaximumInscribedSphereRadius") != nullptr; }

/// Checks every line cell (ids in range, at least two points) and every point the cells use
/// (finite coordinates, finite positive radius).
void require_lines(const PolyData& pd) {
  if (!pd.lines.empty()) return;
  if (pd.points.empty()) throw_input_error(pd.source, "no points and no line cells: the file is empty");
  throw_input_error(pd.source,
                    fmt::format("no line cells (centerline polylines) among {} points{}", pd.points.size(),
                                pd.other_cells > 0 ? fmt::format(" and {} other cells (a surface?)", pd.other_cells)
                                                   : std::string{}));
}

void validate(const PolyData& pd, const std::vector<double>& radii) {
  require_lines(pd);
  const auto np = static_cast<long long>(pd.points.size());
  std::vector<char> checked(pd.points.size(), 0);
  for (size_t c = 0; c < pd.lines.size(); ++c) {
    const auto& ids = pd.lines[c];
    if (ids.size() < 2)
      throw_input_error(pd.source, fmt::format("line cell {} has {} point(s); a line needs at least 2", c, ids.size()));
    for (const long long id : ids) {
      if (id < 0 || id >= np)
        throw_input_error(pd.source,
                          fmt::format("line cell {}: point id {} is out of range (the file has {} points)", c, id, np));
      const auto i = static_cast<size_t>(id);
      if (checked[i]) continue;
      checked[i] = 1;
      if (!pd.points[i].allFinite())
        throw_input_error(pd.source, fmt::format("point {} (line cell {}): coordinate is not finite", id, c));
      if (!std::isfinite(radii[i]))
        throw_input_error(pd.source, fmt::format("point {} (line cell {}): radius is not finite", id, c));
      if (radii[i] <= 0.0)
        throw_input_error(pd.source,
                          fmt::format("point {} (line cell {}): radius {} is not positive", id, c, radii[i]));
    }
  }
}

/// Point ids of a cell with consecutive coincident points removed (VMTK writes a few) or,
/// when `allow_duplicates` is false, reported.
std::vector<long long> cell_ids(const PolyData& pd, size_t c, bool allow_duplicates) {
  const auto& ids = pd.lines[c];
  std::vector<long long> out;
  out.reserve(ids.size());
  for (size_t k = 0; k < ids.size(); ++k) {
    const long long id = ids[k];
    if (!out.empty()) {
      const long long prev = out.back();
      const bool same = prev == id || pd.points[static_cast<size_t>(prev)] == pd.points[static_cast<size_t>(id)];
      if (same) {
        if (allow_duplicates) continue;
        if (ids.size() == 2 && prev == id)
          throw_input_error(pd.source, fmt::format("line cell {} joins point {} to itself (self-loop)", c, id));
        throw_input_error(pd.source, fmt::format("line cell {}: points {} and {} (ids {} and {}) coincide "
                                                 "(duplicate point)",
                                                 c, k - 1, k, ids[k - 1], id));
      }
    }
    out.push_back(id);
  }
  if (out.size() < 2)
    throw_input_error(pd.source, fmt::format("line cell {}: all its points coincide (duplicate point)", c));
  return out;
}

Polyline make_polyline(const PolyData& pd, const std::vector<double>& radii, const std::vector<long long>& ids,
                       std::string name) {
  Polyline p;
  p.name = std::move(name);
  p.points.reserve(ids.size());
  p.radii.reserve(ids.size());
  for (const long long id : ids) {
    p.points.push_back(pd.points[static_cast<size_t>(id)]);
    p.radii.push_back(radii[static_cast<size_t>(id)]);
  }
  return p;
}

/// Appends q to p, skipping points of q that coincide with the last point of p.
void append_points(Polyline& p, const Polyline& q, size_t from = 0) {
  for (size_t i = from; i < q.points.size(); ++i) {
    if (!p.points.empty() && p.points.back() == q.points[i]) continue;
    p.points.push_back(q.points[i]);
    p.radii.push_back(q.radii[i]);
  }
}

// ---------------------------------------------------------------------------------------
// Overlapping paths (vmtkcenterlines): merge into a tree.

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

// ---------------------------------------------------------------------------------------

std::vector<Polyline> branch_split_vmtk(const PolyData& pd, const std::vector<double>& radii) {
  const auto* group = find_array(pd.cell_data, "GroupIds");
  const auto* line = find_array(pd.cell_data, "CenterlineIds");
  const auto* tract = find_array(pd.cell_data, "TractIds");
  const auto* blank = find_array(pd.cell_data, "Blanking");
  const size_t nc = pd.lines.size();
  for (const auto* a : {group, line, tract, blank})
    if (a) require_tuples(pd, *a, nc, "cell");

  struct Tract {
    size_t cell;
    long long group, tract;
    bool blanked;
  };
  std::map<long long, std::vector<Tract>> by_line;
  for (size_t c = 0; c < nc; ++c)
    by_line[int_at(*line, c)].push_back({c, int_at(*group, c), int_at(*tract, c), blank && int_at(*blank, c) != 0});
  for (auto& [id, ts] : by_line) {
    std::stable_sort(ts.begin(), ts.end(), [](const Tract& a, const Tract& b) { return a.tract < b.tract; });
    for (size_t k = 1; k < ts.size(); ++k)
      if (ts[k].tract == ts[k - 1].tract)
        throw_input_error(pd.source, fmt::format("line cells {} and {}: centerline {} has tract {} twice",
                                                 ts[k - 1].cell, ts[k].cell, id, ts[k].tract));
  }

  // Representative tract of each group: the first non-blanked cell with that group id,
  // with the blanked tract before it and the group before that (its parent) on its centerline.
  struct Rep {
    size_t cell;
    std::optional<size_t> blank_cell;
    std::optional<long long> parent;
  };
  std::map<long long, Rep> reps;
  std::vector<long long> order;
  for (size_t c = 0; c < nc; ++c) {
    if (blank && int_at(*blank, c) != 0) continue;
    const long long g = int_at(*group, c);
    if (reps.count(g)) continue;
    const auto& ts = by_line[int_at(*line, c)];
    const auto it = std::find_if(ts.begin(), ts.end(), [&](const Tract& t) { return t.cell == c; });
    Rep rep{c, std::nullopt, std::nullopt};
    auto k = static_cast<size_t>(it - ts.begin());
    if (k > 0 && ts[k - 1].blanked) {
      rep.blank_cell = ts[k - 1].cell;
      --k;
    }
    if (k > 0 && !ts[k - 1].blanked) rep.parent = ts[k - 1].group;
    reps.emplace(g, rep);
    order.push_back(g);
  }
  if (reps.empty()) throw_input_error(pd.source, "every line cell is blanked (Blanking = 1): no branch left");

  // Own points of each group first, then join each group to the end of its parent.
  std::map<long long, Polyline> own;
  for (const long long g : order)
    own.emplace(g, make_polyline(pd, radii, cell_ids(pd, reps.at(g).cell, true), fmt::format("group_{}", g)));

  std::vector<Polyline> out;
  for (const long long g : order) {
    const Rep& rep = reps.at(g);
    Polyline p;
    p.name = own.at(g).name;
    if (rep.parent && own.count(*rep.parent) && *rep.parent != g) {
      const Polyline& parent = own.at(*rep.parent);
      p.points.push_back(parent.points.back());
      p.radii.push_back(parent.radii.back());
      if (rep.blank_cell) append_points(p, make_polyline(pd, radii, cell_ids(pd, *rep.blank_cell, true), {}), 1);
      append_points(p, own.at(g), p.points.size() == 1 && !rep.blank_cell ? 1 : 0);
      // The junction point is the parent's; its radius on this branch is this branch's own.
      if (p.radii.size() > 1) p.radii.front() = p.radii[1];
    } else {
      if (rep.blank_cell) append_points(p, make_polyline(pd, radii, cell_ids(pd, *rep.blank_cell, true), {}));
      append_points(p, own.at(g));
    }
    out.push_back(std::move(p));
  }
  return out;
}

// ---------------------------------------------------------------------------------------

/// The point ids a canonical edge {a, b} (a < b) was read from: `at_a` is the file point at a,
/// `at_b` the one at b, in the first line cell holding the edge. Each cell keeps its own
/// radius there (a junction point repeated in every branch carries each branch's radius).
struct EdgeOrigin {
  long long at_a = -1, at_b = -1;
};
using EdgeOrigins = std::map<std::pair<long long, long long>, EdgeOrigin>;

/// Point adjacency from line cells (each consecutive pair of ids is an edge; duplicates merged).
std::vector<std::vector<long long>> adjacency(const PolyData& pd, const std::vector<long long>& canon,
                                              bool allow_duplicates, EdgeOrigins* origins = nullptr) {
  std::vector<std::vector<long long>> adj(pd.points.size());
  std::set<std::pair<long long, long long>> seen;
  for (size_t c = 0; c < pd.lines.size(); ++c) {
    const auto ids = cell_ids(pd, c, allow_duplicates);
    for (size_t k = 0; k + 1 < ids.size(); ++k) {
      long long a = canon[static_cast<size_t>(ids[k])];
      long long b = canon[static_cast<size_t>(ids[k + 1])];
      if (a == b) continue;
      if (!seen.emplace(std::min(a, b), std::max(a, b)).second) continue;
      if (origins)
        (*origins)[{std::min(a, b), std::max(a, b)}] =
            a < b ? EdgeOrigin{ids[k], ids[k + 1]} : EdgeOrigin{ids[k + 1], ids[k]};
      adj[static_cast<size_t>(a)].push_back(b);
      adj[static_cast<size_t>(b)].push_back(a);
    }
  }
  return adj;
}

/// Points closer than kSamePoint × their radius are one point (sharing the smallest id): the
/// end points two writers compute for the same junction differ in the last bits.
constexpr double kSamePoint = 1e-6;

std::vector<long long> canonical_ids(const PolyData& pd, const std::vector<double>& radii) {
  const size_t n = pd.points.size();
  double rmax = 0.0;
  for (size_t i = 0; i < n; ++i)
    if (std::isfinite(radii[i])) rmax = std::max(rmax, radii[i]);
  const double cell = kSamePoint * rmax;
  std::vector<long long> canon(n);
  for (size_t i = 0; i < n; ++i) canon[i] = static_cast<long long>(i);
  if (!(cell > 0.0)) return canon;
  // Hash grid of cell size ≥ every tolerance: near points are in neighbouring cells.
  using Cell = Eigen::Matrix<int64_t, 3, 1>;
  auto key = [](const Cell& k) {
    return (static_cast<uint64_t>(k.x() & 0x1FFFFF) << 42) ^ (static_cast<uint64_t>(k.y() & 0x1FFFFF) << 21) ^
           static_cast<uint64_t>(k.z() & 0x1FFFFF);
  };
  auto cell_of = [&](const Vec3& x) {
    const Eigen::Array3d f = (x / cell).array().floor().max(-4e18).min(4e18);
    return Cell(static_cast<int64_t>(f.x()), static_cast<int64_t>(f.y()), static_cast<int64_t>(f.z()));
  };
  std::unordered_multimap<uint64_t, long long> grid;
  grid.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec3& x = pd.points[i];
    if (!x.allFinite()) continue;  // validated (and reported) before the chains are built
    const Cell k = cell_of(x);
    for (int dx = -1; dx <= 1 && canon[i] == static_cast<long long>(i); ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto range = grid.equal_range(key(k + Cell(dx, dy, dz)));
          for (auto it = range.first; it != range.second; ++it) {
            const auto j = static_cast<size_t>(it->second);
            if ((pd.points[j] - x).norm() <= kSamePoint * std::max(radii[i], radii[j]))
              canon[i] = std::min(canon[i], canon[j]);
          }
        }
    if (canon[i] == static_cast<long long>(i)) grid.emplace(key(k), static_cast<long long>(i));
  }
  return canon;
}

/// Chains between points of degree != 2 (ends, junctions); closed rings are cut in two.
/// Each point of a chain takes the radius its own line cell gives it; a chain is also cut
/// where two cells meet with different radii at their shared point.
std::vector<Polyline> graph_chains(const PolyData& pd, const std::vector<double>& radii, bool allow_duplicates) {
  const auto canon = canonical_ids(pd, radii);
  EdgeOrigins origins;
  const auto adj = adjacency(pd, canon, allow_duplicates, &origins);
  std::vector<long long> order;  // vertices in order of first use
  {
    std::vector<char> seen(pd.points.size(), 0);
    for (const auto& ids : pd.lines)
      for (const long long id : ids) {
        const auto v = static_cast<size_t>(canon[static_cast<size_t>(id)]);
        if (!seen[v]) seen[v] = 1, order.push_back(static_cast<long long>(v));
      }
  }
  std::set<std::pair<long long, long long>> used;
  auto edge = [](long long a, long long b) { return std::make_pair(std::min(a, b), std::max(a, b)); };
  auto deg = [&](long long v) { return adj[static_cast<size_t>(v)].size(); };
  std::vector<std::vector<long long>> chains;
  auto walk = [&](long long start, long long next) {
    std::vector<long long> chain{start, next};
    used.insert(edge(start, next));
    long long prev = start, cur = next;
    while (deg(cur) == 2 && cur != start) {
      const auto& nb = adj[static_cast<size_t>(cur)];
      const long long nxt = nb[0] == prev ? nb[1] : nb[0];
      if (used.count(edge(cur, nxt))) break;
      used.insert(edge(cur, nxt));
      chain.push_back(nxt);
      prev = cur;
      cur = nxt;
    }
    chains.push_back(std::move(chain));
  };
  for (const long long v : order)
    if (deg(v) != 2)
      for (const long long w : adj[static_cast<size_t>(v)])
        if (!used.count(edge(v, w))) walk(v, w);
  for (const long long v : order)  // what is left are closed rings
    for (const long long w : adj[static_cast<size_t>(v)])
      if (!used.count(edge(v, w))) walk(v, w);

  // The file point that stands for chain vertex `v` on the edge {v, w}.
  auto origin = [&](long long v, long long w) {
    const auto& o = origins.at(edge(v, w));
    return static_cast<size_t>(v < w ? o.at_a : o.at_b);
  };
  std::vector<Polyline> out;
  auto emit = [&](const std::vector<long long>& chain, size_t lo, size_t hi) {
    Polyline p;
    p.name = fmt::format("branch_{}", out.size());
    for (size_t k = lo; k <= hi; ++k) {
      p.points.push_back(pd.points[static_cast<size_t>(chain[k])]);
      p.radii.push_back(radii[k < hi ? origin(chain[k], chain[k + 1]) : origin(chain[k], chain[k - 1])]);
    }
    out.push_back(std::move(p));
  };
  for (auto& chain : chains) {
    std::vector<size_t> cuts{0};
    for (size_t k = 1; k + 1 < chain.size(); ++k)
      if (radii[origin(chain[k], chain[k - 1])] != radii[origin(chain[k], chain[k + 1])]) cuts.push_back(k);
    if (cuts.size() == 1 && chain.size() >= 4 && chain.front() == chain.back())
      cuts.push_back(chain.size() / 2);  // ring
    cuts.push_back(chain.size() - 1);
    for (size_t i = 0; i + 1 < cuts.size(); ++i) emit(chain, cuts[i], cuts[i + 1]);
  }
  return out;
}

// ---------------------------------------------------------------------------------------

std::vector<Polyline> simvascular_rom(const PolyData& pd, const std::vector<double>& radii) {
  const auto* branch_arr = find_array(pd.point_data, "BranchId");
  require_tuples(pd, *branch_arr, pd.points.size(), "point");
  const auto* bif_arr = find_array(pd.point_data, "BifurcationId");
  if (bif_arr) require_tuples(pd, *bif_arr, pd.points.size(), "point");
  const auto* path_arr = find_array(pd.point_data, "Path");
  if (path_arr && path_arr->tuples() != pd.points.size()) path_arr = nullptr;

  std::vector<long long> canon(pd.points.size());
  for (size_t i = 0; i < canon.size(); ++i) canon[i] = static_cast<long long>(i);
  const auto adj = adjacency(pd, canon, false);
  const size_t np = pd.points.size();
  std::vector<char> used(np, 0);
  for (const auto& ids : pd.lines)
    for (const long long id : ids) used[static_cast<size_t>(id)] = 1;

  auto branch_of = [&](size_t i) { return int_at(*branch_arr, i); };

  // Bifurcation regions: connected sets of points with BranchId < 0 (split by BifurcationId).
  std::vector<long long> region(np, -1);
  std::vector<Vec3> junction;
  for (size_t i = 0; i < np; ++i) {
    if (!used[i] || branch_of(i) >= 0 || region[i] >= 0) continue;
    const long long id = static_cast<long long>(junction.size());
    std::vector<size_t> stack{i}, members;
    region[i] = id;
    while (!stack.empty()) {
      const size_t v = stack.back();
      stack.pop_back();
      members.push_back(v);
      for (const long long w : adj[v]) {
        const auto u = static_cast<size_t>(w);
        if (region[u] >= 0 || branch_of(u) >= 0) continue;
        if (bif_arr && int_at(*bif_arr, u) != int_at(*bif_arr, i)) continue;
        region[u] = id;
        stack.push_back(u);
      }
    }
    // The junction is the region's branching point (most neighbours), else its centroid.
    size_t hub = i;
    for (const size_t v : members)
      if (adj[v].size() > adj[hub].size()) hub = v;
    Vec3 x = pd.points[hub];
    if (adj[hub].size() < 3) {
      x.setZero();
      for (const size_t v : members) x += pd.points[v];
      x /= static_cast<double>(members.size());
    }
    junction.push_back(x);
  }

  std::map<long long, std::vector<size_t>> members;
  for (size_t i = 0; i < np; ++i)
    if (used[i] && branch_of(i) >= 0) members[branch_of(i)].push_back(i);
  if (members.empty()) throw_input_error(pd.source, "no point has BranchId >= 0: no branch to read");

  std::vector<Polyline> out;
  for (const auto& entry : members) {
    const long long b = entry.first;
    const std::vector<size_t>& pts = entry.second;
    auto in_branch = [&](long long w) { return branch_of(static_cast<size_t>(w)) == b; };
    size_t start = pts.front();
    for (const size_t v : pts) {
      const auto n = std::count_if(adj[v].begin(), adj[v].end(), in_branch);
      if (n <= 1) {
        start = v;
        break;
      }
    }
    std::vector<long long> chain{static_cast<long long>(start)};
    std::vector<char> seen(np, 0);
    seen[start] = 1;
    for (bool more = true; more;) {
      more = false;
      for (const long long w : adj[static_cast<size_t>(chain.back())])
        if (in_branch(w) && !seen[static_cast<size_t>(w)]) {
          seen[static_cast<size_t>(w)] = 1;
          chain.push_back(w);
          more = true;
          break;
        }
    }
    if (chain.size() != pts.size())
      throw_input_error(
          pd.source,
          fmt::format("BranchId {}: its {} points do not form one chain (point {} is "
                      "reached from neither end)",
                      b, pts.size(), *std::find_if(pts.begin(), pts.end(), [&](size_t v) { return !seen[v]; })));
    if (path_arr && chain.size() > 1 &&
        path_arr->values[static_cast<size_t>(chain.back()) * static_cast<size_t>(path_arr->components)] <
            path_arr->values[static_cast<size_t>(chain.front()) * static_cast<size_t>(path_arr->components)])
      std::reverse(chain.begin(), chain.end());

    Polyline p = make_polyline(pd, radii, chain, fmt::format("branch_{}", b));
    // Extend each end to the junction of the bifurcation region (or the branch) it touches.
    auto attach = [&](size_t end, bool front) {
      for (const long long w : adj[end]) {
        const auto u = static_cast<size_t>(w);
        if (branch_of(u) == b) continue;
        const Vec3 x = region[u] >= 0 ? junction[static_cast<size_t>(region[u])] : pd.points[u];
        const double r = front ? p.radii.front() : p.radii.back();
        if (x == (front ? p.points.front() : p.points.back())) return;
        if (front) {
          p.points.insert(p.points.begin(), x);
          p.radii.insert(p.radii.begin(), r);
        } else {
          p.points.push_back(x);
          p.radii.push_back(r);
        }
        return;
      }
    };
    attach(static_cast<size_t>(chain.front()), true);
    attach(static_cast<size_t>(chain.back()), false);
    if (p.points.size() < 2)
      throw_input_error(pd.source, fmt::format("BranchId {} has a single point and touches no junction", b));
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace

const NumericArray* find_array(const std::vector<NumericArray>& arrays, std::string_view name) {
  const auto key = lower(name);
  for (const auto& a : arrays)
    if (lower(a.name) == key) return &a;
  return nullptr;
}

const char* kind_name(PolyKind k) {
  switch (k) {
    case PolyKind::FlowireNetwork:
      return "flowire network";
    case PolyKind::BranchSplitVmtk:
      return "VMTK branch-split centerlines";
    case PolyKind::SimVascularRom:
      return "SimVascular ROM centerlines";
    case PolyKind::OverlappingPaths:
      return "VMTK centerlines (overlapping paths)";
    case PolyKind::Graph:
      return "polylines";
  }
  return "polylines";
}

PolyKind classify(const PolyData& pd, double merge_tolerance) {
  if (find_array(pd.field_data, "flowire_network")) return PolyKind::FlowireNetwork;
  if (find_array(pd.cell_data, "GroupIds") && find_array(pd.cell_data, "CenterlineIds") &&
      find_array(pd.cell_data, "TractIds"))
    return PolyKind::BranchSplitVmtk;
  if (find_array(pd.point_data, "BranchId")) return PolyKind::SimVascularRom;
  if (pd.lines.size() < 2) return PolyKind::Graph;
  // Overlapping paths never share point ids (vmtkcenterlines duplicates the trunk points).
  std::vector<int> owner(pd.points.size(), -1);
  for (size_t c = 0; c < pd.lines.size(); ++c)
    for (const long long id : pd.lines[c]) {
      if (id < 0 || static_cast<size_t>(id) >= pd.points.size()) return PolyKind::Graph;  // validated later
      auto& o = owner[static_cast<size_t>(id)];
      if (o >= 0 && o != static_cast<int>(c)) return PolyKind::Graph;
      o = static_cast<int>(c);
    }
  try {
    const auto radii = point_radii(pd);
    validate(pd, radii);
    std::vector<Polyline> paths;
    for (size_t c = 0; c < pd.lines.size(); ++c) paths.push_back(make_polyline(pd, radii, cell_ids(pd, c, true), {}));
    if (paths_overlap(std::move(paths), std::max(merge_tolerance, 1e-6))) return PolyKind::OverlappingPaths;
  } catch (const Error&) {
    return PolyKind::Graph;  // the graph reader reports the problem
  }
  return PolyKind::Graph;
}

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

Centerlines polydata_to_centerlines(const PolyData& pd, double merge_tolerance) {
  Centerlines c;
  c.source = pd.source;
  const auto kind = classify(pd, merge_tolerance);
  if (kind == PolyKind::FlowireNetwork) {
    const auto net = polydata_to_network(pd);
    for (const auto& br : net->branches()) {
      Polyline p;
      p.name = br.name;
      for (size_t k = 0; k < br.nodes.size(); ++k) {
        p.points.push_back(net->node(br.nodes[k]));
        // The radius this branch has at the node (the segment after it, the last one at the end).
        p.radii.push_back(k < br.segments.size() ? net->segment(br.segments[k]).radius_from
                                                 : net->segment(br.segments[k - 1]).radius_to);
      }
      c.branches.push_back(std::move(p));
    }
    return c;
  }
  require_lines(pd);
  const auto radii = point_radii(pd);
  validate(pd, radii);
  const bool vmtk = is_vmtk(pd);
  switch (kind) {
    case PolyKind::BranchSplitVmtk:
      c.branches = branch_split_vmtk(pd, radii);
      break;
    case PolyKind::SimVascularRom:
      c.branches = simvascular_rom(pd, radii);
      break;
    case PolyKind::OverlappingPaths: {
      std::vector<Polyline> paths;
      for (size_t k = 0; k < pd.lines.size(); ++k) paths.push_back(make_polyline(pd, radii, cell_ids(pd, k, true), {}));
      c.branches = merge_paths(std::move(paths), merge_tolerance, pd.source);
      break;
    }
    default:
      c.branches = graph_chains(pd, radii, vmtk);
      break;
  }
  return c;
}

std::optional<Network> polydata_to_network(const PolyData& pd) {
  const auto* marker = find_array(pd.field_data, "flowire_network");
  if (!marker) return std::nullopt;
  const std::string& src = pd.source;
  if (marker->values.empty() || marker->values[0] != 1.0)
    throw_input_error(src, "field array flowire_network: unknown version (this flowire reads version 1)");
  const size_t ns = pd.lines.size();
  const size_t nn = pd.points.size();
  if (ns == 0) throw_input_error(src, "a flowire network file without line cells");
  const auto* radius = find_array(pd.cell_data, "radius");
  const auto* length = find_array(pd.cell_data, "length");
  const auto* radius_from = find_array(pd.cell_data, "radius_from");  // absent before end radii: cylinders
  const auto* radius_to = find_array(pd.cell_data, "radius_to");
  if (radius_from) require_tuples(pd, *radius_from, ns, "cell");
  if (radius_to) require_tuples(pd, *radius_to, ns, "cell");
  const auto* branch = find_array(pd.cell_data, "branch_id");
  if (!radius) throw_input_error(src, "flowire network file without the cell array 'radius'");
  if (!branch) throw_input_error(src, "flowire network file without the cell array 'branch_id'");
  require_tuples(pd, *radius, ns, "cell");
  require_tuples(pd, *branch, ns, "cell");
  if (length) require_tuples(pd, *length, ns, "cell");

  std::vector<Segment> segs(ns);
  for (size_t s = 0; s < ns; ++s) {
    const auto& ids = pd.lines[s];
    if (ids.size() != 2)
      throw_input_error(src,
                        fmt::format("line cell {}: a flowire network has 2 points per cell, not {}", s, ids.size()));
    for (const long long id : ids)
      if (id < 0 || static_cast<size_t>(id) >= nn)
        throw_input_error(src,
                          fmt::format("line cell {}: point id {} is out of range (the file has {} points)", s, id, nn));
    segs[s].node_from = static_cast<int>(ids[0]);
    segs[s].node_to = static_cast<int>(ids[1]);
    segs[s].radius = radius->values[s * static_cast<size_t>(radius->components)];
    for (const auto& [arr, out] :
         {std::pair{radius_from, &segs[s].radius_from}, std::pair{radius_to, &segs[s].radius_to}}) {
      if (!arr) continue;
      *out = arr->values[s * static_cast<size_t>(arr->components)];
      if (!(*out > 0.0 && std::isfinite(*out)))
        throw_input_error(src, fmt::format("line cell {}: {} {} is not positive and finite", s, arr->name, *out));
    }
    segs[s].length = length ? length->values[s * static_cast<size_t>(length->components)] : 0.0;
    if (length && !(segs[s].length > 0.0 && std::isfinite(segs[s].length)))
      throw_input_error(src, fmt::format("line cell {}: length {} is not positive and finite", s, segs[s].length));
    const long long b = int_at(*branch, s);
    if (b < 0 || b > static_cast<long long>(ns))
      throw_input_error(src, fmt::format("line cell {}: branch_id {} is out of range", s, b));
    segs[s].branch = static_cast<int>(b);
  }
  for (size_t i = 0; i < nn; ++i)
    if (!pd.points[i].allFinite()) throw_input_error(src, fmt::format("point {}: coordinate is not finite", i));

  // Branch lists: offsets + flat index arrays in field data.
  const auto* names = find_strings(pd.field_strings, "branch_names");
  auto list = [&](const char* offsets_name, const char* values_name, size_t limit) {
    const auto* off = find_array(pd.field_data, offsets_name);
    const auto* val = find_array(pd.field_data, values_name);
    if (!off || !val)
      throw_input_error(
          src, fmt::format("flowire network file without the field arrays {} and {}", offsets_name, values_name));
    std::vector<std::vector<int>> out;
    for (size_t b = 0; b + 1 < off->values.size(); ++b) {
      const long long lo = int_at(*off, b), hi = int_at(*off, b + 1);
      if (lo < 0 || hi < lo || static_cast<size_t>(hi) > val->values.size())
        throw_input_error(src, fmt::format("field array {}: entry {} is out of range", offsets_name, b));
      std::vector<int> ids;
      for (long long k = lo; k < hi; ++k) {
        const long long v = int_at(*val, static_cast<size_t>(k));
        if (v < 0 || static_cast<size_t>(v) >= limit)
          throw_input_error(src, fmt::format("field array {}: entry {} ({}) is out of range", values_name, k, v));
        ids.push_back(static_cast<int>(v));
      }
      out.push_back(std::move(ids));
    }
    return out;
  };
  const auto branch_segments = list("branch_segment_offsets", "branch_segments", ns);
  const auto branch_nodes = list("branch_node_offsets", "branch_nodes", nn);
  if (branch_segments.size() != branch_nodes.size())
    throw_input_error(src, "field arrays branch_segment_offsets and branch_node_offsets differ in length");
  std::vector<Branch> branches(branch_segments.size());
  for (size_t b = 0; b < branches.size(); ++b) {
    branches[b].name = names && b < names->values.size() ? names->values[b] : fmt::format("branch_{}", b);
    branches[b].segments = branch_segments[b];
    branches[b].nodes = branch_nodes[b];
  }
  for (size_t s = 0; s < ns; ++s)
    if (static_cast<size_t>(segs[s].branch) >= branches.size())
      throw_input_error(src, fmt::format("line cell {}: branch_id {} but the file lists {} branches", s, segs[s].branch,
                                         branches.size()));
  return Network::from_graph(pd.points, std::move(segs), std::move(branches), src);
}

}  // namespace flowire::vessels::detail
