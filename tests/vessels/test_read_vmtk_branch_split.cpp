// VMTK vmtkbranchextractor output (read_vmtk_branch_split.cpp): one branch per group, the
// daughters joined at the trunk's end through the blanked bifurcation region; the real VMTK
// abdominal aorta and SimVascular demo aorta as branch-split centerlines (skipped, saying so,
// where ../shared is absent).
#include <gtest/gtest.h>

#include <vector>

#include "flowire/vessels/io.hpp"
#include "reader_test_util.hpp"

namespace flowire::vessels {
namespace {

using flowire::testing::scratch_dir;
using namespace flowire::vessels::test;

TEST_F(ReadersWithVtk, VmtkBranchSplitCenterlinesJoinAtTheBlankedRegion) {
  // Two centerlines: trunk (group 0), bifurcation region (group 1, blanked), daughters 2 and 3.
  TestPoly p;
  std::vector<double> radius;
  std::vector<double> line_ids, tract_ids, blanking, groups;
  auto cell = [&](const std::vector<Vec3>& pts, double r, int line, int tract, int blank, int group) {
    std::vector<long long> ids;
    for (const auto& x : pts) {
      ids.push_back(static_cast<long long>(p.points.size()));
      p.points.push_back(x);
      radius.push_back(r);
    }
    p.lines.push_back(ids);
    line_ids.push_back(line), tract_ids.push_back(tract), blanking.push_back(blank), groups.push_back(group);
  };
  const Vec3 in(0, 0, 0), end_trunk(0, 0, -50), fork(0, 0, -58), left(-20, 0, -100), right(20, 0, -100);
  const Vec3 l0 = fork + (left - fork).normalized() * 5.0, r0 = fork + (right - fork).normalized() * 5.0;
  for (int line = 0; line < 2; ++line) {
    const Vec3 jitter(0, line * 0.01, 0);  // the second centerline's trunk is a slightly different copy
    auto trunk = line_points(in + jitter, end_trunk + jitter, 2.0);
    cell(trunk, 8.0, line, 0, 0, 0);
    const Vec3 d0 = line == 0 ? l0 : r0;
    std::vector<Vec3> blank{end_trunk + jitter, fork, d0};
    cell(blank, 7.0, line, 1, 1, 1);
    cell(line_points(d0, line == 0 ? left : right, 2.0), line == 0 ? 4.0 : 3.0, line, 2, 0, line == 0 ? 2 : 3);
  }
  p.point_data.push_back({"MaximumInscribedSphereRadius", radius});
  p.cell_data.push_back({"CenterlineIds", line_ids, 1, "Int32"});
  p.cell_data.push_back({"TractIds", tract_ids, 1, "Int32"});
  p.cell_data.push_back({"Blanking", blanking, 1, "Int32"});
  p.cell_data.push_back({"GroupIds", groups, 1, "Int32"});
  const auto dir = scratch_dir("io_branch_split");
  const auto path = write_file(dir, "split.vtp", vtp_text(p));
  ReadOptions opt;
  opt.length_unit = "mm";
  const auto cl = read_centerlines(path, opt);
  ASSERT_EQ(cl.branches.size(), 3u);
  EXPECT_EQ(cl.branches[0].name, "group_0");
  EXPECT_EQ(cl.branches[1].name, "group_2");
  EXPECT_EQ(cl.branches[2].name, "group_3");
  // Both daughters start where the (first centerline's) trunk ends, then run through the region.
  for (int b : {1, 2}) {
    EXPECT_LT((cl.branches[static_cast<size_t>(b)].points.front() - end_trunk * 1e-3).norm(), 1e-12);
    EXPECT_LT((cl.branches[static_cast<size_t>(b)].points[1] - fork * 1e-3).norm(), 1e-12);
  }
  EXPECT_LT((cl.branches[1].points.back() - left * 1e-3).norm(), 1e-12);
  EXPECT_LT((cl.branches[2].points.back() - right * 1e-3).norm(), 1e-12);
  EXPECT_DOUBLE_EQ(cl.branches[1].radii.back(), 4e-3);
  const auto c = read_network(path, opt).counts();
  EXPECT_EQ(c.branches, 3);
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
}

#ifdef FLOWIRE_HAVE_VTK

TEST(RealData, VmtkAbdominalAortaBranchSplitIsTheSameTree) {
  FLOWIRE_REQUIRE_SHARED("data/real/vmtk-abdominal-aorta-bifurcation/aorta-centerline-branches.vtp");
  const auto c = read_real("vmtk-abdominal-aorta-bifurcation/aorta-centerline-branches.vtp", "mm").counts();
  RecordProperty("counts", describe(c));
  EXPECT_EQ(c.branches, 3);  // groups 0, 2, 3; the blanked group 1 is the junction region
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
  EXPECT_EQ(c.loops, 0);
  EXPECT_GT(c.total_length, 0.0778);
  EXPECT_LT(c.total_length, 0.0778 + 0.0762 - 0.01);
  EXPECT_GE(c.radius_min, 2.77e-3);
  EXPECT_LE(c.radius_max, 7.58e-3);
}

TEST(RealData, SimVascularDemoBranchSplitCenterlines) {
  FLOWIRE_REQUIRE_SHARED("data/real/simvascular-demo-aorta-iliac/demo-centerlines.vtp");
  const auto c = read_real("simvascular-demo-aorta-iliac/demo-centerlines.vtp", "cm").counts();
  RecordProperty("counts", describe(c));
  EXPECT_EQ(c.branches, 3);
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
  EXPECT_GT(c.total_length, 0.43);
  EXPECT_LT(c.total_length, 0.86);
  EXPECT_GE(c.radius_min, 4.4e-3);
  EXPECT_LE(c.radius_max, 12.7e-3);
}

#endif  // FLOWIRE_HAVE_VTK

}  // namespace
}  // namespace flowire::vessels
