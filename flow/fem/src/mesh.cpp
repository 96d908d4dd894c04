// The lumen of a vessel network as fused OpenCASCADE solids, meshed by gmsh into
// quadratic tetrahedra (see mesh.hpp for the geometry rules and the checks).
#include "flowire/fem/mesh.hpp"

#include <fmt/format.h>
#include <gmsh.h>
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <queue>
#include <unordered_map>

#include "flowire/common/error.hpp"
#include "flowire/fem/element.hpp"
#include "flowire/flow/petsc_runtime.hpp"
#include "mesh_detail.hpp"

namespace flowire::fem {
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

double point_segment_distance(const Vec3& x, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const double l2 = d.squaredNorm();
  const double t = l2 > 0.0 ? std::clamp((x - a).dot(d) / l2, 0.0, 1.0) : 0.0;
  return (x - (a + t * d)).norm();
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

/// Reference coordinates of the nodes of a gmsh element type -> our local node order.
std::vector<int> local_order(int gmsh_type, int dim) {
  std::string name;
  int d = 0, order = 0, nn = 0, np = 0;
  std::vector<double> coords;
  gmsh::model::mesh::getElementProperties(gmsh_type, name, d, order, nn, coords, np);
  const int nv = dim + 1;
  std::vector<std::array<double, 3>> ref(static_cast<size_t>(nn));
  std::vector<std::array<double, 3>> vert = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int k = 0; k < nn; ++k)
    for (int c = 0; c < 3; ++c)
      ref[static_cast<size_t>(k)][c] = c < dim ? coords[static_cast<size_t>(k * dim + c)] : 0.0;
  std::vector<std::array<double, 3>> ours;
  for (int i = 0; i < nv; ++i) ours.push_back(vert[static_cast<size_t>(i)]);
  if (dim == 3) {
    for (const auto& e : kTetEdges) {
      std::array<double, 3> mid{};
      for (int c = 0; c < 3; ++c) mid[c] = 0.5 * (vert[e[0]][c] + vert[e[1]][c]);
      ours.push_back(mid);
    }
  } else {
    for (const auto& e : kTriEdges) {
      std::array<double, 3> mid{};
      for (int c = 0; c < 3; ++c) mid[c] = 0.5 * (vert[e[0]][c] + vert[e[1]][c]);
      ours.push_back(mid);
    }
  }
  if (static_cast<size_t>(nn) != ours.size())
    throw_numerical_error(
        fmt::format("fem mesh: gmsh element type {} has {} nodes, expected {}", gmsh_type, nn, ours.size()));
  std::vector<int> perm(ours.size(), -1);  // perm[our k] = gmsh k
  for (size_t k = 0; k < ours.size(); ++k)
    for (int j = 0; j < nn; ++j) {
      const auto& r = ref[static_cast<size_t>(j)];
      if (std::abs(r[0] - ours[k][0]) + std::abs(r[1] - ours[k][1]) + std::abs(r[2] - ours[k][2]) < 1e-9) perm[k] = j;
    }
  for (int p : perm)
    if (p < 0) throw_numerical_error("fem mesh: unexpected gmsh reference element");
  return perm;
}

double tet_volume_linear(const TetMesh& m, const std::array<int, 10>& t) {
  const Vec3& x0 = m.nodes[static_cast<size_t>(t[0])];
  return (m.nodes[static_cast<size_t>(t[1])] - x0)
             .cross(m.nodes[static_cast<size_t>(t[2])] - x0)
             .dot(m.nodes[static_cast<size_t>(t[3])] - x0) /
         6.0;
}

}  // namespace

namespace detail {

/// The physical groups both mesh builders need (the volume, and every boundary group under
/// its name, tagged group index + 1) and their common meshing options (one thread, so the
/// same geometry gives the same mesh; first order here, raised to second order later).
void tag_groups_and_set_options(int volume, const char* volume_name, const std::vector<BoundaryGroup>& groups,
                                const gmsh::vectorpair& surfs, const std::vector<int>& surf_group, int algorithm3d) {
  gmsh::model::addPhysicalGroup(3, {volume}, 1);
  gmsh::model::setPhysicalName(3, 1, volume_name);
  for (size_t gi = 0; gi < groups.size(); ++gi) {
    std::vector<int> tags;
    for (size_t k = 0; k < surfs.size(); ++k)
      if (surf_group[k] == static_cast<int>(gi)) tags.push_back(surfs[k].second);
    const int tag = static_cast<int>(gi) + 1;
    gmsh::model::addPhysicalGroup(2, tags, tag);
    gmsh::model::setPhysicalName(2, tag, groups[gi].name);
  }
  gmsh::option::setNumber("General.NumThreads", 1);
  gmsh::option::setNumber("Mesh.Algorithm3D", algorithm3d);
  gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
  gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
  gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
  gmsh::option::setNumber("Mesh.ElementOrder", 1);
  gmsh::option::setNumber("Mesh.SecondOrderLinear", 0);
  gmsh::option::setNumber("Mesh.LcIntegrationPrecision", 1e-3);
}

bool set_size_bounds(double mesh_size, double size_factor) {
  if (mesh_size > 0.0) {
    gmsh::option::setNumber("Mesh.MeshSizeMin", mesh_size);
    gmsh::option::setNumber("Mesh.MeshSizeMax", mesh_size);
    return true;
  }
  if (!(size_factor > 0.0)) throw_usage_error("fem: size_factor must be > 0 when mesh_size is not set");
  gmsh::option::setNumber("Mesh.MeshSizeMin", 0.0);
  gmsh::option::setNumber("Mesh.MeshSizeMax", 1e22);
  return false;
}
}  // namespace detail

namespace {

using detail::extract_mesh;
using detail::generate;
using detail::GmshModel;
using detail::tag_groups_and_set_options;

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
  if (!detail::set_size_bounds(opt.mesh_size, opt.size_factor)) {
    const Geometry* geo = &g;
    const Network* nw = &net;
    const double factor = opt.size_factor;
    gmsh::model::mesh::setSizeCallback([geo, nw, factor](int, int, double x, double y, double z) {
      const Vec3 p(x, y, z);
      double best = std::numeric_limits<double>::infinity(), r = geo->pieces.front().radius;
      for (const Piece& pc : geo->pieces) {
        const double d = point_segment_distance(p, nw->node(pc.a), nw->node(pc.b)) - pc.radius;
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

namespace detail {

/// Second-order tetrahedra of the current model (one thread), written to `save_msh`.
void generate(const MeshOptions& opt) {
  gmsh::model::mesh::generate(3);
  gmsh::model::mesh::setOrder(2);
  if (!opt.save_msh.empty()) gmsh::write(opt.save_msh);
}

/// Nodes, tetrahedra and boundary triangles (by group: `surf_group[k]` for surface
/// `surfs[k]`) of the meshed model into `mesh`.
void extract_mesh(TetMesh& mesh, const gmsh::vectorpair& surfs, const std::vector<int>& surf_group,
                  const std::string& at) {
  // Nodes and tetrahedra.
  std::vector<std::size_t> node_tags;
  std::vector<double> coords, param;
  gmsh::model::mesh::getNodes(node_tags, coords, param, -1, -1, false, false);
  std::unordered_map<std::size_t, int> index;
  index.reserve(node_tags.size());
  const std::vector<int> tet_perm = local_order(11, 3);
  const std::vector<int> tri_perm = local_order(9, 2);
  std::vector<std::size_t> etags, enodes;
  gmsh::model::mesh::getElementsByType(11, etags, enodes);
  if (etags.empty()) throw_numerical_error(fmt::format("{}: gmsh produced no tetrahedra", at));
  std::unordered_map<std::size_t, size_t> coord_of;
  coord_of.reserve(node_tags.size());
  for (size_t k = 0; k < node_tags.size(); ++k) coord_of[node_tags[k]] = k;
  auto node_index = [&](std::size_t tag) {
    auto [it, inserted] = index.emplace(tag, static_cast<int>(mesh.nodes.size()));
    if (inserted) {
      const size_t k = coord_of.at(tag);
      mesh.nodes.emplace_back(coords[3 * k], coords[3 * k + 1], coords[3 * k + 2]);
    }
    return it->second;
  };
  mesh.tets.resize(etags.size());
  for (size_t e = 0; e < etags.size(); ++e) {
    auto& t = mesh.tets[e];
    for (int k = 0; k < 10; ++k)
      t[static_cast<size_t>(k)] = node_index(enodes[e * 10 + static_cast<size_t>(tet_perm[static_cast<size_t>(k)])]);
    if (tet_volume_linear(mesh, t) < 0.0) {
      // Swap vertices 1 and 2: edges (0,1)<->(0,2), (1,3)<->(2,3); (1,2) stays.
      std::swap(t[1], t[2]);
      std::swap(t[4], t[6]);
      std::swap(t[8], t[9]);
    }
  }
  mesh.vertex_index.assign(mesh.nodes.size(), -1);
  for (const auto& t : mesh.tets)
    for (int k = 0; k < 4; ++k) {
      int& v = mesh.vertex_index[static_cast<size_t>(t[static_cast<size_t>(k)])];
      if (v < 0) v = mesh.num_vertices++;
    }
  // Boundary triangles by group, oriented outwards.
  struct FaceKey {
    std::array<int, 3> v;
    bool operator==(const FaceKey& o) const { return v == o.v; }
  };
  struct FaceHash {
    size_t operator()(const FaceKey& k) const {
      return (static_cast<size_t>(k.v[0]) * 73856093u) ^ (static_cast<size_t>(k.v[1]) * 19349663u) ^
             (static_cast<size_t>(k.v[2]) * 83492791u);
    }
  };
  std::unordered_map<FaceKey, int, FaceHash> face_of;
  for (size_t k = 0; k < surfs.size(); ++k) {
    std::vector<std::size_t> ftags, fnodes;
    gmsh::model::mesh::getElementsByType(9, ftags, fnodes, surfs[k].second);
    for (size_t f = 0; f < ftags.size(); ++f) {
      std::array<int, 6> tri{};
      for (int j = 0; j < 6; ++j) {
        const auto it = index.find(fnodes[f * 6 + static_cast<size_t>(tri_perm[static_cast<size_t>(j)])]);
        if (it == index.end()) throw_numerical_error(fmt::format("{}: a boundary node belongs to no tetrahedron", at));
        tri[static_cast<size_t>(j)] = it->second;
      }
      FaceKey key{{tri[0], tri[1], tri[2]}};
      std::sort(key.v.begin(), key.v.end());
      face_of.emplace(key, static_cast<int>(mesh.faces.size()));
      mesh.faces.push_back(tri);
      mesh.face_group.push_back(surf_group[k]);
    }
  }
  std::vector<char> oriented(mesh.faces.size(), 0);
  static constexpr int kFaceVerts[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (const auto& t : mesh.tets) {
    for (int f = 0; f < 4; ++f) {
      FaceKey key{{t[static_cast<size_t>(kFaceVerts[f][0])], t[static_cast<size_t>(kFaceVerts[f][1])],
                   t[static_cast<size_t>(kFaceVerts[f][2])]}};
      std::sort(key.v.begin(), key.v.end());
      const auto it = face_of.find(key);
      if (it == face_of.end()) continue;
      auto& tri = mesh.faces[static_cast<size_t>(it->second)];
      const Vec3& x0 = mesh.nodes[static_cast<size_t>(tri[0])];
      const Vec3 n = (mesh.nodes[static_cast<size_t>(tri[1])] - x0).cross(mesh.nodes[static_cast<size_t>(tri[2])] - x0);
      const Vec3 opposite = mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(f)])];
      if (n.dot(x0 - opposite) < 0.0) {
        // Swap vertices 1 and 2: edges (0,1)<->(0,2); (1,2) stays.
        std::swap(tri[1], tri[2]);
        std::swap(tri[3], tri[5]);
      }
      oriented[static_cast<size_t>(it->second)] = 1;
    }
  }
  for (char o : oriented)
    if (!o) throw_numerical_error(fmt::format("{}: a boundary triangle has no tetrahedron", at));
}

}  // namespace detail

namespace {

/// Distance from x to the segment [a, b] and the axial parameter t of its projection
/// (t in units of length from a, unclamped).
double axis_distance(const Vec3& x, const Vec3& a, const Vec3& b, double& t) {
  const Vec3 d = b - a;
  const double l = d.norm();
  t = (x - a).dot(d) / l;
  return (x - a - t * d / l).norm();
}

/// Which face of `s` the point x lies on (tolerance tol), or -1.
int face_of_solid(const Solid& s, const Vec3& x, double tol) {
  if (s.shape == Solid::Shape::Box) {
    for (int f = 0; f < 6; ++f) {
      const int axis = f / 2;
      const double plane = f % 2 == 0 ? s.a[axis] : s.b[axis];
      if (std::abs(x[axis] - plane) > tol) continue;
      bool inside = true;
      for (int c = 0; c < 3; ++c)
        if (c != axis && (x[c] < s.a[c] - tol || x[c] > s.b[c] + tol)) inside = false;
      if (inside) return f;
    }
    return -1;
  }
  double t = 0.0;
  const double r = axis_distance(x, s.a, s.b, t);
  const double l = (s.b - s.a).norm();
  if (std::abs(r - s.radius) <= tol && t >= -tol && t <= l + tol) return 0;
  if (r <= s.radius + tol && std::abs(t) <= tol) return 1;
  if (r <= s.radius + tol && std::abs(t - l) <= tol) return 2;
  return -1;
}

/// Distance from x to the lateral surface of a cylinder (0 inside it), or to a box.
double solid_distance(const Solid& s, const Vec3& x) {
  if (s.shape == Solid::Shape::Box) {
    double d2 = 0.0;
    for (int c = 0; c < 3; ++c) {
      const double e = std::max({s.a[c] - x[c], 0.0, x[c] - s.b[c]});
      d2 += e * e;
    }
    return std::sqrt(d2);
  }
  return std::max(0.0, point_segment_distance(x, s.a, s.b) - s.radius);
}

int add_solid(const Solid& s) {
  namespace occ = gmsh::model::occ;
  if (s.shape == Solid::Shape::Box) {
    const Vec3 d = s.b - s.a;
    return occ::addBox(s.a.x(), s.a.y(), s.a.z(), d.x(), d.y(), d.z());
  }
  const Vec3 d = s.b - s.a;
  return occ::addCylinder(s.a.x(), s.a.y(), s.a.z(), d.x(), d.y(), d.z(), s.radius);
}

void check_domain(const ShapeDomain& dom) {
  const std::string& at = dom.name;
  if (dom.groups.empty() || !dom.groups.front().no_slip())
    throw_input_error(at, "the first boundary group must be a no-slip wall");
  if (!(dom.mesh_size > 0.0)) throw_input_error(at, "mesh_size must be > 0");
  if (!(dom.growth > 0.0)) throw_input_error(at, "growth must be > 0");
  for (size_t i = 0; i < dom.groups.size(); ++i)
    for (size_t j = i + 1; j < dom.groups.size(); ++j)
      if (dom.groups[i].name == dom.groups[j].name)
        throw_input_error(at, fmt::format("two boundary groups are called '{}'", dom.groups[i].name));
  auto check_solid = [&](const Solid& s, const std::string& what) {
    if (s.shape == Solid::Shape::Box) {
      for (int c = 0; c < 3; ++c)
        if (!(s.b[c] > s.a[c])) throw_input_error(at, fmt::format("{}: the box has no volume", what));
    } else if (!(s.radius > 0.0) || !((s.b - s.a).norm() > 0.0)) {
      throw_input_error(at, fmt::format("{}: zero cylinder radius or length", what));
    }
    for (int g : s.face_group)
      if (g < -1 || g >= static_cast<int>(dom.groups.size()))
        throw_input_error(at, fmt::format("{}: face group {} is not one of the {} groups", what, g, dom.groups.size()));
  };
  check_solid(dom.outer, "outer solid");
  for (size_t h = 0; h < dom.holes.size(); ++h) check_solid(dom.holes[h], fmt::format("hole {}", h));
}

TetMesh mesh_domain(const ShapeDomain& dom, const MeshOptions& opt) {
  const auto start = std::chrono::steady_clock::now();
  check_domain(dom);
  const std::string& at = dom.name;
  TetMesh mesh;
  mesh.groups = dom.groups;
  for (auto& g : mesh.groups) g.node = -1;

  GmshModel model(opt.verbose);
  namespace occ = gmsh::model::occ;
  const int outer = add_solid(dom.outer);
  if (!dom.holes.empty()) {
    gmsh::vectorpair tools, out;
    for (const Solid& h : dom.holes) tools.push_back({3, add_solid(h)});
    std::vector<gmsh::vectorpair> map;
    occ::cut({{3, outer}}, tools, out, map);
  }
  occ::synchronize();
  gmsh::vectorpair vols, surfs;
  gmsh::model::getEntities(vols, 3);
  if (vols.size() != 1)
    throw_input_error(
        at, fmt::format("the fluid is {} separate volumes, not one (does a hole cut the domain in two?)", vols.size()));
  gmsh::model::getEntities(surfs, 2);
  // A point of each surface (the middle of its parameter range: on the underlying
  // plane or cylinder even where the face is trimmed) names the solid face it lies on.
  double xmin = 0, ymin = 0, zmin = 0, xmax = 0, ymax = 0, zmax = 0;
  gmsh::model::getBoundingBox(-1, -1, xmin, ymin, zmin, xmax, ymax, zmax);
  const double tol = 1e-7 * (Vec3(xmax, ymax, zmax) - Vec3(xmin, ymin, zmin)).norm();
  std::vector<int> surf_group(surfs.size(), 0);
  std::vector<char> used(mesh.groups.size(), 0);
  for (size_t k = 0; k < surfs.size(); ++k) {
    std::vector<double> lo, hi, xyz;
    gmsh::model::getParametrizationBounds(2, surfs[k].second, lo, hi);
    gmsh::model::getValue(2, surfs[k].second, {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])}, xyz);
    const Vec3 x(xyz[0], xyz[1], xyz[2]);
    int group = -2;
    for (size_t sidx = 0; sidx <= dom.holes.size() && group == -2; ++sidx) {
      const Solid& sol = sidx == 0 ? dom.outer : dom.holes[sidx - 1];
      const int f = face_of_solid(sol, x, tol);
      if (f >= 0) group = std::max(0, sol.face_group[static_cast<size_t>(f)]);
    }
    if (group == -2)
      throw_input_error(
          at, fmt::format("a face of the fluid (near {:.4g}, {:.4g}, {:.4g}) lies on no face of the solids", x.x(),
                          x.y(), x.z()));
    surf_group[k] = group;
    used[static_cast<size_t>(group)] = 1;
  }
  for (size_t g = 0; g < mesh.groups.size(); ++g)
    if (!used[g]) throw_input_error(at, fmt::format("boundary group '{}' has no face", mesh.groups[g].name));
  tag_groups_and_set_options(vols[0].second, "fluid", mesh.groups, surfs, surf_group, opt.algorithm3d);
  gmsh::option::setNumber("Mesh.MeshSizeMin", 0.0);
  gmsh::option::setNumber("Mesh.MeshSizeMax", 1e22);
  const ShapeDomain* d = &dom;
  gmsh::model::mesh::setSizeCallback([d](int, int, double x, double y, double z) {
    const Vec3 p(x, y, z);
    double h = d->mesh_size;
    for (const Solid& hole : d->holes) {
      const double hh = hole.mesh_size > 0.0 ? hole.mesh_size : d->mesh_size;
      h = std::min(h, hh + d->growth * solid_distance(hole, p));
    }
    return h;
  });
  generate(opt);
  extract_mesh(mesh, surfs, surf_group, at);
  mesh.mesh_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return mesh;
}

}  // namespace

namespace detail {

/// Run `build` with gmsh's exceptions turned into flowire errors naming `at`.
TetMesh guarded(const std::string& at, const std::function<TetMesh()>& build) {
  try {
    return build();
  } catch (const Error&) {
    throw;
  } catch (const std::string& s) {
    throw_numerical_error(fmt::format("{}: gmsh failed: {}", at, s));
  } catch (const std::exception& e) {
    throw_numerical_error(fmt::format("{}: gmsh failed: {}", at, e.what()));
  } catch (...) {
    throw_numerical_error(fmt::format("{}: gmsh failed", at));
  }
}

template <class T>
void bcast_vector(std::vector<T>& v, int rank) {
  unsigned long long n = v.size();
  MPI_Bcast(&n, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
  if (rank != 0) v.resize(static_cast<size_t>(n));
  if (n > 0) MPI_Bcast(v.data(), static_cast<int>(n * sizeof(T)), MPI_BYTE, 0, MPI_COMM_WORLD);
}

/// Mesh on rank 0 with `build`; under MPI with more than one rank every rank receives
/// the mesh (or rank 0's error).
TetMesh build_shared(const std::function<TetMesh()>& build) {
  const int size = flow::mpi_size(), rank = flow::mpi_rank();
  if (size == 1) return build();

  // Rank 0 meshes; the outcome (or the error) goes to every rank.
  TetMesh mesh;
  int status = 0;  // 0 ok, else 1 + ErrorKind
  std::string message;
  if (rank == 0) {
    try {
      mesh = build();
    } catch (const Error& e) {
      status = 1 + static_cast<int>(e.kind());
      message = e.what();
    }
  }
  MPI_Bcast(&status, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (status != 0) {
    std::vector<char> text(message.begin(), message.end());
    bcast_vector(text, rank);
    throw Error(static_cast<ErrorKind>(status - 1), std::string(text.begin(), text.end()));
  }
  std::vector<double> xyz;
  if (rank == 0)
    for (const Vec3& x : mesh.nodes) xyz.insert(xyz.end(), {x.x(), x.y(), x.z()});
  bcast_vector(xyz, rank);
  bcast_vector(mesh.tets, rank);
  bcast_vector(mesh.faces, rank);
  bcast_vector(mesh.face_group, rank);
  bcast_vector(mesh.vertex_index, rank);
  std::vector<int> groups;
  std::vector<char> names;  // group names, each ended by a 0
  if (rank == 0)
    for (const auto& g : mesh.groups) {
      groups.insert(groups.end(), {static_cast<int>(g.kind), g.node});
      names.insert(names.end(), g.name.begin(), g.name.end());
      names.push_back('\0');
    }
  bcast_vector(groups, rank);
  bcast_vector(names, rank);
  MPI_Bcast(&mesh.num_vertices, 1, MPI_INT, 0, MPI_COMM_WORLD);
  MPI_Bcast(&mesh.mesh_seconds, 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  if (rank != 0) {
    mesh.nodes.resize(xyz.size() / 3);
    for (size_t i = 0; i < mesh.nodes.size(); ++i) mesh.nodes[i] = Vec3(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    mesh.groups.clear();
    const char* name = names.data();
    for (size_t k = 0; k + 1 < groups.size(); k += 2) {
      mesh.groups.push_back({static_cast<BoundaryGroup::Kind>(groups[k]), groups[k + 1], std::string(name)});
      name += mesh.groups.back().name.size() + 1;
    }
  }
  return mesh;
}

}  // namespace detail

namespace {}  // namespace

int TetMesh::group_named(const std::string& name) const {
  for (size_t g = 0; g < groups.size(); ++g)
    if (groups[g].name == name) return static_cast<int>(g);
  return -1;
}

int TetMesh::group_of_node(int network_node) const {
  for (size_t g = 0; g < groups.size(); ++g)
    if (groups[g].kind != BoundaryGroup::Kind::Wall && groups[g].node == network_node) return static_cast<int>(g);
  return -1;
}

double TetMesh::volume() const {
  double v = 0.0;
  double grads[10][3];
  for (const auto& t : tets)
    for (const QuadPoint& q : tet_quadrature()) {
      tet_p2_grad(q.xi, grads);
      Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
      for (int k = 0; k < 10; ++k)
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) j(a, b) += nodes[static_cast<size_t>(t[static_cast<size_t>(k)])][a] * grads[k][b];
      v += q.weight * j.determinant();
    }
  return v;
}

double TetMesh::area(int group) const {
  double a = 0.0;
  double grads[6][2];
  for (size_t f = 0; f < faces.size(); ++f) {
    if (face_group[f] != group) continue;
    for (const QuadPoint& q : tri_quadrature()) {
      tri_p2_grad(q.xi, grads);
      Vec3 ts = Vec3::Zero(), tt = Vec3::Zero();
      for (int k = 0; k < 6; ++k) {
        ts += grads[k][0] * nodes[static_cast<size_t>(faces[f][static_cast<size_t>(k)])];
        tt += grads[k][1] * nodes[static_cast<size_t>(faces[f][static_cast<size_t>(k)])];
      }
      a += q.weight * ts.cross(tt).norm();
    }
  }
  return a;
}

TetMesh build_mesh(const Network& net, const MeshOptions& opt) {
  return detail::build_shared([&] {
    const Geometry g = make_geometry(net);
    return detail::guarded(where(net), [&] { return mesh_geometry(net, g, opt); });
  });
}

TetMesh build_mesh(const ShapeDomain& domain, const MeshOptions& opt) {
  return detail::build_shared([&] { return detail::guarded(domain.name, [&] { return mesh_domain(domain, opt); }); });
}

}  // namespace flowire::fem
