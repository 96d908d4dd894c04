// What every reader does after parsing (read_common.cpp): the length unit scales coordinates
// and radii (or a factor does; an unknown unit is an error), a network in disconnected pieces
// is an error naming them or keeps the inlet's piece with a warning, and a real anatomy read
// without its unit warns naming the unit it is probably in.
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "flowire/vessels/io.hpp"
#include "reader_test_util.hpp"

namespace flowire::vessels {
namespace {

using flowire::testing::ExpectWarnings;
using flowire::testing::scratch_dir;
using namespace flowire::vessels::test;

TEST_F(ReadersWithVtk, LengthUnitScalesCoordinatesAndRadii) {
  TestPoly p;
  p.points = {Vec3(0, 0, 0), Vec3(10, 0, 0)};
  p.lines = {{0, 1}};
  p.point_data.push_back({"radius", {2.0, 2.0}});
  const auto file = write_file(scratch_dir("io_units"), "tube.vtp", vtp_text(p));
  for (const auto& [unit, f] : std::vector<std::pair<std::string, double>>{{"mm", 1e-3}, {"cm", 1e-2}}) {
    ReadOptions opt;
    opt.length_unit = unit;
    const auto cl = read_centerlines(file, opt);
    EXPECT_NEAR(cl.branches[0].points[1].x(), 10 * f, 1e-15) << unit;
    EXPECT_NEAR(cl.branches[0].radii[0], 2 * f, 1e-15) << unit;
  }
  ReadOptions opt;
  opt.length_factor = 0.5;
  EXPECT_NEAR(read_centerlines(file, opt).branches[0].points[1].x(), 5.0, 1e-15);
  opt = {};
  opt.length_unit = "furlong";
  EXPECT_CONTAINS(error_of([&] { (void)read_centerlines(file, opt); }), "furlong");
}

TEST_F(ReadersWithVtk, DisconnectedPiecesAreAnErrorOrTheInletPieceIsKept) {
  TestPoly p;
  p.points = {Vec3(0, 0, 0), Vec3(0.05, 0, 0), Vec3(0, 0.1, 0), Vec3(0.02, 0.1, 0), Vec3(0.04, 0.1, 0)};
  p.lines = {{0, 1}, {2, 3, 4}};
  p.point_data.push_back({"radius", {0.008, 0.008, 0.003, 0.003, 0.003}});
  const auto file = write_file(scratch_dir("io_pieces"), "pieces.vtp", vtp_text(p));
  const auto msg = error_of([&] { (void)read_network(file); });
  EXPECT_CONTAINS(msg, "2 disconnected pieces");
  EXPECT_CONTAINS(msg, "piece 1");
  EXPECT_CONTAINS(msg, "branch_1");
  ExpectWarnings w;
  ReadOptions opt;
  opt.keep_inlet_piece = true;
  const auto net = read_network(file, opt);
  EXPECT_EQ(net.counts().components, 1);
  EXPECT_NEAR(net.counts().radius_max, 0.008, 1e-15);  // the piece with the widest end
  EXPECT_NEAR(net.counts().total_length, 0.05, 1e-15);
  ASSERT_EQ(w.warnings().size(), 1u);
  EXPECT_TRUE(w.contains("disconnected pieces"));
}

#ifdef FLOWIRE_HAVE_VTK

TEST(RealData, MillimetreFileReadAsMetresWarnsNamingTheUnit) {
  FLOWIRE_REQUIRE_SHARED("data/real/vmtk-abdominal-aorta-bifurcation/aorta-centerline.vtp");
  flowire::testing::ExpectWarnings w;
  ReadOptions opt;
  opt.build.max_segment_length = 5.0;
  const auto net = read_network(real("vmtk-abdominal-aorta-bifurcation/aorta-centerline.vtp"), opt);
  EXPECT_EQ(net.counts().ends, 3);
  ASSERT_EQ(w.warnings().size(), 1u);
  EXPECT_TRUE(w.contains("probably in mm")) << w.warnings()[0];
}

TEST(RealData, EveryFileReadWithoutItsUnitWarnsNamingTheRightUnit) {
  FLOWIRE_REQUIRE_SHARED("data/real/feelpp-aortic-arch/centerlinesAORTA.vtk");
  const std::vector<std::pair<std::string, std::string>> files{
      {"aneurisk-c0015-ica-vampy/artery_centerlines.vtp", "mm"},
      {"simvascular-demo-aorta-iliac/demo-centerlines.vtp", "cm"},
      {"simvascular-demo-aorta-iliac/rom-centerlines.vtp", "cm"},
      {"vmtk-abdominal-aorta-bifurcation/aorta-centerline-branches.vtp", "mm"},
      {"bluefern-coronary-centerlines/227A_Centreline.vtk", "mm"},
      {"bluefern-coronary-centerlines/721A_Centreline.vtk", "mm"},
      {"feelpp-aortic-arch/centerlinesAORTA.vtk", "cm"}};
  for (const auto& [rel, unit] : files) {
    SCOPED_TRACE(rel);
    flowire::testing::ExpectWarnings w;
    ReadOptions opt;
    opt.build.max_segment_length = 1.0;
    (void)read_network(real(rel), opt);
    ASSERT_EQ(w.warnings().size(), 1u);
    EXPECT_TRUE(w.contains("probably in " + unit)) << w.warnings()[0];
  }
}

#endif  // FLOWIRE_HAVE_VTK

}  // namespace
}  // namespace flowire::vessels
