// VMTK vmtkcenterlines output (read_vmtk_paths.cpp): overlapping inlet→outlet paths merged into
// one tree: a three-outlet aorta (junctions exactly where the paths part, with a tight
// tolerance), a 64-outlet tree level by level, and the real VMTK abdominal aorta, AneuRisk
// carotid siphon and Feel++ aortic arch (skipped, saying so, where ../shared is absent).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "flowire/vessels/io.hpp"
#include "reader_test_util.hpp"

namespace flowire::vessels {
namespace {

using flowire::testing::scratch_dir;
using namespace flowire::vessels::test;

TEST_F(ReadersWithVtk, VmtkThreeOutletAortaMergesIntoOneTree) {
  const auto dir = scratch_dir("io_vmtk");
  const Aorta a;
  const auto path = write_file(dir, "aorta.vtp", vtp_text(a.vmtk()));
  ReadOptions opt;
  opt.length_unit = "mm";
  opt.build.max_segment_length = 0.01;
  const auto net = read_network(path, opt);
  const auto c = net.counts();
  EXPECT_EQ(c.ends, 4);  // 1 inlet + 3 outlets
  EXPECT_EQ(c.junctions, 2);
  EXPECT_EQ(c.branches, 5);
  EXPECT_EQ(c.loops, 0);
  EXPECT_EQ(c.components, 1);
  EXPECT_NEAR(c.total_length, a.length() * 1e-3, 0.02 * a.length() * 1e-3);
  EXPECT_NEAR(c.radius_max, 10e-3, 1e-9);
  // The inlet is the widest end, at the origin.
  EXPECT_LT(net.node(net.widest_end()).norm(), 1e-12);
  const auto ends = net.ends();
  EXPECT_EQ(ends.size(), 4u);
  int outlets_found = 0;
  for (const Vec3& o : {a.out_a, a.out_b, a.out_c})
    for (const int e : ends) outlets_found += (net.node(e) - o * 1e-3).norm() < 1e-12;
  EXPECT_EQ(outlets_found, 3);
}

TEST_F(ReadersWithVtk, VmtkPathsWithTightToleranceJoinExactlyAtTheJunctions) {
  const auto dir = scratch_dir("io_vmtk_exact");
  const Aorta a;
  const auto path = write_file(dir, "aorta.vtp", vtp_text(a.vmtk()));
  ReadOptions opt;
  opt.length_unit = "mm";
  opt.merge_tolerance = 0.01;
  opt.build.max_segment_length = 0.01;
  const auto net = read_network(path, opt);
  const auto c = net.counts();
  EXPECT_EQ(c.ends, 4);
  EXPECT_EQ(c.junctions, 2);
  EXPECT_NEAR(c.total_length, a.length() * 1e-3, 1e-9);
  std::vector<Vec3> junctions;
  for (int i = 0; i < net.num_nodes(); ++i)
    if (net.degree(i) == 3) junctions.push_back(net.node(i) * 1e3);
  ASSERT_EQ(junctions.size(), 2u);
  for (const Vec3& j : {a.j1, a.j2}) {
    const bool found = (junctions[0] - j).norm() < 1e-9 || (junctions[1] - j).norm() < 1e-9;
    EXPECT_TRUE(found) << "junction at " << j.transpose() << " mm";
  }
}

TEST_F(ReadersWithVtk, VmtkPathsOfADeepTreeMergeLevelByLevel) {
  // A planar binary tree of depth 6 (64 outlets), one VMTK-style path per outlet.
  constexpr int depth = 6;
  TestPoly p;
  std::vector<double> radius;
  for (int leaf = 0; leaf < (1 << depth); ++leaf) {
    std::vector<long long> ids;
    Vec3 x(0, 0, 0);
    double angle = -std::numbers::pi / 2;
    for (int level = 0; level <= depth; ++level) {
      if (level > 0) angle += ((leaf >> (depth - level)) & 1 ? 1.0 : -1.0) * std::numbers::pi / 6;
      const double len = 40.0 * std::pow(0.8, level), r = 5.0 * std::pow(0.8, level);
      const Vec3 y = x + len * Vec3(std::cos(angle), std::sin(angle), 0);
      for (const auto& q : line_points(x, y, 0.5, level == 0)) {
        ids.push_back(static_cast<long long>(p.points.size()));
        p.points.push_back(q);
        radius.push_back(r);
      }
      x = y;
    }
    p.lines.push_back(ids);
  }
  p.point_data.push_back({"MaximumInscribedSphereRadius", radius});
  const auto file = write_file(scratch_dir("io_vmtk_deep"), "tree.vtp", vtp_text(p));
  ReadOptions opt;
  opt.length_unit = "mm";
  const auto c = read_network(file, opt).counts();
  EXPECT_EQ(c.ends, (1 << depth) + 1);
  EXPECT_EQ(c.junctions, (1 << depth) - 1);
  EXPECT_EQ(c.branches, (1 << (depth + 1)) - 1);
  EXPECT_EQ(c.loops, 0);
}

#ifdef FLOWIRE_HAVE_VTK

TEST(RealData, VmtkAbdominalAortaCenterlinesMergeIntoOneBifurcation) {
  FLOWIRE_REQUIRE_SHARED("data/real/vmtk-abdominal-aorta-bifurcation/aorta-centerline.vtp");
  const auto net = read_real("vmtk-abdominal-aorta-bifurcation/aorta-centerline.vtp", "mm");
  const auto c = net.counts();
  RecordProperty("counts", describe(c));
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
  EXPECT_EQ(c.branches, 3);
  EXPECT_EQ(c.loops, 0);
  EXPECT_EQ(c.components, 1);
  // Two paths of 77.8 and 76.2 mm sharing the trunk: more than the longer, less than the sum.
  EXPECT_GT(c.total_length, 0.0778);
  EXPECT_LT(c.total_length, 0.0778 + 0.0762 - 0.01);
  EXPECT_GE(c.radius_min, 2.77e-3);
  EXPECT_LE(c.radius_max, 7.58e-3);
  expect_physiological(c);
}

TEST(RealData, AneuriskCarotidSiphonHasOneInletTwoOutlets) {
  FLOWIRE_REQUIRE_SHARED("data/real/aneurisk-c0015-ica-vampy/artery_centerlines.vtp");
  const auto c = read_real("aneurisk-c0015-ica-vampy/artery_centerlines.vtp", "mm", 1e-3).counts();
  RecordProperty("counts", describe(c));
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
  EXPECT_EQ(c.branches, 3);
  EXPECT_GT(c.total_length, 0.0202);
  EXPECT_LT(c.total_length, 0.0156 + 0.0202);
  EXPECT_GE(c.radius_min, 0.848e-3);
  EXPECT_LE(c.radius_max, 1.73e-3);
  expect_physiological(c);
}

#endif  // FLOWIRE_HAVE_VTK

// Legacy .vtk files are parsed without VTK.
TEST(RealData, FeelppAorticArchHasThreeSupraAorticBranches) {
  FLOWIRE_REQUIRE_SHARED("data/real/feelpp-aortic-arch/centerlinesAORTA.vtk");
  const auto net = read_real("feelpp-aortic-arch/centerlinesAORTA.vtk", "cm");
  const auto c = net.counts();
  RecordProperty("counts", describe(c));
  EXPECT_EQ(c.ends, 5);  // root, descending aorta, three branches
  EXPECT_EQ(c.junctions, 3);
  EXPECT_EQ(c.loops, 0);
  EXPECT_GT(c.total_length, 0.200);
  EXPECT_LT(c.total_length, 0.200 + 0.112 + 0.095 + 0.096);
  EXPECT_GE(c.radius_min, 2.6e-3);
  EXPECT_LE(c.radius_max, 15.4e-3);
  // The widest end is the aortic root at (12.53, 14.79, 8.54) cm.
  const Vec3 root(0.1253, 0.1479, 0.0854);
  EXPECT_LT((net.node(net.widest_end()) - root).norm(), 1e-3);
  expect_physiological(c);
}

}  // namespace
}  // namespace flowire::vessels
