// The network cut at a lumen's caps (flow/fem/src/cap_cut.cpp): where the cut lands on a
// tapered tube (inside a segment, beyond the centerline's end, at the inlet), what the cut network's
// resistance is against the frustum law integrated over the kept length, a Y cut at its three ends
// with the junction untouched, the boundary values taken along, and the caps it refuses.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/flow/fem/boundary_values.hpp"
#include "flowire/flow/fem/cap_cut.hpp"
#include "flowire/flow/solver.hpp"

namespace flowire::flow::fem {
namespace {

using vessels::Branch;
using vessels::Segment;

constexpr double kMm = 1e-3;

/// A tube along x from 0 to 10 mm in five 2 mm segments, radius 2 mm at x = 0 falling linearly to
/// 1 mm at x = 10 mm (r(x) = 2 − x/10 in mm).
Network tapered_tube() {
  std::vector<Vec3> nodes;
  std::vector<Segment> segs;
  Branch br{"tube", {}, {}};
  for (int i = 0; i <= 5; ++i) {
    nodes.emplace_back(2.0 * i * kMm, 0.0, 0.0);
    br.nodes.push_back(i);
  }
  auto r = [](double x_mm) { return (2.0 - x_mm / 10.0) * kMm; };
  for (int i = 0; i < 5; ++i) {
    Segment s;
    s.node_from = i;
    s.node_to = i + 1;
    s.radius_from = r(2.0 * i);
    s.radius_to = r(2.0 * (i + 1));
    s.radius = 0.5 * (s.radius_from + s.radius_to);
    s.length = 2.0 * kMm;
    s.branch = 0;
    segs.push_back(s);
    br.segments.push_back(i);
  }
  return Network::from_graph(nodes, segs, {br}, "tube");
}

LumenCap cap_at(int node, double x_mm, double normal_x) {
  LumenCap c;
  c.node = node;
  c.centroid = Vec3(x_mm * kMm, 0.0, 0.0);
  c.normal = Vec3(normal_x, 0.0, 0.0);
  return c;
}

double total_length(const Network& n) {
  double l = 0.0;
  for (const auto& s : n.segments()) l += s.length;
  return l;
}

double series_resistance(const Network& n, double eta) {
  double r = 0.0;
  for (const auto& s : n.segments()) r += flow::segment_resistance(eta, s);
  return r;
}

TEST(CapCut, ACapInsideASegmentEndsTheTubeThereWithItsRadius) {
  const Network net = tapered_tube();
  const std::vector<LumenCap> caps{cap_at(0, 0.0, -1.0), cap_at(5, 7.0, 1.0)};
  const CapCut cut = cut_at_caps(net, caps, "tube.vtp");
  ASSERT_EQ(cut.network.num_nodes(), 5);  // the node at 8 mm is beyond the cap
  EXPECT_EQ(cut.node[4], -1);
  EXPECT_EQ(cut.node[5], 4);  // the end keeps its identity, moved to the cap
  EXPECT_NEAR(cut.network.node(4).x(), 7.0 * kMm, 1e-15);
  EXPECT_NEAR(total_length(cut.network), 7.0 * kMm, 1e-15);
  EXPECT_NEAR(cut.cut_length[1], 3.0 * kMm, 1e-15);
  EXPECT_NEAR(cut.cut_length[0], 0.0, 1e-15);  // the inlet cap lies on the first node
  const auto& last = cut.network.segment(cut.network.num_segments() - 1);
  EXPECT_NEAR(last.radius_to, 1.3 * kMm, 1e-15);
  EXPECT_NEAR(last.length, 1.0 * kMm, 1e-15);
  // The cut tube's resistance is the frustum law over 0..7 mm: 8η/π ∫ r⁻⁴ dx with r = 2 − x/10 mm.
  const double eta = 3.5e-3;
  auto exact = [&](double a_mm, double b_mm) {  // ∫ (2 − x/10)⁻⁴ dx = (10/3)[(2 − x/10)⁻³] in mm units
    const double ra = 2.0 - a_mm / 10.0, rb = 2.0 - b_mm / 10.0;
    return 8.0 * eta / std::numbers::pi * (10.0 / 3.0) * (std::pow(rb, -3) - std::pow(ra, -3)) / std::pow(kMm, 3);
  };
  EXPECT_NEAR(series_resistance(cut.network, eta) / exact(0.0, 7.0), 1.0, 1e-12);
  EXPECT_EQ(cut.network.branch(0).nodes.size(), cut.network.branch(0).segments.size() + 1);
}

TEST(CapCut, ACapBeyondTheCenterlinesEndLengthensTheLastSegmentAlongItsTaper) {
  const Network net = tapered_tube();
  const std::vector<LumenCap> caps{cap_at(0, -0.5, -1.0), cap_at(5, 11.0, 1.0)};
  const CapCut cut = cut_at_caps(net, caps, "tube.vtp");
  ASSERT_EQ(cut.network.num_nodes(), 6);
  EXPECT_NEAR(cut.cut_length[0], -0.5 * kMm, 1e-15);
  EXPECT_NEAR(cut.cut_length[1], -1.0 * kMm, 1e-15);
  EXPECT_NEAR(total_length(cut.network), 11.5 * kMm, 1e-15);
  EXPECT_NEAR(cut.network.node(0).x(), -0.5 * kMm, 1e-15);
  EXPECT_NEAR(cut.network.segment(0).radius_from, 2.05 * kMm, 1e-15);
  EXPECT_NEAR(cut.network.segment(4).radius_to, 0.9 * kMm, 1e-15);
}

TEST(CapCut, AnOutletCutInsideItsBranchCarriesTheWholeDropOfTheCutTube) {
  // Pressure 100 Pa at the inlet, 0 at the outlet cap: the cut network's outlet flow is the drop
  // over the frustum resistance of the kept tube, and its node pressures fall along it.
  const Network net = tapered_tube();
  const std::vector<LumenCap> caps{cap_at(0, 1.0, -1.0), cap_at(5, 9.0, 1.0)};
  const CapCut cut = cut_at_caps(net, caps, "tube.vtp");
  BoundaryValues bv;
  bv.inlet_node = 0;
  bv.inlet_pressure = 100.0;
  bv.outlet_pressures = {{5, 0.0}};
  const BoundaryValues on_cut = renumbered(bv, net, cut.node);
  EXPECT_EQ(on_cut.inlet_node, cut.node[0]);
  EXPECT_EQ(on_cut.outlet_pressures[0].first, cut.node[5]);
  const NetworkFlow f = network_flow(cut.network, on_cut);
  const double eta = on_cut.viscosity;
  EXPECT_NEAR(f.segment_flow[0] * series_resistance(cut.network, eta) / 100.0, 1.0, 1e-10);
  EXPECT_NEAR(total_length(cut.network), 8.0 * kMm, 1e-15);
  for (int n = 1; n < cut.network.num_nodes(); ++n)
    EXPECT_LT(f.node_pressure[static_cast<size_t>(n)], f.node_pressure[static_cast<size_t>(n - 1)]);
}

TEST(CapCut, AYIsCutAtItsThreeEndsAndKeepsItsJunction) {
  // Parent along x to the junction at the origin, daughters at ±45° in the xy plane, 3 segments each.
  std::vector<Vec3> nodes{Vec3::Zero()};
  std::vector<Segment> segs;
  std::vector<Branch> brs;
  const Vec3 dirs[3] = {Vec3(-1, 0, 0), Vec3(1, 1, 0).normalized(), Vec3(1, -1, 0).normalized()};
  for (int b = 0; b < 3; ++b) {
    Branch br{std::string(1, static_cast<char>('a' + b)), {0}, {}};
    for (int i = 1; i <= 3; ++i) {
      nodes.push_back(dirs[b] * (4.0 * i * kMm));
      Segment s;
      s.node_from = br.nodes.back();
      s.node_to = static_cast<int>(nodes.size()) - 1;
      s.radius = b == 0 ? 2.0 * kMm : 1.5 * kMm;
      s.length = 4.0 * kMm;
      s.branch = b;
      br.segments.push_back(static_cast<int>(segs.size()));
      br.nodes.push_back(s.node_to);
      segs.push_back(s);
    }
    brs.push_back(br);
  }
  const Network net = Network::from_graph(nodes, segs, brs, "y");
  // Caps 10 mm along each branch, facing out: each end branch loses 2 mm (half its last segment).
  std::vector<LumenCap> caps;
  for (int b = 0; b < 3; ++b) {
    LumenCap c;
    c.node = 3 * b + 3;
    c.centroid = dirs[b] * (10.0 * kMm);
    c.normal = dirs[b];
    caps.push_back(c);
  }
  const CapCut cut = cut_at_caps(net, caps, "y.vtp");
  EXPECT_EQ(cut.network.num_nodes(), net.num_nodes());
  EXPECT_EQ(cut.network.degree(cut.node[0]), 3);
  for (int b = 0; b < 3; ++b) {
    EXPECT_NEAR(cut.cut_length[static_cast<size_t>(b)], 2.0 * kMm, 1e-15);
    EXPECT_NEAR(
        (cut.network.node(cut.node[static_cast<size_t>(3 * b + 3)]) - caps[static_cast<size_t>(b)].centroid).norm(),
        0.0, 1e-15);
  }
  EXPECT_NEAR(total_length(cut.network), 30.0 * kMm, 1e-14);
}

TEST(CapCut, RefusesACapBeyondTheWholeBranchOrFacingAwayNamingTheFile) {
  const Network net = tapered_tube();
  {  // the outlet cap's plane behind the inlet: every node of the branch lies beyond it
    const std::vector<LumenCap> caps{cap_at(0, 0.0, -1.0), cap_at(5, -1.0, 1.0)};
    try {
      (void)cut_at_caps(net, caps, "tube.vtp");
      FAIL() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
      EXPECT_NE(std::string(e.what()).find("tube.vtp"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("whole branch"), std::string::npos) << e.what();
    }
  }
  {  // a cap before the end, its normal pointing back into the tube
    const std::vector<LumenCap> caps{cap_at(0, 0.0, -1.0), cap_at(5, 8.0, -1.0)};
    try {
      (void)cut_at_caps(net, caps, "tube.vtp");
      FAIL() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
      EXPECT_NE(std::string(e.what()).find("faces away"), std::string::npos) << e.what();
    }
  }
}

TEST(CapCut, RenumberedRefusesABoundaryNodeThatWasCutAway) {
  const Network net = tapered_tube();
  const CapCut cut = cut_at_caps(net, std::vector<LumenCap>{cap_at(0, 0.0, -1.0), cap_at(5, 7.0, 1.0)}, "tube.vtp");
  BoundaryValues bv;
  bv.inlet_node = 0;
  bv.outlet_pressures = {{4, 0.0}};  // the node at 8 mm, beyond the cap
  EXPECT_THROW((void)renumbered(bv, net, cut.node), Error);
}

}  // namespace
}  // namespace flowire::flow::fem
