// WireOcclusion (coupling/occlusion.hpp): the occupied length, the offset, and the factors
// against resistances and inertances integrated by hand along the wire.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "flowire/coupling/occlusion.hpp"
#include "flowire/flow/annulus.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/vessels/network.hpp"

namespace flowire::coupling {
namespace {

using Vec3 = Eigen::Vector3d;
constexpr double kPi = std::numbers::pi;
constexpr double kA = 0.178e-3;

struct Line {
  vessels::Network net;
  std::unique_ptr<flow::FlowSolver> flow;
};

/// Two segments of radius 1.5 mm along x: [0, 20 mm] and [20, 40 mm].
Line two_segments() {
  Line l;
  l.net = vessels::Network::from_graph({Vec3(0, 0, 0), Vec3(0.02, 0, 0), Vec3(0.04, 0, 0)},
                                       {{0, 1, 1.5e-3, 0.02, -1}, {1, 2, 1.5e-3, 0.02, -1}});
  l.flow = flow::make_solver(l.net, flow::default_spec(l.net, flow::Waveform::constant(100.0)));
  return l;
}

/// A straight wire along y = offset from x0 to x1 (tip at x1), vertex spacing h; every
/// vertex located in the segment its x lies in.
struct Wire {
  std::vector<Eigen::Vector3d> x;
  std::vector<int> segment;
  std::vector<double> radius;
};
Wire straight_wire(double x0, double x1, double offset, double h) {
  Wire w;
  const int n = static_cast<int>(std::lround((x1 - x0) / h)) + 1;
  for (int i = 0; i < n; ++i) {
    const double x = x1 - (x1 - x0) * i / (n - 1);
    w.x.emplace_back(x, offset, 0.0);
    w.segment.push_back(x < 0.02 ? 0 : 1);
  }
  w.radius.assign(static_cast<size_t>(n - 1), kA);
  return w;
}

TEST(WireOcclusion, PartOfASegmentByItsOccupiedLength) {
  Line l = two_segments();
  WireOcclusion occ(*l.flow);
  // The wire from x = 25 mm to 33 mm, coaxial, in segment 1 only.
  const Wire w = straight_wire(0.025, 0.033, 0.0, 0.5e-3);
  const auto o = occ.update(w.x, static_cast<int>(w.x.size()), w.segment, w.radius);
  EXPECT_EQ(o[0].occupied_fraction, 0.0);
  EXPECT_EQ(o[0].resistance_factor, 1.0);
  EXPECT_NEAR(o[1].occupied_fraction, 8.0 / 20.0, 1e-12);
  // Resistance: 12 mm of empty tube and 8 mm of annulus, R_annulus = R/q (per length).
  const double q = flow::annulus_flow_fraction(kA / 1.5e-3, 0.0);
  EXPECT_NEAR(o[1].resistance_factor, (12.0 + 8.0 / q) / 20.0, 1e-12);
  EXPECT_NEAR(o[1].gradient_factor, 1.0 / q, 1e-12);
  // Inertance: ρ∫dx/A with the wire's area taken out over 8 mm.
  const double area = kPi * 1.5e-3 * 1.5e-3, annulus = area - kPi * kA * kA;
  EXPECT_NEAR(o[1].inertance_factor, (12.0 / area + 8.0 / annulus) / (20.0 / area), 1e-12);
  EXPECT_EQ(occ.stats().occupied_segments, 1);
  // The wire moved on: segment 1 is released, segment 0 taken.
  const Wire w2 = straight_wire(0.002, 0.018, 0.0, 0.5e-3);
  const auto o2 = occ.update(w2.x, static_cast<int>(w2.x.size()), w2.segment, w2.radius);
  EXPECT_EQ(o2[1].resistance_factor, 1.0);
  EXPECT_EQ(o2[1].occupied_fraction, 0.0);
  EXPECT_NEAR(o2[0].occupied_fraction, 16.0 / 20.0, 1e-12);
}

TEST(WireOcclusion, OffsetSetsTheEccentricity) {
  Line l = two_segments();
  WireOcclusion occ(*l.flow);
  const double gap = 1.5e-3 - kA;
  for (double e : {0.0, 0.5, 0.95}) {
    const Wire w = straight_wire(0.021, 0.039, e * gap, 0.5e-3);
    const auto o = occ.update(w.x, static_cast<int>(w.x.size()), w.segment, w.radius);
    EXPECT_NEAR(o[1].gradient_factor, flow::annulus_resistance_factor(kA / 1.5e-3, e), 1e-9) << e;
  }
}

TEST(WireOcclusion, OnlyTheFreeVerticesAndALoopOccupiesOnce) {
  Line l = two_segments();
  WireOcclusion occ(*l.flow);
  Wire w = straight_wire(0.021, 0.039, 0.0, 0.5e-3);
  // Vertices past `free` are in the introducer: not counted.
  const auto o = occ.update(w.x, 10, w.segment, w.radius);
  EXPECT_NEAR(o[1].occupied_fraction, 9.5 * 0.5e-3 / 0.02, 1e-12);
  // A wire folded back on itself along the segment three times occupies it once.
  Wire fold;
  for (int pass = 0; pass < 3; ++pass)
    for (int i = 0; i <= 38; ++i) {
      const double x = pass % 2 == 0 ? 0.0205 + 0.0005 * i : 0.0395 - 0.0005 * i;
      fold.x.emplace_back(x, 1e-5 * pass, 0.0);
      fold.segment.push_back(1);
    }
  fold.radius.assign(fold.x.size() - 1, kA);
  const auto of = occ.update(fold.x, static_cast<int>(fold.x.size()), fold.segment, fold.radius);
  EXPECT_EQ(of[1].occupied_fraction, 1.0);
  const double q = flow::annulus_flow_fraction(kA / 1.5e-3, 0.0);
  EXPECT_NEAR(of[1].resistance_factor, 1.0 / q, 1e-3);
}

TEST(WireOcclusion, AWireTooWideForTheVesselIsTakenAtTheModelsLimit) {
  Line l = two_segments();
  WireOcclusion occ(*l.flow);
  Wire w = straight_wire(0.021, 0.039, 0.0, 0.5e-3);
  w.radius.assign(w.radius.size(), 1.45e-3);
  const auto o = occ.update(w.x, static_cast<int>(w.x.size()), w.segment, w.radius);
  EXPECT_NEAR(o[1].gradient_factor, flow::annulus_resistance_factor(kMaxOcclusionRadiusRatio, 0.0), 1e-9);
  EXPECT_TRUE(std::isfinite(o[1].inertance_factor));
  EXPECT_EQ(occ.stats().radius_ratio_clamped, 1);
}

}  // namespace
}  // namespace flowire::coupling
