// Localized helical buckling (PyElastica's HelicalBuckling case after van der Heijden et
// al. 2003; reference README "Rods"): L = 100, B = 1.345, C = 0.789, both ends clamped,
// pushed together by 3 and twisted 27 full turns → mid-span helix radius 1.500 and
// maximum tangent tilt 47.65°; the end moment and tension of that solution are
// M = 98.5415 B/L and T = 2900.99 B/L². Quasi-static continuation with static solves;
// labelled slow (800 segments).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "flowire/rod/simulator.hpp"
#include "flowire_test.hpp"

namespace flowire::rod {
namespace {

using testing::tol;

TEST(RodHelicalBuckling, LocalizedHelixMatchesVanDerHeijden) {
  const int n = 800;
  const double L = 100.0, B = 1.345, C = 0.789, D = 3.0, turns = 27.0;
  WireSpec spec;
  spec.length = L;
  spec.segments = n;
  spec.radius = 0.35;
  spec.youngs_modulus = 1e6;
  spec.tip.length = 0.0;
  spec.bending_stiffness = B;
  spec.twist_stiffness = C;
  spec.stretch_stiffness = 1e5;  // inextensible at these loads (T ≈ 0.4)
  spec.mass_per_length = 1.0;
  spec.base_normal = Eigen::Vector3d::UnitZ();
  RodSimulator sim(spec);
  const double h = L / n;
  sim.clamp_tip({L, 0.0, 0.0}, {L - h, 0.0, 0.0});
  // A tiny lateral nudge at mid-span selects the buckled branch.
  sim.add_point_force(0.5 * L, {0.0, 1e-4, 0.0});
  ASSERT_TRUE(sim.solve_static().converged());
  sim.clear_point_forces();
  // Ramp end shortening and twist together, as the reference simulation does.
  const int increments = 216;
  for (int i = 1; i <= increments; ++i) {
    const double a = static_cast<double>(i) / increments;
    sim.clamp_tip({L - a * D, 0.0, 0.0}, {L - a * D - h, 0.0, 0.0});
    sim.set_base_angle(2.0 * std::numbers::pi * turns * a);
    flowire::testing::ExpectWarnings intermediate;  // intermediate states may stall
    sim.solve_static();
  }
  ASSERT_TRUE(sim.solve_static().converged());

  const auto x = sim.positions();
  double radius = 0.0, tilt = 0.0;
  for (int k = 0; k < sim.vertex_count(); ++k) radius = std::max(radius, std::hypot(x[k].y(), x[k].z()));
  for (int j = 0; j < sim.first_clamped_vertex(); ++j) {
    const Eigen::Vector3d t = (x[j + 1] - x[j]).normalized();
    tilt = std::max(tilt, std::acos(std::min(1.0, std::abs(t.x()))));
  }
  EXPECT_NEAR(radius, 1.500, tol(0.05 * 1.500));
  EXPECT_NEAR(tilt * 180.0 / std::numbers::pi, 47.65, tol(0.05 * 47.65));
  // End loads carried by the clamp: torque about the axis and tension.
  EXPECT_NEAR(std::abs(sim.base_torque().x()), 98.5415 * B / L, tol(0.05 * 98.5415 * B / L));
  EXPECT_NEAR(std::abs(sim.base_force().x()), 2900.99 * B / (L * L), tol(0.05 * 2900.99 * B / (L * L)));
}

}  // namespace
}  // namespace flowire::rod
