// The wall around a triangulated lumen surface: its open ends cut square, the lumen remeshed by
// gmsh at the wall's element size, offset along its smoothed normals by the wall's thickness
// (reduced where the lumen leaves no room), closed by a ring at each open end; the lumen, the
// offset and the rings handed to gmsh as discrete surfaces and filled with quadratic tetrahedra.
#include "flowire/solid/surface_wall.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <memory>
#include <mutex>
#include <numbers>
#include <numeric>
#include <string>
#include <unordered_map>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/mesh/extract.hpp"
#include "flowire/mesh/gmsh_session.hpp"
#include "flowire/vessels/spatial.hpp"

namespace flowire::solid {
namespace {

using mesh::BoundaryGroup;
using mesh::TetMesh;
using vessels::mm;
using vessels::Vec3;

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b);
}

/// The lumen's open ends: loops of boundary edges, each in the direction its triangle runs it.
std::vector<std::vector<int>> open_loops(const vessels::LumenSurface& lumen,
                                         std::vector<std::vector<int>>& neighbours) {
  const auto& tri = lumen.triangles();
  const int n = static_cast<int>(lumen.vertices().size());
  std::unordered_map<std::uint64_t, std::pair<int, std::pair<int, int>>> uses;  // count, first directed edge
  for (const auto& t : tri)
    for (int k = 0; k < 3; ++k) {
      const int a = t[static_cast<size_t>(k)], b = t[static_cast<size_t>((k + 1) % 3)];
      auto [it, fresh] = uses.try_emplace(edge_key(a, b), 0, std::pair{a, b});
      ++it->second.first;
    }
  neighbours.assign(static_cast<size_t>(n), {});
  std::vector<int> next(static_cast<size_t>(n), -1);
  for (const auto& [key, use] : uses) {
    const auto [a, b] = use.second;
    neighbours[static_cast<size_t>(a)].push_back(b);
    neighbours[static_cast<size_t>(b)].push_back(a);
    if (use.first > 2)
      throw_input_error(fmt::format("{}: edge at {}", lumen.source(), mm(lumen.vertices()[static_cast<size_t>(a)])),
                        "the surface is not manifold there (an edge of more than two triangles): no wall can be "
                        "grown around it");
    if (use.first == 1) {
      if (next[static_cast<size_t>(a)] >= 0)
        throw_input_error(
            fmt::format("{}: open end at {}", lumen.source(), mm(lumen.vertices()[static_cast<size_t>(a)])),
            "two open ends touch at this vertex (a pinched rim): no wall can be grown around it");
      next[static_cast<size_t>(a)] = b;
    }
  }
  std::vector<std::vector<int>> loops;
  std::vector<char> seen(static_cast<size_t>(n), 0);
  for (int v = 0; v < n; ++v) {
    if (next[static_cast<size_t>(v)] < 0 || seen[static_cast<size_t>(v)]) continue;
    std::vector<int> loop;
    for (int u = v; !seen[static_cast<size_t>(u)]; u = next[static_cast<size_t>(u)]) {
      seen[static_cast<size_t>(u)] = 1;
      loop.push_back(u);
      if (next[static_cast<size_t>(u)] < 0)
        throw_input_error(
            fmt::format("{}: open end at {}", lumen.source(), mm(lumen.vertices()[static_cast<size_t>(u)])),
            "its rim does not close");
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

/// The network end @p e's segment and its unit axis out of the vessel.
std::pair<const vessels::Segment*, Vec3> end_axis(const vessels::Network& net, int e) {
  const auto& seg = net.segment(*net.node_segments(e).first);
  const int other = seg.node_from == e ? seg.node_to : seg.node_from;
  return {&seg, (net.node(e) - net.node(other)).normalized()};
}

/// Points inside the lumen that orient a surface built from it: the segments' midpoints.
std::vector<Vec3> segment_midpoints(const vessels::Network& net) {
  std::vector<Vec3> inside;
  for (int k = 0; k < net.num_segments(); ++k)
    inside.push_back(0.5 * (net.node(net.segment(k).node_from) + net.node(net.segment(k).node_to)));
  return inside;
}

/// The nominal thickness at @p x: the nearest segment's branch's, the wall's, or its ratio × that
/// segment's radius.
double nominal_thickness(const vessels::SpatialIndex& index, const vessels::Network& net, const SurfaceWall& wall,
                         const Vec3& x, int& hint) {
  if (wall.thickness > 0.0 && wall.branches.empty()) return wall.thickness;
  const vessels::Location at = index.locate(x, hint);
  hint = at.segment;
  const auto& seg = net.segment(at.segment);
  return wall_thickness_at(wall.thickness, wall.thickness_ratio, wall.branches, seg.branch, seg.radius);
}

/// The thickness at each vertex, the normals it is offset along; counts what was thinned.
struct Offset {
  std::vector<Vec3> normal;
  std::vector<double> thickness, nominal;
};

Offset offset_lumen(const vessels::LumenSurface& lumen, const vessels::Network& net, const SurfaceWall& wall,
                    const std::vector<std::vector<int>>& neighbours, const std::vector<std::vector<int>>& loops,
                    const std::vector<Vec3>& loop_axis, SurfaceWallStats& stats) {
  const auto& x = lumen.vertices();
  const auto& tri = lumen.triangles();
  const size_t n = x.size();
  Offset o;
  o.normal.assign(n, Vec3::Zero());
  for (const auto& t : tri) {  // angle-weighted face normals (out of the lumen)
    const Vec3 fn = (x[static_cast<size_t>(t[1])] - x[static_cast<size_t>(t[0])])
                        .cross(x[static_cast<size_t>(t[2])] - x[static_cast<size_t>(t[0])])
                        .normalized();
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = x[static_cast<size_t>(t[static_cast<size_t>(k)])];
      const Vec3 e1 = (x[static_cast<size_t>(t[static_cast<size_t>((k + 1) % 3)])] - p).normalized();
      const Vec3 e2 = (x[static_cast<size_t>(t[static_cast<size_t>((k + 2) % 3)])] - p).normalized();
      o.normal[static_cast<size_t>(t[static_cast<size_t>(k)])] += std::acos(std::clamp(e1.dot(e2), -1.0, 1.0)) * fn;
    }
  }
  for (auto& v : o.normal) v.normalize();
  for (int pass = 0; pass < 2; ++pass) {  // smoothed over the neighbours
    std::vector<Vec3> s = o.normal;
    for (size_t i = 0; i < n; ++i)
      for (int j : neighbours[i]) s[i] += o.normal[static_cast<size_t>(j)];
    for (size_t i = 0; i < n; ++i) o.normal[i] = s[i].normalized();
  }
  for (size_t l = 0; l < loops.size(); ++l)  // an end's ring in the end's plane
    for (int v : loops[l]) {
      Vec3& nv = o.normal[static_cast<size_t>(v)];
      nv = (nv - nv.dot(loop_axis[l]) * loop_axis[l]).normalized();
    }

  const vessels::SpatialIndex index(net, 4);
  o.nominal.resize(n);
  int hint = -1;
  for (size_t i = 0; i < n; ++i) o.nominal[i] = nominal_thickness(index, net, wall, x[i], hint);
  o.thickness = o.nominal;
  // Room: the point 1.25 t out must lie 0.9 × 1.25 t × c from the lumen, else t shrinks (c the
  // rate at which the distance grows along the normal at the vertex: the normal, smoothed, need
  // not be the faces' own).
  int tri_hint = -1;
  for (size_t i = 0; i < n; ++i) {
    double& t = o.thickness[i];
    const double eps = 1e-3 * t;
    const double c = std::abs(lumen.distance(x[i] + eps * o.normal[i], tri_hint).distance) / eps;
    for (int k = 0; k < 30; ++k) {
      const vessels::SurfaceDistance d = lumen.distance(x[i] + 1.25 * t * o.normal[i], tri_hint);
      tri_hint = d.triangle;
      if (std::abs(d.distance) >= 0.9 * 1.25 * t * c) break;
      t *= 0.8;
    }
  }
  auto limit_steps = [&o, &neighbours, n] {  // at most 30% between neighbours
    for (int pass = 0; pass < 10; ++pass) {
      bool changed = false;
      for (size_t i = 0; i < n; ++i)
        for (int j : neighbours[i])
          if (o.thickness[i] > 1.3 * o.thickness[static_cast<size_t>(j)]) {
            o.thickness[i] = 1.3 * o.thickness[static_cast<size_t>(j)];
            changed = true;
          }
      if (!changed) break;
    }
  };
  limit_steps();
  // No offset face turned more than 60 degrees from its lumen face (a fold of the outer surface
  // where the lumen is rough on the scale of the thickness): its vertices thinned until none is.
  for (int pass = 0; pass < 40; ++pass) {
    int turned = 0;
    for (const auto& t : tri) {
      const auto a = static_cast<size_t>(t[0]), b = static_cast<size_t>(t[1]), c = static_cast<size_t>(t[2]);
      const Vec3 nl = (x[b] - x[a]).cross(x[c] - x[a]);
      // (a sliver's own height is no measure: its offset turns at any thickness)
      const double edges2 = (x[b] - x[a]).squaredNorm() + (x[c] - x[b]).squaredNorm() + (x[a] - x[c]).squaredNorm();
      if (2.0 * std::sqrt(3.0) * nl.norm() < 0.1 * edges2) continue;
      const Vec3 ya = x[a] + o.thickness[a] * o.normal[a], yb = x[b] + o.thickness[b] * o.normal[b],
                 yc = x[c] + o.thickness[c] * o.normal[c];
      const Vec3 no = (yb - ya).cross(yc - ya);
      if (nl.dot(no) >= 0.5 * nl.norm() * no.norm()) continue;
      ++turned;
      for (size_t v : {a, b, c}) o.thickness[v] *= 0.8;
    }
    if (turned == 0) break;
  }
  limit_steps();
  for (size_t i = 0; i < n; ++i)
    if (o.thickness[i] < o.nominal[i]) ++stats.thinned_vertices;
  stats.lumen_vertices = static_cast<int>(n);
  stats.min_thickness = *std::min_element(o.thickness.begin(), o.thickness.end());
  stats.max_thickness = *std::max_element(o.thickness.begin(), o.thickness.end());
  return o;
}

/// The lumen with every open end cut square to its vessel: by the plane normal to the network
/// end's axis just inside the innermost point of the rim near it (a rim left jagged by removing
/// a cap, or cut obliquely, becomes a planar loop; one square already is kept), unused points
/// dropped.
vessels::LumenSurface square_ends(const vessels::LumenSurface& lumen, const vessels::Network& net) {
  std::vector<Vec3> x = lumen.vertices();
  std::vector<std::array<int, 3>> tri = lumen.triangles();
  std::unordered_map<std::uint64_t, int> uses;
  for (const auto& t : tri)
    for (int k = 0; k < 3; ++k) ++uses[edge_key(t[static_cast<size_t>(k)], t[static_cast<size_t>((k + 1) % 3)])];
  std::vector<char> rim(x.size(), 0);
  for (const auto& [key, count] : uses)
    if (count == 1) rim[key >> 32] = rim[key & 0xffffffffu] = 1;
  for (int e : net.ends()) {
    const auto [seg, out] = end_axis(net, e);
    const double r = seg->radius;
    double innermost = std::numeric_limits<double>::infinity(), outermost = -innermost, reach = 0.0;
    for (size_t v = 0; v < x.size(); ++v)
      if (rim[v] && (x[v] - net.node(e)).norm() < 3.0 * r) {
        innermost = std::min(innermost, (x[v] - net.node(e)).dot(out));
        outermost = std::max(outermost, (x[v] - net.node(e)).dot(out));
      }
    if (!std::isfinite(innermost) || outermost - innermost < 1e-3 * r) continue;  // closed, or square already
    const Vec3 origin = net.node(e) + (innermost - 0.1 * r) * out;
    for (size_t v = 0; v < x.size(); ++v)
      if (rim[v] && (x[v] - net.node(e)).norm() < 3.0 * r) reach = std::max(reach, (x[v] - origin).norm());
    vessels::clip_surface(x, tri, origin, out, reach + r, 0.2 * lumen.counts().mean_edge);
  }
  vessels::SurfaceMesh m;
  m.source = lumen.source();
  std::vector<int> index(x.size(), -1);
  for (auto& t : tri) {
    for (int& v : t) {
      if (index[static_cast<size_t>(v)] < 0) {
        index[static_cast<size_t>(v)] = static_cast<int>(m.vertices.size());
        m.vertices.push_back(x[static_cast<size_t>(v)]);
      }
      v = index[static_cast<size_t>(v)];
    }
    m.triangles.push_back(t);
  }
  return vessels::LumenSurface(std::move(m), segment_midpoints(net));
}

/// The lumen triangulated anew by gmsh at the wall's element size (the image's triangles are
/// small and uneven; their offset would be worse): classified into patches at 40-degree creases,
/// reparametrized, meshed; the new triangles lie on the old surface.
vessels::LumenSurface remesh_lumen(const vessels::LumenSurface& lumen, const vessels::Network& net,
                                   const SurfaceWall& wall) {
  mesh::GmshModel model(false);
  const auto& x = lumen.vertices();
  gmsh::model::addDiscreteEntity(2, 1);
  std::vector<std::size_t> node_tags(x.size());
  std::iota(node_tags.begin(), node_tags.end(), std::size_t{1});
  std::vector<double> coords;
  for (const Vec3& p : x) coords.insert(coords.end(), {p.x(), p.y(), p.z()});
  gmsh::model::mesh::addNodes(2, 1, node_tags, coords);
  std::vector<std::size_t> tri_tags(lumen.triangles().size()), tri_nodes;
  std::iota(tri_tags.begin(), tri_tags.end(), std::size_t{1});
  for (const auto& t : lumen.triangles())
    for (int v : t) tri_nodes.push_back(static_cast<std::size_t>(v) + 1);
  gmsh::model::mesh::addElementsByType(1, 2, tri_tags, tri_nodes);
  gmsh::model::mesh::classifySurfaces(40.0 * std::numbers::pi / 180.0, true, true, std::numbers::pi);
  gmsh::model::mesh::createGeometry();
  mesh::set_common_options(1);
  if (!mesh::set_size_bounds(wall.mesh_size, 1.0)) {
    auto index = std::make_shared<vessels::SpatialIndex>(net, 4);
    gmsh::model::mesh::setSizeCallback([index, &net, wall](int, int, double px, double py, double pz) {
      int hint = -1;
      return wall.size_per_thickness * nominal_thickness(*index, net, wall, Vec3(px, py, pz), hint);
    });
  }
  gmsh::model::mesh::generate(2);
  std::vector<std::size_t> tags;
  std::vector<double> xyz, param;
  gmsh::model::mesh::getNodes(tags, xyz, param, -1, -1, true, false);
  std::unordered_map<std::size_t, int> index_of;
  vessels::SurfaceMesh m;
  m.source = lumen.source();
  for (size_t k = 0; k < tags.size(); ++k) {
    index_of[tags[k]] = static_cast<int>(m.vertices.size());
    m.vertices.emplace_back(xyz[3 * k], xyz[3 * k + 1], xyz[3 * k + 2]);
  }
  std::vector<std::size_t> etags, enodes;
  gmsh::model::mesh::getElementsByType(2, etags, enodes, -1);
  for (size_t e = 0; e < etags.size(); ++e)
    m.triangles.push_back({index_of.at(enodes[3 * e]), index_of.at(enodes[3 * e + 1]), index_of.at(enodes[3 * e + 2])});
  return vessels::LumenSurface(std::move(m), segment_midpoints(net));
}

/// Each boundary face's edge nodes moved onto @p surface (gmsh places them on its own
/// reparametrization of the shell, up to a sixtieth of a radius off it).
void project_edge_nodes(TetMesh& m, int group, const vessels::LumenSurface& surface) {
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (m.face_group[f] != group) continue;
    for (int k = 3; k < 6; ++k) {
      Vec3& y = m.nodes[static_cast<size_t>(m.faces[f][static_cast<size_t>(k)])];
      y = surface.distance(y).closest;
    }
  }
}

/// The lumen's loops named by the network's ends (the end nearest each loop's centroid), and
/// each end's axis out of the vessel.
struct Ends {
  std::vector<int> node;   ///< (loops) the network end
  std::vector<Vec3> axis;  ///< (loops)
};
Ends name_ends(const vessels::LumenSurface& lumen, const vessels::Network& net,
               const std::vector<std::vector<int>>& loops) {
  const auto& x = lumen.vertices();
  Ends ends;
  for (size_t l = 0; l < loops.size(); ++l) {
    Vec3 c = Vec3::Zero();
    for (int v : loops[l]) c += x[static_cast<size_t>(v)];
    c /= static_cast<double>(loops[l].size());
    int e = -1;
    double best = std::numeric_limits<double>::infinity();
    for (int end : net.ends())
      if (const double d = (net.node(end) - c).norm(); d < best) best = d, e = end;
    const auto [seg, axis] = end_axis(net, e);
    if (best > 3.0 * seg->radius)
      throw_input_error(fmt::format("{}: open end at {}", lumen.source(), mm(c)),
                        fmt::format("no end of the network {} lies within three radii of it", net.source()));
    if (std::find(ends.node.begin(), ends.node.end(), e) != ends.node.end())
      throw_input_error(fmt::format("{}: open end at {}", lumen.source(), mm(c)),
                        fmt::format("two open ends lie at the network's end node {}", e));
    ends.node.push_back(e);
    ends.axis.push_back(axis);
  }
  return ends;
}

TetMesh mesh_wall(const vessels::LumenSurface& given, const vessels::Network& net, const SurfaceWall& wall,
                  SurfaceWallStats* stats_out) {
  if (!(wall.thickness > 0.0) && !(wall.thickness_ratio > 0.0))
    throw_usage_error(fmt::format("surface wall: the thickness must be > 0, got {} m", wall.thickness));
  if (!(wall.mesh_size > 0.0) && !(wall.size_per_thickness > 0.0))
    throw_usage_error("surface wall: mesh_size or size_per_thickness must be > 0");
  for (const BranchThickness& b : wall.branches)
    if (b.branch < 0 || b.branch >= net.num_branches() || !(b.thickness > 0.0 || b.ratio > 0.0))
      throw_usage_error(
          fmt::format("surface wall: branch {}'s thickness {} m / ratio {} (a branch of {}, one of "
                      "them > 0)",
                      b.branch, b.thickness, b.ratio, net.num_branches()));
  const auto start = std::chrono::steady_clock::now();
  const std::string& at = given.source();
  const vessels::LumenSurface squared = square_ends(given, net);
  const vessels::LumenSurface lumen = remesh_lumen(squared, net, wall);
  const auto& x = lumen.vertices();
  const int n = static_cast<int>(x.size());
  std::vector<std::vector<int>> neighbours;
  const std::vector<std::vector<int>> loops = open_loops(lumen, neighbours);
  const Ends ends = name_ends(lumen, net, loops);
  SurfaceWallStats stats;
  const Offset o = offset_lumen(lumen, net, wall, neighbours, loops, ends.axis, stats);

  // The shell as discrete surfaces of their own: the lumen (turned: the solid lies outside it),
  // the offset, one ring per open end; meshed inside as they are (their triangles are gmsh's).
  TetMesh m;
  m.groups.push_back({BoundaryGroup::Kind::Wall, -1, "lumen"});
  m.groups.push_back({BoundaryGroup::Kind::Wall, -1, "outer"});
  for (int e : ends.node) m.groups.push_back({BoundaryGroup::Kind::Wall, -1, fmt::format("end_{}", e)});
  mesh::GmshModel model(false);
  gmsh::vectorpair surfs;
  std::vector<int> surf_group;
  for (int k = 0; k < 2 + static_cast<int>(loops.size()); ++k) {
    gmsh::model::addDiscreteEntity(2, k + 1);
    surfs.emplace_back(2, k + 1);
    surf_group.push_back(k);
  }
  std::vector<std::size_t> node_tags(static_cast<size_t>(n));
  std::vector<double> coords;
  std::iota(node_tags.begin(), node_tags.end(), std::size_t{1});
  for (const Vec3& p : x) coords.insert(coords.end(), {p.x(), p.y(), p.z()});
  gmsh::model::mesh::addNodes(2, 1, node_tags, coords);
  coords.clear();
  for (int i = 0; i < n; ++i) {
    const Vec3 y = x[static_cast<size_t>(i)] + o.thickness[static_cast<size_t>(i)] * o.normal[static_cast<size_t>(i)];
    coords.insert(coords.end(), {y.x(), y.y(), y.z()});
    node_tags[static_cast<size_t>(i)] = static_cast<std::size_t>(n + i) + 1;
  }
  gmsh::model::mesh::addNodes(2, 2, node_tags, coords);
  std::size_t next_tag = 1;
  auto add = [&next_tag](int surface, const std::vector<std::size_t>& nodes) {
    std::vector<std::size_t> tags(nodes.size() / 3);
    std::iota(tags.begin(), tags.end(), next_tag);
    next_tag += tags.size();
    gmsh::model::mesh::addElementsByType(surface, 2, tags, nodes);
  };
  auto tag = [](int v) { return static_cast<std::size_t>(v) + 1; };
  std::vector<std::size_t> inner, outer;
  for (const auto& t : lumen.triangles()) {
    inner.insert(inner.end(), {tag(t[0]), tag(t[2]), tag(t[1])});
    outer.insert(outer.end(), {tag(t[0] + n), tag(t[1] + n), tag(t[2] + n)});
  }
  add(1, inner);
  add(2, outer);
  for (size_t l = 0; l < loops.size(); ++l) {  // edge a -> b as its triangle runs it: the ring faces out of the end
    std::vector<std::size_t> ring;
    for (size_t k = 0; k < loops[l].size(); ++k) {
      const int a = loops[l][k], b = loops[l][(k + 1) % loops[l].size()];
      ring.insert(ring.end(), {tag(a), tag(b), tag(b + n), tag(a), tag(b + n), tag(a + n)});
    }
    add(3 + static_cast<int>(l), ring);
  }
  gmsh::model::mesh::createTopology();
  std::vector<int> shell;
  for (const auto& sf : surfs) shell.push_back(sf.second);
  const int loop = gmsh::model::geo::addSurfaceLoop(shell);
  gmsh::model::geo::addVolume({loop});
  gmsh::model::geo::synchronize();
  gmsh::vectorpair vols;
  gmsh::model::getEntities(vols, 3);
  if (vols.size() != 1) throw_numerical_error(fmt::format("{}: the wall gave {} volumes, not one", at, vols.size()));
  mesh::tag_groups_and_set_options(vols[0].second, "wall", m.groups, surfs, surf_group, 1);
  mesh::generate(mesh::MeshOptions{});
  mesh::extract_mesh(m, surfs, surf_group, at);
  // The lumen's edge nodes on the image's surface (gmsh leaves them on the chords).
  project_edge_nodes(m, 0, squared);
  // The outer surface's edge nodes the thickness out from the image's surface, along the
  // direction to them from it (gmsh leaves them on the offset's chords).
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (m.face_group[f] != 1) continue;
    for (int k = 3; k < 6; ++k) {
      Vec3& y = m.nodes[static_cast<size_t>(m.faces[f][static_cast<size_t>(k)])];
      const vessels::SurfaceDistance near = lumen.distance(y);
      const auto& t = lumen.triangles()[static_cast<size_t>(near.triangle)];
      const Vec3 &a = x[static_cast<size_t>(t[0])], &b = x[static_cast<size_t>(t[1])],
                 &c = x[static_cast<size_t>(t[2])];
      const Vec3 normal = (b - a).cross(c - a);
      const double area = normal.squaredNorm();
      const double wa = (c - b).cross(near.closest - b).dot(normal) / area,
                   wb = (a - c).cross(near.closest - c).dot(normal) / area;
      const double thick = wa * o.thickness[static_cast<size_t>(t[0])] + wb * o.thickness[static_cast<size_t>(t[1])] +
                           (1.0 - wa - wb) * o.thickness[static_cast<size_t>(t[2])];
      const Vec3 on = squared.distance(y).closest;
      y = on + thick * (y - on).normalized();
    }
  }
  mesh::repair_edge_nodes(m);
  m.mesh_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (stats_out) *stats_out = stats;
  return m;
}
}  // namespace

namespace {
struct Kept {
  std::uint64_t key;
  TetMesh mesh;
  SurfaceWallStats stats;
};
std::pair<std::mutex, std::deque<Kept>>& kept_walls() {
  static std::pair<std::mutex, std::deque<Kept>> walls;
  return walls;
}

/// A digest of everything a wall is built from (FNV-1a over the bytes).
std::uint64_t digest(const vessels::LumenSurface& lumen, const vessels::Network& net, const SurfaceWall& wall) {
  std::uint64_t h = 1469598103934665603ULL;
  auto mix = [&h](const void* data, size_t bytes) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (size_t k = 0; k < bytes; ++k) h = (h ^ b[k]) * 1099511628211ULL;
  };
  mix(lumen.vertices().data(), lumen.vertices().size() * sizeof(Vec3));
  mix(lumen.triangles().data(), lumen.triangles().size() * sizeof(std::array<int, 3>));
  for (int k = 0; k < net.num_nodes(); ++k) mix(net.node(k).data(), sizeof(Vec3));
  for (int k = 0; k < net.num_segments(); ++k) {
    const auto& s = net.segment(k);
    mix(&s.node_from, sizeof(int));
    mix(&s.node_to, sizeof(int));
    mix(&s.radius, sizeof(double));
    mix(&s.branch, sizeof(int));
  }
  for (double v : {wall.thickness, wall.thickness_ratio, wall.mesh_size, wall.size_per_thickness})
    mix(&v, sizeof(double));
  for (const BranchThickness& b : wall.branches) {
    mix(&b.branch, sizeof(int));
    mix(&b.thickness, sizeof(double));
    mix(&b.ratio, sizeof(double));
  }
  return h;
}
}  // namespace

TetMesh mesh_surface_wall(const vessels::LumenSurface& lumen, const vessels::Network& net, const SurfaceWall& wall,
                          SurfaceWallStats* stats) {
  // gmsh's reparametrization of an image's surface does not give the same mesh twice in one
  // process (its partitions of the surface differ from one build to the next), so a study or a
  // fit that runs the same scene again would see another wall each time: the last few walls
  // are kept and given again for the same surface, network and sizes.
  auto& [lock, kept] = kept_walls();
  const std::uint64_t key = digest(lumen, net, wall);
  {
    const std::lock_guard<std::mutex> guard(lock);
    for (const Kept& k : kept)
      if (k.key == key) {
        if (stats) *stats = k.stats;
        TetMesh m = k.mesh;
        m.mesh_seconds = 0.0;
        return m;
      }
  }
  SurfaceWallStats built;
  TetMesh m = mesh::guarded(lumen.source(), [&] { return mesh_wall(lumen, net, wall, &built); });
  if (stats) *stats = built;
  const std::lock_guard<std::mutex> guard(lock);
  kept.push_back({key, m, built});
  if (kept.size() > 4) kept.pop_front();
  return m;
}

void forget_kept_walls() {
  auto& [lock, kept] = kept_walls();
  const std::lock_guard<std::mutex> guard(lock);
  kept.clear();
}

}  // namespace flowire::solid
