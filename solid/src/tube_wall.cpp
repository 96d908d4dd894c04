// The wall of a straight tube meshed with gmsh's OpenCASCADE kernel: a cylinder minus the
// lumen's cylinder (and for a quarter, intersected with the first quadrant's box); each face
// named by where a point of it lies.
#include "flowire/solid/tube_wall.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/mesh/extract.hpp"
#include "flowire/mesh/gmsh_session.hpp"
#include "flowire/mesh/network_solids.hpp"

namespace flowire::solid {
namespace {

using mesh::BoundaryGroup;
using mesh::TetMesh;
using vessels::Vec3;

void check(const TubeWall& t) {
  if (!(t.inner_radius > 0.0) || !(t.outer_radius > t.inner_radius))
    throw_usage_error(
        fmt::format("tube wall: need 0 < inner_radius < outer_radius, got {} and {}", t.inner_radius, t.outer_radius));
  if (!(t.length > 0.0)) throw_usage_error(fmt::format("tube wall: length must be > 0, got {}", t.length));
  if (!(t.mesh_size > 0.0)) throw_usage_error(fmt::format("tube wall: mesh_size must be > 0, got {}", t.mesh_size));
  if (!(t.refine_size >= 0.0 && t.refine_size <= t.mesh_size))
    throw_usage_error(fmt::format("tube wall: refine_size must lie in [0, mesh_size], got {}", t.refine_size));
}

TetMesh mesh_tube(const TubeWall& t) {
  const auto start = std::chrono::steady_clock::now();
  TetMesh m;
  const std::vector<std::string> names = {"lumen", "outer", "end_0", "end_1", "symmetry_x", "symmetry_y"};
  const size_t num_groups = t.quarter ? 6 : 4;
  for (size_t g = 0; g < num_groups; ++g) m.groups.push_back({BoundaryGroup::Kind::Wall, -1, names[g]});

  mesh::GmshModel model(false);
  namespace occ = gmsh::model::occ;
  const int outer = occ::addCylinder(0, 0, 0, 0, 0, t.length, t.outer_radius);
  const int inner = occ::addCylinder(0, 0, 0, 0, 0, t.length, t.inner_radius);
  gmsh::vectorpair out;
  std::vector<gmsh::vectorpair> map;
  occ::cut({{3, outer}}, {{3, inner}}, out, map);
  if (t.quarter) {
    const double r = 2.0 * t.outer_radius;
    const int box = occ::addBox(0, 0, 0, r, r, t.length);
    gmsh::vectorpair quarter;
    occ::intersect(out, {{3, box}}, quarter, map);
  }
  occ::synchronize();
  gmsh::vectorpair vols, surfs;
  gmsh::model::getEntities(vols, 3);
  gmsh::model::getEntities(surfs, 2);
  if (vols.size() != 1) throw_numerical_error(fmt::format("tube wall: {} volumes, expected one", vols.size()));
  const double tol = 1e-5 * t.outer_radius;
  std::vector<int> surf_group(surfs.size(), -1);
  for (size_t k = 0; k < surfs.size(); ++k) {
    std::vector<double> lo, hi, xyz;
    gmsh::model::getParametrizationBounds(2, surfs[k].second, lo, hi);
    gmsh::model::getValue(2, surfs[k].second, {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])}, xyz);
    const Vec3 x(xyz[0], xyz[1], xyz[2]);
    std::vector<double> normal;
    gmsh::model::getNormal(surfs[k].second, {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])}, normal);
    const Vec3 nrm(normal[0], normal[1], normal[2]);
    const double r = std::hypot(x.x(), x.y());
    int g = -1;
    if (std::abs(nrm.z()) > 0.999) {
      g = std::abs(x.z()) < tol ? 2 : 3;
    } else if (t.quarter && std::abs(nrm.x()) > 0.999 && std::abs(x.x()) < tol) {
      g = 4;
    } else if (t.quarter && std::abs(nrm.y()) > 0.999 && std::abs(x.y()) < tol) {
      g = 5;
    } else if (std::abs(r - t.inner_radius) < tol) {
      g = 0;
    } else if (std::abs(r - t.outer_radius) < tol) {
      g = 1;
    }
    if (g < 0) throw_numerical_error("tube wall: a face of the meshed wall lies on none of its surfaces");
    surf_group[k] = g;
  }
  mesh::tag_groups_and_set_options(vols[0].second, "wall", m.groups, surfs, surf_group, 1);
  if (t.refine_size > 0.0) {
    const Vec3& c = t.refine_at;
    const int field = gmsh::model::mesh::field::add("MathEval");
    gmsh::model::mesh::field::setString(
        field, "F",
        // (below refine_size within refine_radius: Mesh.MeshSizeMin holds it there)
        fmt::format("{:.17g} + 0.5 * (Sqrt((x - {:.17g})^2 + (y - {:.17g})^2 + (z - {:.17g})^2) - {:.17g})",
                    t.refine_size, c.x(), c.y(), c.z(), t.refine_radius));
    gmsh::model::mesh::field::setAsBackgroundMesh(field);
    gmsh::option::setNumber("Mesh.MeshSizeMin", t.refine_size);
  } else {
    gmsh::option::setNumber("Mesh.MeshSizeMin", t.mesh_size);
  }
  gmsh::option::setNumber("Mesh.MeshSizeMax", t.mesh_size);
  mesh::generate(mesh::MeshOptions{});
  mesh::extract_mesh(m, surfs, surf_group, "tube wall");
  m.mesh_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return m;
}

/// One branch of one radius that bends: an annulus swept along the spline through its nodes
/// (a union of capsules along a finely sampled curve has faces meeting at glancing angles,
/// which OpenCASCADE's booleans do not survive). The lumen then departs from the capsules the
/// wire's contact sees by the chords' sagitta, ℓ²/8R for segments ℓ on a bend of radius R.
bool sweepable(const vessels::Network& net, const mesh::NetworkSolids& solids) {
  if (net.num_branches() != 1 || solids.pieces.size() < 2) return false;
  for (const auto& p : solids.pieces)
    if (std::abs(p.radius - solids.pieces.front().radius) > 1e-9 * p.radius) return false;
  return true;
}

void add_swept_annulus(const vessels::Network& net, double inner, double outer) {
  namespace occ = gmsh::model::occ;
  const auto& br = net.branch(0);
  // The spline through nodes about a radius apart (and the last): a finely sampled centerline
  // makes a surface of as many patches, slow to mesh, and the curve between such nodes departs
  // from the finer polyline by far less than the sagitta of its own segments.
  std::vector<int> points;
  Vec3 last = net.node(br.nodes.front());
  points.push_back(occ::addPoint(last.x(), last.y(), last.z()));
  for (size_t k = 1; k < br.nodes.size(); ++k) {
    const Vec3& x = net.node(br.nodes[k]);
    if (k + 1 < br.nodes.size() && (x - last).norm() < inner) continue;
    points.push_back(occ::addPoint(x.x(), x.y(), x.z()));
    last = x;
  }
  const int path = occ::addWire({occ::addSpline(points)});
  // The annulus in the plane z = 0 about the origin, turned to face the first segment and moved
  // to the first node.
  const int disk = occ::addDisk(0, 0, 0, outer, outer);
  const int hole = occ::addDisk(0, 0, 0, inner, inner);
  gmsh::vectorpair annulus;
  std::vector<gmsh::vectorpair> map;
  occ::cut({{2, disk}}, {{2, hole}}, annulus, map);
  const Vec3 x0 = net.node(br.nodes[0]);
  const Vec3 t = (net.node(br.nodes[1]) - x0).normalized();
  const Vec3 axis = Vec3::UnitZ().cross(t);
  const double angle = std::atan2(axis.norm(), Vec3::UnitZ().dot(t));
  if (axis.norm() > 1e-12) {
    const Vec3 a = axis.normalized();
    occ::rotate(annulus, 0, 0, 0, a.x(), a.y(), a.z(), angle);
  } else if (t.z() < 0.0) {
    occ::rotate(annulus, 0, 0, 0, 1, 0, 0, std::acos(-1.0));
  }
  occ::translate(annulus, x0.x(), x0.y(), x0.z());
  gmsh::vectorpair swept;
  occ::addPipe(annulus, path, swept);
  occ::remove(annulus, true);
  occ::remove({{1, path}}, true);
}

TetMesh mesh_network(const vessels::Network& net, const NetworkWall& w, const mesh::NetworkSolids& solids,
                     const std::string& at) {
  const bool swept = sweepable(net, solids);
  const auto start = std::chrono::steady_clock::now();
  const mesh::GrownRadius grown = [&](double r, int branch) {
    return r + wall_thickness_at(w.thickness, w.thickness_ratio, w.branches, branch, r);
  };
  const mesh::GrownRadius same = [](double r, int) { return r; };
  const std::vector<int> ends = net.ends();
  TetMesh m;
  m.groups.push_back({BoundaryGroup::Kind::Wall, -1, "lumen"});
  m.groups.push_back({BoundaryGroup::Kind::Wall, -1, "outer"});
  for (int e : ends) m.groups.push_back({BoundaryGroup::Kind::Wall, e, fmt::format("end_{}", e)});

  mesh::GmshModel model(false);
  namespace occ = gmsh::model::occ;
  if (swept) {
    const auto& front = solids.pieces.front();
    add_swept_annulus(net, same(front.radius, front.branch), grown(front.radius, front.branch));
  } else {
    const gmsh::vectorpair outer = mesh::add_network_solids(net, solids, grown);
    const gmsh::vectorpair inner = mesh::add_network_solids(net, solids, same);
    gmsh::vectorpair out;
    std::vector<gmsh::vectorpair> map;
    occ::cut(outer, inner, out, map);
  }
  occ::synchronize();
  gmsh::vectorpair vols, surfs;
  gmsh::model::getEntities(vols, 3);
  gmsh::model::getEntities(surfs, 2);
  if (vols.size() != 1)
    throw_input_error(at,
                      fmt::format("the wall is {} separate volumes, not one; is the network connected?", vols.size()));
  // Each face by where a point of its surface lies: on an end's plane (an annulus about the end
  // node), on one of the lumen's cylinders or spheres, or on one of the outer ones.
  double rmin = std::numeric_limits<double>::infinity();
  for (const auto& p : solids.pieces) rmin = std::min(rmin, grown(p.radius, p.branch) - p.radius);
  const double tol = 0.25 * rmin;
  std::vector<int> surf_group(surfs.size(), -1);
  for (size_t k = 0; k < surfs.size(); ++k) {
    std::string type;
    gmsh::model::getType(2, surfs[k].second, type);
    double cx = 0, cy = 0, cz = 0;
    occ::getCenterOfMass(2, surfs[k].second, cx, cy, cz);
    if (type == "Plane") {
      for (size_t e = 0; e < ends.size(); ++e)
        if ((Vec3(cx, cy, cz) - net.node(ends[e])).norm() <= 1e-3 * rmin) surf_group[k] = 2 + static_cast<int>(e);
      if (surf_group[k] >= 0) continue;
    }
    std::vector<double> lo, hi, xyz;
    gmsh::model::getParametrizationBounds(2, surfs[k].second, lo, hi);
    gmsh::model::getValue(2, surfs[k].second, {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])}, xyz);
    const Vec3 x(xyz[0], xyz[1], xyz[2]);
    if (mesh::distance_to_network_solid_surfaces(net, solids, x, same) < tol) {
      surf_group[k] = 0;
    } else if (mesh::distance_to_network_solid_surfaces(net, solids, x, grown) < tol) {
      surf_group[k] = 1;
    } else if (type == "Plane") {
      // A step between collinear pieces (a radius or a branch's thickness changes), an annulus
      // whose parametric middle may lie in its hole: by a point of its rim, which lies on the
      // pieces it joins.
      gmsh::vectorpair rim;
      gmsh::model::getBoundary({surfs[k]}, rim, false, false, false);
      double rim_lumen = std::numeric_limits<double>::infinity(), rim_outer = rim_lumen;
      if (!rim.empty()) {
        std::vector<double> clo, chi, cxyz;
        gmsh::model::getParametrizationBounds(1, rim.front().second, clo, chi);
        gmsh::model::getValue(1, rim.front().second, {0.5 * (clo[0] + chi[0])}, cxyz);
        const Vec3 y(cxyz[0], cxyz[1], cxyz[2]);
        rim_lumen = mesh::distance_to_network_solid_surfaces(net, solids, y, same);
        rim_outer = mesh::distance_to_network_solid_surfaces(net, solids, y, grown);
      }
      if (std::min(rim_lumen, rim_outer) >= tol)
        throw_numerical_error(fmt::format("{}: a plane face of the meshed wall lies on none of its surfaces", at));
      surf_group[k] = rim_lumen < rim_outer ? 0 : 1;
    } else {
      throw_numerical_error(fmt::format("{}: a face of the meshed wall lies on none of its surfaces", at));
    }
  }
  for (size_t e = 0; e < ends.size(); ++e)
    if (std::find(surf_group.begin(), surf_group.end(), 2 + static_cast<int>(e)) == surf_group.end())
      throw_input_error(at, fmt::format("end node {}: its end face was not found in the wall (a junction's sphere "
                                        "covers it?)",
                                        ends[e]));
  mesh::tag_groups_and_set_options(vols[0].second, "wall", m.groups, surfs, surf_group, 1);
  gmsh::option::setNumber("Mesh.MeshSizeMin", w.mesh_size);
  gmsh::option::setNumber("Mesh.MeshSizeMax", w.mesh_size);
  // gmsh places the mid-edge nodes on a swept surface by projection, slowly (17 s for a wall of
  // 19,000 nodes, against 0.6 s for the rest): they are placed at mid-edge here and moved onto
  // the tube below.
  if (swept) gmsh::option::setNumber("Mesh.SecondOrderLinear", 1);
  mesh::generate(mesh::MeshOptions{});
  mesh::extract_mesh(m, surfs, surf_group, at);
  if (swept) {
    // Every node of the lumen and outer faces onto its tube about the centerline polyline (the
    // capsules the wire's contact sees): radius r for the lumen, grown for the outer surface.
    const auto& br = net.branch(0);
    const double r = solids.pieces.front().radius;
    const int branch = solids.pieces.front().branch;
    for (size_t f = 0; f < m.faces.size(); ++f) {
      if (m.face_group[f] > 1) continue;
      const double target = m.face_group[f] == 0 ? same(r, branch) : grown(r, branch);
      for (int node : m.faces[f]) {
        Vec3& x = m.nodes[static_cast<size_t>(node)];
        Vec3 nearest = x;
        double best = std::numeric_limits<double>::infinity();
        for (size_t k = 0; k + 1 < br.nodes.size(); ++k) {
          const Vec3 a = net.node(br.nodes[k]), d = net.node(br.nodes[k + 1]) - a;
          const Vec3 c = a + std::clamp((x - a).dot(d) / d.squaredNorm(), 0.0, 1.0) * d;
          if ((x - c).norm() < best) best = (x - c).norm(), nearest = c;
        }
        if (best > 0.0) x = nearest + (x - nearest) * (target / best);
      }
    }
  }
  m.mesh_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return m;
}

}  // namespace

mesh::TetMesh mesh_network_wall(const vessels::Network& net, const NetworkWall& wall) {
  const std::string at = net.source().empty() ? std::string("wall") : fmt::format("wall of {}", net.source());
  if (!(wall.mesh_size > 0.0)) throw_usage_error(fmt::format("wall: mesh_size must be > 0, got {}", wall.mesh_size));
  if (!(wall.thickness > 0.0) && !(wall.thickness_ratio > 0.0))
    throw_usage_error("wall: thickness or thickness_ratio must be > 0");
  for (const BranchThickness& b : wall.branches)
    if (b.branch < 0 || b.branch >= net.num_branches() || !(b.thickness > 0.0 || b.ratio > 0.0))
      throw_usage_error(fmt::format("wall: branch {}'s thickness {} m / ratio {} (a branch of {}, one of them > 0)",
                                    b.branch, b.thickness, b.ratio, net.num_branches()));
  const mesh::NetworkSolids solids = mesh::make_network_solids(net, at);
  return mesh::guarded(at, [&] { return mesh_network(net, wall, solids, at); });
}

mesh::TetMesh mesh_tube_wall(const TubeWall& tube) {
  check(tube);
  return mesh::guarded("tube wall", [&] { return mesh_tube(tube); });
}

}  // namespace flowire::solid
