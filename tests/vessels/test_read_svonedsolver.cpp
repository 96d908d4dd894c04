// svOneDSolver input decks (read_svonedsolver.cpp): a small deck's segments joined at its JOINT
// with the deck's lengths and tapers in metres; bad decks give one error naming the file and
// line; the real aorto-femoral and left coronary decks (skipped, saying so, where ../shared is
// absent).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "flowire/vessels/io.hpp"
#include "reader_test_util.hpp"

namespace flowire::vessels {
namespace {

using flowire::testing::scratch_dir;
using namespace flowire::vessels::test;

TEST(ReadSvOneD, DeckSegmentsJoinedAtTheJoint) {
  const auto file = write_file(scratch_dir("io_oned"), "deck.in", small_deck());
  ReadOptions opt;
  opt.build.max_segment_length = 0.0;
  opt.build.radius_change = 0.0;
  const auto net = read_network(file, opt);
  const auto c = net.counts();
  EXPECT_EQ(c.segments, 3);
  EXPECT_EQ(c.nodes, 4);  // node 5 is merged into node 1, node 9 is unused
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
  EXPECT_NEAR(c.total_length, (2.0 + 3.0 + 2.7) * 1e-2, 1e-15);  // deck lengths, cm -> m
  const auto r = [](double area_cm2) { return std::sqrt(area_cm2 / std::numbers::pi) * 1e-2; };
  // Each segment's radius is the mean of its end radii.
  EXPECT_NEAR(net.segment(0).radius, 0.5 * (r(1.0) + r(0.8)), 1e-15);
  EXPECT_NEAR(net.segment(2).radius, 0.5 * (r(0.2) + r(0.1)), 1e-15);
  EXPECT_EQ(net.branch(0).name, "main.1");  // main is cut at the junction
  EXPECT_EQ(net.branch(1).name, "main.2");
  EXPECT_EQ(net.branch(2).name, "side");
  // The daughter starts at the parent's node 1.
  EXPECT_EQ(net.segment(2).node_from, net.segment(0).node_to);
  EXPECT_LT((net.node(net.segment(2).node_from) - Vec3(0, 0, -0.02)).norm(), 1e-15);
  // Split further by max_segment_length (1 cm): 2 + 3 + 3 pieces, same total length.
  opt.build.max_segment_length = 0.01;
  const auto fine = read_network(file, opt).counts();
  EXPECT_EQ(fine.segments, 8);
  EXPECT_NEAR(fine.total_length, c.total_length, 1e-15);
  const auto cl = read_centerlines(file);
  ASSERT_EQ(cl.branches.size(), 3u);
  EXPECT_NEAR(cl.branches[0].radii[0], r(1.0), 1e-15);
}

TEST(ReadBadInput, SvOneDErrorsNameFileAndLine) {
  const auto dir = scratch_dir("io_bad_oned");
  const auto deck = small_deck();
  struct Case {
    std::string name, text, expected;
  };
  auto replace = [&](const std::string& from, const std::string& to) {
    auto s = deck;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  std::vector<Case> cases{
      {"empty.in", "", "the file is empty"},
      {"zero_area.in", small_deck("0.0"), "deck.in"},
      {"nan_node.in", replace("NODE 6 2.0", "NODE 6 nan"), "NODE 6: coordinate is not finite"},
      {"missing_node.in", replace("0 1 1.0 0.8", "0 7 1.0 0.8"), "SEGMENT main_0: node 7 is not defined"},
      {"self_loop.in", replace("0 1 1.0 0.8", "1 1 1.0 0.8"), "SEGMENT main_0 starts and ends at node 1 (self-loop)"},
      {"dup_node.in", replace("NODE 9 9.0", "NODE 2 9.0"), "NODE 2 is defined twice"},
      {"no_segments.in", "NODE 0 0 0 0\n", "no SEGMENT cards"},
      {"bad_joint.in", replace("JOINTOUTLET OUT1 2 1 2", "JOINTOUTLET OUT1 2 1 42"), "segment 42 is not defined"},
      {"short.in", replace("SEGMENT side_0 2 2.7 10 5 6 0.2 0.1", "SEGMENT side_0 2 2.7 10 5"),
       "short.in:11: SEGMENT side_0 inlet area: 'MAT1' is not a number"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const auto file = write_file(dir, c.name, c.text);
    const auto msg = error_of([&] { (void)read_network(file); });
    EXPECT_CONTAINS(msg, c.name == "zero_area.in"
                             ? std::string("zero_area.in:11: SEGMENT side_0: area 0 is not positive")
                             : c.expected);
    EXPECT_CONTAINS(msg, file);
  }
}

TEST(RealData, SvOneDAortoFemoralDeckHasNineOutlets) {
  FLOWIRE_REQUIRE_SHARED("data/real/svonedsolver-aortofemoral-coronary/12_AortoFem_Pulse_R.in");
  for (const char* name : {"12_AortoFem_Pulse_R.in", "14_AortoFem_Pulse_RCR.in"}) {
    SCOPED_TRACE(name);
    ReadOptions opt;  // the deck is CGS: cm by declaration
    opt.build.max_segment_length = 0.0;
    opt.build.radius_change = 0.0;
    const auto net = read_network(real(std::string("svonedsolver-aortofemoral-coronary/") + name), opt);
    const auto c = net.counts();
    RecordProperty("counts", describe(c));
    EXPECT_EQ(c.segments, 124);
    EXPECT_EQ(c.nodes, 125);  // a tree: one node more than segments
    EXPECT_EQ(c.ends, 10);    // 1 inlet + 9 outlets
    // 8 branching links at 7 joints: J9 (aorta_8 -> aorta_9, celiac trunk, superior mesenteric)
    // is a node of degree 4.
    EXPECT_EQ(c.junctions, 7);
    int degree4 = 0;
    for (int i = 0; i < net.num_nodes(); ++i) degree4 += net.degree(i) == 4;
    EXPECT_EQ(degree4, 1);
    EXPECT_EQ(c.loops, 0);
    EXPECT_EQ(c.components, 1);
    EXPECT_NEAR(c.total_length, 1.075, 0.001);
    EXPECT_GE(c.radius_min, 1.85e-3 * 0.99);
    EXPECT_LE(c.radius_max, 9.23e-3 * 1.01);
    expect_physiological(c);
  }
}

TEST(RealData, SvOneDLeftCoronaryDeckHasSixOutlets) {
  FLOWIRE_REQUIRE_SHARED(
      "data/real/svonedsolver-aortofemoral-coronary/Left_coronary_inlet_pressure_wave_outlet_coronary.in");
  ReadOptions opt;
  opt.build.max_segment_length = 0.0;
  opt.build.radius_change = 0.0;
  const auto net = read_network(
      real("svonedsolver-aortofemoral-coronary/Left_coronary_inlet_pressure_wave_outlet_coronary.in"), opt);
  const auto c = net.counts();
  RecordProperty("counts", describe(c));
  EXPECT_EQ(c.segments, 86);
  EXPECT_EQ(c.ends, 7);  // 1 inlet + 6 outlets
  EXPECT_EQ(c.junctions, 5);
  EXPECT_EQ(c.loops, 0);
  EXPECT_NEAR(c.total_length, 0.413, 0.001);
  EXPECT_GE(c.radius_min, 0.60e-3 * 0.99);
  EXPECT_LE(c.radius_max, 2.62e-3 * 1.01);
  // Coronary radii are below the 0.3 mm floor only if the deck is misread.
  expect_physiological(c);
}

TEST(RealData, SvOneDDeckSplitByMaxSegmentLength) {
  FLOWIRE_REQUIRE_SHARED("data/real/svonedsolver-aortofemoral-coronary/12_AortoFem_Pulse_R.in");
  ReadOptions opt;
  opt.build.max_segment_length = 2e-3;
  const auto c = read_network(real("svonedsolver-aortofemoral-coronary/12_AortoFem_Pulse_R.in"), opt).counts();
  EXPECT_GT(c.segments, 124);
  EXPECT_EQ(c.ends, 10);
  EXPECT_EQ(c.junctions, 7);
  EXPECT_NEAR(c.total_length, 1.075, 0.001);
  const auto cl = read_centerlines(real("svonedsolver-aortofemoral-coronary/12_AortoFem_Pulse_R.in"));
  EXPECT_EQ(static_cast<int>(cl.branches.size()), c.branches);
}

}  // namespace
}  // namespace flowire::vessels
