// Force-driven feeding (RodSimulator::set_push_force) against force balances derived by hand:
// - a straight wire pushed with F along its axis against a dead tip load Q and viscous damping
//   d per unit length: quasi-statically F = Q + d L dL/dt, so d (L² − L0²)/2 = (F − Q) t; with
//   Q > F the wire backs out along the same law (here from 5 cm to 4.5 cm);
// - a wire whose tip is held (pushed against a wall): the feed stops where the clamp's axial
//   force is F, the wire then shortened by F ℓ/(EA) over its free length ℓ.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "flowire/rod/simulator.hpp"

using flowire::rod::RodSimulator;
using flowire::rod::WireSpec;

namespace {
WireSpec straight_wire() {
  WireSpec spec;
  spec.length = 0.4;
  spec.segment_length = 2e-3;
  spec.radius = 3e-4;
  spec.youngs_modulus = 60e9;
  spec.tip.length = 0.0;
  spec.inserted_length = 0.05;
  return spec;
}
}  // namespace

TEST(ForceFeed, FeedAgainstDampingAndLoadFollowsTheForceBalance) {
  // The clamped vertices behind the entry move with the feed and carry their share of the
  // damping (about one segment's worth), an O(h) difference from the continuous balance:
  // the error is asserted to fall at first order as the segments are refined.
  const double F = 0.05, d = 20.0, dt = 1e-3, T = 0.5;
  for (const double Q : {0.0, 0.02, 0.07}) {
    std::vector<double> err;
    const std::vector<double> hs = {2e-3, 1e-3, 5e-4};
    for (const double h : hs) {
      WireSpec spec = straight_wire();
      spec.damping = d;
      spec.segment_length = h;
      RodSimulator sim(spec);
      sim.set_tip_force({-Q, 0.0, 0.0});
      sim.set_push_force(F);
      const double L0 = sim.inserted_length();
      for (int i = 0; i < static_cast<int>(std::lround(T / dt)); ++i) ASSERT_TRUE(sim.step(dt).converged()) << i;
      // By hand: d (L² − L0²)/2 = (F − Q) T.
      const double L_hand = std::sqrt(L0 * L0 + 2.0 * (F - Q) * T / d);
      const double fed_hand = L_hand - L0, fed = sim.inserted_length() - L0;
      err.push_back(std::abs(fed - fed_hand) / std::abs(fed_hand));
      // The clamp carries F at every step's end, and the speed is the balance's (F − Q)/(d L).
      EXPECT_NEAR(sim.base_force().x(), F, 1e-3 * F);
      EXPECT_NEAR(sim.force_feed_speed(), (F - Q) / (d * sim.inserted_length()),
                  2.0 * err.back() * std::abs(F - Q) / (d * sim.inserted_length()) + 1e-9);
      // Only the first step from rest may need more than half a segment.
      EXPECT_LE(sim.force_feed_unbalanced(), 1);
    }
    const double slope = std::log(err[0] / err[2]) / std::log(hs[0] / hs[2]);
    std::printf("Q = %g: relative error of the fed length %.3g %.3g %.3g, slope %.2f\n", Q, err[0], err[1], err[2],
                slope);
    EXPECT_GT(slope, 0.8) << "Q = " << Q;
    EXPECT_LT(err[2], 0.03) << "Q = " << Q;
  }
}

TEST(ForceFeed, WireAgainstAWallStopsWhereTheAxialForceIsTheApplied) {
  const double F = 0.05, dt = 1e-3;
  WireSpec spec = straight_wire();
  spec.youngs_modulus = 5e9;  // EA = 1.4 kN: a measurable shortening, buckling load 0.5 N
  spec.damping = 0.5;
  RodSimulator sim(spec);
  const auto x = sim.positions();
  sim.clamp_tip(x[0], x[1]);
  const double L0 = sim.inserted_length();
  // Rest length compressed: from the tip's clamped edge to the base clamp's first vertex
  // (the first grid point at or behind the entry).
  sim.set_push_force(F);
  double last = 0.0;
  for (int i = 0; i < 2000; ++i) {
    ASSERT_TRUE(sim.step(dt).converged()) << i;
    last = sim.inserted_length();
  }
  // Rest length compressed: from the tip's clamped edge to the base clamp's first vertex
  // (the first grid point behind the entry once anything is fed).
  const auto s0 = sim.arc_lengths();
  size_t first_clamped = 0;
  while (s0[first_clamped] > 0.0) ++first_clamped;
  const double ell = s0[1] - s0[first_clamped];
  const double EA = spec.youngs_modulus * std::numbers::pi * spec.radius * spec.radius;
  EXPECT_NEAR(last - L0, F * ell / EA, 0.03 * F * ell / EA);
  EXPECT_NEAR(sim.base_force().x(), F, 1e-3 * F);
  EXPECT_LT(std::abs(sim.force_feed_speed()), 1e-3 * F * ell / EA / dt);  // stopped
}
