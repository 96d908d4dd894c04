// insertion.schedule: a push–hold–pull–twist table drives the wire so that the inserted
// length and the base angle at every step's end are the table's integrals (computed here by
// hand, row by row), with rows that do not fall on step boundaries; and every malformed
// schedule is one error naming the file and the line.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include <fmt/format.h>

#include "flowire/common/error.hpp"
#include "flowire/coupling/cosimulation.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/coupling/schedule.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire_test.hpp"

using namespace flowire;
using namespace flowire::coupling;

namespace {

std::string write(const std::filesystem::path& dir, const std::string& name, const std::string& text) {
  const auto p = dir / name;
  std::ofstream(p) << text;
  return p.string();
}

std::string error_of(const std::string& path) {
  try {
    (void)DriveSchedule::read_csv(path);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    return e.what();
  }
  return "(no error)";
}

// push 2 cm/s from 0.013 s, hold from 0.5 s, pull 1 cm/s turning 3 rad/s from 0.8 s, twist
// alone (−2 rad/s) from 1.1 s; times off the 10 ms grid.
constexpr const char* kSchedule =
    "time,speed,rotation_speed\n"
    "0.013,0.02,0\n"
    "0.5,0,0\n"
    "0.8,-0.01,3\n"
    "1.1,0,-2\n";

}  // namespace

TEST(Schedule, IntegralsAreTheRowsSums) {
  const auto dir = flowire::testing::scratch_dir("schedule_integral");
  const auto s = DriveSchedule::read_csv(write(dir, "s.csv", kSchedule));
  double L = 0, a = 0;
  s.integral_to(1.3, L, a);
  EXPECT_NEAR(L, 0.02 * (0.5 - 0.013) - 0.01 * (1.1 - 0.8), 1e-15);
  EXPECT_NEAR(a, 3.0 * 0.3 - 2.0 * 0.2, 1e-14);
  s.integral_to(0.01, L, a);  // before the first row: held
  EXPECT_EQ(L, 0.0);
  double v = 0, w = 0;
  s.mean_over(0.49, 0.51, v, w);  // half pushing, half held
  EXPECT_NEAR(v, 0.01, 1e-12);
}

TEST(Schedule, DrivesTheWireToTheIntegralsAtEveryStep) {
  const auto dir = flowire::testing::scratch_dir("schedule_run");
  write(dir, "drive.csv", kSchedule);
  const std::string scene = fmt::format(R"(
vessels:
  generator: {{type: straight_tube, length: 0.2, radius: 3 mm}}
wire: {{length: 0.3, radius: 0.2 mm, segment_length: 2 mm, tip: {{length: 0}}}}
insertion: {{initial_length: 5 cm, schedule: drive.csv}}
solve: {{dt: 10 ms, duration: 1.3 s}}
output: {{dir: {}, csv: false, vtk: false}}
)",
                                        (dir / "out").string());
  const auto path = write(dir, "scene.yaml", scene);
  const auto cfg = config::load_config(path, scene_schema());
  CoSimulation sim(cfg);
  sim.start();
  const double L0 = sim.rod()->inserted_length();
  double worst_length = 0.0, worst_angle = 0.0;
  for (long n = 0; n < sim.planned_steps(); ++n) {
    sim.step();
    // By hand: the rows' contributions up to t.
    const double t = sim.time();
    auto part = [&](double from, double to) { return std::max(0.0, std::min(t, to) - from); };
    const double L = L0 + 0.02 * part(0.013, 0.5) - 0.01 * part(0.8, 1.1);
    const double angle = 3.0 * part(0.8, 1.1) - 2.0 * part(1.1, 1e9);
    worst_length = std::max(worst_length, std::abs(sim.rod()->inserted_length() - L));
    worst_angle = std::max(worst_angle, std::abs(sim.rod()->state().base_angle - angle));
  }
  ASSERT_EQ(sim.planned_steps(), 130);
  EXPECT_NEAR(sim.rod()->inserted_length() - L0, 0.02 * 0.487 - 0.01 * 0.3, 1e-12);  // pushed, then pulled
  EXPECT_NEAR(sim.rod()->state().base_angle, 0.9 - 0.4, 1e-12);                      // turned both ways
  EXPECT_LT(worst_length, 1e-12);
  EXPECT_LT(worst_angle, 1e-12);
}

TEST(Schedule, MalformedFilesNameTheFileAndLine) {
  const auto dir = flowire::testing::scratch_dir("schedule_bad");
  struct Case {
    const char* name;
    const char* text;
    const char* expect;
  };
  const Case cases[] = {
      {"empty.csv", "", "empty"},
      {"header_only.csv", "time,speed,rotation_speed\n", "no row"},
      {"unknown.csv", "time,speed,rotation_speed,force\n0,1,0,2\n", "unknown.csv:1: unknown column 'force'"},
      {"missing.csv", "time,speed\n0,1\n", "missing.csv:1: missing column 'rotation_speed'"},
      {"twice.csv", "time,speed,speed,rotation_speed\n", "twice.csv:1: column 'speed' appears twice"},
      {"nan.csv", "time,speed,rotation_speed\n0,nan,0\n", "nan.csv:2: speed is not finite"},
      {"word.csv", "time,speed,rotation_speed\n0,0.1,0\n1,fast,0\n", "word.csv:3: speed: 'fast' is not a number"},
      {"trailing.csv", "time,speed,rotation_speed\n0,0.1x,0\n", "trailing.csv:2"},
      {"short.csv", "time,speed,rotation_speed\n0,0.1\n", "short.csv:2: expected 3 values, found 2"},
      {"negative.csv", "time,speed,rotation_speed\n-1,0.1,0\n", "negative.csv:2: time -1 s is negative"},
      {"unsorted.csv", "time,speed,rotation_speed\n0,0.1,0\n2,0,0\n1,0,0\n",
       "unsorted.csv:4: time 1 s does not come after"},
      {"repeated.csv", "time,speed,rotation_speed\n0,0.1,0\n0,0.2,0\n", "repeated.csv:3"},
  };
  for (const auto& c : cases) {
    const auto msg = error_of(write(dir, c.name, c.text));
    EXPECT_NE(msg.find(c.expect), std::string::npos) << c.name << ": " << msg;
  }
  EXPECT_NE(error_of((dir / "absent.csv").string()).find("absent.csv"), std::string::npos);
  // Columns in another order are fine.
  const auto s = DriveSchedule::read_csv(write(dir, "order.csv", "rotation_speed,time,speed\n1,0,0.5\n"));
  EXPECT_EQ(s.rows().front().speed, 0.5);
  EXPECT_EQ(s.rows().front().rotation_speed, 1.0);
}

TEST(Schedule, ScheduleAndSpeedTogetherIsAnError) {
  const auto dir = flowire::testing::scratch_dir("schedule_both");
  write(dir, "drive.csv", kSchedule);
  const auto path = write(dir, "scene.yaml", R"(
vessels:
  generator: {type: straight_tube, length: 0.2, radius: 3 mm}
wire: {length: 0.3, radius: 0.2 mm}
insertion: {initial_length: 5 cm, schedule: drive.csv, speed: 1 cm/s}
solve: {dt: 10 ms, duration: 0.1 s}
)");
  const auto cfg = config::load_config(path, scene_schema());
  try {
    CoSimulation sim(cfg);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("insertion.speed"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not both"), std::string::npos) << e.what();
  }
}
