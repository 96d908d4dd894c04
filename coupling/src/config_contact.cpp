// The scene's contact: section: its keys and the wall contact they describe. A wire in
// vessels touches the walls without a contact: section: then the declared defaults apply.
#include "scene_sections.hpp"

namespace flowire::coupling {

void declare_contact_keys(config::Schema& s) {
  using config::Type;
  using D = units::Dimension;
  s.add("contact", Type::Section, "", D::None, "wall contact (present by default when a wire moves in vessels)");
  s.add("contact.enabled", Type::Bool, "true", D::None,
        "false: no wall contact at all (no lookup or wall distance unless the blood drag needs them)");
  s.add("contact.friction", Type::Number, "0.1", D::None, "Coulomb friction coefficient (shaft)").non_negative();
  s.add("contact.tip_friction", Type::Number, "", D::None,
        "Coulomb friction coefficient of the tip (default: friction)")
      .non_negative();
  s.add("contact.stiffness", Type::Number, "3e4", D::None,
        "penalty stiffness per vertex of the segment_length grid (N/m): a vertex pressed with force F sinks F/k into "
        "the wall (scaled with the edge length where wire.adapt refines)")
      .positive();
  s.add("contact.settle", Type::Bool, "true", D::None,
        "start a dynamic run from the static equilibrium of the initial wire against the walls (a pre-shaped tip "
        "squeezed into the lumen) instead of from its free shape");
  s.add("contact.allow_outside", Type::Bool, "false", D::None,
        "a wire that ends up more than its radius outside the lumen makes the run fail (status outside, exit 3) "
        "unless this is true (status outside, exit 0)");
  s.add("contact.introducer", Type::Bool, "true", D::None,
        "the entry is an introducer sheath: the wire cannot come back out behind the entry plane (within twice the "
        "entry vessel's radius of its axis)");
  s.add("contact.onset", Type::Number, "", D::Length,
        "width of the wall penalty's smoothed onset: the contact force ramps in over +-onset/2 around first touch "
        "(its stiffness without a jump), so that Newton sees a wall before it reaches it; a lightly touching wire "
        "rests up to onset/2 short of the wall (default: 0.2 wire radii, which takes 5-20% of the Newton iterations "
        "and most line-search cuts off a pushed wire: docs/performance.md; 0: the sharp onset)")
      .non_negative();
  s.add("contact.viscous_friction", Type::Number, "0", D::None, "viscous wall friction (N*s/m per unit length)")
      .non_negative();
}

ContactSettings contact_settings(const config::Config& scene) {
  const config::Config& c = given_or_declared(scene, "contact");
  ContactSettings k;
  k.params.enabled = c.boolean("contact.enabled");
  k.params.stiffness = c.number("contact.stiffness");
  k.params.friction = c.number("contact.friction");
  k.params.tip_friction = c.number_or("contact.tip_friction", k.params.friction);
  k.params.viscous_friction = c.number("contact.viscous_friction");
  k.params.onset = c.number_or("contact.onset", 0.2 * given_or_declared(scene, "wire").number("wire.radius"));
  k.settle = c.boolean("contact.settle");
  k.allow_outside = c.boolean("contact.allow_outside");
  k.introducer = c.boolean("contact.introducer");
  return k;
}

}  // namespace flowire::coupling
