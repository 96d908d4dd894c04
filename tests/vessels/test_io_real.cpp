// The readers on the real anatomies in the shared data folder (image-derived VMTK and
// SimVascular centerlines, svOneDSolver decks, legacy VTK coronary trees). Expected counts and
// ranges come from each folder's PROVENANCE.md; every test skips, saying so, if the data is absent.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/vessels/io.hpp"
#include "flowire/vessels/spatial.hpp"
#include "flowire_test.hpp"

namespace flowire::vessels {
namespace {

using flowire::testing::shared_dir;

std::string real(const std::string& rel) { return (shared_dir() / "data/real" / rel).string(); }

Network read_real(const std::string& rel, const char* unit, double max_segment_length = 5e-3) {
  ReadOptions opt;
  opt.length_unit = unit;
  opt.build.max_segment_length = max_segment_length;
  return read_network(real(rel), opt);
}

/// Radii (m) of a human artery: 0.3 mm to 20 mm.
void expect_physiological(const NetworkCounts& c) {
  EXPECT_GE(c.radius_min, 0.3e-3);
  EXPECT_LE(c.radius_max, 20e-3);
}

std::string describe(const NetworkCounts& c) {
  return "branches " + std::to_string(c.branches) + ", nodes " + std::to_string(c.nodes) + ", segments " +
         std::to_string(c.segments) + ", junctions " + std::to_string(c.junctions) + ", ends " +
         std::to_string(c.ends) + ", loops " + std::to_string(c.loops) + ", length " + std::to_string(c.total_length) +
         " m, radius " + std::to_string(c.radius_min) + " - " + std::to_string(c.radius_max) + " m";
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

#ifdef FLOWIRE_HAVE_VTK
TEST(RealData, SimVascularRomCenterlinesGiveAortaAndIliac) {
  FLOWIRE_REQUIRE_SHARED("data/real/simvascular-demo-aorta-iliac/rom-centerlines.vtp");
  const auto net = read_real("simvascular-demo-aorta-iliac/rom-centerlines.vtp", "cm");
  const auto c = net.counts();
  RecordProperty("counts", describe(c));
  EXPECT_EQ(c.branches, 3);   // BranchId 0, 1, 2
  EXPECT_EQ(c.junctions, 1);  // BifurcationId 0
  EXPECT_EQ(c.ends, 3);
  EXPECT_EQ(c.loops, 0);
  // Per-branch paths 20.3 + 20.2 + 22.2 cm, plus the bifurcation region.
  EXPECT_GT(c.total_length, 0.60);
  EXPECT_LT(c.total_length, 0.70);
  EXPECT_GE(c.radius_min, 4.4e-3);
  EXPECT_LE(c.radius_max, 12.8e-3);
  expect_physiological(c);
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

TEST(RealData, SurfaceOnlyPhantomIsRejectedClearly) {
  FLOWIRE_REQUIRE_SHARED("data/real/cathsim-elastrat-arch-phantom/phantom-elastrat-simple.obj");
  try {
    (void)read_network(real("cathsim-elastrat-arch-phantom/phantom-elastrat-simple.obj"));
    FAIL() << "a surface mesh is not a network";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("phantom-elastrat-simple.obj"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace flowire::vessels

// Bends are not cut: on every real centerline, no centerline point lies farther than 0.1 of
// its radius from the axis of the nearest segment of its own branch (measured here against the
// file's points), while the uniform 5 mm sampling alone cuts the carotid siphon's bends by more.
TEST(RealCenterlines, SegmentsFollowTheBendsWithinATenthOfTheRadius) {
  struct F {
    const char* path;
    const char* unit;
  };
  for (const F f :
       {F{"aneurisk-c0015-ica-vampy/artery_centerlines.vtp", "mm"}, F{"feelpp-aortic-arch/centerlinesAORTA.vtk", "cm"},
        F{"vmtk-abdominal-aorta-bifurcation/aorta-centerline-branches.vtp", "mm"},
        F{"simvascular-demo-aorta-iliac/rom-centerlines.vtp", "cm"}}) {
    FLOWIRE_REQUIRE_SHARED(std::string("data/real/") + f.path);
    const auto file = (flowire::testing::shared_dir() / "data/real" / f.path).string();
    auto deviation = [&](double max_chord) {
      flowire::vessels::ReadOptions ro;
      ro.length_unit = f.unit;
      ro.build.max_chord_deviation = max_chord;
      const auto net = flowire::vessels::read_network(file, ro);
      // Each network branch's polyline is the file branch cut into segments: measure every
      // node-to-node piece against the points of the file's branches that project into it.
      const auto cl = flowire::vessels::read_centerlines(file, ro);
      double worst = 0.0;
      for (const auto& b : cl.branches)
        for (size_t i = 1; i + 1 < b.points.size(); ++i) {
          double best = 1e300;
          for (const auto& s : net.segments()) {
            const auto pr = flowire::vessels::project_on_axis(b.points[i], net.node(s.node_from), net.node(s.node_to));
            best = std::min(best, pr.distance);
          }
          worst = std::max(worst, best / b.radii[i]);
        }
      return worst;
    };
    const double with = deviation(0.1), without = deviation(0.0);
    std::printf("%s: largest chord deviation / radius %.3f (uniform 5 mm sampling alone: %.3f)\n", f.path, with,
                without);
    EXPECT_LE(with, 0.1 + 1e-9) << f.path;
  }
}
