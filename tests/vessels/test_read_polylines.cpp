// Plain polylines (read_polylines.cpp): cells joined at shared point ids and at repeated
// coordinates, two-point cells chained, a closed ring a loop; trees written one polyline per
// branch keep each branch's own radius, ends that differ by rounding are one node and a real gap
// is still an error; the real BlueFern coronary trees (skipped, saying so, where ../shared is
// absent).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "flowire/vessels/io.hpp"
#include "reader_test_util.hpp"

namespace flowire::vessels {
namespace {

using flowire::testing::scratch_dir;
using namespace flowire::vessels::test;

TEST_F(ReadersWithVtk, PlainPolylinesWithRadiusAreJoinedAtSharedPoints) {
  // A tree of three polylines: cell 1 shares the end point id of cell 0, cell 2 repeats its
  // coordinates under a new id. Array named "Radius" (any case is accepted).
  TestPoly p;
  std::vector<double> r;
  auto pts = [&](const std::vector<Vec3>& xs, double radius) {
    std::vector<long long> ids;
    for (const auto& x : xs) {
      ids.push_back(static_cast<long long>(p.points.size()));
      p.points.push_back(x);
      r.push_back(radius);
    }
    return ids;
  };
  auto c0 = pts(line_points(Vec3(0, 0, 0), Vec3(0.05, 0, 0), 0.01), 0.004);
  auto c1 = pts(line_points(Vec3(0.05, 0, 0), Vec3(0.08, 0.03, 0), 0.01, false), 0.003);
  c1.insert(c1.begin(), c0.back());
  auto c2 = pts(line_points(Vec3(0.05, 0, 0), Vec3(0.08, -0.03, 0), 0.01), 0.002);
  p.lines = {c0, c1, c2};
  p.point_data.push_back({"Radius", r});
  const auto dir = scratch_dir("io_plain");
  const auto file = write_file(dir, "plain.vtp", vtp_text(p));
  const auto net = read_network(file);
  const auto c = net.counts();
  EXPECT_EQ(c.branches, 3);
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
  EXPECT_NEAR(c.total_length, 0.05 + 2 * std::sqrt(2.0) * 0.03, 1e-12);
  EXPECT_NEAR(c.radius_min, 0.002, 1e-15);
  EXPECT_NEAR(c.radius_max, 0.004, 1e-15);
}

TEST_F(ReadersWithVtk, TwoPointLineCellsAreChainedIntoBranches) {
  TestPoly p;
  std::vector<double> r;
  for (int i = 0; i <= 20; ++i) {
    p.points.emplace_back(0.001 * i, 0, 0);
    r.push_back(0.002);
  }
  for (long long i = 0; i < 20; ++i) p.lines.push_back({i, i + 1});
  p.point_data.push_back({"radii", r});
  const auto file = write_file(scratch_dir("io_soup"), "soup.vtp", vtp_text(p));
  ReadOptions opt;
  opt.build.max_segment_length = 0.0;
  const auto cl = read_centerlines(file, opt);
  ASSERT_EQ(cl.branches.size(), 1u);
  EXPECT_EQ(cl.branches[0].points.size(), 21u);
  const auto c = read_network(file, opt).counts();
  EXPECT_EQ(c.segments, 1);
  EXPECT_NEAR(c.total_length, 0.02, 1e-15);
}

TEST_F(ReadersWithVtk, ClosedRingIsALoopOfTwoBranches) {
  // One closed polyline cell (last id = first id) plus a feeding vessel: one loop.
  TestPoly p;
  std::vector<double> r;
  for (int i = 0; i < 12; ++i) {
    const double a = 2 * std::numbers::pi * i / 12;
    p.points.emplace_back(0.01 * std::cos(a), 0.01 * std::sin(a), 0);
    r.push_back(0.001);
  }
  p.points.emplace_back(0.03, 0, 0);
  r.push_back(0.002);
  std::vector<long long> ring;
  for (long long i = 0; i < 12; ++i) ring.push_back(i);
  ring.push_back(0);
  p.lines = {ring, {12, 0}};
  p.point_data.push_back({"radius", r});
  const auto file = write_file(scratch_dir("io_ring"), "ring.vtp", vtp_text(p));
  const auto c = read_network(file).counts();
  EXPECT_EQ(c.loops, 1);
  EXPECT_EQ(c.ends, 1);
  EXPECT_EQ(c.branches, 3);
  EXPECT_EQ(c.components, 1);
}

// ---------------------------------------------------------------------------------------
// Trees written one polyline per branch, as a VTK writer or VMTK's branch export does: every
// branch carries its own radius, the junction point is repeated at the start of each daughter.

struct SplitTree {
  TestPoly poly;
  std::vector<double> branch_radius;  // per line cell
};

/// A Y (parent r0, daughters r1 and r2) as three polylines with their own point ids. The
/// parent's points are a + (b − a)·i/n, as writers compute them; `gap` moves each daughter's
/// first point away from b by that vector.
SplitTree split_y(double r0, double r1, double r2, const Vec3& gap = Vec3::Zero()) {
  SplitTree t;
  std::vector<double> r;
  const Vec3 a(0.0, 0.0, 0.0), b(0.0137, 0.0011, -0.0023);
  auto branch = [&](const Vec3& from, const Vec3& to, double radius, int n) {
    std::vector<long long> ids;
    for (int i = 0; i <= n; ++i) {
      ids.push_back(static_cast<long long>(t.poly.points.size()));
      t.poly.points.push_back(from + (to - from) * (static_cast<double>(i) / n));
      r.push_back(radius);
    }
    t.poly.lines.push_back(ids);
    t.branch_radius.push_back(radius);
  };
  branch(a, b, r0, 7);
  branch(b + gap, b + Vec3(0.011, 0.007, 0.001), r1, 5);
  branch(b + gap, b + Vec3(0.009, -0.006, 0.002), r2, 3);
  t.poly.point_data.push_back({"radius", r});
  return t;
}

TEST(ReadSplitPolylines, EverySegmentTakesTheRadiusOfItsOwnBranch) {
  const auto t = split_y(2e-3, 1.6e-3, 1.1e-3);
  const auto file = write_file(scratch_dir("io_split_radius"), "y.vtk", legacy_text(t.poly));
  ReadOptions opt;
  opt.build.max_segment_length = 2e-3;
  const auto net = read_network(file, opt);
  const auto c = net.counts();
  ASSERT_EQ(c.branches, 3);
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
  for (int s = 0; s < net.num_segments(); ++s) {
    const auto& seg = net.segment(s);
    // The branch of a segment: the line cell whose straight line holds its midpoint.
    const Vec3 mid = 0.5 * (net.node(seg.node_from) + net.node(seg.node_to));
    int cell = -1;
    for (size_t k = 0; k < t.poly.lines.size(); ++k) {
      const Vec3 p = t.poly.points[static_cast<size_t>(t.poly.lines[k].front())];
      const Vec3 q = t.poly.points[static_cast<size_t>(t.poly.lines[k].back())];
      if ((mid - p).cross(q - p).norm() <= 1e-12 * (q - p).norm() * (q - p).norm()) cell = static_cast<int>(k);
    }
    ASSERT_GE(cell, 0) << "segment " << s;
    const double r = t.branch_radius[static_cast<size_t>(cell)];
    EXPECT_DOUBLE_EQ(seg.radius, r) << "segment " << s;
    EXPECT_DOUBLE_EQ(seg.radius_from, r) << "segment " << s;
    EXPECT_DOUBLE_EQ(seg.radius_to, r) << "segment " << s;
  }
}

TEST(ReadSplitPolylines, EndsThatDifferByRoundingAreOneNode) {
  // The daughters start one unit in the last place away from the parent's end, on every
  // axis: what two writers computing the same point in different orders produce.
  const Vec3 b(0.0137, 0.0011, -0.0023);
  const Vec3 ulp(std::nextafter(b.x(), 1.0) - b.x(), std::nextafter(b.y(), 1.0) - b.y(),
                 std::nextafter(b.z(), 1.0) - b.z());
  for (const Vec3& gap : {ulp, Vec3(-ulp), Vec3(3.0 * ulp)}) {
    const auto t = split_y(2e-3, 1.6e-3, 1.1e-3, gap);
    const auto file = write_file(scratch_dir("io_split_rounding"), "y.vtk", legacy_text(t.poly));
    const auto c = read_network(file).counts();
    EXPECT_EQ(c.components, 1);
    EXPECT_EQ(c.junctions, 1);
    EXPECT_EQ(c.ends, 3);
    EXPECT_EQ(c.branches, 3);
  }
}

TEST(ReadSplitPolylines, ARealGapIsStillAnError) {
  // 1% of the smaller daughter's radius is a gap, not rounding: one clear error naming the pieces.
  const auto t = split_y(2e-3, 1.6e-3, 1.1e-3, Vec3(0.0, 1.1e-5, 0.0));
  const auto file = write_file(scratch_dir("io_split_gap"), "y.vtk", legacy_text(t.poly));
  const auto msg = error_of([&] { (void)read_network(file); });
  EXPECT_CONTAINS(msg, "y.vtk");
  EXPECT_CONTAINS(msg, "disconnected pieces");
}

TEST(RealData, BluefernCoronaryTree227AHasThreeBifurcations) {
  FLOWIRE_REQUIRE_SHARED("data/real/bluefern-coronary-centerlines/227A_Centreline.vtk");
  const auto c = read_real("bluefern-coronary-centerlines/227A_Centreline.vtk", "mm").counts();
  RecordProperty("counts", describe(c));
  EXPECT_EQ(c.branches, 7);
  EXPECT_EQ(c.junctions, 3);
  EXPECT_EQ(c.ends, 5);
  EXPECT_EQ(c.loops, 0);
  // Segments are chords of the curved lines: a little shorter than the polylines.
  EXPECT_NEAR(c.total_length, (11.6 + 34.5 + 93.5 + 98.5 + 20.3 + 96.1 + 42.2) * 1e-3, 0.01);
  ReadOptions opt;
  opt.length_unit = "mm";
  const auto cl = read_centerlines(real("bluefern-coronary-centerlines/227A_Centreline.vtk"), opt);
  std::vector<double> lengths;
  for (const auto& b : cl.branches) {
    double len = 0.0;
    for (size_t i = 1; i < b.points.size(); ++i) len += (b.points[i] - b.points[i - 1]).norm();
    lengths.push_back(len * 1e3);
  }
  std::sort(lengths.begin(), lengths.end());
  const std::vector<double> expected{11.6, 20.3, 34.5, 42.2, 93.5, 96.1, 98.5};
  ASSERT_EQ(lengths.size(), expected.size());
  for (size_t k = 0; k < expected.size(); ++k) EXPECT_NEAR(lengths[k], expected[k], 0.06);
  EXPECT_GE(c.radius_min, 0.5e-3 - 1e-9);
  EXPECT_LE(c.radius_max, 2.501e-3);
  expect_physiological(c);
}

TEST(RealData, BluefernCoronaryTree721AHasOneBifurcation) {
  FLOWIRE_REQUIRE_SHARED("data/real/bluefern-coronary-centerlines/721A_Centreline.vtk");
  const auto c = read_real("bluefern-coronary-centerlines/721A_Centreline.vtk", "mm").counts();
  RecordProperty("counts", describe(c));
  EXPECT_EQ(c.branches, 3);
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
  EXPECT_NEAR(c.total_length, (54.3 + 77.1 + 40.4) * 1e-3, 4e-3);
  EXPECT_GE(c.radius_min, 0.5e-3 - 1e-9);
  EXPECT_LE(c.radius_max, 2.563e-3);
}

}  // namespace
}  // namespace flowire::vessels
