// A fluid domain built in code (an outer box or cylinder minus cylinders) meshed by gmsh:
// the domain's checks, the OpenCASCADE cut, each fluid face given the group of the solid
// face it lies on, and sizes growing with the distance from the holes.
#include "flowire/flow/fem/shape_domain.hpp"

#include <fmt/format.h>
#include <gmsh.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/mesh/extract.hpp"
#include "flowire/mesh/gmsh_session.hpp"
#include "flowire/vessels/spatial.hpp"
#include "mesh_broadcast.hpp"

namespace flowire::flow::fem {
namespace {

using mesh::extract_mesh;
using mesh::generate;
using mesh::GmshModel;
using mesh::tag_groups_and_set_options;

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
  return std::max(0.0, vessels::project_on_axis(x, s.a, s.b).distance - s.radius);
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

TetMesh build_mesh(const ShapeDomain& domain, const MeshOptions& opt) {
  return detail::build_shared([&] { return mesh::guarded(domain.name, [&] { return mesh_domain(domain, opt); }); });
}

}  // namespace flowire::flow::fem
