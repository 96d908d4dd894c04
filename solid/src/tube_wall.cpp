// The wall of a straight tube meshed with gmsh's OpenCASCADE kernel: a cylinder minus the
// lumen's cylinder (and for a quarter, intersected with the first quadrant's box); each face
// named by where a point of it lies.
#include "flowire/solid/tube_wall.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/mesh/extract.hpp"
#include "flowire/mesh/gmsh_session.hpp"

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
  gmsh::option::setNumber("Mesh.MeshSizeMin", t.mesh_size);
  gmsh::option::setNumber("Mesh.MeshSizeMax", t.mesh_size);
  mesh::generate(mesh::MeshOptions{});
  mesh::extract_mesh(m, surfs, surf_group, "tube wall");
  m.mesh_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return m;
}

}  // namespace

mesh::TetMesh mesh_tube_wall(const TubeWall& tube) {
  check(tube);
  return mesh::guarded("tube wall", [&] { return mesh_tube(tube); });
}

}  // namespace flowire::solid
