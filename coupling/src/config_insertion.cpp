// The scene's insertion: section: its keys and how they drive the wire at its base.
#include <fmt/format.h>

#include <string>

#include "flowire/common/error.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {

void declare_insertion_keys(config::Schema& s) {
  using config::Type;
  using D = units::Dimension;
  s.add("insertion", Type::Section, "", D::None, "pushing and turning the wire at its base");
  s.add("insertion.speed", Type::Number, "0", D::Velocity, "insertion speed (negative: pull back)");
  s.add("insertion.rotation_speed", Type::Number, "0", D::AngularSpeed, "base rotation speed");
  s.add("insertion.rotation_angle", Type::Number, "0", D::Angle, "base rotation at the start (turns a pre-shaped tip)");
  s.add("insertion.initial_length", Type::Number, "2 cm", D::Length,
        "length inside at t = 0 (at least two rod segments, at most wire.length)")
      .positive();
  s.add("insertion.schedule", Type::String, "", D::None,
        "CSV with columns time,speed,rotation_speed (SI): from each row's time on, push (> 0), pull (< 0) or hold, "
        "and turn; replaces speed and rotation_speed (docs/insertion.md)");
  s.add("insertion.max_length", Type::Number, "", D::Length, "stop pushing at this inserted length").non_negative();
  s.add("insertion.max_force", Type::Number, "", D::Force,
        "force-limited feeding: hold the feed in steps that start with the wire pushed in harder than this "
        "(a drive's or a hand's limit); default unlimited (the feed is kinematic)")
      .positive();
  s.add("insertion.force", Type::Number, "", D::Force,
        "force-driven feeding: push the base with this constant force; each step's feed is the one for which the "
        "clamp's axial force equals it (replaces speed; docs/insertion.md)")
      .positive();
}

void drive_wire(const config::Config& c, rod::RodSimulator& sim) {
  if (!c.has_section("insertion")) return;
  sim.set_insertion_speed(c.number("insertion.speed"));
  sim.set_rotation_speed(c.number("insertion.rotation_speed"));
  sim.set_base_angle(c.number("insertion.rotation_angle"));
  if (c.has("insertion.max_force")) sim.set_max_insertion_force(c.number("insertion.max_force"));  // > 0, declared
  if (c.has("insertion.force")) {
    const double f = c.number("insertion.force");  // > 0, declared
    for (const char* key : {"insertion.speed", "insertion.schedule", "insertion.max_force"})
      if (c.given(key))
        throw_input_error(
            c.where(key),
            fmt::format("give either insertion.force (the feed follows from the force) or {}, not both", key));
    sim.set_push_force(f);
  }
}

InsertionPlan insertion_plan(const config::Config& c, bool has_wire) {
  InsertionPlan plan;
  if (c.has("insertion.max_length")) plan.max_length = c.number("insertion.max_length");
  if (has_wire && c.has_section("insertion")) {
    plan.speed = c.number("insertion.speed");
    plan.rotation_speed = c.number("insertion.rotation_speed");
  }
  if (c.has("insertion.schedule")) {
    for (const char* key : {"insertion.speed", "insertion.rotation_speed"})
      if (c.given(key))
        throw_input_error(c.where(key),
                          "give either insertion.schedule or insertion.speed and rotation_speed, not both");
    if (!has_wire) throw_input_error(c.where("insertion.schedule"), "a schedule drives the wire: the scene has none");
    plan.schedule =
        std::make_unique<DriveSchedule>(DriveSchedule::read_csv(c.resolve_path(c.string("insertion.schedule"))));
  }
  return plan;
}

}  // namespace flowire::coupling
