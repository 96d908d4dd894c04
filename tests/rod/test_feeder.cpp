// The feeder alone (rod/feeder.hpp): which vertices a fed wire simulates and where the held
// ones are, without a solve. The expected layouts are the grid and the insertion line, written
// from the material coordinate, not from the feeder's arithmetic.
#include "flowire/rod/feeder.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "rod_test_util.hpp"

namespace flowire::rod {
namespace {

// A 1 m unit rod with 20 segments (h = 5 cm), along +x from the origin.
struct FeederRig {
  explicit FeederRig(double inserted) : body{RodModel::from_spec(unit_rod_spec(20)), {}, {}}, feeder(body) {
    body.state.reserve(body.max_vertices());
    feeder.build(inserted);
  }
  // Where material coordinate u lies on the insertion line for inserted length L.
  [[nodiscard]] Eigen::Vector3d on_line(double u, double L) const {
    return body.model.base_position - body.model.base_direction * (u - L);
  }
  RodBody body;
  Feeder feeder;
};

TEST(RodFeeder, BuildsTheGridUpToTwoPointsBehindTheEntry) {
  FeederRig rig(0.32);  // 6.4 segments inserted: the clamp vertex is grid point 7
  const RodState& s = rig.body.state;
  ASSERT_EQ(s.vertex_count(), 9);
  EXPECT_EQ(rig.feeder.first_clamped(), 7);
  for (int k = 0; k < s.vertex_count(); ++k) {
    EXPECT_NEAR(s.u[k], 0.05 * k, 1e-15);
    EXPECT_NEAR(rig.feeder.arc_lengths()[k], 0.32 - 0.05 * k, 1e-15);
    EXPECT_LT((s.x[k] - rig.on_line(s.u[k], 0.32)).norm(), 1e-14) << "straight rod at rest on the line, vertex " << k;
  }
  EXPECT_EQ(rig.feeder.first_fixed_dof(), 28);
  EXPECT_EQ(rig.feeder.first_free_dof(), 0);
  EXPECT_TRUE(rig.feeder.free_vertex(6));
  EXPECT_FALSE(rig.feeder.free_vertex(7));
}

TEST(RodFeeder, FeedingAppendsGridPointsAndPullingBackHoldsThemOnTheLine) {
  FeederRig rig(0.32);
  RodState& s = rig.body.state;
  // Push 12 cm in (0.32 → 0.44 m): grid points 7 and 8 pass the entry, 9 becomes the clamp vertex.
  rig.feeder.set_feed_speed(0.12);
  const double L = rig.feeder.feed_vertex_set(1.0);
  EXPECT_NEAR(L, 0.44, 1e-15);
  ASSERT_EQ(s.vertex_count(), 11);
  EXPECT_EQ(rig.feeder.first_clamped(), 9);  // ceil(0.44 / 0.05) = 9
  for (int k = 9; k < 11; ++k) EXPECT_NEAR(s.u[k], 0.05 * k, 1e-15);
  s.inserted_length = L;
  rig.feeder.set_prescribed(L, 0.0, s.x, s.theta);
  for (int k = 9; k < 11; ++k) EXPECT_LT((s.x[k] - rig.on_line(s.u[k], L)).norm(), 1e-14);

  // Bend the free part, then pull back 20 cm (0.44 → 0.24 m): vertices 5..8 enter the clamp, the
  // set shrinks to the new clamp vertex 5 and one more, both laid on the line of the step's start
  // (the wire behind the entry is straight).
  for (int k = 0; k < 9; ++k) s.x[k].y() += 1e-3 * k * k;
  rig.feeder.set_feed_speed(-0.20);
  const double L2 = rig.feeder.feed_vertex_set(1.0);
  EXPECT_NEAR(L2, 0.24, 1e-15);
  ASSERT_EQ(s.vertex_count(), 7);
  EXPECT_EQ(rig.feeder.first_clamped(), 5);
  for (int k = 5; k < 7; ++k) EXPECT_LT((s.x[k] - rig.on_line(s.u[k], 0.44)).norm(), 1e-14) << k;
  for (int k = 0; k < 5; ++k) EXPECT_NEAR(s.x[k].y(), 1e-3 * k * k, 1e-15) << "free vertex " << k << " untouched";
}

TEST(RodFeeder, HoldsTheInsertedLengthAtTheWiresEnd) {
  FeederRig rig(0.9);
  rig.feeder.drive().set_insertion_speed(1.0);
  rig.feeder.set_feed_speed(1.0);
  testing::ExpectWarnings warnings;
  const double L = rig.feeder.feed_vertex_set(1.0);
  EXPECT_TRUE(warnings.contains("wire end reached"));
  EXPECT_NEAR(L, 1.0, 1e-15);
  EXPECT_EQ(rig.feeder.feed_speed(), 0.0);
  EXPECT_EQ(rig.feeder.drive().insertion_speed(), 0.0);
}

TEST(RodFeeder, PredictsAStraightWireSlidingAlongItself) {
  // On the insertion line, "where material u − fed lay" is the line itself, fed metres further:
  // the predictor must put every free vertex exactly there.
  FeederRig rig(0.32);
  RodState& s = rig.body.state;
  const std::vector<Eigen::Vector3d> x0 = s.x;
  const std::vector<Eigen::Vector3d> v0(x0.size(), Eigen::Vector3d::Zero());
  const double fed = 0.037;
  rig.feeder.predict_feed(fed, 1e-3, x0, v0);
  for (int k = 0; k < rig.feeder.first_clamped(); ++k)
    EXPECT_LT((s.x[k] - rig.on_line(s.u[k], 0.32 + fed)).norm(), 1e-14) << k;
}

TEST(RodFeeder, ATipClampHoldsTheDistalEdge) {
  FeederRig rig(0.32);
  RodState& s = rig.body.state;
  const Eigen::Vector3d a = s.x[0] + Eigen::Vector3d(0, 0.01, 0), b = s.x[1] + Eigen::Vector3d(0, 0.01, 0);
  rig.feeder.clamp_tip(a, b);
  EXPECT_EQ(rig.feeder.first_free_dof(), 7);
  EXPECT_FALSE(rig.feeder.free_vertex(0));
  EXPECT_FALSE(rig.feeder.free_vertex(1));
  EXPECT_TRUE(rig.feeder.free_vertex(2));
  rig.feeder.set_prescribed(0.32, 0.0, s.x, s.theta);
  EXPECT_EQ(s.x[0], a);
  EXPECT_EQ(s.x[1], b);
  // The vertex next to a held edge owns half its cell (as the base clamp's does).
  VertexParams p;
  rig.feeder.vertex_params(1, p);
  EXPECT_NEAR(p.voronoi_length, 0.5 * rig.body.disc.cell_length[1], 1e-15);
  rig.feeder.vertex_params(rig.feeder.first_clamped(), p);
  EXPECT_NEAR(p.voronoi_length, 0.5 * 0.05, 1e-15);
  rig.feeder.release_tip();
  EXPECT_EQ(rig.feeder.first_free_dof(), 0);
}

}  // namespace
}  // namespace flowire::rod
