// rod-work-precision: error against analytic references vs run time.
//  - cantilever (Bisshopp–Drucker elastica, α = PL²/EI = 1, 5, 10), static solve, over segments,
//    uniform and curvature-adaptive;
//  - Euler buckling, clamped–free, P_cr = π²EI/(4L²), by bisection on the stability of the
//    straight state (negative eigenvalues of the static Hessian), over segments;
//  - first cantilever frequency ω₁ = 1.87510²·√(EI/(ρAL⁴)) vs dt, per integrator;
//  - cost of one implicit step vs vertex count (the published rods: 5–36 ms per step).
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "flowire/common/diagnostics.hpp"
#include "flowire/rod/simulator.hpp"
#include "studies.hpp"

namespace flowire::bench {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// Unit cantilever along +x: L = 1, EI = GJ = ρA = 1, EA = 1e7 (nearly inextensible).
rod::WireSpec unit_rod(int segments) {
  rod::WireSpec s;
  s.length = 1.0;
  s.radius = 0.01;
  s.youngs_modulus = 1e9;
  s.density = 1000.0;
  s.segments = segments;
  s.tip.length = 0.0;
  s.bending_stiffness = 1.0;
  s.twist_stiffness = 1.0;
  s.stretch_stiffness = 1e7;
  s.mass_per_length = 1.0;
  s.base_direction = Eigen::Vector3d::UnitX();
  s.base_normal = Eigen::Vector3d::UnitZ();
  return s;
}

double period_from_crossings(const std::vector<double>& t, const std::vector<double>& y) {
  std::vector<double> c;
  for (size_t i = 1; i < y.size(); ++i)
    if (y[i - 1] < 0.0 && y[i] >= 0.0) c.push_back(t[i - 1] + (t[i] - t[i - 1]) * (-y[i - 1]) / (y[i] - y[i - 1]));
  if (c.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  return (c.back() - c.front()) / static_cast<double>(c.size() - 1);
}

}  // namespace

int rod_work_precision(const Options& o) {
  std::string csv = "case,integrator,segments,dt,error,seconds\n";
  const std::vector<int> seg_static =
      o.reduced ? std::vector<int>{10, 20, 40, 80} : std::vector<int>{10, 20, 40, 80, 160, 320, 400};
  struct Ref {
    double alpha, deflection, shortening;
  };
  const Ref refs[] = {{1.0, 0.30172, 0.05643}, {5.0, 0.71379, 0.38763}, {10.0, 0.81061, 0.55500}};
  // Uniform segments, then curvature-adaptive ones from a coarse grid (segments column:
  // the free edges at the end; refined near the clamp where the bending moment is largest).
  for (const bool adaptive : {false, true})
    for (const auto& ref : refs)
      for (int n : adaptive ? std::vector<int>{5, 10, 20, 40} : seg_static) {
        const auto t0 = Clock::now();
        rod::WireSpec spec = unit_rod(n);
        if (adaptive) {
          spec.adapt.enabled = true;
          spec.adapt.min_segment_length = 1.0 / (8 * n);
          spec.adapt.split_angle = 0.05;
        }
        rod::RodSimulator sim(spec);
        sim.set_tip_force({0.0, ref.alpha, 0.0});
        sim.settings().static_load_steps = ref.alpha > 5 ? 2 : 1;
        const auto rep = sim.solve_static();
        const double sec = since(t0);
        const auto tip = sim.tip_position();
        const double err = rep.converged() ? std::hypot(tip.y() - ref.deflection, 1.0 - tip.x() - ref.shortening)
                                           : std::numeric_limits<double>::quiet_NaN();
        csv += fmt::format("cantilever_alpha{:g},{},{},0,{:.6e},{:.6e}\n", ref.alpha,
                           adaptive ? "static_adaptive" : "static", sim.first_clamped_vertex(), err, sec);
      }

  // Euler buckling by bisection (30 halvings of [0.5, 1.5]·P_cr).
  const double pcr = std::numbers::pi * std::numbers::pi / 4.0;
  const std::vector<int> seg_buckle = o.reduced ? std::vector<int>{10, 20, 40} : std::vector<int>{10, 20, 40, 80, 160};
  for (int n : seg_buckle) {
    const auto t0 = Clock::now();
    auto unstable = [&](double P) {
      rod::RodSimulator sim(unit_rod(n));
      sim.set_tip_force({-P, 0.0, 0.0});
      (void)sim.solve_static();
      return sim.static_hessian_negative_eigenvalues() > 0;
    };
    double lo = 0.5 * pcr, hi = 1.5 * pcr;
    const int halvings = 30;
    for (int i = 0; i < halvings; ++i) {
      const double mid = 0.5 * (lo + hi);
      (unstable(mid) ? hi : lo) = mid;
    }
    const double sec = since(t0);
    csv += fmt::format("buckling,static,{},0,{:.6e},{:.6e}\n", n, std::abs(0.5 * (lo + hi) - pcr) / pcr, sec);
  }

  // First cantilever frequency vs dt, 50 segments, 3 periods from a small static deflection.
  const double omega = 1.87510 * 1.87510;
  const double period = 2.0 * std::numbers::pi / omega;
  const std::vector<int> per_period =
      o.reduced ? std::vector<int>{10, 20, 40, 80} : std::vector<int>{5, 10, 20, 40, 80, 160, 320};
  for (auto integ : {rod::Integrator::ImplicitEuler, rod::Integrator::ImplicitMidpoint})
    for (int k : per_period) {
      rod::RodSimulator sim(unit_rod(50));
      sim.set_tip_force({0.0, 1e-3, 0.0});
      (void)sim.solve_static();
      sim.set_tip_force(Eigen::Vector3d::Zero());
      sim.set_integrator(integ);
      const double dt = period / k;
      std::vector<double> t, y;
      const auto t0 = Clock::now();
      for (int i = 0; i < 3 * k + 2; ++i) {
        (void)sim.step(dt);
        t.push_back(sim.time());
        y.push_back(sim.tip_position().y());
      }
      const double sec = since(t0);
      const double T = period_from_crossings(t, y);
      csv +=
          fmt::format("frequency,{},50,{:.6e},{:.6e},{:.6e}\n", rod::to_string(integ), dt,
                      std::isfinite(T) ? std::abs(T - period) / period : std::numeric_limits<double>::quiet_NaN(), sec);
    }

  // Cost of one implicit step vs vertex count: a guidewire (E = 60 GPa, r = 0.445 mm, 1 mm
  // segments) under gravity, 20 steps of 1 ms after 3 warm-up steps; error column empty.
  const std::vector<int> seg_cost =
      o.reduced ? std::vector<int>{100, 400, 1700} : std::vector<int>{10, 30, 100, 300, 1000, 1700, 3000, 10000};
  for (auto integ : {rod::Integrator::ImplicitEuler, rod::Integrator::ImplicitMidpoint})
    for (int n : seg_cost) {
      rod::WireSpec s;
      s.length = 1e-3 * n;
      s.segments = n;
      s.youngs_modulus = 60e9;
      s.radius = 4.45e-4;
      s.tip.length = 0.0;
      s.base_direction = Eigen::Vector3d::UnitX();
      rod::RodSimulator sim(s);
      sim.set_integrator(integ);
      sim.set_gravity({0.0, 0.0, -9.81});
      for (int i = 0; i < 3; ++i) (void)sim.step(1e-3);
      const int steps = 20;
      const auto t0 = Clock::now();
      for (int i = 0; i < steps; ++i) (void)sim.step(1e-3);
      csv += fmt::format("step_cost,{},{},1e-3,,{:.6e}\n", rod::to_string(integ), n, since(t0) / steps);
    }
  (void)take_warnings();
  emit(o, "rod_work_precision.csv", csv);
  return 0;
}

}  // namespace flowire::bench
