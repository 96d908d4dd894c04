// The solids of a vessel network's tube (one cylinder per run of collinear segments of one
// radius, one sphere at each bend and junction) with the checks that a tube can be built along
// it, and those solids added to the current gmsh model at a radius grown by an offset.
#include "flowire/mesh/network_solids.hpp"

#include <fmt/format.h>
#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <queue>
#include <string>
#include <unordered_map>
#include <vector>

#include "flowire/common/error.hpp"

namespace flowire::mesh {
namespace {

using vessels::Vec3;

double piece_length(const vessels::Network& net, const NetworkPiece& p) {
  return (net.node(p.b) - net.node(p.a)).norm();
}

/// Closest distance between segments [p0, p1] and [q0, q1].
double segment_distance(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0.0, t = 0.0;
  if (a <= 1e-300 && e <= 1e-300) return r.norm();
  if (a <= 1e-300) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 1e-300) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 1e-300 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return ((p0 + s * d1) - (q0 + t * d2)).norm();
}

std::string branch_name(const vessels::Network& net, int b) {
  const auto& n = net.branch(b).name;
  return n.empty() ? fmt::format("branch {}", b) : fmt::format("branch '{}'", n);
}

}  // namespace

NetworkSolids make_network_solids(const vessels::Network& net, const std::string& at) {
  NetworkSolids g;
  if (net.num_segments() == 0) throw_input_error(at, "the network has no segment");
  for (int s = 0; s < net.num_segments(); ++s) {
    const auto& seg = net.segment(s);
    if (!(seg.radius > 0.0) || !((net.node(seg.node_to) - net.node(seg.node_from)).norm() > 0.0))
      throw_input_error(at, fmt::format("segment {}: zero length or radius", s));
  }
  // Pieces: consecutive collinear segments of equal radius along each branch.
  for (int b = 0; b < net.num_branches(); ++b) {
    const auto& br = net.branch(b);
    if (br.segments.empty()) continue;
    NetworkPiece cur{br.nodes[0], br.nodes[1], net.segment(br.segments[0]).radius, b};
    Vec3 dir = (net.node(br.nodes[1]) - net.node(br.nodes[0])).normalized();
    for (size_t k = 1; k < br.segments.size(); ++k) {
      const Vec3 d = (net.node(br.nodes[k + 1]) - net.node(br.nodes[k])).normalized();
      const double r = net.segment(br.segments[k]).radius;
      if (d.dot(dir) > 1.0 - 1e-10 && std::abs(r - cur.radius) <= 1e-9 * cur.radius) {
        cur.b = br.nodes[k + 1];
      } else {
        g.pieces.push_back(cur);
        cur = NetworkPiece{br.nodes[k], br.nodes[k + 1], r, b};
        dir = d;
      }
    }
    g.pieces.push_back(cur);
  }
  // Pieces at each node.
  std::vector<std::vector<int>> at_node(static_cast<size_t>(net.num_nodes()));
  for (int p = 0; p < static_cast<int>(g.pieces.size()); ++p) {
    at_node[static_cast<size_t>(g.pieces[static_cast<size_t>(p)].a)].push_back(p);
    at_node[static_cast<size_t>(g.pieces[static_cast<size_t>(p)].b)].push_back(p);
  }
  g.sphere_at.assign(static_cast<size_t>(net.num_nodes()), 0.0);
  auto out_dir = [&](int p, int node) {
    const NetworkPiece& pc = g.pieces[static_cast<size_t>(p)];
    const int other = pc.a == node ? pc.b : pc.a;
    return Vec3((net.node(other) - net.node(node)).normalized());
  };
  for (int n = 0; n < net.num_nodes(); ++n) {
    const auto& ps = at_node[static_cast<size_t>(n)];
    if (ps.size() < 2) continue;
    double rmax = 0.0;
    int widest = -1;
    for (int p : ps)
      if (g.pieces[static_cast<size_t>(p)].radius > rmax)
        rmax = g.pieces[static_cast<size_t>(p)].radius, widest = g.pieces[static_cast<size_t>(p)].branch;
    if (ps.size() == 2) {
      const Vec3 u = out_dir(ps[0], n), v = out_dir(ps[1], n);
      const double c = std::clamp(-u.dot(v), -1.0, 1.0);
      if (c > 1.0 - 1e-10) continue;  // collinear: a straight continuation (maybe a step)
      const double turn = std::acos(c);
      if (turn > 170.0 * std::numbers::pi / 180.0)
        throw_input_error(at, fmt::format("node {}: the centerline turns back by {:.0f} deg; a tube cannot "
                                          "be built there",
                                          n, turn * 180.0 / std::numbers::pi));
      const double reach = rmax * std::tan(0.5 * turn);
      const double lmin = std::min(piece_length(net, g.pieces[static_cast<size_t>(ps[0])]),
                                   piece_length(net, g.pieces[static_cast<size_t>(ps[1])]));
      if (reach >= lmin)
        throw_input_error(at, fmt::format("node {} of {}: radius {:.3g} mm too large for the bend of "
                                          "{:.0f} deg (the inner wall folds {:.3g} mm from the node, the "
                                          "adjacent straight part is {:.3g} mm); smooth the centerline or "
                                          "use a smaller radius",
                                          n, branch_name(net, g.pieces[static_cast<size_t>(ps[0])].branch), rmax * 1e3,
                                          turn * 180.0 / std::numbers::pi, reach * 1e3, lmin * 1e3));
    }
    g.sphere_at[static_cast<size_t>(n)] = rmax;
    g.spheres.push_back({n, rmax, widest});
  }
  // End pieces must reach past the sphere at their other end.
  for (int n = 0; n < net.num_nodes(); ++n) {
    const auto& ps = at_node[static_cast<size_t>(n)];
    if (ps.size() != 1) continue;
    const NetworkPiece& pc = g.pieces[static_cast<size_t>(ps[0])];
    const int other = pc.a == n ? pc.b : pc.a;
    const double rs = g.sphere_at[static_cast<size_t>(other)];
    const double len = piece_length(net, pc);
    if (rs > 0.0 && len <= 1.05 * rs)
      throw_input_error(at, fmt::format("end node {} of {}: the end piece ({:.3g} mm) is not longer than the "
                                        "junction sphere at node {} ({:.3g} mm radius), which would cut the "
                                        "end face; lengthen the vessel",
                                        n, branch_name(net, pc.branch), len * 1e3, other, rs * 1e3));
  }
  // Self-intersection: pieces without a common node that come closer than r1 + r2 while
  // the path between them along the network is long.
  std::vector<int> ids;  // piece-graph nodes
  std::unordered_map<int, int> local;
  for (const NetworkPiece& p : g.pieces)
    for (int n : {p.a, p.b})
      if (local.emplace(n, static_cast<int>(ids.size())).second) ids.push_back(n);
  const size_t m = ids.size();
  if (m <= 800 && g.pieces.size() >= 2) {
    std::vector<std::vector<std::pair<int, double>>> adj(m);
    for (const NetworkPiece& p : g.pieces) {
      const int i = local[p.a], j = local[p.b];
      const double l = piece_length(net, p);
      adj[static_cast<size_t>(i)].push_back({j, l});
      adj[static_cast<size_t>(j)].push_back({i, l});
    }
    std::vector<double> dist(m * m, std::numeric_limits<double>::infinity());
    for (size_t s = 0; s < m; ++s) {
      double* d = &dist[s * m];
      using Item = std::pair<double, int>;
      std::priority_queue<Item, std::vector<Item>, std::greater<>> pq;
      d[s] = 0.0;
      pq.push({0.0, static_cast<int>(s)});
      while (!pq.empty()) {
        const auto [du, u] = pq.top();
        pq.pop();
        if (du > d[u]) continue;
        for (const auto& [v, w] : adj[static_cast<size_t>(u)])
          if (du + w < d[v]) {
            d[v] = du + w;
            pq.push({d[v], v});
          }
      }
    }
    for (size_t i = 0; i < g.pieces.size(); ++i)
      for (size_t j = i + 1; j < g.pieces.size(); ++j) {
        const NetworkPiece &p = g.pieces[i], &q = g.pieces[j];
        if (p.a == q.a || p.a == q.b || p.b == q.a || p.b == q.b) continue;
        const double rr = p.radius + q.radius;
        const double d = segment_distance(net.node(p.a), net.node(p.b), net.node(q.a), net.node(q.b));
        if (d >= rr) continue;
        double path = std::numeric_limits<double>::infinity();
        for (int u : {p.a, p.b})
          for (int v : {q.a, q.b})
            path = std::min(path, dist[static_cast<size_t>(local[u]) * m + static_cast<size_t>(local[v])]);
        if (path > 2.0 * rr)
          throw_input_error(at, fmt::format("{} and {} intersect: their axes come {:.3g} mm close, less than "
                                            "the sum of their radii ({:.3g} mm)",
                                            branch_name(net, p.branch), branch_name(net, q.branch), d * 1e3, rr * 1e3));
      }
  }
  return g;
}

gmsh::vectorpair add_network_solids(const vessels::Network& net, const NetworkSolids& solids,
                                    const GrownRadius& grown) {
  namespace occ = gmsh::model::occ;
  gmsh::vectorpair out;
  for (const NetworkPiece& p : solids.pieces) {
    const Vec3 a = net.node(p.a), d = net.node(p.b) - a;
    out.push_back({3, occ::addCylinder(a.x(), a.y(), a.z(), d.x(), d.y(), d.z(), grown(p.radius, p.branch))});
  }
  for (const NetworkSphere& s : solids.spheres) {
    const Vec3 c = net.node(s.node);
    out.push_back({3, occ::addSphere(c.x(), c.y(), c.z(), grown(s.radius, s.branch))});
  }
  if (out.size() > 1) {
    gmsh::vectorpair fused;
    std::vector<gmsh::vectorpair> map;
    occ::fuse({out.front()}, gmsh::vectorpair(out.begin() + 1, out.end()), fused, map);
    return fused;
  }
  return out;
}

double distance_to_network_solid_surfaces(const vessels::Network& net, const NetworkSolids& solids,
                                          const vessels::Vec3& x, const GrownRadius& grown) {
  double best = std::numeric_limits<double>::infinity();
  for (const NetworkPiece& p : solids.pieces) {
    const Vec3 a = net.node(p.a), d = net.node(p.b) - a;
    const double t = std::clamp((x - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
    best = std::min(best, std::abs((x - (a + t * d)).norm() - grown(p.radius, p.branch)));
  }
  for (const NetworkSphere& s : solids.spheres)
    best = std::min(best, std::abs((x - net.node(s.node)).norm() - grown(s.radius, s.branch)));
  return best;
}

}  // namespace flowire::mesh
