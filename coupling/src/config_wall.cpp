// The scene's wall: section: the vessel wall as an elastic solid the wire deforms; its keys,
// their checks, and the wall they build (deformable_wall.hpp; built with gmsh).
#include <fmt/format.h>

#include <cmath>

#include "flowire/common/error.hpp"
#include "flowire/common/units.hpp"
#include "scene_sections.hpp"
#ifdef FLOWIRE_HAVE_SOLID
#include "flowire/coupling/deformable_wall.hpp"
#endif

namespace flowire::coupling {

void declare_wall_keys(config::Schema& s) {
  using config::Type;
  using D = units::Dimension;
  s.add("wall", Type::Section, "", D::None,
        "the vessel wall as an elastic solid that the wire pushes and that pushes back (neo-Hookean, meshed with "
        "gmsh, ends held; linear about its rest state, its compliance condensed onto the wire's contacts; this "
        "version: a network of one straight vessel of one radius; not with a catheter)");
  s.add("wall.thickness", Type::Number, "", D::Length, "wall thickness (default: thickness_ratio × radius)").positive();
  s.add("wall.thickness_ratio", Type::Number, "0.15", D::None, "wall thickness as a fraction of the lumen radius")
      .positive();
  s.add("wall.youngs_modulus", Type::Number, "1 MPa", D::Pressure,
        "Young's modulus of the wall (arteries: about 0.3-3 MPa)")
      .positive();
  s.add("wall.poisson_ratio", Type::Number, "0.45", D::None,
        "Poisson's ratio, below 0.5 (the law is compressible; arterial tissue is nearly incompressible)");
  s.add("wall.support", Type::Number, "0 Pa/m", D::SupportStiffness,
        "elastic support of the wall's outer surface by the surrounding tissue: traction per displacement")
      .non_negative();
  s.add("wall.mesh_size", Type::Number, "", D::Length, "target tetrahedron size (default: twice the thickness)")
      .positive();
}

std::unique_ptr<CompliantWall> make_scene_wall(const config::Config& c, const vessels::Network& net,
                                               nlohmann::json& facts) {
  if (!c.has_section("wall")) return nullptr;
  if (c.has_section("catheter"))
    throw_input_error(c.where("wall"), "a deformable wall is not yet available with a catheter");
  const double nu = c.number("wall.poisson_ratio");
  if (!(nu > -1.0 && nu < 0.5))
    throw_input_error(c.where("wall.poisson_ratio"),
                      fmt::format("must lie in (-1, 0.5) for the compressible law, got {}", nu));
  // One straight vessel of one radius.
  if (net.num_branches() != 1)
    throw_input_error(c.where("wall"), fmt::format("this version builds the wall of one straight vessel; the network "
                                                   "has {} branches",
                                                   net.num_branches()));
  const auto& br = net.branch(0);
  const Vec3 p0 = net.node(br.nodes.front()), p1 = net.node(br.nodes.back());
  const double radius = net.segment(br.segments.front()).radius;
  for (size_t k = 0; k < br.segments.size(); ++k) {
    const auto& seg = net.segment(br.segments[k]);
    const Vec3 mid = 0.5 * (net.node(seg.node_from) + net.node(seg.node_to));
    const Vec3 axis = (p1 - p0).normalized();
    const double off = (mid - p0 - (mid - p0).dot(axis) * axis).norm();
    if (std::abs(seg.radius - radius) > 1e-6 * radius || off > 1e-3 * radius)
      throw_input_error(c.where("wall"), fmt::format("this version builds the wall of one straight vessel of one "
                                                     "radius; segment {} bends away or changes radius",
                                                     br.segments[k]));
  }
  const double thickness =
      c.has("wall.thickness") ? c.number("wall.thickness") : c.number("wall.thickness_ratio") * radius;
  const double mesh_size = c.has("wall.mesh_size") ? c.number("wall.mesh_size") : 2.0 * thickness;
#ifdef FLOWIRE_HAVE_SOLID
  WallSpec spec{thickness, c.number("wall.youngs_modulus"), nu, c.number("wall.support"), mesh_size};
  auto wall = std::make_unique<DeformableWall>(p0, p1, radius, spec);
  facts["wall"] = {{"thickness", thickness},
                   {"youngs_modulus", spec.youngs_modulus},
                   {"poisson_ratio", nu},
                   {"support", spec.support},
                   {"mesh_size", mesh_size},
                   {"nodes", wall->mesh().num_nodes()},
                   {"tets", wall->mesh().num_tets()},
                   {"mesh_seconds", wall->mesh_seconds()}};
  return wall;
#else
  (void)facts;
  (void)mesh_size;
  throw_input_error(c.where("wall"), "this build has no gmsh (FLOWIRE_WITH_FEM off): a deformable wall needs it");
#endif
}

}  // namespace flowire::coupling
