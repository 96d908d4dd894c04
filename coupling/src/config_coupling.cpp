// The scene's obstacles: and coupling: sections: their keys, the blood drag, the tip forces
// (obstacles, steering) and how the wire and the flow are coupled; with contact: they make
// the forces of the walls and the blood on a rod. A wire in vessels is coupled without a
// coupling: section: then the declared defaults apply.
#include <fmt/format.h>

#include <numbers>
#include <string>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/coupling/tip_forces.hpp"
#include "flowire/flow/solver.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {

void declare_obstacle_keys(config::Schema& s) {
  using config::Type;
  using D = units::Dimension;
  s.add("obstacles", Type::List, "", D::None, "regions that resist the tip (a clot, a tight lesion)");
  s.add("obstacles[].center", Type::Vector3, "", D::Length, "centre of the spherical region");
  s.add("obstacles[].radius", Type::Number, "", D::Length, "radius of the region").positive();
  s.add("obstacles[].force", Type::Number, "", D::Force, "resistance opposing the tip's advance while it is inside")
      .non_negative();
}

void declare_coupling_keys(config::Schema& s) {
  using config::Type;
  using D = units::Dimension;
  s.add("coupling", Type::Section, "", D::None, "how blood acts on the wire");
  s.add("coupling.drag", Type::Enum, "cylinder", D::None,
        "cylinder: cross-flow drag from the cylinder drag curve C_D(Re) (creeping flow to Re 2e5) and the exact "
        "annular Poiseuille shear along the wire | slender_body: resistive-force (Stokes) drag, Re << 1 only | "
        "velocity_offset: the published form (blood velocity added to the velocity update) | none",
        {"cylinder", "slender_body", "velocity_offset", "none"});
  s.add("coupling.drag_scale", Type::Number, "1", D::None, "multiplies the drag force (0: no drag)").non_negative();
  s.add("coupling.drag_update", Type::Enum, "step", D::None,
        "step: the drag law is evaluated once a step, at Newton's initial guess, and taken into the step linearized in "
        "the wire velocity (linearly implicit; docs/blood-drag.md) | iterate: evaluated again at every Newton iterate "
        "(fully implicit)",
        {"step", "iterate"});
  s.add("coupling.occlusion", Type::Enum, "annulus", D::None,
        "annulus: the wire raises the resistance of the segments it lies in (concentric to eccentric annular "
        "Poiseuille flow at its offset; updated every flow evaluation; needs flow.solver superposition, sparse or "
        "flow.model rlc) | none: the flow ignores the wire",
        {"annulus", "none"});
  s.add("coupling.flow_every", Type::Integer, "1", D::None, "evaluate the flow every this many rod steps").at_least(1);
  s.add("coupling.steering", Type::Section, "", D::None, "a lateral force on the tip towards a chosen branch");
  s.add("coupling.steering.branch", Type::String, "", D::None, "name of the branch to steer into");
  s.add("coupling.steering.force", Type::Number, "5 mN", D::Force, "steering force").non_negative();
  s.add("coupling.steering.range", Type::Number, "2 cm", D::Length, "active while the tip is this close to the target")
      .positive();
  s.add("coupling.steering.offset", Type::Number, "1 cm", D::Length, "target: this far along the branch from its start")
      .non_negative();
}

DragModel drag_model(const config::Config& scene, const rod::WireSpec& spec, bool has_flow) {
  const config::Config& c = given_or_declared(scene, "coupling");
  const config::Config& blood = given_or_declared(scene, "flow");
  DragModel dp;
  const std::string& law = c.string("coupling.drag");
  dp.law = !has_flow || law == "none" ? DragLaw::None
           : law == "velocity_offset" ? DragLaw::VelocityOffset
           : law == "slender_body"    ? DragLaw::SlenderBody
                                      : DragLaw::Cylinder;
  dp.scale = c.number("coupling.drag_scale");
  dp.once_per_step = c.string("coupling.drag_update") == "step";
  dp.viscosity = blood.number("flow.viscosity");
  dp.density = blood.number("flow.density");
  dp.wire_radius = spec.radius;
  dp.wire_length = spec.length;
  dp.mass_per_length = spec.density * std::numbers::pi * spec.radius * spec.radius;
  return dp;
}

std::shared_ptr<VesselForces> make_vessel_forces(const config::Config& c, const vessels::SpatialIndex& index,
                                                 const rod::WireSpec& spec, flow::FlowSolver* flow) {
  ContactParams cp = contact_settings(c).params;
  cp.tip_length = spec.tip.length;  // the wire's tip (wire.tip.length); a catheter has none
  const DragModel dp = drag_model(c, spec, flow != nullptr);
  if (!cp.enabled && dp.law == DragLaw::None) return nullptr;
  VelocityField vf;
  if (flow) vf = [flow](int seg_id, const vessels::Vec3& p) { return flow->velocity_at(seg_id, p); };
  // The radius per vertex comes from the rod; the largest sizes the surface neighbourhoods.
  return std::make_shared<VesselForces>(index, std::max(spec.radius, spec.tip.radius), cp, dp, vf);
}

std::shared_ptr<TipForces> make_tip_forces(const config::Config& c, const vessels::Network* net) {
  std::vector<Obstacle> obstacles;
  for (int i = 0; i < c.count("obstacles"); ++i) {
    const std::string p = fmt::format("obstacles[{}].", i);
    for (const char* k : {"center", "radius", "force"})
      if (!c.has(p + k)) throw_input_error(c.where(p.substr(0, p.size() - 1)), fmt::format("an obstacle needs {}", k));
    obstacles.push_back({c.vector3(p + "center"), c.number(p + "radius"), c.number(p + "force")});
  }
  Steering steer;
  if (c.has_section("coupling.steering")) {
    if (!net) throw_input_error(c.where("coupling.steering"), "steering needs a vessels: section");
    if (!c.has("coupling.steering.branch")) throw_input_error(c.where("coupling.steering"), "steering needs branch");
    const auto& name = c.string("coupling.steering.branch");
    const int found = net->branch_named(name);
    if (found < 0)
      throw_input_error(c.where("coupling.steering.branch"),
                        fmt::format("no branch '{}' (branches: {})", name, net->branch_names()));
    const vessels::Branch* target = &net->branch(found);
    // The point `offset` along the branch from its first node.
    double left = c.number("coupling.steering.offset");
    vessels::Vec3 p = net->node(target->nodes.front());
    for (size_t k = 0; k + 1 < target->nodes.size() && left > 0; ++k) {
      const vessels::Vec3 a = net->node(target->nodes[k]), b = net->node(target->nodes[k + 1]);
      const double len = (b - a).norm();
      p = left >= len ? b : vessels::Vec3(a + (left / len) * (b - a));
      left -= len;
    }
    steer = {true, p, c.number("coupling.steering.force"), c.number("coupling.steering.range")};
  }
  if (obstacles.empty() && !steer.enabled) return nullptr;
  return std::make_shared<TipForces>(std::move(obstacles), steer);
}

CouplingSettings coupling_settings(const config::Config& scene) {
  const config::Config& c = given_or_declared(scene, "coupling");
  CouplingSettings k;
  k.occlusion = c.string("coupling.occlusion") == "annulus";
  // Given by the scene (or --set), not filled in from the declared default: only a requested
  // annulus is an error where the flow solver cannot take it; the default quietly falls back.
  k.occlusion_given = scene.given("coupling.occlusion");
  k.flow_every = c.integer("coupling.flow_every");  // at least 1, declared
  return k;
}

}  // namespace flowire::coupling
