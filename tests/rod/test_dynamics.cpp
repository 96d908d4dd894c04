// Dynamics: cantilever frequency (implicit midpoint), damping of backward Euler, base
// rotation travelling to the tip, feeding in and out, external forces with Jacobians,
// and non-convergence being reported.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire_test.hpp"
#include "rod_test_util.hpp"

namespace flowire::rod {
namespace {

using testing::tol;

/// Period from the upward zero crossings of a sampled signal (linear interpolation).
double measured_period(const std::vector<double>& t, const std::vector<double>& y) {
  std::vector<double> crossings;
  for (size_t i = 1; i < y.size(); ++i)
    if (y[i - 1] < 0.0 && y[i] >= 0.0)
      crossings.push_back(t[i - 1] + (t[i] - t[i - 1]) * (-y[i - 1]) / (y[i] - y[i - 1]));
  if (crossings.size() < 2) return 0.0;
  return (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
}

TEST(RodDynamics, FirstCantileverFrequencyWithImplicitMidpoint) {
  // ω₁ = 1.87510² √(EI/(ρA L⁴)); EI = ρA = L = 1.
  const double omega = 1.87510 * 1.87510;
  const double period = 2.0 * std::numbers::pi / omega;
  RodSimulator sim(unit_rod_spec(50));
  sim.set_tip_force({0.0, 1e-3, 0.0});
  ASSERT_TRUE(sim.solve_static().converged());
  sim.set_tip_force(Eigen::Vector3d::Zero());
  sim.set_integrator(Integrator::ImplicitMidpoint);
  const double e0 = sim.energy().total();
  const double dt = period / 200.0;
  std::vector<double> t, y;
  for (int i = 0; i < 700; ++i) {
    ASSERT_TRUE(sim.step(dt).converged());
    t.push_back(sim.time());
    y.push_back(sim.tip_position().y());
  }
  const double T = measured_period(t, y);
  EXPECT_NEAR(T, period, tol(0.01 * period));
  // No numerical damping: the energy after about four periods is the initial one.
  EXPECT_NEAR(sim.energy().total(), e0, 0.01 * e0);
}

TEST(RodDynamics, BackwardEulerDampsAtLargeSteps) {
  RodSimulator sim(unit_rod_spec(30));
  sim.set_tip_force({0.0, 1e-3, 0.0});
  ASSERT_TRUE(sim.solve_static().converged());
  sim.set_tip_force(Eigen::Vector3d::Zero());
  const double e0 = sim.energy().total();
  for (int i = 0; i < 60; ++i) ASSERT_TRUE(sim.step(0.1).converged());
  EXPECT_LT(sim.energy().total(), 0.05 * e0);
}

TEST(RodDynamics, StaticBaseRotationTwistsTheWholeWire) {
  RodSimulator sim(unit_rod_spec(20));
  const Eigen::Vector3d m1_before = sim.material_frame(0).first;
  sim.set_base_angle(1.0);
  ASSERT_TRUE(sim.solve_static().converged());
  const Eigen::Vector3d m1_after = sim.material_frame(0).first;
  const Eigen::Vector3d axis = Eigen::Vector3d::UnitX();  // right-handed about insertion
  EXPECT_NEAR(std::atan2(m1_before.cross(m1_after).dot(axis), m1_before.dot(m1_after)), 1.0, 1e-9);
}

TEST(RodDynamics, RotationSpeedTravelsToTheTip) {
  // A J-tipped wire spun at the base: the tip's material frame follows the clamp.
  WireSpec spec;
  spec.length = 0.2;
  spec.segment_length = 2e-3;
  spec.youngs_modulus = 67e9;
  spec.tip.length = 0.03;
  spec.tip.youngs_modulus = 10e9;
  spec.tip.shape = TipShape::J;
  spec.tip.bend_radius = 0.004;
  spec.damping = 1e-3;
  RodSimulator sim(spec);
  const Eigen::Vector3d tip0 = sim.tip_position();
  sim.set_rotation_speed(2.0 * std::numbers::pi);  // one turn per second
  const double dt = 1e-3;
  for (int i = 0; i < 250; ++i) ASSERT_TRUE(sim.step(dt).converged());
  // After a quarter turn the hooked tip has swung by a quarter turn about the axis.
  const Eigen::Vector3d axis = sim.model().base_direction;
  const Eigen::Vector3d base = sim.model().base_position;
  auto lateral = [&](const Eigen::Vector3d& p) {
    Eigen::Vector3d r = p - base;
    return Eigen::Vector3d(r - axis * axis.dot(r));
  };
  const Eigen::Vector3d a = lateral(tip0), b = lateral(sim.tip_position());
  const double turned = std::atan2(a.cross(b).dot(axis), a.dot(b));
  EXPECT_NEAR(turned, 0.5 * std::numbers::pi, 0.05);
  EXPECT_NEAR(b.norm(), a.norm(), 0.05 * a.norm());
  EXPECT_LT(sim.length_drift(), 1e-3);
}

TEST(RodDynamics, FeedingAddsAndRemovesVertices) {
  WireSpec spec;
  spec.length = 0.3;
  spec.segment_length = 1e-3;
  spec.inserted_length = 0.1;
  spec.youngs_modulus = 67e9;
  RodSimulator sim(spec);
  const int n0 = sim.vertex_count();
  const Eigen::Vector3d tip0 = sim.tip_position();
  sim.set_insertion_speed(0.1);
  for (int i = 0; i < 500; ++i) ASSERT_TRUE(sim.step(1e-3).converged());
  EXPECT_NEAR(sim.inserted_length(), 0.15, 1e-9);
  EXPECT_EQ(sim.vertex_count(), n0 + 50);
  EXPECT_NEAR((sim.tip_position() - tip0).x(), 0.05, 2e-4);
  EXPECT_LT(sim.length_drift(), 1e-3);
  // Arc length: 0 at the entry, the tip at the inserted length.
  EXPECT_NEAR(sim.arc_lengths()[0], 0.15, 1e-12);
  EXPECT_LE(sim.arc_lengths()[sim.first_clamped_vertex()], 1e-12);
  sim.set_insertion_speed(-0.1);
  for (int i = 0; i < 500; ++i) ASSERT_TRUE(sim.step(1e-3).converged());
  EXPECT_NEAR(sim.inserted_length(), 0.1, 1e-9);
  EXPECT_EQ(sim.vertex_count(), n0);
  EXPECT_NEAR((sim.tip_position() - tip0).norm(), 0.0, 2e-4);
  // The trace has one sample per step plus the initial one.
  EXPECT_EQ(sim.tip_trace().size(), 1001u);
}

TEST(RodDynamics, ImplicitMidpointFeedsAndSpins) {
  WireSpec spec;
  spec.length = 0.2;
  spec.inserted_length = 0.1;
  spec.segment_length = 1e-3;
  spec.youngs_modulus = 67e9;
  spec.tip.length = 0.03;
  spec.tip.youngs_modulus = 10e9;
  spec.tip.shape = TipShape::Angled;
  spec.damping = 1e-3;
  RodSimulator sim(spec);
  sim.set_integrator(Integrator::ImplicitMidpoint);
  sim.set_insertion_speed(0.1);
  sim.set_rotation_speed(2.0 * std::numbers::pi);
  for (int i = 0; i < 200; ++i) ASSERT_TRUE(sim.step(1e-3).converged());
  EXPECT_NEAR(sim.inserted_length(), 0.12, 1e-9);
  EXPECT_LT(sim.length_drift(), 1e-3);
  for (const auto& x : sim.positions()) EXPECT_TRUE(x.allFinite());
}

TEST(RodDynamics, ExternalSpringWithJacobianMatchesTheory) {
  // Tip spring k: small-deflection tip δ = P / (3EI/L³ + k).
  RodSimulator sim(unit_rod_spec(60));
  const double k = 5.0, P = 1e-3;
  auto spring = std::make_shared<ExternalForceFunction>([k](const RodView& rod, ForceAccumulator& out) {
    const Eigen::Vector3d anchor(1.0, 0.0, 0.0);
    out.add_force(0, -k * (rod.position(0) - anchor));
    out.add_position_jacobian(0, -k * Eigen::Matrix3d::Identity());
  });
  sim.add_external(spring);
  sim.set_tip_force({0.0, P, 0.0});
  const StepReport r = sim.solve_static();
  ASSERT_TRUE(r.converged());
  EXPECT_LE(r.newton_iterations, 5);  // the Jacobian keeps Newton quadratic
  EXPECT_NEAR(sim.tip_position().y(), P / (3.0 + k), 1e-3 * P / (3.0 + k));
}

TEST(RodDynamics, ExternalDragUsesVelocityJacobian) {
  // Heavy drag on every vertex: an implicit step at a large dt stays stable and slow.
  RodSimulator sim(unit_rod_spec(30));
  const double c = 1e3;
  sim.add_external(std::make_shared<ExternalForceFunction>([c](const RodView& rod, ForceAccumulator& out) {
    for (int i = 0; i < rod.first_clamped_vertex; ++i) {
      out.add_force(i, -c * rod.velocity(i));
      out.add_velocity_jacobian(i, -c * Eigen::Matrix3d::Identity());
    }
  }));
  sim.set_gravity({0.0, 0.0, -9.81});
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(sim.step(0.05).converged());
  // Terminal velocity of the tip region ≈ m g / c is tiny; the tip barely moved.
  EXPECT_LT(std::abs(sim.tip_position().z()), 0.02);
  EXPECT_LT(sim.velocities()[0].norm(), 0.05);
}

TEST(RodDynamics, ExternalTwistTorqueWithSpinJacobian) {
  // A rotational drag −c·ω on every free edge of a wire spun at a constant rate: in the
  // steady state the clamp supplies the total drag torque, n_free · c · ω.
  WireSpec spec = unit_rod_spec(20);
  RodSimulator sim(spec);
  const double c = 1e-2, omega = 3.0;
  sim.add_external(std::make_shared<ExternalForceFunction>([c](const RodView& rod, ForceAccumulator& out) {
    for (int j = 0; j < rod.first_clamped_vertex; ++j) out.add_twist_torque(j, -c * rod.spin_rates[j], -c);
  }));
  sim.set_rotation_speed(omega);
  for (int i = 0; i < 200; ++i) ASSERT_TRUE(sim.step(1e-2).converged());
  const int free_edges = sim.first_clamped_vertex();
  EXPECT_NEAR(sim.base_torque().x(), free_edges * c * omega, 1e-3 * free_edges * c * omega);
  // The tip spins with the clamp.
  EXPECT_NEAR(-sim.state().omega[0], omega, 1e-6);
}

TEST(RodDynamics, WireFedAlongATubeWallByPenaltyContact) {
  // A wire entering a straight tube (radius 1.5 mm about the x axis) at 3° is pushed in at
  // 5 cm/s and spun at 1 turn/s: it meets the wall after about 3 cm and slides along it.
  // The wall is a stiff penalty supplied through ExternalForce with its Jacobian; at a
  // frame-size step (1/60 s) Newton converges every step and the wire stays inside.
  WireSpec spec;
  spec.length = 0.2;
  spec.inserted_length = 0.02;
  spec.segment_length = 1e-3;
  spec.youngs_modulus = 67e9;
  spec.tip.length = 0.03;
  spec.tip.youngs_modulus = 10e9;
  spec.damping = 1e-3;
  const double tilt = 3.0 * std::numbers::pi / 180.0;
  spec.base_direction = Eigen::Vector3d(std::cos(tilt), std::sin(tilt), 0.0);
  RodSimulator sim(spec);
  const double R = 1.5e-3, k = 2e4;
  sim.add_external(std::make_shared<ExternalForceFunction>([R, k](const RodView& rod, ForceAccumulator& out) {
    Eigen::Matrix3d P = Eigen::Matrix3d::Identity();  // projection onto the cross-section
    P(0, 0) = 0.0;
    for (int i = 0; i < rod.first_clamped_vertex; ++i) {
      const Eigen::Vector3d p = rod.position(i);
      const Eigen::Vector3d radial(0.0, p.y(), p.z());
      const double r = radial.norm();
      if (r <= R) continue;
      const Eigen::Vector3d n = radial / r;
      out.add_force(i, -k * (r - R) * n);
      out.add_position_jacobian(i, -k * n * n.transpose() - k * (r - R) / r * (P - n * n.transpose()));
    }
  }));
  sim.set_insertion_speed(0.05);
  sim.set_rotation_speed(2.0 * std::numbers::pi);
  double worst = 0.0;
  for (int i = 0; i < 60; ++i) {  // 1 s at 60 Hz
    ASSERT_TRUE(sim.step(1.0 / 60.0).converged()) << "step " << i;
    for (int v = 0; v < sim.first_clamped_vertex(); ++v)
      worst = std::max(worst, std::hypot(sim.positions()[v].y(), sim.positions()[v].z()));
  }
  EXPECT_NEAR(sim.inserted_length(), 0.07, 1e-9);
  EXPECT_GT(worst, R);         // the wall was reached
  EXPECT_LT(worst, R + 2e-4);  // penetration a fraction of a millimetre
  EXPECT_LT(sim.length_drift(), 1e-3);
}

/// The tube-wall scene above with a stiff penalty, reported either as a plain force
/// or as a conservative force with its energy. Returns (steps converged, line-search cuts,
/// worst radial position).
struct TubeRun {
  int converged = 0, cuts = 0, iterations = 0;
  double worst = 0.0;
};
TubeRun stiff_tube_run(bool conservative, double k) {
  WireSpec spec;
  spec.length = 0.2;
  spec.inserted_length = 0.02;
  spec.segment_length = 1e-3;
  spec.youngs_modulus = 67e9;
  spec.tip.length = 0.03;
  spec.tip.youngs_modulus = 10e9;
  spec.damping = 1e-3;
  const double tilt = 3.0 * std::numbers::pi / 180.0;
  spec.base_direction = Eigen::Vector3d(std::cos(tilt), std::sin(tilt), 0.0);
  RodSimulator sim(spec);
  const double R = 1.5e-3;
  sim.add_external(
      std::make_shared<ExternalForceFunction>([R, k, conservative](const RodView& rod, ForceAccumulator& out) {
        Eigen::Matrix3d P = Eigen::Matrix3d::Identity();
        P(0, 0) = 0.0;
        for (int i = 0; i < rod.first_clamped_vertex; ++i) {
          const Eigen::Vector3d p = rod.position(i);
          const Eigen::Vector3d radial(0.0, p.y(), p.z());
          const double r = radial.norm();
          if (r <= R) continue;
          const Eigen::Vector3d n = radial / r;
          if (conservative) {
            out.add_conservative_force(i, -k * (r - R) * n);
            out.add_energy(0.5 * k * (r - R) * (r - R));
          } else {
            out.add_force(i, -k * (r - R) * n);
          }
          out.add_position_jacobian(i, -k * n * n.transpose() - k * (r - R) / r * (P - n * n.transpose()));
        }
      }));
  sim.set_insertion_speed(0.05);
  sim.set_rotation_speed(2.0 * std::numbers::pi);
  TubeRun run;
  flowire::testing::ExpectWarnings quiet;  // the plain-force run may warn
  for (int i = 0; i < 60; ++i) {
    const StepReport r = sim.step(1.0 / 60.0);
    run.converged += r.converged() ? 1 : 0;
    run.cuts += r.line_search_cuts;
    run.iterations += r.newton_iterations;
    for (int v = 0; v < sim.first_clamped_vertex(); ++v)
      run.worst = std::max(run.worst, std::hypot(sim.positions()[v].y(), sim.positions()[v].z()));
  }
  return run;
}

TEST(RodDynamics, ConservativeExternalEnergyKeepsStiffContactLineSearchExact) {
  // With its potential reported, a stiff penalty (k = 10⁶ N/m) is measured exactly by the
  // line search: every step converges and the search needs no more cuts than when the
  // same force is treated as a non-conservative load (trapezoidal work along the ray).
  const double k = 1e6;
  const TubeRun with_energy = stiff_tube_run(true, k);
  const TubeRun without = stiff_tube_run(false, k);
  EXPECT_EQ(with_energy.converged, 60);
  EXPECT_LE(with_energy.cuts, without.cuts);
  EXPECT_LT(with_energy.worst, 1.5e-3 + 2e-5);  // penetration ~ F/k, a few µm
}

TEST(RodDynamics, NonConvergenceIsReportedNotSilent) {
  RodSimulator sim(unit_rod_spec(30));
  sim.settings().max_static_iterations = 1;
  sim.set_tip_force({0.0, 10.0, 0.0});
  flowire::testing::ExpectWarnings warnings;
  const StepReport r = sim.solve_static();
  EXPECT_FALSE(r.converged());
  EXPECT_EQ(r.status, SolveStatus::MaxIterations);
  EXPECT_TRUE(warnings.contains("static solve"));
  EXPECT_EQ(sim.last_report().status, SolveStatus::MaxIterations);
}

TEST(RodDynamics, InvalidInputIsAnError) {
  WireSpec spec;
  spec.length = -1.0;
  EXPECT_THROW(RodSimulator{spec}, flowire::Error);
  RodSimulator sim(unit_rod_spec(10));
  EXPECT_THROW(sim.step(0.0), flowire::Error);
  EXPECT_THROW((void)parse_tip_shape("hook"), flowire::Error);
  EXPECT_EQ(parse_tip_shape("j"), TipShape::J);
  EXPECT_EQ(parse_integrator("implicit_midpoint"), Integrator::ImplicitMidpoint);
  EXPECT_THROW((void)parse_integrator("rk4"), flowire::Error);
}

}  // namespace
}  // namespace flowire::rod
