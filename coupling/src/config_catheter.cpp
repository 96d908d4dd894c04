// The scene's catheter: section: its keys and the catheter they describe.
#include <fmt/format.h>

#include <string>

#include "flowire/common/error.hpp"
#include "flowire/coupling/scene.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {

void declare_catheter_keys(config::Schema& s) {
  using config::Type;
  using D = units::Dimension;
  s.add("catheter", Type::Section, "", D::None,
        "a hollow catheter over the wire, entering at the same point (docs/catheter.md); the wire runs in its lumen");
  s.add("catheter.length", Type::Number, "1.0", D::Length, "total catheter length").positive();
  s.add("catheter.outer_radius", Type::Number, "1 mm", D::Length, "outer radius (the wall contact uses it)").positive();
  s.add("catheter.inner_radius", Type::Number, "0.55 mm", D::Length,
        "lumen radius: the wire's axis stays within inner_radius - wire.radius of the catheter's axis")
      .positive();
  s.add("catheter.youngs_modulus", Type::Number, "2 GPa", D::Pressure, "Young's modulus of the catheter wall")
      .positive();
  s.add("catheter.density", Type::Number, "1200", D::Density, "density of the catheter wall").positive();
  s.add("catheter.initial_length", Type::Number, "2 cm", D::Length,
        "catheter length inside at t = 0 (at most catheter.length)")
      .non_negative();
  s.add("catheter.stiffness", Type::Number, "3e4", D::None,
        "lumen penalty per wire vertex (N/m): a wire vertex pushing on the lumen with force F above k*delta/2 sinks "
        "F/k into it (its onset is smoothed over delta = 0.3 of the clearance, docs/catheter.md)")
      .positive();
  s.add("catheter.inner_friction", Type::Number, "0", D::None,
        "Coulomb friction coefficient between the wire and the catheter's lumen (0: frictionless; docs/catheter.md)")
      .non_negative();
  s.add("catheter.insertion", Type::Section, "", D::None, "pushing and turning the catheter at the entry");
  s.add("catheter.insertion.speed", Type::Number, "0", D::Velocity, "catheter insertion speed (negative: pull back)");
  s.add("catheter.insertion.rotation_speed", Type::Number, "0", D::AngularSpeed, "catheter rotation speed");
}

CatheterSpec scene_catheter_spec(const config::Config& c, const rod::WireSpec& wire) {
  CatheterSpec k;
  k.length = c.number("catheter.length");
  k.outer_radius = c.number("catheter.outer_radius");
  k.inner_radius = c.number("catheter.inner_radius");
  k.youngs_modulus = c.number("catheter.youngs_modulus");
  k.density = c.number("catheter.density");
  k.initial_length = c.number("catheter.initial_length");
  k.stiffness = c.number("catheter.stiffness");
  k.inner_friction = c.number("catheter.inner_friction");
  if (c.has_section("catheter.insertion")) {
    k.speed = c.number("catheter.insertion.speed");
    k.rotation_speed = c.number("catheter.insertion.rotation_speed");
  }
  // Each value's own range is declared; what is checked here relates two of them.
  if (k.initial_length > k.length)
    throw_input_error(c.where("catheter.initial_length"),
                      fmt::format("catheter.initial_length ({:.4g} m) must not exceed catheter.length ({:.4g} m)",
                                  k.initial_length, k.length));
  if (!(k.outer_radius > k.inner_radius))
    throw_input_error(c.where("catheter.outer_radius"),
                      fmt::format("catheter.outer_radius ({:.4g} m) must exceed catheter.inner_radius ({:.4g} m)",
                                  k.outer_radius, k.inner_radius));
  if (!c.has_section("wire"))
    throw_input_error(c.where("catheter"), "a catheter runs over a wire: the scene has no wire: section");
  if (!(k.inner_radius >= wire.radius))
    throw_input_error(c.where("catheter.inner_radius"),
                      fmt::format("catheter.inner_radius ({:.4g} m) is narrower than the wire (wire.radius {:.4g} m)",
                                  k.inner_radius, wire.radius));
  return k;
}

}  // namespace flowire::coupling
