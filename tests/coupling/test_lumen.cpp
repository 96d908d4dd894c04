// A scene's lumen surface (coupling/src/lumen.cpp): a capped 16-sided tube written by hand as
// an OBJ file in millimetres, read for a straight-tube network in metres. Its caps are found
// at the network's two ends and removed (an axis point past an end is then beyond an open
// end), the length unit applies (the axis lies one apothem R·cos(π/16) inside the wall),
// and the smoothing width and its errors come from the scene's keys.
#include "flowire/coupling/lumen.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include "flowire/common/error.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/vessels/generators.hpp"
#include "flowire_test.hpp"

using namespace flowire;
namespace fs = std::filesystem;

namespace {

constexpr int kSides = 16, kRings = 11;
constexpr double kRadiusMm = 2.0, kLengthMm = 50.0;

/// The tube along +x from 0 to 50 mm, radius 2 mm, closed by a fan at each end.
fs::path write_capped_tube(const fs::path& dir) {
  const fs::path path = dir / "tube.obj";
  std::ofstream out(path);
  out.precision(17);
  for (int k = 0; k < kRings; ++k)
    for (int j = 0; j < kSides; ++j) {
      const double phi = 2.0 * M_PI * j / kSides;
      out << "v " << kLengthMm * k / (kRings - 1) << ' ' << kRadiusMm * std::cos(phi) << ' '
          << kRadiusMm * std::sin(phi) << '\n';
    }
  out << "v 0 0 0\nv " << kLengthMm << " 0 0\n";
  auto id = [](int k, int j) { return k * kSides + (j % kSides) + 1; };  // OBJ counts from 1
  for (int k = 0; k + 1 < kRings; ++k)
    for (int j = 0; j < kSides; ++j) {
      out << "f " << id(k, j) << ' ' << id(k + 1, j) << ' ' << id(k + 1, j + 1) << '\n';
      out << "f " << id(k, j) << ' ' << id(k + 1, j + 1) << ' ' << id(k, j + 1) << '\n';
    }
  const int first_centre = kRings * kSides + 1, last_centre = first_centre + 1;
  for (int j = 0; j < kSides; ++j) {
    out << "f " << first_centre << ' ' << id(0, j + 1) << ' ' << id(0, j) << '\n';
    out << "f " << last_centre << ' ' << id(kRings - 1, j) << ' ' << id(kRings - 1, j + 1) << '\n';
  }
  return path;
}

config::Config scene(const std::string& extra) {
  return config::load_config_text("vessels:\n  generator: {type: straight_tube}\n" + extra, "scene.yaml",
                                  coupling::scene_schema());
}

const vessels::Network& tube_network() {
  static const vessels::Network net = vessels::Network::build(
      vessels::straight_tube({.length = kLengthMm * 1e-3, .radius = kRadiusMm * 1e-3}), {.max_segment_length = 5e-3});
  return net;
}

TEST(SceneLumen, NoSurfaceKeyNoSurface) {
  nlohmann::json info = "untouched";
  double smoothing = -1.0;
  EXPECT_EQ(coupling::make_scene_surface(scene(""), tube_network(), info, smoothing), nullptr);
  EXPECT_EQ(info, "untouched");
  EXPECT_EQ(smoothing, -1.0);
}

TEST(SceneLumen, CapsAtTheNetworksEndsAreRemovedAndTheUnitApplies) {
#ifndef FLOWIRE_TEST_HAVE_VTK
  GTEST_SKIP() << "built without VTK: surface files cannot be read";
#endif
  const auto dir = flowire::testing::scratch_dir("scene_lumen_caps");
  const fs::path obj = write_capped_tube(dir);
  nlohmann::json info;
  double smoothing = 0.0;
  const auto s = coupling::make_scene_surface(scene("  length_unit: mm\n  surface: " + obj.string() + "\n"),
                                              tube_network(), info, smoothing);
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(info["cap_triangles_removed"], 2 * kSides);
  EXPECT_EQ(info["triangles"], 2 * kSides * (kRings - 1));
  EXPECT_EQ(info["boundary_loops"], 2);
  EXPECT_EQ(info["components"], 1);
  EXPECT_EQ(info["nonmanifold_edges"], 0);
  EXPECT_EQ(info["file"], obj.string());
  // In metres: the axis lies one apothem inside every wall facet.
  const double apothem = kRadiusMm * 1e-3 * std::cos(M_PI / kSides);
  for (const double x : {0.012, 0.025, 0.0371}) {
    const auto d = s->distance(vessels::Vec3(x, 0, 0));
    EXPECT_NEAR(d.distance, -apothem, 1e-9) << x;  // VTK reads OBJ coordinates as floats
    EXPECT_FALSE(d.open);
  }
  // Past either end on the axis: outside, nearest to the open end's rim (no cap there).
  for (const double x : {-0.003, 0.053}) EXPECT_TRUE(s->distance(vessels::Vec3(x, 0, 0)).open) << x;
  // The default smoothing: 0.4 of the mean edge, which lies between the shortest edge
  // (the rim chord 2R sin(π/16)) and the longest (the wall's diagonal).
  const double chord = 2.0 * kRadiusMm * 1e-3 * std::sin(M_PI / kSides);
  const double step = kLengthMm * 1e-3 / (kRings - 1);
  const double mean_edge = info["mean_edge"].get<double>();
  EXPECT_GE(mean_edge, chord * (1 - 1e-6));
  EXPECT_LE(mean_edge, std::hypot(chord, step) * (1 + 1e-6));
  EXPECT_DOUBLE_EQ(smoothing, 0.4 * mean_edge);
  EXPECT_DOUBLE_EQ(info["smoothing"].get<double>(), smoothing);
}

TEST(SceneLumen, SmoothingAndFileComeFromTheSceneAndBadValuesNameTheirKey) {
#ifndef FLOWIRE_TEST_HAVE_VTK
  GTEST_SKIP() << "built without VTK: surface files cannot be read";
#endif
  const auto dir = flowire::testing::scratch_dir("scene_lumen_keys");
  const fs::path obj = write_capped_tube(dir);
  nlohmann::json info;
  double smoothing = 0.0;
  (void)coupling::make_scene_surface(
      scene("  length_unit: mm\n  surface: " + obj.string() + "\n  surface_smoothing: 0.1 mm\n"), tube_network(), info,
      smoothing);
  EXPECT_DOUBLE_EQ(smoothing, 1e-4);
  try {
    (void)coupling::make_scene_surface(
        scene("  length_unit: mm\n  surface: " + obj.string() + "\n  surface_smoothing: -1 mm\n"), tube_network(), info,
        smoothing);
    ADD_FAILURE() << "a negative smoothing was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("scene.yaml:5: vessels.surface_smoothing"), std::string::npos) << e.what();
  }
  try {
    (void)coupling::make_scene_surface(scene("  surface: " + (dir / "nowhere.stl").string() + "\n"), tube_network(),
                                       info, smoothing);
    ADD_FAILURE() << "a missing surface was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("nowhere.stl"), std::string::npos) << e.what();
  }
}

}  // namespace
