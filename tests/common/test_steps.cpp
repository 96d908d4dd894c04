#include "flowire/common/steps.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "flowire/common/error.hpp"

using flowire::kMaxSteps;
using flowire::step_count;

namespace {

std::string error_of(double span, double step) {
  try {
    (void)step_count(span, step, "scene.yaml:9: solve.duration", "solve.duration / solve.dt");
  } catch (const flowire::Error& e) {
    EXPECT_EQ(e.kind(), flowire::ErrorKind::Input) << e.what();
    return e.what();
  }
  return "";
}

}  // namespace

TEST(StepCount, RoundsTheQuotient) {
  EXPECT_EQ(step_count(0.0, 1e-3, "", ""), 0);
  EXPECT_EQ(step_count(1.0, 1e-3, "", ""), 1000);
  EXPECT_EQ(step_count(0.0104, 1e-3, "", ""), 10);
  EXPECT_EQ(step_count(0.0106, 1e-3, "", ""), 11);
}

TEST(StepCount, TheLimitItselfIsPlannedOneStepMoreIsRefusedNamingTheKeysAndTheLimit) {
  const double dt = 1e-3;
  EXPECT_EQ(step_count(kMaxSteps * dt, dt, "", ""), static_cast<long>(kMaxSteps));
  const std::string e = error_of((kMaxSteps + 1.0) * dt, dt);
  EXPECT_EQ(e.rfind("scene.yaml:9: solve.duration: solve.duration / solve.dt = ", 0), 0u) << e;
  EXPECT_NE(e.find(fmt::format("{:.0e}", kMaxSteps)), std::string::npos) << e;
}

TEST(StepCount, OverflowingAndMeaninglessQuotientsAreInputErrorsNeverNegativeCounts) {
  for (const auto& [span, step] : {std::pair{1e20, 1e-3}, {1.0, 1e-300}, {1e300, 1e-300}, {1e308, 1e-308}}) {
    const std::string e = error_of(span, step);
    EXPECT_NE(e.find("solve.duration / solve.dt"), std::string::npos) << span << " / " << step;
  }
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  for (const auto& [span, step] :
       {std::pair{-1.0, 1e-3}, {1.0, 0.0}, {1.0, -1e-3}, {inf, 1e-3}, {1.0, inf}, {nan, 1.0}, {1.0, nan}}) {
    EXPECT_NE(error_of(span, step), "") << span << " / " << step;
  }
}
