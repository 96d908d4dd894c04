// What every poly data convention shares (polydata.cpp): bad .vtp / .vtk input (no radius
// array, radii not positive or not finite, coordinates not finite, duplicate points, self-loops,
// ids out of range, empty, truncated, corrupt or huge files, not poly data) gives one
// flowire::Error naming the file and the point or cell, and VTK prints nothing; lumen surfaces
// (no line cells) are not centerlines.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/vessels/io.hpp"
#include "reader_test_util.hpp"

namespace flowire::vessels {
namespace {

using flowire::testing::scratch_dir;
using namespace flowire::vessels::test;

TestPoly tube(std::vector<double> radii, std::string radius_name = "radius") {
  TestPoly p;
  for (size_t i = 0; i < radii.size(); ++i) p.points.emplace_back(0.01 * static_cast<double>(i), 0, 0);
  std::vector<long long> ids;
  for (size_t i = 0; i < radii.size(); ++i) ids.push_back(static_cast<long long>(i));
  p.lines = {ids};
  p.point_data.push_back({std::move(radius_name), std::move(radii)});
  return p;
}

TEST_F(ReadersWithVtk, BadVtkInputGivesOneErrorNamingFileAndPoint) {
  const auto dir = scratch_dir("io_bad_vtk");
  struct Case {
    std::string name, text, expected;
  };
  auto dup = tube({1, 1, 1, 1});
  dup.points[2] = dup.points[1];
  auto loop = tube({1, 1, 1});
  loop.lines.push_back({2, 2});
  auto out_of_range = tube({1, 1, 1});
  out_of_range.lines[0].push_back(7);
  auto nan_point = tube({1, 1, 1});
  nan_point.points[2].y() = std::nan("");
  const std::string valid = vtp_text(tube({1, 1, 1}));
  std::vector<Case> cases{
      {"noradius.vtp", vtp_text(tube({1, 1, 1}, "Scalars_")), "no radius array"},
      {"zero.vtp", vtp_text(tube({1, 0, 1})), "point 1 (line cell 0): radius 0 is not positive"},
      {"negative.vtp", vtp_text(tube({1, 1, -2})), "point 2 (line cell 0): radius -2 is not positive"},
      {"nan.vtp", vtp_text(tube({1, std::nan(""), 1})), "point 1 (line cell 0): radius is not finite"},
      {"nanx.vtk", legacy_text(nan_point), "point 2 (line cell 0): coordinate is not finite"},
      {"empty.vtp", "", "the file is empty"},
      {"empty.vtk", "", "the file is empty"},
      {"truncated.vtp", valid.substr(0, valid.size() / 2), "truncated"},
      {"duplicate.vtp", vtp_text(dup), "line cell 0: points 1 and 2 (ids 1 and 2) coincide (duplicate point)"},
      {"selfloop.vtp", vtp_text(loop), "line cell 1 joins point 2 to itself (self-loop)"},
      {"range.vtp", vtp_text(out_of_range), "line cell 0: point id 7 is out of range"},
      {"garbage.vtp", "<VTKFile type=\"PolyData\"><PolyData><Piece NumberOfPoints=\"2\">&&&<<</VTKFile>",
       "cannot read"},
      {"notvtk.vtp", "hello", "not a VTK file"},
      {"huge.vtp",
       "<VTKFile type=\"PolyData\"><PolyData><Piece NumberOfPoints=\"99999999999\"></Piece></PolyData></VTKFile>",
       "NumberOfPoints=\"99999999999\" does not fit"},
      {"legacy_bad.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 99999999999 float\n",
       "POINTS"},
      {"surface.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 1 float\n0 0 0\n",
       "POLYDATA"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const auto file = write_file(dir, c.name, c.text);
    ::testing::internal::CaptureStderr();
    const auto msg = error_of([&] { (void)read_network(file); });
    const auto printed = ::testing::internal::GetCapturedStderr();
    EXPECT_CONTAINS(msg, c.expected);
    EXPECT_CONTAINS(msg, file);
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    EXPECT_EQ(printed, "") << "VTK printed: " << printed;
  }
}

#ifdef FLOWIRE_HAVE_VTK

TEST(RealData, LumenSurfacesAreNotCenterlines) {
  FLOWIRE_REQUIRE_SHARED("data/real/simvascular-demo-aorta-iliac/model_surface.vtp");
  for (const char* rel : {"simvascular-demo-aorta-iliac/model_surface.vtp", "aneurisk-c0015-ica-vampy/artery.vtp",
                          "vmtk-abdominal-aorta-bifurcation/aorta-surface.vtp"}) {
    SCOPED_TRACE(rel);
    try {
      (void)read_network(real(rel));
      ADD_FAILURE() << "a surface is not a network";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("no line cells"), std::string::npos) << e.what();
    }
  }
}

#endif  // FLOWIRE_HAVE_VTK

}  // namespace
}  // namespace flowire::vessels
