// VTK XML poly data read with VTK (read_vtk_xml.cpp): a flowire .vtp cut short anywhere is one
// error naming the file, VTK printing nothing; the cell arrays of a file with vertex cells
// before its lines are read for the lines (VTK numbers vertex cells first).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "flowire/vessels/io.hpp"
#include "reader_test_util.hpp"

namespace flowire::vessels {
namespace {

using flowire::testing::scratch_dir;
using namespace flowire::vessels::test;

TEST_F(ReadersWithVtk, TruncatedFlowireVtpIsAnError) {
  const auto dir = scratch_dir("io_truncated_vtp");
  const auto file = (dir / "net.vtp").string();
  write_network_vtp(sample_network(), file);
  std::ifstream in(file, std::ios::binary);
  const std::string full((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const double f : {0.1, 0.5, 0.9, 0.99}) {
    const auto cut =
        write_file(dir, "cut.vtp", full.substr(0, static_cast<size_t>(f * static_cast<double>(full.size()))));
    ::testing::internal::CaptureStderr();
    const auto msg = error_of([&] { (void)read_network(cut); });
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
    EXPECT_CONTAINS(msg, "cut.vtp");
  }
}

TEST_F(ReadersWithVtk, CellArraysBelongToTheLinesAfterVertexCells) {
  // VMTK branch-split arrays on one centerline cut in two tracts (groups 0 and 5, mm), behind a
  // vertex cell whose own values (group 9, centerline 3, tract 7) must not shift onto the lines.
  std::string points, radius;
  for (int i = 0; i <= 10; ++i) {
    points += fmt::format(" 0 0 {}", -2.0 * i);
    radius += " 1.5";
  }
  const std::string file = write_file(scratch_dir("read_vtk_xml_verts"), "verts.vtp",
                                      fmt::format(R"(<?xml version="1.0"?>
<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">
<PolyData>
<Piece NumberOfPoints="11" NumberOfVerts="1" NumberOfLines="2" NumberOfStrips="0" NumberOfPolys="0">
<PointData>
<DataArray type="Float64" Name="MaximumInscribedSphereRadius" NumberOfComponents="1" format="ascii">{}</DataArray>
</PointData>
<CellData>
<DataArray type="Int32" Name="GroupIds" NumberOfComponents="1" format="ascii">9 0 5</DataArray>
<DataArray type="Int32" Name="CenterlineIds" NumberOfComponents="1" format="ascii">3 0 0</DataArray>
<DataArray type="Int32" Name="TractIds" NumberOfComponents="1" format="ascii">7 0 1</DataArray>
</CellData>
<Points>
<DataArray type="Float64" NumberOfComponents="3" format="ascii">{}</DataArray>
</Points>
<Verts>
<DataArray type="Int64" Name="connectivity" format="ascii">10</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">1</DataArray>
</Verts>
<Lines>
<DataArray type="Int64" Name="connectivity" format="ascii">0 1 2 3 4 5 5 6 7 8 9 10</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">6 12</DataArray>
</Lines>
</Piece>
</PolyData>
</VTKFile>
)",
                                                  radius, points));
  ReadOptions opt;
  opt.length_unit = "mm";
  const auto cl = read_centerlines(file, opt);
  ASSERT_EQ(cl.branches.size(), 2u);
  EXPECT_EQ(cl.branches[0].name, "group_0");
  EXPECT_EQ(cl.branches[1].name, "group_5");
  // Group 5 starts where group 0 ends (its parent on the centerline) and ends at the outlet.
  EXPECT_LT((cl.branches[0].points.back() - Vec3(0, 0, -10e-3)).norm(), 1e-15);
  EXPECT_LT((cl.branches[1].points.front() - Vec3(0, 0, -10e-3)).norm(), 1e-15);
  EXPECT_LT((cl.branches[1].points.back() - Vec3(0, 0, -20e-3)).norm(), 1e-15);
  EXPECT_EQ(cl.branches[0].points.size() + cl.branches[1].points.size(), 12u);
  EXPECT_DOUBLE_EQ(cl.branches[1].radii.back(), 1.5e-3);
  const auto c = read_network(file, opt).counts();
  EXPECT_EQ(c.branches, 2);
  EXPECT_EQ(c.ends, 2);
  EXPECT_NEAR(c.total_length, 20e-3, 1e-15);
}

}  // namespace
}  // namespace flowire::vessels
