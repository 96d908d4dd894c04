// Cross-sections of a lumen surface and the network's radii from them (sections.hpp).
#include "flowire/vessels/sections.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <unordered_map>
#include <vector>

namespace flowire::vessels {

double Section::equivalent_radius() const { return std::sqrt(area / std::numbers::pi); }

namespace {

std::uint64_t edge_key(int a, int b) {
  const auto lo = static_cast<std::uint64_t>(std::min(a, b)), hi = static_cast<std::uint64_t>(std::max(a, b));
  return (lo << 32U) | hi;
}

/// One triangle's piece of the cut: the two triangle edges it joins and its ends on them.
struct Piece {
  std::uint64_t key[2];
  Vec3 x[2];
};

}  // namespace

std::optional<Section> cut_section(const LumenSurface& surface, const Vec3& p, const Vec3& t, double reach) {
  const Vec3 n = t.normalized();
  const auto& v = surface.vertices();
  const auto& tri = surface.triangles();
  std::vector<int> near;
  surface.triangles_within(p, reach, near);
  // A vertex on the plane counts as above it, so that every crossing edge has one vertex on
  // each side and two triangles sharing an edge cut it at the same point.
  auto height = [&](int i) { return (v[static_cast<size_t>(i)] - p).dot(n); };
  auto crossing = [&](int a, int b) {
    const double ha = height(a), hb = height(b);
    const double s = ha / (ha - hb);
    return Vec3(v[static_cast<size_t>(a)] + s * (v[static_cast<size_t>(b)] - v[static_cast<size_t>(a)]));
  };
  std::vector<Piece> pieces;
  std::unordered_map<std::uint64_t, std::vector<int>> at_edge;
  for (int f : near) {
    const auto& tv = tri[static_cast<size_t>(f)];
    Piece piece{};
    int found = 0;
    for (int k = 0; k < 3 && found < 2; ++k) {
      const int a = tv[static_cast<size_t>(k)], b = tv[static_cast<size_t>((k + 1) % 3)];
      if ((height(a) >= 0.0) == (height(b) >= 0.0)) continue;
      piece.key[found] = edge_key(a, b);
      piece.x[found] = crossing(a, b);
      ++found;
    }
    if (found != 2) continue;
    const int id = static_cast<int>(pieces.size());
    pieces.push_back(piece);
    at_edge[piece.key[0]].push_back(id);
    at_edge[piece.key[1]].push_back(id);
  }
  // Chain the pieces into contours; a contour that runs into an edge without a second piece
  // (an open end of the surface, or the edge of the gathered reach) is not closed.
  const Vec3 e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  std::vector<char> used(pieces.size(), 0);
  std::optional<Section> best;
  int contours = 0;
  for (size_t start = 0; start < pieces.size(); ++start) {
    if (used[start]) continue;
    used[start] = 1;
    std::vector<Vec3> loop{pieces[start].x[0]};
    std::uint64_t key = pieces[start].key[1];
    Vec3 x = pieces[start].x[1];
    bool closed = false;
    for (size_t guard = 0; guard <= pieces.size(); ++guard) {
      if (key == pieces[start].key[0]) {
        closed = true;
        break;
      }
      loop.push_back(x);
      const auto it = at_edge.find(key);
      int next = -1;
      if (it != at_edge.end())
        for (int q : it->second)
          if (!used[static_cast<size_t>(q)]) next = q;
      if (next < 0) break;
      used[static_cast<size_t>(next)] = 1;
      const Piece& pc = pieces[static_cast<size_t>(next)];
      const int enter = pc.key[0] == key ? 0 : 1;
      key = pc.key[1 - enter];
      x = pc.x[1 - enter];
    }
    if (!closed || loop.size() < 3) continue;
    ++contours;
    // In the plane's coordinates about p: the area (shoelace), the winding number of p, the
    // perimeter and the distances from p.
    Section sec;
    double twice_area = 0.0, winding = 0.0;
    double mx = 0.0, my = 0.0, mxx = 0.0, myy = 0.0, mxy = 0.0;  // first and second moments (signed)
    sec.min_distance = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < loop.size(); ++i) {
      const Vec3 a = loop[i] - p, b = loop[(i + 1) % loop.size()] - p;
      const double ax = a.dot(e1), ay = a.dot(e2), bx = b.dot(e1), by = b.dot(e2);
      const double cross = ax * by - ay * bx;
      twice_area += cross;
      mx += (ax + bx) * cross;
      my += (ay + by) * cross;
      mxx += (ax * ax + ax * bx + bx * bx) * cross;
      myy += (ay * ay + ay * by + by * by) * cross;
      mxy += (ax * by + 2.0 * ax * ay + 2.0 * bx * by + bx * ay) * cross;
      winding += std::atan2(ax * by - ay * bx, ax * bx + ay * by);
      sec.perimeter += (loop[(i + 1) % loop.size()] - loop[i]).norm();
      sec.max_distance = std::max(sec.max_distance, std::hypot(ax, ay));
      // The nearest point of the contour's edge [a, b] to p.
      const double ex = bx - ax, ey = by - ay, ee = ex * ex + ey * ey;
      const double u = ee > 0.0 ? std::clamp(-(ax * ex + ay * ey) / ee, 0.0, 1.0) : 0.0;
      sec.min_distance = std::min(sec.min_distance, std::hypot(ax + u * ex, ay + u * ey));
    }
    if (std::abs(winding) < std::numbers::pi) continue;  // p is not inside this contour
    sec.area = 0.5 * std::abs(twice_area);
    {
      // The polygon's moments (Green's theorem over its edges), central, and the principal ones.
      const double sign = twice_area < 0.0 ? -1.0 : 1.0;  // the sums carry the contour's orientation
      const double cx = mx / (3.0 * twice_area), cy = my / (3.0 * twice_area);
      const double ixx = sign * mxx / 12.0 - sec.area * cx * cx, iyy = sign * myy / 12.0 - sec.area * cy * cy;
      const double ixy = sign * mxy / 24.0 - sec.area * cx * cy;
      const double mean = 0.5 * (ixx + iyy), dev = std::hypot(0.5 * (ixx - iyy), ixy);
      const double i1 = mean + dev, i2 = mean - dev;
      if (i2 > 0.0) {
        const double k = std::sqrt(i1 / i2);  // a/b of the equivalent ellipse
        sec.shape_factor = 0.5 * (k + 1.0 / k);
      }
    }
    if (!best || sec.area < best->area) best = sec;
  }
  if (best) best->contours = contours;
  return best;
}

SectionRadii section_radii(const Network& net, const LumenSurface& surface, const SectionRadiiOptions& options) {
  SectionRadii out;
  std::vector<Segment> segments;
  segments.reserve(static_cast<size_t>(net.num_segments()));
  for (int s = 0; s < net.num_segments(); ++s) segments.push_back(net.segment(s));
  auto radius_at = [](const Segment& g, bool from) {
    const double r = from ? g.radius_from : g.radius_to;
    return r > 0.0 ? r : g.radius;
  };
  std::vector<double> ratios, shapes;
  for (int b = 0; b < net.num_branches(); ++b) {
    const Branch& br = net.branch(b);
    const auto nk = br.nodes.size();
    if (nk < 2) continue;
    // The inscribed radius at each node of the branch (the segment ends there), arc length.
    std::vector<double> r_in(nk), arc(nk, 0.0), ratio(nk, -1.0), shape(nk, 1.0);
    for (size_t k = 0; k < nk; ++k) {
      const Segment& g = net.segment(br.segments[std::min(k, nk - 2)]);
      const bool from = g.node_from == br.nodes[k];
      r_in[k] = radius_at(g, from);
      if (k > 0) arc[k] = arc[k - 1] + (net.node(br.nodes[k]) - net.node(br.nodes[k - 1])).norm();
    }
    for (size_t k = 0; k < nk; ++k) {
      const Vec3 t = net.node(br.nodes[std::min(k + 1, nk - 1)]) - net.node(br.nodes[k == 0 ? 0 : k - 1]);
      ++out.points;
      if (!(r_in[k] > 0.0) || !(t.norm() > 0.0)) continue;
      const auto sec = cut_section(surface, net.node(br.nodes[k]), t, options.reach * r_in[k]);
      if (!sec) continue;
      const double r = sec->equivalent_radius();
      if (r > options.max_ratio * r_in[k] || sec->max_distance > options.max_extent * r_in[k]) continue;
      ratio[k] = r / r_in[k];
      shape[k] = sec->shape_factor;
      ratios.push_back(ratio[k]);
      shapes.push_back(shape[k]);
      ++out.measured;
    }
    // Unmeasured nodes take the ratio of the nearest measured node of the branch.
    bool any = false;
    for (double q : ratio) any = any || q > 0.0;
    if (!any) ++out.branches_unmeasured;
    for (size_t k = 0; k < nk; ++k) {
      if (ratio[k] > 0.0) continue;
      ++out.filled;
      double best = std::numeric_limits<double>::infinity(), q = 1.0, f = 1.0;
      for (size_t m = 0; m < nk; ++m)
        if (ratio[m] > 0.0 && std::abs(arc[m] - arc[k]) < best)
          best = std::abs(arc[m] - arc[k]), q = ratio[m], f = shape[m];
      ratio[k] = -q;  // negative: filled (kept apart from the measured ones for the loop above)
      shape[k] = f;
    }
    for (size_t k = 0; k + 1 < nk; ++k) {
      Segment& g = segments[static_cast<size_t>(br.segments[k])];
      const bool forward = g.node_from == br.nodes[k];
      const double r0 = radius_at(g, forward), r1 = radius_at(g, !forward);
      const double s0 = std::abs(ratio[k]), s1 = std::abs(ratio[k + 1]);
      (forward ? g.radius_from : g.radius_to) = s0 * r0;
      (forward ? g.radius_to : g.radius_from) = s1 * r1;
      g.radius = 0.5 * (g.radius_from + g.radius_to);
      g.shape = 0.5 * (shape[k] + shape[k + 1]);
    }
  }
  if (!ratios.empty()) {
    auto median = [](std::vector<double>& v) {
      std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
      return v[v.size() / 2];
    };
    out.median_ratio = median(ratios);
    out.max_shape = *std::max_element(shapes.begin(), shapes.end());
    out.median_shape = median(shapes);
  }
  std::vector<Vec3> nodes;
  nodes.reserve(static_cast<size_t>(net.num_nodes()));
  for (int i = 0; i < net.num_nodes(); ++i) nodes.push_back(net.node(i));
  std::vector<Branch> branches;
  for (int b = 0; b < net.num_branches(); ++b) branches.push_back(net.branch(b));
  out.network = Network::from_graph(std::move(nodes), std::move(segments), std::move(branches), net.source());
  return out;
}

}  // namespace flowire::vessels
