// The scene's wall: section: the vessel wall as an elastic solid the wire deforms; its keys,
// their checks, and the wall they build (deformable_wall.hpp; built with gmsh).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

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
        "gmsh around the lumen the wire's contact sees: vessels.surface where given, else the network's tubes; "
        "every end held; linear about its rest state, its compliance condensed onto the contacts of the wire and "
        "of the catheter)");
  s.add("wall.thickness", Type::Number, "", D::Length, "wall thickness (default: thickness_ratio × radius)").positive();
  s.add("wall.thickness_ratio", Type::Number, "0.15", D::None, "wall thickness as a fraction of the lumen radius")
      .positive();
  s.add("wall.youngs_modulus", Type::Number, "1 MPa", D::Pressure,
        "Young's modulus of the wall (arteries: about 0.3-3 MPa)")
      .positive();
  s.add("wall.poisson_ratio", Type::Number, "0.45", D::None,
        "Poisson's ratio, below 0.5 (the law is compressible; arterial tissue is nearly incompressible)");
  s.add("wall.support_stiffness", Type::Number, "0 Pa/m", D::SupportStiffness,
        "elastic support of the wall's outer surface by the surrounding tissue: traction per displacement")
      .non_negative();
  s.add("wall.density", Type::Number, "1100 kg/m^3", D::Density,
        "wall density: the method is quasi-static (the wall's inertia is left out); the density gives the period "
        "of the wall's breathing mode, reported in summary.json beside the step, which should be well above it")
      .positive();
  s.add("wall.model", Type::Enum, "neo_hookean", D::None,
        "the wall's law: neo_hookean (compressible; the contact condenses it linearized about rest)", {"neo_hookean"});
  s.add("wall.blood_pressure", Type::Bool, "false", D::None,
        "the flow's blood pressure loads the wall's lumen (a dead load, less wall.reference_pressure; the wall is "
        "linear about rest, so it inflates by K^-1 f_p and the wire meets it there); needs flow:");
  s.add("wall.flow_radii", Type::Bool, "false", D::None,
        "the flow's segments widen with the wall: each segment's radius r becomes r + its lumen's mean radial "
        "displacement (the blood pressure's and the wire's), its resistance (r/(r+u))^4 of Poiseuille's; the wall "
        "of the last step, as the occlusion; needs flow.solver superposition or sparse, not flow.model rlc (whose "
        "compliance widens its segments already)");
  s.add("wall.relinearize", Type::Number, "1", D::None,
        "the wall is linear about a state: rest at first, then, once a point the wire presses has moved this "
        "fraction of the wall's local thickness from that state, the neo-Hookean wall solved under its loads "
        "(Newton) and linearized there (large displacements: a stiff wire straightening a vessel); 0: linear "
        "about rest throughout")
      .non_negative();
  s.add("wall.reference_pressure", Type::Number, "0 Pa", D::Pressure,
        "the pressure at which the rest geometry was taken (imaged): the wall is loaded by the blood pressure less "
        "this");
  s.add("wall.*", Type::Section, "", D::None,
        "a branch's wall, by the branch's name, where it differs from the rest (each tetrahedron takes the branch "
        "of the segment nearest it)");
  s.add("wall.*.youngs_modulus", Type::Number, "", D::Pressure,
        "this branch: the wall's Young's modulus (default: the flow's wall of this branch, flow.wall.<branch> or an "
        "openBF model's E, where the scene has one; else wall.youngs_modulus)")
      .positive();
  s.add("wall.*.thickness", Type::Number, "", D::Length,
        "this branch: the wall's thickness (default: the flow's wall of this branch, flow.wall.<branch> or an openBF "
        "model's h0, where the scene has one; else the wall section's)")
      .positive();
  s.add("wall.*.thickness_ratio", Type::Number, "", D::None,
        "this branch: the wall's thickness as a fraction of the lumen radius, where it has no thickness")
      .positive();
  s.add("wall.mesh_size", Type::Number, "", D::Length,
        "target tetrahedron size (default: twice the thinnest wall; around vessels.surface, twice the local "
        "thickness)")
      .positive();
}

#ifdef FLOWIRE_HAVE_SOLID
namespace {
/// The period [s] of the wall's lowest breathing mode, a ring of the widest radius R and thickness
/// t held by its hoop stiffness and the tissue's support: ω² = (E/R² + k/t)/ρ (plane stress).
double breathing_period(const vessels::Network& net, const WallSpec& spec, double density) {
  double radius = 0.0;
  int branch = -1;
  for (int k = 0; k < net.num_segments(); ++k)
    if (net.segment(k).radius > radius) radius = net.segment(k).radius, branch = net.segment(k).branch;
  const double t = spec.thickness_at(branch, radius);
  double modulus = spec.youngs_modulus;
  for (const auto& [b, e] : spec.branch_youngs_modulus)
    if (b == branch) modulus = e;
  const double omega2 = (modulus / (radius * radius) + spec.support / t) / density;
  return 2.0 * std::acos(-1.0) / std::sqrt(omega2);
}
}  // namespace
#endif

std::unique_ptr<CompliantWall> make_scene_wall(const config::Config& c, const vessels::Network& net,
                                               const vessels::LumenSurface* surface, nlohmann::json& facts,
                                               std::span<const flow::BranchWall> flow_walls) {
  if (!c.has_section("wall")) return nullptr;
  const double nu = c.number("wall.poisson_ratio");
  if (!(nu > -1.0 && nu < 0.5))
    throw_input_error(c.where("wall.poisson_ratio"),
                      fmt::format("must lie in (-1, 0.5) for the compressible law, got {}", nu));
  const double thickness = c.has("wall.thickness") ? c.number("wall.thickness") : 0.0;
  const double ratio = c.number("wall.thickness_ratio");
#ifdef FLOWIRE_HAVE_SOLID
  WallSpec spec{thickness,
                thickness > 0.0 ? 0.0 : ratio,
                c.number("wall.youngs_modulus"),
                nu,
                c.number("wall.support_stiffness"),
                0.0,
                {},
                {}};
  // Branches with a wall of their own: wall.<branch>, else the flow's wall of that branch.
  nlohmann::json branch_moduli = nlohmann::json::object(), branch_thickness = nlohmann::json::object();
  std::vector<int> named;
  for (const auto& [path, value] : c.values()) {
    if (value.type != config::Type::Section || path.rfind("wall.", 0) != 0) continue;
    const std::string name = path.substr(std::string("wall.").size());
    if (name.find('.') != std::string::npos) continue;
    const int branch = net.branch_named(name);
    if (branch < 0)
      throw_input_error(c.where(path), fmt::format("no branch named '{}' (branches: {})", name, net.branch_names()));
    named.push_back(branch);
    const flow::BranchWall* fw = nullptr;
    for (const auto& w : flow_walls)
      if (w.branch == branch) fw = &w;
    if (c.has(path + ".youngs_modulus") || (fw && fw->youngs_modulus > 0.0))
      spec.branch_youngs_modulus.emplace_back(
          branch, c.has(path + ".youngs_modulus") ? c.number(path + ".youngs_modulus") : fw->youngs_modulus);
    if (c.has(path + ".thickness") || c.has(path + ".thickness_ratio"))
      spec.branch_thickness.push_back({branch, c.has(path + ".thickness") ? c.number(path + ".thickness") : 0.0,
                                       c.has(path + ".thickness_ratio") ? c.number(path + ".thickness_ratio") : 0.0});
    else if (fw && (fw->thickness > 0.0 || fw->thickness_ratio > 0.0))
      spec.branch_thickness.push_back({branch, fw->thickness, fw->thickness_ratio});
  }
  for (const auto& w : flow_walls) {  // the flow's branch walls the wall section does not name
    if (w.branch < 0 || std::find(named.begin(), named.end(), w.branch) != named.end()) continue;
    if (w.youngs_modulus > 0.0) spec.branch_youngs_modulus.emplace_back(w.branch, w.youngs_modulus);
    if (w.thickness > 0.0 || w.thickness_ratio > 0.0)
      spec.branch_thickness.push_back({w.branch, w.thickness, w.thickness_ratio});
  }
  for (const auto& [branch, modulus] : spec.branch_youngs_modulus) branch_moduli[net.branch(branch).name] = modulus;
  for (const auto& b : spec.branch_thickness)
    branch_thickness[net.branch(b.branch).name] =
        b.thickness > 0.0 ? nlohmann::json{{"thickness", b.thickness}} : nlohmann::json{{"thickness_ratio", b.ratio}};
  // Around a surface, without a size: twice the local thickness (the aorta's and a branch's differ);
  // around the network's tubes, twice the thinnest wall.
  double thinnest = std::numeric_limits<double>::infinity();
  for (int k = 0; k < net.num_segments(); ++k)
    thinnest = std::min(thinnest, spec.thickness_at(net.segment(k).branch, net.segment(k).radius));
  const double mesh_size = c.has("wall.mesh_size") ? c.number("wall.mesh_size") : surface ? 0.0 : 2.0 * thinnest;
  spec.mesh_size = mesh_size;
  spec.relinearize = c.number("wall.relinearize");
  auto wall = std::make_unique<DeformableWall>(net, spec, surface);
  facts["wall"] = {{"thickness", thickness > 0.0 ? nlohmann::json(thickness) : nlohmann::json(nullptr)},
                   {"thickness_ratio", thickness > 0.0 ? nlohmann::json(nullptr) : nlohmann::json(ratio)},
                   {"thinnest", wall->thinnest()},
                   {"youngs_modulus", spec.youngs_modulus},
                   {"branch_youngs_modulus", branch_moduli},
                   {"branch_thickness", branch_thickness},
                   {"poisson_ratio", nu},
                   {"support_stiffness", spec.support},
                   {"density", c.number("wall.density")},
                   {"model", c.string("wall.model")},
                   {"breathing_period", breathing_period(net, spec, c.number("wall.density"))},
                   {"mesh_size", mesh_size > 0.0 ? nlohmann::json(mesh_size) : nlohmann::json("2 x local thickness")},
                   {"nodes", wall->mesh().num_nodes()},
                   {"tets", wall->mesh().num_tets()},
                   {"mesh_seconds", wall->mesh_seconds()}};
  return wall;
#else
  (void)facts;
  (void)surface;
  (void)flow_walls;
  (void)thickness;
  (void)ratio;
  (void)net;
  throw_input_error(c.where("wall"), "this build has no gmsh (FLOWIRE_WITH_FEM off): a deformable wall needs it");
#endif
}

}  // namespace flowire::coupling
