// The lumen of a vessel network as fused OpenCASCADE solids, meshed by gmsh into
// quadratic tetrahedra (see network_mesh.hpp for the geometry rules and the checks): the
// pieces and spheres of the network and their checks, then the solids, the end faces
// tagged as inlet and outlets, and the size field.
#include "flowire/flow/fem/network_mesh.hpp"

#include <fmt/format.h>
#include <gmsh.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <queue>
#include <string>
#include <unordered_map>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/mesh/extract.hpp"
#include "flowire/mesh/gmsh_session.hpp"
#include "flowire/vessels/spatial.hpp"
#include "mesh_broadcast.hpp"

namespace flowire::flow::fem {
namespace {

/// A run of collinear segments of one radius: one cylinder from node a to node b.
struct Piece {
  int a = -1, b = -1;
  double radius = 0.0;
  int branch = -1;
};

struct Sphere {
  int node = -1;
  double radius = 0.0;
};

struct Geometry {
  std::vector<Piece> pieces;
  std::vector<Sphere> spheres;
  std::vector<double> sphere_at;  // (num_nodes) sphere radius at a node, 0 if none
};

double piece_length(const Network& net, const Piece& p) { return (net.node(p.b) - net.node(p.a)).norm(); }

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

std::string branch_name(const Network& net, int b) {
  const auto& n = net.branch(b).name;
  return n.empty() ? fmt::format("branch {}", b) : fmt::format("branch '{}'", n);
}

std::string where(const Network& net) {
  return net.source().empty() ? std::string("fem geometry") : fmt::format("fem geometry of {}", net.source());
}

Geometry make_geometry(const Network& net) {
  Geometry g;
  const std::string at = where(net);
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
    Piece cur{br.nodes[0], br.nodes[1], net.segment(br.segments[0]).radius, b};
    Vec3 dir = (net.node(br.nodes[1]) - net.node(br.nodes[0])).normalized();
    for (size_t k = 1; k < br.segments.size(); ++k) {
      const Vec3 d = (net.node(br.nodes[k + 1]) - net.node(br.nodes[k])).normalized();
      const double r = net.segment(br.segments[k]).radius;
      if (d.dot(dir) > 1.0 - 1e-10 && std::abs(r - cur.radius) <= 1e-9 * cur.radius) {
        cur.b = br.nodes[k + 1];
      } else {
        g.pieces.push_back(cur);
        cur = Piece{br.nodes[k], br.nodes[k + 1], r, b};
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
    const Piece& pc = g.pieces[static_cast<size_t>(p)];
    const int other = pc.a == node ? pc.b : pc.a;
    return Vec3((net.node(other) - net.node(node)).normalized());
  };
  for (int n = 0; n < net.num_nodes(); ++n) {
    const auto& ps = at_node[static_cast<size_t>(n)];
    if (ps.size() < 2) continue;
    double rmax = 0.0;
    for (int p : ps) rmax = std::max(rmax, g.pieces[static_cast<size_t>(p)].radius);
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
    g.spheres.push_back({n, rmax});
  }
  // End pieces must reach past the sphere at their other end.
  for (int n = 0; n < net.num_nodes(); ++n) {
    const auto& ps = at_node[static_cast<size_t>(n)];
    if (ps.size() != 1) continue;
    const Piece& pc = g.pieces[static_cast<size_t>(ps[0])];
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
  for (const Piece& p : g.pieces)
    for (int n : {p.a, p.b})
      if (local.emplace(n, static_cast<int>(ids.size())).second) ids.push_back(n);
  const size_t m = ids.size();
  if (m <= 800 && g.pieces.size() >= 2) {
    std::vector<std::vector<std::pair<int, double>>> adj(m);
    for (const Piece& p : g.pieces) {
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
        const Piece &p = g.pieces[i], &q = g.pieces[j];
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

using mesh::extract_mesh;
using mesh::generate;
using mesh::GmshModel;
using mesh::tag_groups_and_set_options;

TetMesh mesh_geometry(const Network& net, const Geometry& g, const MeshOptions& opt) {
  const auto start = std::chrono::steady_clock::now();
  const std::string at = where(net);
  const std::vector<int> ends = net.ends();
  const int inlet = opt.inlet_node >= 0 ? opt.inlet_node : net.widest_end();
  if (std::find(ends.begin(), ends.end(), inlet) == ends.end())
    throw_input_error(at, fmt::format("inlet node {} is not a network end", inlet));
  if (ends.size() < 2) throw_input_error(at, "the network needs an inlet and at least one outlet");

  TetMesh mesh;
  mesh.groups.push_back({BoundaryGroup::Kind::Wall, -1, "wall"});
  mesh.groups.push_back({BoundaryGroup::Kind::Inlet, inlet, "inlet"});
  for (int e : ends)
    if (e != inlet) mesh.groups.push_back({BoundaryGroup::Kind::Outlet, e, fmt::format("outlet_{}", e)});

  GmshModel model(opt.verbose);
  namespace occ = gmsh::model::occ;
  gmsh::vectorpair solids;
  for (const Piece& p : g.pieces) {
    const Vec3 a = net.node(p.a), d = net.node(p.b) - a;
    solids.push_back({3, occ::addCylinder(a.x(), a.y(), a.z(), d.x(), d.y(), d.z(), p.radius)});
  }
  for (const Sphere& s : g.spheres) {
    const Vec3 c = net.node(s.node);
    solids.push_back({3, occ::addSphere(c.x(), c.y(), c.z(), s.radius)});
  }
  if (solids.size() > 1) {
    gmsh::vectorpair out;
    std::vector<gmsh::vectorpair> map;
    occ::fuse({solids.front()}, gmsh::vectorpair(solids.begin() + 1, solids.end()), out, map);
  }
  occ::synchronize();
  gmsh::vectorpair vols, surfs;
  gmsh::model::getEntities(vols, 3);
  if (vols.size() != 1)
    throw_input_error(
        at, fmt::format("the fused lumen is {} separate volumes, not one; is the network connected?", vols.size()));
  gmsh::model::getEntities(surfs, 2);
  // End faces: planar faces centred on the end nodes.
  std::vector<int> surf_group(surfs.size(), 0);
  for (size_t gi = 1; gi < mesh.groups.size(); ++gi) {
    const int node = mesh.groups[gi].node;
    const Vec3 x = net.node(node);
    const double r = net.segment(*net.node_segments(node).first).radius;
    int found = -1;
    for (size_t k = 0; k < surfs.size(); ++k) {
      std::string type;
      gmsh::model::getType(2, surfs[k].second, type);
      if (type != "Plane") continue;
      double cx = 0, cy = 0, cz = 0;
      occ::getCenterOfMass(2, surfs[k].second, cx, cy, cz);
      if ((Vec3(cx, cy, cz) - x).norm() <= 1e-3 * r) found = static_cast<int>(k);
    }
    if (found < 0)
      throw_input_error(at, fmt::format("end node {}: its end face was not found after fusing (another vessel "
                                        "or a junction sphere covers it)",
                                        node));
    surf_group[static_cast<size_t>(found)] = static_cast<int>(gi);
  }
  tag_groups_and_set_options(vols[0].second, "lumen", mesh.groups, surfs, surf_group, opt.algorithm3d);
  // Sizes: fixed, or a fraction of the radius of the nearest piece.
  double hmin = std::numeric_limits<double>::infinity();
  for (const Piece& p : g.pieces) hmin = std::min(hmin, opt.size_factor * p.radius);
  if (!mesh::set_size_bounds(opt.mesh_size, opt.size_factor)) {
    const Geometry* geo = &g;
    const Network* nw = &net;
    const double factor = opt.size_factor;
    gmsh::model::mesh::setSizeCallback([geo, nw, factor](int, int, double x, double y, double z) {
      const Vec3 p(x, y, z);
      double best = std::numeric_limits<double>::infinity(), r = geo->pieces.front().radius;
      for (const Piece& pc : geo->pieces) {
        const double d = vessels::project_on_axis(p, nw->node(pc.a), nw->node(pc.b)).distance - pc.radius;
        if (d < best) {
          best = d;
          r = pc.radius;
        }
      }
      return factor * r;
    });
  }
  generate(opt);
  extract_mesh(mesh, surfs, surf_group, at);
  mesh.mesh_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return mesh;
}

}  // namespace

TetMesh build_mesh(const Network& net, const MeshOptions& opt) {
  return detail::build_shared([&] {
    const Geometry g = make_geometry(net);
    return mesh::guarded(where(net), [&] { return mesh_geometry(net, g, opt); });
  });
}

}  // namespace flowire::flow::fem
