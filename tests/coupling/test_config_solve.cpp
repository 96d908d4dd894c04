// The solve: section (coupling/src/config_solve.cpp): its keys and the time stepping they set.
#include <gtest/gtest.h>

#include "scene_config_test.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {
namespace {

TEST(ConfigSolve, DeclaresTheSolveKeysOfTheScene) {
  test::expect_section_of_scene(test::declared_paths(declare_solve_keys), {"solve"});
}

TEST(ConfigSolve, StepsFollowFromDurationAndDtAndAStaticSceneHasNone) {
  const auto d = solve_settings(test::scene("solve: {dt: 2 ms, duration: 0.5 s}\n"));
  EXPECT_FALSE(d.is_static);
  EXPECT_DOUBLE_EQ(d.dt, 2e-3);
  EXPECT_EQ(d.steps, 250);
  const auto s = solve_settings(test::scene("solve: {mode: static, duration: 1 s}\n"));
  EXPECT_TRUE(s.is_static);
  EXPECT_EQ(s.steps, 0);
  // Nothing given: the declared 1 ms and 0 s, one frame.
  const auto none = solve_settings(test::scene(""));
  EXPECT_DOUBLE_EQ(none.dt, 1e-3);
  EXPECT_EQ(none.steps, 0);
  EXPECT_EQ(scene_integrator(test::scene("solve: {integrator: implicit_midpoint}\n")),
            rod::Integrator::ImplicitMidpoint);
  EXPECT_EQ(scene_integrator(test::scene("")), rod::Integrator::ImplicitEuler);
}

TEST(ConfigSolve, ANonPositiveDtOrNegativeDurationIsRejectedNamingFileLineAndKey) {
  // Refused as the scene is read (the declared ranges).
  EXPECT_NE(test::input_error([] { (void)test::scene("solve:\n  dt: 0\n"); }).find("scene.yaml:2: solve.dt"),
            std::string::npos);
  EXPECT_NE(test::input_error([] {
              (void)test::scene("solve:\n  dt: 1 ms\n  duration: -1 s\n");
            }).find("scene.yaml:3: solve.duration"),
            std::string::npos);
  // Their quotient, more steps than a run may plan, when the steps are planned.
  const auto long_run = test::scene("solve:\n  dt: 1 us\n  duration: 2000 s\n");
  const std::string e = test::input_error([&] { (void)solve_settings(long_run); });
  EXPECT_NE(e.find("scene.yaml:3: solve.duration"), std::string::npos) << e;
  EXPECT_NE(e.find("solve.duration / solve.dt = 2e+09 steps"), std::string::npos) << e;
}

}  // namespace
}  // namespace flowire::coupling
