// The rod as a body (rod/body.hpp): how many vertices it can ever have, which sizes every buffer.
#include "flowire/rod/body.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "rod_test_util.hpp"

namespace flowire::rod {
namespace {

TEST(RodBody, MostVerticesAreTheGridsOrOnePerFinestEdge) {
  // 20 segments: 21 grid points on the wire and two behind its proximal end, for the clamp's
  // stub when the whole wire is in.
  WireSpec spec = unit_rod_spec(20);
  RodBody fixed{RodModel::from_spec(spec), {}, {}};
  EXPECT_EQ(fixed.max_vertices(), 23);
  spec.adapt.enabled = true;
  spec.adapt.min_segment_length = 0.05 / 8;  // three levels below the 5 cm grid
  RodBody adaptive{RodModel::from_spec(spec), {}, {}};
  EXPECT_EQ(adaptive.max_vertices(), 160 + 4);
  // The state reserves that many: a vertex set of that size never reallocates.
  adaptive.state.reserve(adaptive.max_vertices());
  const auto* before = adaptive.state.x.data();
  adaptive.state.x.resize(static_cast<size_t>(adaptive.max_vertices()));
  EXPECT_EQ(adaptive.state.x.data(), before);
  EXPECT_GE(adaptive.state.u.capacity(), 164u);
}

TEST(RodBody, RediscretizeFollowsTheVertexSet) {
  RodBody body{RodModel::from_spec(unit_rod_spec(10)), {}, {}};
  body.state.u = {0.0, 0.1, 0.15, 0.2, 0.3};  // one edge halved
  body.rediscretize();
  ASSERT_GE(body.disc.rest_length.size(), 4u);
  EXPECT_NEAR(body.disc.rest_length[0], 0.1, 1e-15);
  EXPECT_NEAR(body.disc.rest_length[1], 0.05, 1e-15);
  EXPECT_NEAR(body.disc.rest_length[2], 0.05, 1e-15);
  EXPECT_NEAR(body.disc.mass[2], 0.5 * (0.05 + 0.05) * 1.0, 1e-15) << "ρA times the vertex's cell";
}

}  // namespace
}  // namespace flowire::rod
