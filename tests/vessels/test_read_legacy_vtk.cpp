// Legacy VTK poly data (read_legacy_vtk.cpp), parsed without VTK: VMTK paths and a tree of
// polylines written as ASCII, and a BINARY file (big-endian, the old cell layout) read exactly;
// a binary file cut short is an error, not garbage.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "flowire/vessels/io.hpp"
#include "reader_test_util.hpp"

namespace flowire::vessels {
namespace {

using flowire::testing::scratch_dir;
using namespace flowire::vessels::test;

TEST(ReadLegacyVtk, VmtkPathsAsLegacyVtkGiveTheSameTree) {
  const auto dir = scratch_dir("io_vmtk_legacy");
  const Aorta a;
  auto poly = a.vmtk();
  poly.point_data.pop_back();  // legacy SCALARS: one component
  const auto path = write_file(dir, "aorta.vtk", legacy_text(poly));
  ReadOptions opt;
  opt.length_unit = "mm";
  const auto c = read_network(path, opt).counts();
  EXPECT_EQ(c.ends, 4);
  EXPECT_EQ(c.junctions, 2);
}

TEST(ReadLegacyVtk, TreeWithRadii) {
  // Like the BlueFern coronary files: lines between bifurcations sharing end-point ids, mm.
  TestPoly p;
  std::vector<double> r;
  auto add = [&](const Vec3& x, double radius) {
    p.points.push_back(x);
    r.push_back(radius);
    return static_cast<long long>(p.points.size() - 1);
  };
  std::vector<long long> l0, l1, l2;
  for (int i = 0; i <= 10; ++i) l0.push_back(add(Vec3(i, 0, 0), 2.0));
  l1.push_back(l0.back());
  l2.push_back(l0.back());
  for (int i = 1; i <= 5; ++i) l1.push_back(add(Vec3(10 + i, i, 0), 1.5));
  for (int i = 1; i <= 7; ++i) l2.push_back(add(Vec3(10 + i, -i, 0.5 * i), 1.0));
  p.lines = {l0, l1, l2};
  p.point_data.push_back({"radii", r});
  const auto file = write_file(scratch_dir("io_legacy"), "tree.vtk", legacy_text(p));
  ReadOptions opt;
  opt.length_unit = "mm";
  opt.build.max_segment_length = 0.0;
  opt.build.radius_change = 0.0;
  const auto net = read_network(file, opt);
  const auto c = net.counts();
  EXPECT_EQ(c.branches, 3);
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
  EXPECT_EQ(c.segments, 3);
  EXPECT_NEAR(c.total_length, (10 + 5 * std::sqrt(2.0) + 7 * 1.5) * 1e-3, 1e-12);
  EXPECT_NEAR(c.radius_max, 2e-3, 1e-15);
  EXPECT_NEAR(c.radius_min, (1.0 * 7 + 2.0 * 0) / 7 * 1e-3, 0.2e-3);
}

/// Big-endian bytes of a value, as legacy BINARY files store them.
template <class T>
std::string big_endian(T v) {
  std::string b(sizeof v, '\0');
  std::memcpy(b.data(), &v, sizeof v);
  if (std::endian::native == std::endian::little) std::reverse(b.begin(), b.end());
  return b;
}

TEST(ReadLegacyVtk, BinaryFileWithOldCellLayout) {
  std::string s = "# vtk DataFile Version 4.2\nbinary test\nBINARY\nDATASET POLYDATA\nPOINTS 3 double\n";
  for (const double x : {0.0, 0.0, 0.0, 10.0, 0.0, 0.0, 10.0, 5.0, 0.0}) s += big_endian(x);
  s += "\nLINES 1 4\n";
  for (const int32_t v : {3, 0, 1, 2}) s += big_endian(v);
  s += "\nPOINT_DATA 3\nSCALARS radius float 1\nLOOKUP_TABLE default\n";
  for (const float r : {2.0F, 1.5F, 1.0F}) s += big_endian(r);
  s += "\n";
  const auto file = write_file(scratch_dir("io_legacy_binary"), "bin.vtk", s);
  ReadOptions opt;
  opt.length_unit = "mm";
  const auto cl = read_centerlines(file, opt);
  ASSERT_EQ(cl.branches.size(), 1u);
  ASSERT_EQ(cl.branches[0].points.size(), 3u);
  EXPECT_NEAR(cl.branches[0].points[2].y(), 5e-3, 1e-15);
  EXPECT_NEAR(cl.branches[0].radii[1], 1.5e-3, 1e-15);
  // Cut short inside the point coordinates: an error, not garbage.
  const auto cut = write_file(scratch_dir("io_legacy_binary"), "cut.vtk", s.substr(0, 100));
  EXPECT_CONTAINS(error_of([&] { (void)read_network(cut); }), "cut.vtk");
}

}  // namespace
}  // namespace flowire::vessels
