// Three points of the stress matrix (tools/bench/stress.hpp), short enough for the default
// run: the scene at its own step, the coarsest step with the stiffest wire pushed fastest,
// and the softest wire under ten-fold flow.
#include <gtest/gtest.h>

#include <string>

#include "flowire_test.hpp"
#include "stress.hpp"

namespace flowire::bench {
namespace {

const std::string kScene = std::string(FLOWIRE_SOURCE_DIR) + "/examples/aortic_arch/scene.yaml";

void expect_pass(const StressPoint& p) {
  testing::ExpectWarnings guard;  // unconverged Newton steps warn; they are counted, not failures
  const StressResult r = run_stress_point(kScene, p);
  EXPECT_TRUE(r.pass) << stress_point_id(p) << ": step " << r.first_bad_step << ": " << r.reason;
  EXPECT_GT(r.steps, 0);
  EXPECT_LE(r.max_outside_over_radius, 0.1);
  EXPECT_LT(r.max_length_drift, 1e-3);
  EXPECT_GT(r.inserted_length, 0.02);  // the wire went in
}

TEST(StressSmoke, SceneStep) {
  expect_pass({.dt = 0.01,
               .youngs_modulus = 60e9,
               .wire_length = 0.8,
               .speed = 0.05,
               .rotation = 0.0,
               .flow_scale = 1.0,
               .friction = 0.2,
               .duration = 0.3});
}

TEST(StressSmoke, CoarseStepStiffFast) {
  expect_pass({.dt = 1.0 / 30.0,
               .youngs_modulus = 200e9,
               .wire_length = 1.7,
               .speed = 0.1,
               .rotation = 2.0,
               .flow_scale = 1.0,
               .friction = 0.05,
               .duration = 0.5});
}

TEST(StressSmoke, SoftWireStrongFlow) {
  expect_pass({.dt = 0.01,
               .youngs_modulus = 5e9,
               .wire_length = 0.8,
               .speed = 0.1,
               .rotation = 0.0,
               .flow_scale = 10.0,
               .friction = 0.2,
               .duration = 0.3});
}

}  // namespace
}  // namespace flowire::bench
