// The scene's solve: section: its keys and the time stepping they describe.
#include <cmath>

#include "flowire/common/error.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {

void declare_solve_keys(config::Schema& s) {
  using config::Type;
  using D = units::Dimension;
  s.add("solve", Type::Section, "{}", D::None, "time stepping (also drives flow-only scenes: one flow frame per step)");
  s.add("solve.mode", Type::Enum, "dynamic", D::None, "static: equilibrium; dynamic: time stepping",
        {"static", "dynamic"});
  s.add("solve.dt", Type::Number, "1 ms", D::Time, "time step");
  s.add("solve.duration", Type::Number, "0", D::Time, "simulated time (0: one frame / the steady state)");
  s.add("solve.integrator", Type::Enum, "implicit_euler", D::None, "rod time integrator",
        {"implicit_euler", "implicit_midpoint"});
}

SolveSettings solve_settings(const config::Config& c) {
  const double dt = c.number("solve.dt");
  const double duration = c.number("solve.duration");
  if (!(dt > 0)) throw_input_error(c.where("solve.dt"), "must be positive");
  if (duration < 0) throw_input_error(c.where("solve.duration"), "must not be negative");
  SolveSettings s;
  s.is_static = c.string("solve.mode") == "static";
  s.dt = dt;
  s.steps = s.is_static ? 0 : static_cast<long>(std::llround(duration / dt));
  return s;
}

rod::Integrator scene_integrator(const config::Config& c) {
  return rod::parse_integrator(c.string("solve.integrator"));
}

}  // namespace flowire::coupling
