// The scene's solve: section: its keys and the time stepping they describe.
#include "flowire/common/steps.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {

void declare_solve_keys(config::Schema& s) {
  using config::Type;
  using D = units::Dimension;
  s.add("solve", Type::Section, "{}", D::None, "time stepping (also drives flow-only scenes: one flow frame per step)");
  s.add("solve.mode", Type::Enum, "dynamic", D::None, "static: equilibrium; dynamic: time stepping",
        {"static", "dynamic"});
  s.add("solve.dt", Type::Number, "1 ms", D::Time, "time step").positive();
  s.add("solve.duration", Type::Number, "0", D::Time,
        "simulated time (0: one frame / the steady state; at most 1e9 steps of solve.dt)")
      .non_negative();
  s.add("solve.integrator", Type::Enum, "implicit_euler", D::None, "rod time integrator",
        {"implicit_euler", "implicit_midpoint"});
}

SolveSettings solve_settings(const config::Config& c) {
  // dt > 0 and duration >= 0 are declared; their quotient is checked here.
  SolveSettings s;
  s.is_static = c.string("solve.mode") == "static";
  s.dt = c.number("solve.dt");
  s.steps = s.is_static
                ? 0
                : step_count(c.number("solve.duration"), s.dt, c.where("solve.duration"), "solve.duration / solve.dt");
  return s;
}

rod::Integrator scene_integrator(const config::Config& c) {
  return rod::parse_integrator(c.string("solve.integrator"));
}

}  // namespace flowire::coupling
