// RodModel from WireSpec: material along the arc length (soft tip, taper), rest
// curvature of pre-shaped tips, and the initial layout of the rest shape.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "flowire/common/error.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire_test.hpp"

namespace flowire::rod {
namespace {

WireSpec tipped(TipShape shape, double angle) {
  WireSpec spec;
  spec.length = 0.2;
  spec.segment_length = 5e-4;
  spec.radius = 4.45e-4;
  spec.youngs_modulus = 67e9;
  spec.tip.length = 0.03;
  spec.tip.youngs_modulus = 5e9;
  spec.tip.radius = 2e-4;
  spec.tip.shape = shape;
  spec.tip.angle = angle;
  spec.tip.bend_radius = 0.004;
  return spec;
}

TEST(RodModel, SofterThinnerTipAndShaftStiffness) {
  const RodModel m = RodModel::from_spec(tipped(TipShape::Straight, 0.0));
  const double I_shaft = std::numbers::pi * std::pow(4.45e-4, 4) / 4.0;
  const double I_tip = std::numbers::pi * std::pow(2e-4, 4) / 4.0;
  const int k_tip = 10;     // u = 5 mm: in the tip
  const int k_shaft = 200;  // u = 10 cm: in the shaft
  EXPECT_NEAR(m.bend_stiffness[k_tip], 5e9 * I_tip, 1e-9 * 5e9 * I_tip);
  EXPECT_NEAR(m.bend_stiffness[k_shaft], 67e9 * I_shaft, 1e-9 * 67e9 * I_shaft);
  // G from the Poisson ratio 0.3; GJ = G · 2I.
  EXPECT_NEAR(m.twist_stiffness[k_shaft], 67e9 / 2.6 * 2.0 * I_shaft, 1e-6 * m.twist_stiffness[k_shaft]);
  EXPECT_NEAR(m.stretch_stiffness[k_shaft], 67e9 * std::numbers::pi * 4.45e-4 * 4.45e-4, 1e-3);
  // Lumped masses add up to ρ × volume of the discretized grid.
  double mass = 0.0, volume = 0.0;
  for (double mk : m.mass) mass += mk;
  for (int j = 0; j + 1 < m.grid_vertices; ++j) volume += m.rho_a[j] * m.h / 6450.0;
  EXPECT_NEAR(mass, 6450.0 * volume, 1e-12);
}

TEST(RodModel, RestCurvatureIntegratesToTheTipAngle) {
  for (auto [shape, angle] :
       {std::pair{TipShape::Angled, std::numbers::pi / 4.0}, std::pair{TipShape::J, std::numbers::pi}}) {
    const RodModel m = RodModel::from_spec(tipped(shape, angle));
    double turn = 0.0;
    for (double k : m.rest_kappa1) turn += 2.0 * std::atan(0.5 * k);
    EXPECT_NEAR(turn, angle, 1e-12) << to_string(shape);
  }
}

TEST(RodModel, InitialLayoutFollowsTheRestShape) {
  // A J tip: the distal edge points back along the insertion direction.
  RodSimulator sim(tipped(TipShape::J, std::numbers::pi));
  const auto x = sim.positions();
  const Eigen::Vector3d tip_edge = (x[1] - x[0]).normalized();       // from tip toward base
  EXPECT_NEAR(tip_edge.dot(sim.model().base_direction), 1.0, 1e-6);  // tip points back
  // Its elastic energy is zero: the rest shape is stress free.
  EXPECT_LT(sim.energy().total(), 1e-18);
  // And it stays put in a static solve without loads.
  ASSERT_TRUE(sim.solve_static().converged());
  EXPECT_LT((sim.positions()[0] - x[0]).norm(), 1e-12);
}

TEST(RodModel, RejectsInvalidSpecs) {
  WireSpec bad;
  bad.radius = -1.0;
  EXPECT_THROW((void)RodModel::from_spec(bad), flowire::Error);
  WireSpec bad2;
  bad2.poisson_ratio = 0.7;
  EXPECT_THROW((void)RodModel::from_spec(bad2), flowire::Error);
  WireSpec bad3;
  bad3.inserted_length = 5.0;  // longer than the wire
  EXPECT_THROW(RodSimulator{bad3}, flowire::Error);
}

}  // namespace
}  // namespace flowire::rod
