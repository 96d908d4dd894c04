// Where the wire starts: on every anatomy of ../shared/data/real that has a lumen surface, from
// every end of its network as the entry, 3 mm, 5 mm, 1 cm and 2 cm of wire initially inside
// start along the vessel path and inside the lumen (the run's own outside check, against the
// surface the contact uses, after the settle and one step). Laid straight out of the entry,
// as a short wire once was, 3 mm to 1 cm on the AneuRisk siphon ended 3-13 wire radii
// outside the surface at t = 0. Skipped, saying so, where ../shared is absent.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "flowire/common/error.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/vessels/network.hpp"
#include "flowire_test.hpp"

using namespace flowire;

namespace {

struct Anatomy {
  const char* scene;       // examples/real/<scene>.yaml
  const char* surface;     // data/real/...
  const char* centerline;  // data/real/...
};

void check_every_entry(const Anatomy& k) {
  const auto shared = flowire::testing::shared_dir() / "data/real";
  // The example's scene without a wire.base of its own (which would hold the wire wherever
  // the entry is): the entry decides where the wire starts.
  std::ifstream in(std::filesystem::path(FLOWIRE_SOURCE_DIR) / "examples/real" / (std::string(k.scene) + ".yaml"));
  std::stringstream text;
  std::string line;
  while (std::getline(in, line))
    if (line.find("base: {") == std::string::npos) text << line << "\n";
  const auto scene = flowire::testing::scratch_dir(std::string("placement_scene_") + k.scene) / "scene.yaml";
  std::ofstream(scene) << text.str();
  const std::vector<std::string> data = {"vessels.file=" + (shared / k.centerline).string(),
                                         "vessels.surface=" + (shared / k.surface).string(), "output.vtk=false",
                                         "output.csv=false", "output.png=false"};
  const auto net = coupling::build_scene_network(coupling::load_scene(scene.string(), data));
  int runs = 0, too_long = 0;
  for (const int entry : net.ends()) {
    for (const double initial : {3e-3, 5e-3, 1e-2, 2e-2}) {
      // The clamp holds two segments: a shorter initial length is refused as bad input.
      if (initial < 2.0 * coupling::load_scene(scene.string(), data).number("wire.segment_length")) continue;
      auto sets = data;
      sets.push_back("wire.entry=" + std::to_string(entry));
      sets.push_back("insertion.initial_length=" + std::to_string(initial));
      sets.push_back("insertion.speed=0");
      const auto out = flowire::testing::scratch_dir(std::string("placement_") + k.scene);
      const auto cfg = coupling::load_scene(scene.string(), sets, out.string());
      sets.push_back("solve.duration=" + std::to_string(cfg.number("solve.dt")));
      coupling::RunResult r;
      try {
        r = coupling::run_scene(coupling::load_scene(scene.string(), sets, out.string()));
      } catch (const Error& e) {
        // A branch shorter than the wire (there and back) cannot hold it: said as bad input.
        if (e.kind() == ErrorKind::Input &&
            std::string(e.what()).find("longer than the vessel path") != std::string::npos) {
          ++too_long;
          continue;
        }
        ADD_FAILURE() << k.scene << ", entry " << entry << ", " << initial << " m: " << e.what();
        continue;
      }
      ++runs;
      const auto& s = r.summary;
      EXPECT_EQ(s["status"], "ok") << k.scene << ", entry " << entry << ", " << initial << " m: " << s.dump(1);
      EXPECT_EQ(s["wire"]["initial_layout"], "vessel_path") << k.scene << ", entry " << entry;
      EXPECT_LE(s["contact"]["max_outside_over_wire_radius"].get<double>(), 1.0)
          << k.scene << ", entry " << entry << ", " << initial << " m";
    }
  }
  std::printf("%s: %d entries, %d runs inside the lumen, %d wires longer than their path\n", k.scene,
              static_cast<int>(net.ends().size()), runs, too_long);
  EXPECT_GE(runs, 2 * static_cast<int>(net.ends().size()));
}

}  // namespace

TEST(InitialPlacement, FeelppAorticArchFromEveryEnd) {
  FLOWIRE_REQUIRE_SHARED("data/real/feelpp-aortic-arch/aorta2.stl");
  check_every_entry({"feelpp_arch", "feelpp-aortic-arch/aorta2.stl", "feelpp-aortic-arch/centerlinesAORTA.vtk"});
}
TEST(InitialPlacement, VmtkAbdominalAortaFromEveryEnd) {
  FLOWIRE_REQUIRE_SHARED("data/real/vmtk-abdominal-aorta-bifurcation/aorta-surface.vtp");
  check_every_entry({"vmtk_abdominal", "vmtk-abdominal-aorta-bifurcation/aorta-surface.vtp",
                     "vmtk-abdominal-aorta-bifurcation/aorta-centerline.vtp"});
}
TEST(InitialPlacement, AneuriskCarotidSiphonFromEveryEnd) {
  FLOWIRE_REQUIRE_SHARED("data/real/aneurisk-c0015-ica-vampy/artery.vtp");
  check_every_entry(
      {"aneurisk_ica", "aneurisk-c0015-ica-vampy/artery.vtp", "aneurisk-c0015-ica-vampy/artery_centerlines.vtp"});
}
TEST(InitialPlacement, SimvascularAortaIliacFromEveryEnd) {
  FLOWIRE_REQUIRE_SHARED("data/real/simvascular-demo-aorta-iliac/model_surface.vtp");
  check_every_entry({"simvascular_aorta", "simvascular-demo-aorta-iliac/model_surface.vtp",
                     "simvascular-demo-aorta-iliac/demo-centerlines.vtp"});
}
