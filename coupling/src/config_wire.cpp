// The scene's wire: and loads: sections: their keys, the wire they describe, where it
// enters the network, and the loads on it.
#include <fmt/format.h>
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include <exception>
#include <string>

#include "flowire/common/error.hpp"
#include "flowire/coupling/scene.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {

void declare_wire_keys(config::Schema& s) {
  using config::Type;
  using D = units::Dimension;
  s.add("wire", Type::Section, "", D::None, "the guidewire (absent: no rod is simulated)");
  s.add("wire.length", Type::Number, "1.0", D::Length, "total wire length").positive();
  s.add("wire.radius", Type::Number, "0.45 mm", D::Length, "wire radius (0.035 inch wire: 0.445 mm)").positive();
  s.add("wire.youngs_modulus", Type::Number, "60 GPa", D::Pressure, "shaft Young's (flexural) modulus").positive();
  s.add("wire.poisson_ratio", Type::Number, "0.33", D::None, "Poisson ratio (shear modulus G = E / (2 (1 + nu)))")
      .above(-1.0)
      .below(0.5);
  s.add("wire.shear_modulus", Type::Number, "", D::Pressure, "shear modulus (overrides poisson_ratio)").positive();
  s.add("wire.density", Type::Number, "6450", D::Density, "wire density").positive();
  s.add("wire.segments", Type::Integer, "100", D::None, "number of rod segments").at_least(1);
  s.add("wire.segment_length", Type::Number, "", D::Length, "rod segment length (overrides segments)").positive();
  s.add("wire.damping", Type::Number, "0", D::None, "viscous damping (1/s, mass-proportional)").non_negative();
  s.add("wire.tip", Type::Section, "", D::None, "a softer, possibly pre-shaped tip");
  s.add("wire.tip.length", Type::Number, "3 cm", D::Length, "tip length").non_negative();
  s.add("wire.tip.youngs_modulus", Type::Number, "10 GPa", D::Pressure, "tip Young's modulus").positive();
  s.add("wire.tip.radius", Type::Number, "", D::Length,
        "tip radius (default: the shaft's; a tapered tip, e.g. 0.18 mm on a 0.45 mm shaft): the tip's bending and "
        "twisting stiffness, mass, wall contact, blood drag and occlusion all take it")
      .positive();
  s.add("wire.tip.shape", Type::Enum, "straight", D::None, "tip shape", {"straight", "angled", "j"});
  s.add("wire.tip.angle", Type::Number, "", D::Angle,
        "angled/j: total bend angle of the tip (default by shape: 45 deg angled, 180 deg j, the J of the published "
        "experiment)")
      .at_least(0.0)
      .below(2.0 * std::numbers::pi);
  s.add("wire.tip.bend_radius", Type::Number, "3 mm", D::Length, "angled/j: radius of the pre-bent arc").positive();
  s.add("wire.adapt", Type::Section, "", D::None,
        "curvature-adaptive resampling: split edges where the wire bends, merge them back where it is straight");
  s.add("wire.adapt.min_segment_length", Type::Number, "", D::Length,
        "finest edge (default a quarter of the segment length)")
      .positive();
  s.add("wire.adapt.max_segment_length", Type::Number, "", D::Length,
        "coarsest edge (default the segment length: merging only undoes refinement)")
      .positive();
  s.add("wire.adapt.split_angle", Type::Number, "0.1 rad", D::Angle,
        "turning angle at a vertex above which its edges are split")
      .above(0.0)
      .below(1.5);
  s.add("wire.adapt.merge_angle", Type::Number, "", D::Angle,
        "turning angle below which edges merge (default split_angle / 4; below split_angle / 2)")
      .non_negative();
  s.add("wire.base", Type::Section, "", D::None, "where the wire is held");
  s.add("wire.base.position", Type::Vector3, "[0, 0, 0]", D::Length, "base position (vessel scenes: the entry node)");
  s.add("wire.base.direction", Type::Vector3, "[1, 0, 0]", D::None,
        "base direction (vessel scenes: into the entry vessel)");
  s.add("wire.entry", Type::StringOrInteger, "auto", D::None,
        "network end where the wire enters: auto (the end farthest from the flow inlet), a node id, or a branch name "
        "(its end)");
}

void declare_load_keys(config::Schema& s) {
  using config::Type;
  using D = units::Dimension;
  s.add("loads", Type::List, "", D::None, "external loads on the wire");
  s.add("loads[].type", Type::Enum, "", D::None, "load kind", {"tip_force", "tip_moment", "gravity", "point_force"});
  s.add("loads[].value", Type::Vector3, "", D::None, "force (N), moment (N*m) or acceleration (m/s^2), SI");
  s.add("loads[].s", Type::Number, "", D::Length, "point_force: arc length from the base (at most wire.length)")
      .non_negative();
}

rod::WireSpec scene_wire_spec(const config::Config& c) {
  rod::WireSpec w;
  w.length = c.number("wire.length");
  w.radius = c.number("wire.radius");
  w.youngs_modulus = c.number("wire.youngs_modulus");
  w.poisson_ratio = c.number("wire.poisson_ratio");
  if (c.has("wire.shear_modulus")) w.shear_modulus = c.number("wire.shear_modulus");
  w.density = c.number("wire.density");
  if (c.has("wire.segment_length")) {
    w.segments = 0;
    w.segment_length = c.number("wire.segment_length");
  } else {
    w.segments = c.integer("wire.segments");
  }
  // Declared in 1/s, mass-proportional: the rod's mass damping (not its per-length one).
  w.mass_damping = c.number("wire.damping");
  w.tip.length = 0.0;
  if (c.has_section("wire.tip")) {
    w.tip.length = c.number("wire.tip.length");
    w.tip.youngs_modulus = c.number("wire.tip.youngs_modulus");
    w.tip.radius = c.number_or("wire.tip.radius", 0.0);  // 0: the shaft's (rod::TipSpec)
    const auto& shape = c.string("wire.tip.shape");
    w.tip.shape = shape == "j" ? rod::TipShape::J : shape == "angled" ? rod::TipShape::Angled : rod::TipShape::Straight;
    w.tip.angle = c.number_or("wire.tip.angle", -1.0);  // < 0: the shape's own default (rod::TipSpec)
    w.tip.bend_radius = c.number("wire.tip.bend_radius");
  }
  if (c.has_section("wire.adapt")) {
    w.adapt.enabled = true;
    const double h = w.segments > 0 ? w.length / w.segments : w.segment_length;
    if (c.has("wire.adapt.min_segment_length")) {
      w.adapt.min_segment_length = c.number("wire.adapt.min_segment_length");
      if (!(w.adapt.min_segment_length > 0.0 && w.adapt.min_segment_length <= h))
        throw_input_error(c.where("wire.adapt.min_segment_length"),
                          fmt::format("min_segment_length must be in (0, {:g} m] (the segment length)", h));
    }
    if (c.has("wire.adapt.max_segment_length")) {
      w.adapt.max_segment_length = c.number("wire.adapt.max_segment_length");
      if (!(w.adapt.max_segment_length >= h))
        throw_input_error(c.where("wire.adapt.max_segment_length"),
                          fmt::format("max_segment_length must be at least the segment length ({:g} m)", h));
    }
    w.adapt.split_angle = c.number("wire.adapt.split_angle");
    if (c.has("wire.adapt.merge_angle")) {
      w.adapt.merge_angle = c.number("wire.adapt.merge_angle");
      if (!(w.adapt.merge_angle < 0.5 * w.adapt.split_angle))
        throw_input_error(
            c.where("wire.adapt.merge_angle"),
            fmt::format("merge_angle must be below split_angle / 2 ({:g} rad)", 0.5 * w.adapt.split_angle));
    }
  }
  if (c.has_section("wire.base")) {
    w.base_position = c.vector3("wire.base.position");
    w.base_direction = c.vector3("wire.base.direction");
    if (!(w.base_direction.norm() > 0)) throw_input_error(c.where("wire.base.direction"), "direction must be non-zero");
  }
  if (c.has_section("insertion")) w.inserted_length = c.number("insertion.initial_length");
  if (const double n = w.segments > 0 ? w.segments : w.length / w.segment_length; !(n <= rod::kMaxRodSegments)) {
    const char* key = w.segments > 0 ? "wire.segments" : "wire.segment_length";
    throw_input_error(c.where(key), fmt::format("wire.length / segment length = {:.3g} segments; a wire may have at "
                                                "most {:.0e} (a longer segment or a shorter wire)",
                                                n, rod::kMaxRodSegments));
  }
  return w;
}

int enter_network(const config::Config& c, const vessels::Network& net, rod::WireSpec& w) {
  const int inlet = net.widest_end();
  int entry = -1;
  const auto entry_key = c.string("wire.entry");
  if (entry_key == "auto") {
    entry = net.farthest_end(inlet);
  } else {
    size_t used = 0;
    try {
      entry = std::stoi(entry_key, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != entry_key.size()) {
      // A branch name: the end of that branch which is a network end (the one farther from the
      // flow's inlet where both are).
      entry = -1;
      std::string names;
      for (const auto& b : net.branches()) {
        const int first = b.nodes.front(), last = b.nodes.back();
        if (net.degree(first) == 1 || net.degree(last) == 1) names += (names.empty() ? "" : ", ") + b.name;
        if (b.name != entry_key) continue;
        for (int e : {last, first})
          if (entry < 0 && net.degree(e) == 1 && e != inlet) entry = e;
        if (entry < 0 && net.degree(first) == 1) entry = first;
      }
      if (entry < 0)
        throw_input_error(c.where("wire.entry"),
                          fmt::format("'{}' is neither auto, a node id nor a branch with an end (branches with an "
                                      "end: {})",
                                      entry_key, names.empty() ? "none named" : names));
    }
    if (entry < 0 || entry >= net.num_nodes() || net.degree(entry) != 1)
      throw_input_error(c.where("wire.entry"), fmt::format("node {} is not an end of the network", entry));
  }
  const auto& seg = net.segment(*net.node_segments(entry).first);
  const int other = seg.node_from == entry ? seg.node_to : seg.node_from;
  if (!c.has_section("wire.base")) {
    w.base_position = net.node(entry);
    w.base_direction = (net.node(other) - net.node(entry)).normalized();
  } else {
    // A base far from every vessel is a wrong unit or a typo, not a scene: refused before any
    // lookup has to cope with coordinates of 1e15 m.
    Eigen::AlignedBox3d box;
    for (int i = 0; i < net.num_nodes(); ++i) box.extend(net.node(i));
    const double size = box.diagonal().norm();
    if (const double away = box.exteriorDistance(w.base_position); !(away <= size))
      throw_input_error(c.where("wire.base.position"),
                        fmt::format("[{:.6g}, {:.6g}, {:.6g}] m lies outside the vessel network's bounding box by "
                                    "more than the network's own size ({:.3g} m): a wrong unit?",
                                    w.base_position.x(), w.base_position.y(), w.base_position.z(), size));
  }
  if (w.inserted_length < 0)
    w.inserted_length = declared_scene_defaults("insertion").number("insertion.initial_length");
  return entry;
}

void apply_loads(const config::Config& c, rod::RodSimulator& sim, rod::RodSimulator* catheter) {
  for (int i = 0; i < c.count("loads"); ++i) {
    const std::string p = fmt::format("loads[{}].", i);
    if (!c.has(p + "type") || !c.has(p + "value"))
      throw_input_error(c.where(p + "type"), "a load needs type and value");
    const auto& type = c.string(p + "type");
    const Eigen::Vector3d v = c.vector3(p + "value");
    if (type == "tip_force")
      sim.set_tip_force(v);
    else if (type == "tip_moment")
      sim.set_tip_moment(v);
    else if (type == "gravity") {
      sim.set_gravity(v);
      if (catheter) catheter->set_gravity(v);  // gravity acts on the catheter too (the other loads are the wire's)
    } else {
      if (!c.has(p + "s")) throw_input_error(c.where(p + "type"), "point_force needs s (arc length from the base)");
      if (const double s = c.number(p + "s"), length = c.number("wire.length"); s > length)
        throw_input_error(c.where(p + "s"),
                          fmt::format("{:g} m lies beyond the end of the wire (wire.length {:g} m)", s, length));
      sim.add_point_force(c.number(p + "s"), v);
    }
  }
}

}  // namespace flowire::coupling
