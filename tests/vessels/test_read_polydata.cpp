// Which container and which centerline convention a .vtp / .vtk file is read as
// (read_polydata.cpp): the container by the file's first bytes whatever its extension, the
// convention by its arrays, in order of precedence. Each convention names its branches its own
// way (group_<GroupId>, branch_<BranchId>, branch_<k> in order), which shows which one read a file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "flowire/vessels/io.hpp"
#include "reader_test_util.hpp"

namespace flowire::vessels {
namespace {

using flowire::testing::scratch_dir;
using namespace flowire::vessels::test;

std::vector<std::string> branch_names(const Centerlines& c) {
  std::vector<std::string> out;
  for (const auto& b : c.branches) out.push_back(b.name);
  return out;
}

TEST_F(ReadersWithVtk, TheContainerIsToldByContentNotByExtension) {
  // A Y of three polylines sharing the junction's point id (mm): written as legacy text under
  // .vtp and as VTK XML under .vtk, each must be read as what it is.
  TestPoly p;
  std::vector<double> r;
  auto add = [&](const Vec3& x, double radius) {
    p.points.push_back(x);
    r.push_back(radius);
    return static_cast<long long>(p.points.size() - 1);
  };
  std::vector<long long> trunk, left, right;
  for (int i = 0; i <= 4; ++i) trunk.push_back(add(Vec3(0, 0, -5.0 * i), 3.0));
  left.push_back(trunk.back());
  right.push_back(trunk.back());
  for (int i = 1; i <= 3; ++i) left.push_back(add(Vec3(-3.0 * i, 0, -20 - 4.0 * i), 2.0));
  for (int i = 1; i <= 2; ++i) right.push_back(add(Vec3(3.0 * i, 0, -20 - 4.0 * i), 1.5));
  p.lines = {trunk, left, right};
  p.point_data.push_back({"radius", r});
  const auto dir = scratch_dir("read_polydata_container");
  ReadOptions opt;
  opt.length_unit = "mm";
  opt.build.max_segment_length = 0.0;
  opt.build.radius_change = 0.0;
  for (const auto& file : {write_file(dir, "legacy.vtp", legacy_text(p)), write_file(dir, "xml.vtk", vtp_text(p))}) {
    SCOPED_TRACE(file);
    const auto c = read_network(file, opt).counts();
    EXPECT_EQ(c.branches, 3);
    EXPECT_EQ(c.junctions, 1);
    EXPECT_EQ(c.ends, 3);
    EXPECT_EQ(c.segments, 3);
    EXPECT_NEAR(c.total_length, (20.0 + 3 * 5.0 + 2 * 5.0) * 1e-3, 1e-12);  // 3-4-5 steps of 5 mm
    EXPECT_NEAR(c.radius_max, 3e-3, 1e-15);
    const auto cl = read_centerlines(file, opt);
    ASSERT_EQ(cl.branches.size(), 3u);
    double r_min = 1.0;
    for (const auto& b : cl.branches)
      for (const double x : b.radii) r_min = std::min(r_min, x);
    EXPECT_NEAR(r_min, 1.5e-3, 1e-15);
  }
}

/// One centerline cut in two tracts (as vmtkbranchextractor cuts it) that meet at z = -10 under
/// point ids of their own, radius 1, with the arrays `point` and `cell` added.
TestPoly two_tracts(const std::vector<TestArray>& point, const std::vector<TestArray>& cell) {
  TestPoly p;
  p.points = line_points(Vec3(0, 0, 0), Vec3(0, 0, -10), 2.0);
  p.lines.push_back({0, 1, 2, 3, 4, 5});
  for (const auto& x : line_points(Vec3(0, 0, -10), Vec3(0, 0, -20), 2.0)) p.points.push_back(x);
  p.lines.push_back({6, 7, 8, 9, 10, 11});
  p.point_data.push_back({"radius", std::vector<double>(p.points.size(), 1.0)});
  for (const auto& a : point) p.point_data.push_back(a);
  for (const auto& a : cell) p.cell_data.push_back(a);
  return p;
}

TEST_F(ReadersWithVtk, ConventionsAreToldApartByTheirArraysInOrder) {
  const auto dir = scratch_dir("read_polydata_conventions");
  const TestArray group{"GroupIds", {0, 5}, 1, "Int32"}, line{"CenterlineIds", {0, 0}, 1, "Int32"},
      tract{"TractIds", {0, 1}, 1, "Int32"};
  std::vector<double> ids(6, 4.0);  // BranchId 4 on the first tract's points, 7 on the second's
  ids.insert(ids.end(), 6, 7.0);
  const TestArray branch_ids{"BranchId", ids, 1, "Int64"};
  auto names = [&](const std::string& name, const TestPoly& p) {
    return branch_names(read_centerlines(write_file(dir, name, vtp_text(p))));
  };
  using Names = std::vector<std::string>;
  // GroupIds, CenterlineIds and TractIds: VMTK branch-split, one branch per group, even where
  // SimVascular's BranchId is there too.
  EXPECT_EQ(names("split.vtp", two_tracts({}, {group, line, tract})), (Names{"group_0", "group_5"}));
  EXPECT_EQ(names("split_and_rom.vtp", two_tracts({branch_ids}, {group, line, tract})), (Names{"group_0", "group_5"}));
  // BranchId (and no TractIds): SimVascular ROM, one branch per BranchId, named by it.
  EXPECT_EQ(names("rom.vtp", two_tracts({branch_ids}, {group, line})), (Names{"branch_4", "branch_7"}));
  // Neither, and the two cells do not overlap (they meet end to end): plain polylines, joined at
  // their common point into one branch of one radius.
  const auto plain = read_centerlines(write_file(dir, "plain.vtp", vtp_text(two_tracts({}, {group, line}))));
  ASSERT_EQ(branch_names(plain), (Names{"branch_0"}));
  EXPECT_EQ(plain.branches[0].points.size(), 11u);
  EXPECT_DOUBLE_EQ(std::abs(plain.branches[0].points.back().z() - plain.branches[0].points.front().z()), 20.0);
}

}  // namespace
}  // namespace flowire::vessels
