// The stability stress matrix: one aortic-arch co-simulation per point, watched step by step.
#include "stress.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <queue>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/coupling/vessel_forces.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/flow/spec.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire/vessels/spatial.hpp"

namespace flowire::bench {

namespace {

using Clock = std::chrono::steady_clock;

std::string num(double v) { return fmt::format("{:.9g}", v); }

/// Force limit of the feed [N]: a guidewire is pushed with well under 2 N by hand.
constexpr double kMaxInsertionForce = 2.0;
/// The friction of the matrix's unturned points where its axis says 1: unturned, the 2 N drive
/// cannot feed a wire at friction 0.5 or 1 in this scene (72 of 456 points fed less than half
/// their length at 0.5, every one at 1), and a point that is not fed tests a held wire. Friction
/// 1 is fed turning, as a clinician feeds a wire that sticks.
constexpr double kUnturnedHighFriction = 0.2;

}  // namespace

std::string stress_point_id(const StressPoint& p) {
  return fmt::format("dt={:g}ms,E={:g}GPa,L={:g}m,v={:g}cm/s,rot={:g}turn/s,flow=x{:g},mu={:g},T={:g}s", p.dt * 1e3,
                     p.youngs_modulus * 1e-9, p.wire_length, p.speed * 1e2, p.rotation, p.flow_scale, p.friction,
                     p.duration);
}

StressResult run_stress_point(const std::string& scene, const StressPoint& p) {
  StressResult r;
  r.point = p;
  const auto t_start = Clock::now();
  (void)take_warnings();
  const std::vector<std::string> sets = {
      "solve.dt=" + num(p.dt),
      "solve.duration=" + num(p.duration),
      "wire.youngs_modulus=" + num(p.youngs_modulus),
      "wire.length=" + num(p.wire_length),
      "insertion.speed=" + num(p.speed),
      "insertion.rotation_speed=" + num(2.0 * std::numbers::pi * p.rotation),
      "coupling.drag_scale=" + num(p.flow_scale),
      "contact.friction=" + num(p.friction),
      "contact.tip_friction=" + num(p.friction),
      "output.vtk=false",
      "output.csv=false",
      "output.every=0",
  };
  const config::Config c = coupling::load_scene(scene, sets);

  const vessels::Network net = coupling::build_scene_network(c);
  std::unique_ptr<flow::FlowSolver> fs;
  if (c.has_section("flow")) fs = flow::make_solver(net, flow::from_config(c, net));

  rod::WireSpec spec = coupling::scene_wire_spec(c);
  const int entry = net.farthest_end(net.widest_end());
  const auto& seg = net.segment(*net.node_segments(entry).first);
  const int other = seg.node_from == entry ? seg.node_to : seg.node_from;
  spec.base_position = net.node(entry);
  spec.base_direction = (net.node(other) - net.node(entry)).normalized();
  rod::RodSimulator sim(spec);
  sim.set_integrator(rod::parse_integrator(c.string("solve.integrator")));
  sim.set_insertion_speed(c.number("insertion.speed"));
  sim.set_rotation_speed(c.number("insertion.rotation_speed"));
  sim.set_base_angle(c.number("insertion.rotation_angle"));
  // The matrix drives the wire as a force-limited drive would (an unlimited kinematic feed
  // against friction 1 demands tens of newtons and compresses the wire).
  sim.set_max_insertion_force(kMaxInsertionForce);

  const vessels::SpatialIndex index(net, 4);
  auto forces = coupling::make_vessel_forces(c, index, spec, fs.get());
  if (!forces) throw_usage_error("stress: the scene has neither wall contact nor blood drag");
  sim.add_external(forces);

  if (!c.has("contact.settle") || c.boolean("contact.settle")) (void)sim.solve_static();  // as run_scene
  const double dt = c.number("solve.dt");
  const long steps = std::lround(c.number("solve.duration") / dt);
  const double max_length = c.number_or("insertion.max_length", std::numeric_limits<double>::infinity());
  const double rho_a = spec.density * std::numbers::pi * spec.radius * spec.radius;
  const double radius = spec.radius;
  if (fs) fs->advance(0.0);
  const double initial_length = sim.inserted_length();
  r.planned_feed = std::max(
      0.0, std::min(std::abs(c.number("insertion.speed")) * c.number("solve.duration"), max_length - initial_length));
  // Energy caps: a simulated wire moving at an rms speed above 10 m/s (100× the fastest
  // insertion, 10× the peak blood velocity), or storing more elastic energy than if all of it
  // were bent to a 1 mm radius, has blown up.
  constexpr double kMaxSpeed = 10.0, kMaxCurvature = 1e3;
  const double bend_stiffness = *std::max_element(sim.model().bend_stiffness.begin(), sim.model().bend_stiffness.end());

  auto fail = [&](long step, std::string why) {
    if (r.first_bad_step < 0) {
      r.first_bad_step = step;
      r.reason = std::move(why);
    }
  };
  for (long step = 1; step <= steps; ++step) {
    const double t1 = static_cast<double>(step) * dt;
    if (fs) fs->advance(t1);
    if (sim.inserted_length() >= max_length) sim.set_insertion_speed(0.0);
    rod::StepReport rep;
    try {
      rep = sim.step(dt);
    } catch (const Error& e) {
      fail(step, fmt::format("exception: {}", e.what()));
      r.steps = step;
      break;
    }
    r.steps = step;
    if (!rep.converged()) ++r.unconverged_steps;
    if (rep.status == rod::SolveStatus::NonFinite || rep.status == rod::SolveStatus::SingularMatrix) {
      fail(step, fmt::format("state not finite ({})", rod::to_string(rep.status)));
      break;
    }
    bool finite = true;
    for (const auto& x : sim.positions()) finite = finite && x.allFinite();
    if (!finite) {
      fail(step, "non-finite position");
      break;
    }
    const double outside = forces->stats().max_outside / radius;
    r.max_outside_over_radius = std::max(r.max_outside_over_radius, outside);
    if (outside > 0.1) fail(step, fmt::format("outside the lumen by {:.3g} wire radii", outside));
    const double drift = sim.length_drift();
    r.max_length_drift = std::max(r.max_length_drift, drift);
    if (!(drift < 1e-3)) fail(step, fmt::format("length drift {:.3g}", drift));
    const auto e = sim.energy();
    const double simulated_length = std::max(sim.inserted_length(), 0.0) + 2.0 * sim.model().h;
    const double mass = rho_a * simulated_length;
    const double ke_cap = 0.5 * mass * kMaxSpeed * kMaxSpeed;
    const double elastic_cap = 0.5 * bend_stiffness * kMaxCurvature * kMaxCurvature * simulated_length;
    const double elastic = e.stretching + e.bending_twisting;
    r.max_rms_speed = std::max(r.max_rms_speed, std::sqrt(2.0 * std::max(e.kinetic, 0.0) / mass));
    r.max_energy_ratio = std::max({r.max_energy_ratio, e.kinetic / ke_cap, elastic / elastic_cap});
    if (!(e.kinetic <= ke_cap)) fail(step, fmt::format("kinetic energy {:.3g} J above {:.3g} J", e.kinetic, ke_cap));
    if (!(elastic <= elastic_cap))
      fail(step, fmt::format("elastic energy {:.3g} J above {:.3g} J", elastic, elastic_cap));
    if (step % 256 == 0) (void)take_warnings();  // unconverged steps are counted above
  }
  (void)take_warnings();
  r.pass = r.first_bad_step < 0;
  r.held_steps = sim.held_steps();
  r.inserted_length = sim.inserted_length();
  r.fed = std::abs(r.inserted_length - initial_length);
  r.seconds = std::chrono::duration<double>(Clock::now() - t_start).count();
  return r;
}

std::vector<StressPoint> stress_matrix(bool reduced) {
  std::vector<StressPoint> m;
  if (reduced) {
    // The corners that stress each axis, at a short duration.
    const StressPoint base{.dt = 0.01,
                           .youngs_modulus = 60e9,
                           .wire_length = 0.8,
                           .speed = 0.05,
                           .rotation = 0.0,
                           .flow_scale = 1.0,
                           .friction = 0.2,
                           .duration = 0.6};
    auto add = [&](auto edit) {
      StressPoint p = base;
      edit(p);
      m.push_back(p);
    };
    add([](StressPoint&) {});
    add([](StressPoint& p) {
      p.dt = 1.0 / 30.0;
      p.youngs_modulus = 200e9;
      p.speed = 0.1;
    });
    // Friction 1 without rotation cannot be fed by the 2 N drive (the wire is held at the
    // entry, which tests a held wire): the unrotated points take 0.5, and friction 1 is fed
    // turning (as a clinician feeds a wire that sticks); so is the 5 GPa wire in 10x flow,
    // which 0.5 still holds.
    add([](StressPoint& p) {
      p.youngs_modulus = 5e9;
      p.flow_scale = 10.0;
      p.friction = 0.5;
      p.rotation = 2.0;
    });
    add([](StressPoint& p) {
      p.dt = 1e-3;
      p.wire_length = 1.7;
      p.rotation = 2.0;
      p.duration = 0.3;
    });
    add([](StressPoint& p) {
      p.dt = 1.0 / 30.0;
      p.youngs_modulus = 5e9;
      p.friction = 0.05;
      p.flow_scale = 0.0;
      p.rotation = 2.0;
    });
    add([](StressPoint& p) {
      p.youngs_modulus = 200e9;
      p.wire_length = 1.7;
      p.speed = 0.1;
      p.flow_scale = 10.0;
      p.friction = 1.0;
      p.rotation = 2.0;
    });
    // A long insertion: the 1.7 m wire fed to the scene's 50 cm limit, then held.
    add([](StressPoint& p) {
      p.wire_length = 1.7;
      p.speed = 0.1;
      p.friction = 0.5;
      p.duration = 5.5;
    });
    return m;
  }
  for (double dt : {1e-3, 1e-2, 1.0 / 30.0})
    for (double E : {5e9, 67e9, 200e9})
      for (double L : {0.8, 1.7})
        for (double v : {0.01, 0.1})
          for (double rot : {0.0, 2.0})
            for (double flow : {0.0, 1.0, 10.0})
              for (double mu : {0.05, 1.0}) {
                // Friction 1 is fed turning; unturned, kUnturnedHighFriction.
                StressPoint p{.dt = dt,
                              .youngs_modulus = E,
                              .wire_length = L,
                              .speed = v,
                              .rotation = rot,
                              .flow_scale = flow,
                              .friction = rot == 0.0 && mu == 1.0 ? kUnturnedHighFriction : mu,
                              .duration = 1.0};
                m.push_back(p);
              }
  // Long insertions: the 1.7 m wire fed at 10 cm/s to the scene's 50 cm limit (the aorta
  // from the femoral entry towards the root) and held there, with and without rotation.
  for (double dt : {1e-3, 1e-2})
    for (double E : {5e9, 67e9, 200e9})
      for (double rot : {0.0, 2.0})
        for (double mu : {0.05, 1.0})
          m.push_back(StressPoint{.dt = dt,
                                  .youngs_modulus = E,
                                  .wire_length = 1.7,
                                  .speed = 0.1,
                                  .rotation = rot,
                                  .flow_scale = 1.0,
                                  .friction = rot == 0.0 && mu == 1.0 ? kUnturnedHighFriction : mu,
                                  .duration = 5.5});
  return m;
}

std::string stress_csv_header() {
  return "dt,youngs_modulus,wire_length,speed,rotation_turns_per_s,flow_scale,friction,duration,pass,reason,"
         "first_bad_step,steps,unconverged_steps,max_outside_over_radius,max_length_drift,max_energy_ratio,max_rms_"
         "speed,"
         "inserted_length,seconds,held_steps,planned_feed,fed,stalled\n";
}

std::string stress_csv_row(const StressResult& r) {
  const auto& p = r.point;
  std::string reason = r.reason;
  for (char& ch : reason)
    if (ch == ',' || ch == '\n') ch = ';';
  return fmt::format(
      "{:g},{:g},{:g},{:g},{:g},{:g},{:g},{:g},{},{},{},{},{},{:.4g},{:.4g},{:.4g},{:.4g},{:.4g},{:.4g},{},{:.4g},{:."
      "4g},{}\n",
      p.dt, p.youngs_modulus, p.wire_length, p.speed, p.rotation, p.flow_scale, p.friction, p.duration, r.pass ? 1 : 0,
      reason, r.first_bad_step, r.steps, r.unconverged_steps, r.max_outside_over_radius, r.max_length_drift,
      r.max_energy_ratio, r.max_rms_speed, r.inserted_length, r.seconds, r.held_steps, r.planned_feed, r.fed,
      r.stalled() ? 1 : 0);
}

}  // namespace flowire::bench
