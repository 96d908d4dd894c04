// The insertion: section (coupling/src/config_insertion.cpp): its keys and how they drive
// the wire.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "flowire/rod/simulator.hpp"
#include "flowire_test.hpp"
#include "scene_config_test.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {
namespace {

TEST(ConfigInsertion, DeclaresTheInsertionKeysOfTheScene) {
  test::expect_section_of_scene(test::declared_paths(declare_insertion_keys), {"insertion"});
}

TEST(ConfigInsertion, SpeedsAndLimitGivenInTheSceneAreRead) {
  const auto c = test::scene("wire: {}\ninsertion: {speed: 2 cm/s, rotation_speed: 1 rad/s, max_length: 10 cm}\n");
  const InsertionPlan p = insertion_plan(c, true);
  EXPECT_DOUBLE_EQ(p.speed, 0.02);
  EXPECT_DOUBLE_EQ(p.rotation_speed, 1.0);
  EXPECT_DOUBLE_EQ(p.max_length, 0.1);
  EXPECT_EQ(p.schedule, nullptr);
  const InsertionPlan none = insertion_plan(test::scene("wire: {}\n"), true);
  EXPECT_EQ(none.speed, 0.0);
  EXPECT_TRUE(std::isinf(none.max_length));
  rod::RodSimulator sim(scene_wire_spec(c));
  drive_wire(c, sim);
}

TEST(ConfigInsertion, ConflictingDrivesAreRejectedNamingFileLineAndKey) {
  const auto dir = flowire::testing::scratch_dir("config_insertion");
  std::ofstream(dir / "drive.csv") << "time,speed,rotation_speed\n0,0.01,0\n1,0,0\n";
  const std::string file = (dir / "drive.csv").string();
  const auto both = test::scene("wire: {}\ninsertion:\n  speed: 1 cm/s\n  schedule: " + file + "\n");
  EXPECT_NE(test::input_error([&] { (void)insertion_plan(both, true); }).find("scene.yaml:3: insertion.speed"),
            std::string::npos);
  const auto scheduled = test::scene("insertion:\n  schedule: " + file + "\n");
  EXPECT_NE(insertion_plan(scheduled, true).schedule, nullptr);
  EXPECT_NE(test::input_error([&] { (void)insertion_plan(scheduled, false); }).find("scene.yaml:2: insertion.schedule"),
            std::string::npos);

  const auto force = test::scene("wire: {}\ninsertion:\n  force: 0.1 N\n  speed: 1 cm/s\n");
  rod::RodSimulator sim(scene_wire_spec(force));
  EXPECT_NE(test::input_error([&] { drive_wire(force, sim); }).find("scene.yaml:4: insertion.speed"),
            std::string::npos);
  EXPECT_NE(test::input_error([] {
              (void)test::scene("wire: {}\ninsertion:\n  max_force: -1 N\n");
            }).find("scene.yaml:3: insertion.max_force"),
            std::string::npos);
}

}  // namespace
}  // namespace flowire::coupling
