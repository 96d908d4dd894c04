#include "flowire/vessels/network.hpp"
#include "flowire/common/union_find.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <unordered_map>

#include "flowire/common/error.hpp"

namespace flowire::vessels {
namespace {

std::string branch_label(const Polyline& p, size_t index) {
  return p.name.empty() ? fmt::format("branch {}", index) : fmt::format("branch {} ('{}')", index, p.name);
}

void validate_polyline(const Polyline& p, size_t bi, const std::string& src) {
  const auto label = branch_label(p, bi);
  if (p.points.size() < 2)
    throw_input_error(src, fmt::format("{} has {} point(s); a branch needs at least 2", label, p.points.size()));
  if (p.radii.size() != p.points.size())
    throw_input_error(src, fmt::format("{} has {} points but {} radii", label, p.points.size(), p.radii.size()));
  for (size_t i = 0; i < p.points.size(); ++i) {
    if (!p.points[i].allFinite())
      throw_input_error(src, fmt::format("{}, point {}: coordinate is not finite", label, i));
    if (!std::isfinite(p.radii[i])) throw_input_error(src, fmt::format("{}, point {}: radius is not finite", label, i));
    if (p.radii[i] <= 0.0)
      throw_input_error(src, fmt::format("{}, point {}: radius {} is not positive", label, i, p.radii[i]));
    if (i > 0 && (p.points[i] - p.points[i - 1]).norm() <= 1e-12 * std::max(1.0, p.points[i].norm()))
      throw_input_error(src, fmt::format("{}, points {} and {} coincide (duplicate point)", label, i - 1, i));
  }
}

/// Piecewise-linear interpolation along a polyline by arc length.
struct ArcLength {
  const Polyline& p;
  std::vector<double> s;
  explicit ArcLength(const Polyline& poly) : p(poly), s(poly.points.size(), 0.0) {
    for (size_t i = 1; i < s.size(); ++i) s[i] = s[i - 1] + (p.points[i] - p.points[i - 1]).norm();
  }
  [[nodiscard]] double total() const { return s.back(); }
  [[nodiscard]] size_t interval(double t) const {
    auto it = std::upper_bound(s.begin(), s.end(), t);
    size_t i = static_cast<size_t>(std::max<std::ptrdiff_t>(1, it - s.begin())) - 1;
    return std::min(i, s.size() - 2);
  }
  [[nodiscard]] Vec3 point(double t) const {
    const size_t i = interval(t);
    const double w = (t - s[i]) / (s[i + 1] - s[i]);
    return (1.0 - w) * p.points[i] + w * p.points[i + 1];
  }
  [[nodiscard]] double radius(double t) const {
    const size_t i = interval(t);
    const double w = std::clamp((t - s[i]) / (s[i + 1] - s[i]), 0.0, 1.0);
    return (1.0 - w) * p.radii[i] + w * p.radii[i + 1];
  }
  /// Arc-length mean of the (piecewise-linear) radius over [a, b].
  [[nodiscard]] double mean_radius(double a, double b) const {
    if (b - a <= 0.0) return radius(a);
    double integral = 0.0;
    double t0 = a;
    while (t0 < b) {
      const size_t i = interval(t0);
      const double t1 = std::min(b, i + 2 < s.size() ? s[i + 1] : b);
      const double t_end = t1 > t0 ? t1 : b;
      integral += 0.5 * (radius(t0) + radius(t_end)) * (t_end - t0);
      t0 = t_end;
    }
    return integral / (b - a);
  }
};

/// Arc-length positions where a branch is cut into segments.
std::vector<double> cut_positions(const ArcLength& al, const BuildOptions& opt) {
  const auto& r = al.p.radii;
  std::vector<double> coarse{0.0};
  double r_ref = r.front();
  for (size_t i = 1; i + 1 < r.size(); ++i) {
    if (opt.radius_change > 0.0 && std::abs(r[i] - r_ref) > opt.radius_change * r_ref) {
      coarse.push_back(al.s[i]);
      r_ref = r[i];
    }
  }
  coarse.push_back(al.total());
  std::vector<double> cuts{0.0};
  const double hmax = opt.max_segment_length > 0.0 ? opt.max_segment_length : std::numeric_limits<double>::infinity();
  for (size_t k = 0; k + 1 < coarse.size(); ++k) {
    const double len = coarse[k + 1] - coarse[k];
    const double want = std::isfinite(hmax) ? std::ceil(len / hmax - 1e-9) : 1.0;
    if (want > 1e7)
      throw_input_error(
          al.p.name, fmt::format("branch of length {} m would need {:.3g} segments of at most {} m", len, want, hmax));
    const int pieces = std::max(1, static_cast<int>(want));
    for (int j = 1; j <= pieces; ++j) cuts.push_back(coarse[k] + len * j / pieces);
  }
  if (opt.max_chord_deviation > 0.0) {
    // Where a branch bends, a straight segment cuts the bend: halve a piece until no point of
    // the polyline between its ends lies farther from its chord than max_chord_deviation of
    // the radius there.
    std::vector<double> fine{cuts.front()};
    for (size_t k = 0; k + 1 < cuts.size(); ++k) {
      std::vector<std::pair<double, double>> todo{{cuts[k], cuts[k + 1]}};
      std::vector<double> here;
      while (!todo.empty()) {
        const auto [a, b] = todo.back();
        todo.pop_back();
        const Vec3 pa = al.point(a), pb = al.point(b);
        double worst = 0.0;
        for (size_t i = 0; i < al.s.size(); ++i) {
          if (al.s[i] <= a || al.s[i] >= b) continue;
          const Vec3& x = al.p.points[i];
          const Vec3 ab = pb - pa;
          const double t = std::clamp((x - pa).dot(ab) / std::max(ab.squaredNorm(), 1e-300), 0.0, 1.0);
          worst = std::max(worst, (x - (pa + t * ab)).norm() / (opt.max_chord_deviation * al.p.radii[i]));
        }
        if (worst > 1.0 && b - a > 1e-9 * std::max(1.0, al.total())) {
          const double m = 0.5 * (a + b);
          todo.push_back({m, b});
          todo.push_back({a, m});
        } else {
          here.push_back(b);
        }
      }
      fine.insert(fine.end(), here.begin(), here.end());
    }
    cuts = std::move(fine);
  }
  return cuts;
}

}  // namespace

Network Network::build(const Centerlines& c, const BuildOptions& opt) {
  const std::string& src = c.source.empty() ? std::string("centerlines") : c.source;
  if (c.branches.empty()) throw_input_error(src, "no centerline branches found");
  double rmin = std::numeric_limits<double>::infinity();
  for (size_t b = 0; b < c.branches.size(); ++b) {
    validate_polyline(c.branches[b], b, src);
    rmin = std::min(rmin, *std::min_element(c.branches[b].radii.begin(), c.branches[b].radii.end()));
  }
  const double tol = opt.join_tolerance > 0.0 ? opt.join_tolerance : 1e-3 * rmin;

  // Cluster branch end points (2 per branch) into nodes with a hash grid of cell `tol`.
  const size_t nb = c.branches.size();
  std::vector<Vec3> ends(2 * nb);
  for (size_t b = 0; b < nb; ++b) {
    ends[2 * b] = c.branches[b].points.front();
    ends[2 * b + 1] = c.branches[b].points.back();
  }
  UnionFind uf(ends.size());
  {
    using Cell = Eigen::Matrix<int64_t, 3, 1>;
    auto key = [&](const Cell& k) {
      return (static_cast<uint64_t>(k.x() & 0x1FFFFF) << 42) ^ (static_cast<uint64_t>(k.y() & 0x1FFFFF) << 21) ^
             static_cast<uint64_t>(k.z() & 0x1FFFFF);
    };
    // Cell of a point; clamped so that absurd coordinate/tolerance ratios stay defined
    // (far-apart points may then share a cell: the distance test below still decides).
    auto cell = [&](const Vec3& x) {
      const Eigen::Array3d f = (x / tol).array().floor().max(-4e18).min(4e18);
      return Cell(static_cast<int64_t>(f.x()), static_cast<int64_t>(f.y()), static_cast<int64_t>(f.z()));
    };
    std::unordered_multimap<uint64_t, int> grid;
    grid.reserve(ends.size());
    for (size_t i = 0; i < ends.size(); ++i) {
      const Cell k = cell(ends[i]);
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            auto range = grid.equal_range(key(k + Cell(dx, dy, dz)));
            for (auto it = range.first; it != range.second; ++it)
              if ((ends[static_cast<size_t>(it->second)] - ends[i]).norm() <= tol)
                uf.unite(static_cast<int>(i), it->second);
          }
      grid.emplace(key(k), static_cast<int>(i));
    }
  }

  Network net;
  net.source_ = src;
  std::vector<int> end_node(ends.size(), -1);
  for (size_t i = 0; i < ends.size(); ++i) {
    const auto root = static_cast<size_t>(uf.find(static_cast<int>(i)));
    if (end_node[root] < 0) {
      end_node[root] = net.num_nodes();
      net.nodes_.push_back(ends[root]);
    }
    end_node[i] = end_node[root];
  }

  for (size_t b = 0; b < nb; ++b) {
    const Polyline& p = c.branches[b];
    const ArcLength al(p);
    if (end_node[2 * b] == end_node[2 * b + 1]) {
      // A branch back to its own start is one self-looping segment unless its length or
      // taper cut it (the bend criterion would always cut it: judged without it).
      BuildOptions plain = opt;
      plain.max_chord_deviation = 0.0;
      if (cut_positions(al, plain).size() == 2)
        throw_input_error(src, fmt::format("{} starts and ends at the same point (self-loop)", branch_label(p, b)));
    }
    const auto cuts = cut_positions(al, opt);
    Branch br;
    br.name = p.name.empty() ? fmt::format("branch_{}", b) : p.name;
    br.nodes.push_back(end_node[2 * b]);
    for (size_t k = 1; k + 1 < cuts.size(); ++k) {
      br.nodes.push_back(net.num_nodes());
      net.nodes_.push_back(al.point(cuts[k]));
    }
    br.nodes.push_back(end_node[2 * b + 1]);
    if (br.nodes.size() == 2 && br.nodes[0] == br.nodes[1])
      throw_input_error(src, fmt::format("{} starts and ends at the same point (self-loop)", branch_label(p, b)));
    for (size_t k = 0; k + 1 < br.nodes.size(); ++k) {
      Segment seg;
      seg.node_from = br.nodes[k];
      seg.node_to = br.nodes[k + 1];
      seg.radius = al.mean_radius(cuts[k], cuts[k + 1]);
      seg.radius_from = al.radius(cuts[k]);
      seg.radius_to = al.radius(cuts[k + 1]);
      seg.branch = static_cast<int>(b);
      br.segments.push_back(net.num_segments());
      net.segments_.push_back(seg);
    }
    net.branches_.push_back(std::move(br));
  }
  net.finalize();
  return net;
}

Network Network::from_graph(std::vector<Vec3> nodes, std::vector<Segment> segments, std::vector<Branch> branches,
                            std::string source) {
  Network net;
  net.source_ = source.empty() ? std::string("network") : std::move(source);
  net.nodes_ = std::move(nodes);
  net.segments_ = std::move(segments);
  if (branches.empty()) {
    net.branches_.resize(net.segments_.size());
    for (size_t s = 0; s < net.segments_.size(); ++s) {
      net.segments_[s].branch = static_cast<int>(s);
      net.branches_[s].name = fmt::format("vessel_{}", s);
      net.branches_[s].segments = {static_cast<int>(s)};
      net.branches_[s].nodes = {net.segments_[s].node_from, net.segments_[s].node_to};
    }
  } else {
    net.branches_ = std::move(branches);
  }
  for (const auto& p : net.nodes_)
    if (!p.allFinite()) throw_input_error(net.source_, "a node coordinate is not finite");
  net.finalize();
  return net;
}

void Network::finalize() {
  const auto nn = nodes_.size();
  if (segments_.empty()) throw_input_error(source_, "the network has no segments");
  std::vector<int> deg(nn, 0);
  for (size_t s = 0; s < segments_.size(); ++s) {
    auto& seg = segments_[s];
    if (seg.node_from < 0 || seg.node_to < 0 || static_cast<size_t>(seg.node_from) >= nn ||
        static_cast<size_t>(seg.node_to) >= nn)
      throw_input_error(source_, fmt::format("segment {}: node index out of range", s));
    if (seg.node_from == seg.node_to)
      throw_input_error(source_, fmt::format("segment {} joins node {} to itself (self-loop)", s, seg.node_from));
    if (!(seg.radius > 0.0) || !std::isfinite(seg.radius))
      throw_input_error(source_, fmt::format("segment {}: radius {} is not positive and finite", s, seg.radius));
    if (seg.radius_from <= 0.0) seg.radius_from = seg.radius;
    if (seg.radius_to <= 0.0) seg.radius_to = seg.radius;
    if (!std::isfinite(seg.radius_from) || !std::isfinite(seg.radius_to))
      throw_input_error(source_,
                        fmt::format("segment {}: end radius {} / {} is not finite", s, seg.radius_from, seg.radius_to));
    const double len = (nodes_[static_cast<size_t>(seg.node_to)] - nodes_[static_cast<size_t>(seg.node_from)]).norm();
    if (seg.length <= 0.0) seg.length = len;
    if (!(seg.length > 0.0) || !std::isfinite(seg.length))
      throw_input_error(source_,
                        fmt::format("segment {} (nodes {}-{}) has zero length", s, seg.node_from, seg.node_to));
    ++deg[static_cast<size_t>(seg.node_from)];
    ++deg[static_cast<size_t>(seg.node_to)];
  }
  node_offsets_.assign(nn + 1, 0);
  for (size_t i = 0; i < nn; ++i) node_offsets_[i + 1] = node_offsets_[i] + deg[i];
  node_adjacency_.assign(static_cast<size_t>(node_offsets_[nn]), -1);
  std::vector<int> fill(node_offsets_.begin(), node_offsets_.end() - 1);
  for (size_t s = 0; s < segments_.size(); ++s) {
    node_adjacency_[static_cast<size_t>(fill[static_cast<size_t>(segments_[s].node_from)]++)] = static_cast<int>(s);
    node_adjacency_[static_cast<size_t>(fill[static_cast<size_t>(segments_[s].node_to)]++)] = static_cast<int>(s);
  }
  for (size_t i = 0; i < nn; ++i)
    if (deg[i] == 0) throw_input_error(source_, fmt::format("node {} is not connected to any segment", i));
}

std::string mm(const Vec3& x) {
  return fmt::format("({:.2f}, {:.2f}, {:.2f}) mm", 1e3 * x.x(), 1e3 * x.y(), 1e3 * x.z());
}

int Network::branch_named(const std::string& name) const {
  int found = -1;
  for (size_t b = 0; b < branches_.size(); ++b)
    if (branches_[b].name == name) found = static_cast<int>(b);
  return found;
}

std::string Network::branch_names() const {
  std::string names;
  for (const auto& b : branches_)
    if (!b.name.empty()) names += (names.empty() ? "" : ", ") + b.name;
  return names.empty() ? "none named" : names;
}

std::vector<int> Network::ends() const {
  std::vector<int> out;
  for (int i = 0; i < num_nodes(); ++i)
    if (degree(i) == 1) out.push_back(i);
  return out;
}

int Network::widest_end() const {
  int best = -1;
  double rbest = -1.0;
  for (int i : ends()) {
    const auto& seg = segment(*node_segments(i).first);
    const double r = seg.radius_at(i);  // the radius at the end itself
    if (r > rbest) rbest = r, best = i;
  }
  return best;
}

std::vector<int> Network::components(int* count) const {
  UnionFind uf(nodes_.size());
  for (const auto& s : segments_) uf.unite(s.node_from, s.node_to);
  std::vector<int> comp(nodes_.size(), -1);
  std::vector<int> label(nodes_.size(), -1);
  int n = 0;
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const auto r = static_cast<size_t>(uf.find(static_cast<int>(i)));
    if (label[r] < 0) label[r] = n++;
    comp[i] = label[r];
  }
  if (count) *count = n;
  return comp;
}

NetworkCounts Network::counts() const {
  NetworkCounts c;
  c.branches = num_branches();
  c.nodes = num_nodes();
  c.segments = num_segments();
  (void)components(&c.components);
  c.loops = c.segments - c.nodes + c.components;
  c.radius_min = std::numeric_limits<double>::infinity();
  for (int i = 0; i < num_nodes(); ++i) {
    if (degree(i) == 1) ++c.ends;
    if (degree(i) >= 3) ++c.junctions;
  }
  for (const auto& s : segments_) {
    c.total_length += s.length;
    c.radius_min = std::min(c.radius_min, s.radius);
    c.radius_max = std::max(c.radius_max, s.radius);
  }
  return c;
}

std::vector<double> Network::path_lengths_from(int from) const {
  std::vector<double> dist(nodes_.size(), std::numeric_limits<double>::infinity());
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  dist[static_cast<size_t>(from)] = 0.0;
  queue.emplace(0.0, from);
  while (!queue.empty()) {
    const auto [d, n] = queue.top();
    queue.pop();
    if (d > dist[static_cast<size_t>(n)]) continue;
    auto [b, e] = node_segments(n);
    for (const int* it = b; it != e; ++it) {
      const auto& s = segments_[static_cast<size_t>(*it)];
      const int m = s.node_from == n ? s.node_to : s.node_from;
      if (d + s.length < dist[static_cast<size_t>(m)]) {
        dist[static_cast<size_t>(m)] = d + s.length;
        queue.emplace(d + s.length, m);
      }
    }
  }
  return dist;
}

int Network::farthest_end(int from) const {
  const auto dist = path_lengths_from(from);
  int best = -1;
  for (int e : ends())
    if (e != from && std::isfinite(dist[static_cast<size_t>(e)]) &&
        (best < 0 || dist[static_cast<size_t>(e)] > dist[static_cast<size_t>(best)] + 1e-12))
      best = e;
  return best;
}

Network Network::keep_component(int keep) const {
  const auto comp = components();
  const int target = comp.at(static_cast<size_t>(keep));
  std::vector<int> new_node(nodes_.size(), -1);
  std::vector<Vec3> nodes;
  for (size_t i = 0; i < nodes_.size(); ++i)
    if (comp[i] == target) {
      new_node[i] = static_cast<int>(nodes.size());
      nodes.push_back(nodes_[i]);
    }
  std::vector<int> new_seg(segments_.size(), -1);
  std::vector<Segment> segs;
  for (size_t s = 0; s < segments_.size(); ++s) {
    if (comp[static_cast<size_t>(segments_[s].node_from)] != target) continue;
    Segment seg = segments_[s];
    seg.node_from = new_node[static_cast<size_t>(seg.node_from)];
    seg.node_to = new_node[static_cast<size_t>(seg.node_to)];
    new_seg[s] = static_cast<int>(segs.size());
    segs.push_back(seg);
  }
  std::vector<Branch> branches;
  std::vector<int> new_branch(branches_.size(), -1);
  for (size_t b = 0; b < branches_.size(); ++b) {
    if (branches_[b].segments.empty() || new_seg[static_cast<size_t>(branches_[b].segments.front())] < 0) continue;
    Branch br = branches_[b];
    for (auto& n : br.nodes) n = new_node[static_cast<size_t>(n)];
    for (auto& s : br.segments) s = new_seg[static_cast<size_t>(s)];
    new_branch[b] = static_cast<int>(branches.size());
    branches.push_back(std::move(br));
  }
  for (auto& s : segs) s.branch = new_branch[static_cast<size_t>(s.branch)];
  return from_graph(std::move(nodes), std::move(segs), std::move(branches), source_);
}

}  // namespace flowire::vessels
