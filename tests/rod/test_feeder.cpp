// The feeder alone (rod/feeder.hpp): which vertices a fed wire simulates and where the held
// ones are, without a solve. The expected layouts are the grid and the insertion line, written
// from the material coordinate, not from the feeder's arithmetic.
#include "flowire/rod/feeder.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

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

TEST(RodFeeder, BuildsTheFreeGridAndTheClampsBoundaryAtTheEntry) {
  FeederRig rig(0.32);  // 6.4 segments inserted: free grid points 0 … 5 (7 cm from the entry)
  const RodState& s = rig.body.state;
  ASSERT_EQ(s.vertex_count(), 8);
  EXPECT_EQ(rig.feeder.first_clamped(), 6);
  const std::vector<double> u = {0.0, 0.05, 0.10, 0.15, 0.20, 0.25, 0.32, 0.37};
  for (int k = 0; k < s.vertex_count(); ++k) {
    EXPECT_NEAR(s.u[k], u[k], 1e-15);
    EXPECT_NEAR(rig.feeder.arc_lengths()[k], 0.32 - u[k], 1e-15);
    EXPECT_LT((s.x[k] - rig.on_line(s.u[k], 0.32)).norm(), 1e-14) << "straight rod at rest on the line, vertex " << k;
  }
  EXPECT_LT((s.x[6] - rig.body.model.base_position).norm(), 1e-15) << "the boundary vertex is the entry";
  EXPECT_NEAR(rig.body.disc.rest_length[5], 0.07, 1e-15);
  EXPECT_EQ(rig.feeder.first_fixed_dof(), 24);
  EXPECT_EQ(rig.feeder.first_free_dof(), 0);
  EXPECT_TRUE(rig.feeder.free_vertex(5));
  EXPECT_FALSE(rig.feeder.free_vertex(6));
}

/// The wire's total twist from edge @p j0 to the clamp's edge: Σ (θ_k − θ_{k−1} + m_k) over the
/// vertices between them.
double twist_to_clamp(const RodState& s, int j0, int clamp_edge) {
  double t = 0.0;
  for (int k = j0 + 1; k <= clamp_edge; ++k) t += s.theta[k] - s.theta[k - 1] + s.ref_twist[k];
  return t;
}

TEST(RodFeeder, FeedingInsertsGridPointsOnTheBoundaryEdgeAndPullingBackRemovesThem) {
  FeederRig rig(0.32);
  RodState& s = rig.body.state;
  const Eigen::Vector3d& pb = rig.body.model.base_position;
  const Eigen::Vector3d& db = rig.body.model.base_direction;
  // The free part on a circle of radius 0.5 m leaving the entry along the insertion line (each
  // vertex at its arc length from the entry); every edge an angle, every vertex a reference twist.
  const double R = 0.5;
  auto circle = [&](double sigma) {
    return Eigen::Vector3d(pb + R * std::sin(sigma / R) * db +
                           R * (1.0 - std::cos(sigma / R)) * Eigen::Vector3d::UnitY());
  };
  for (int k = 0; k < 6; ++k) s.x[k] = circle(0.32 - s.u[k]);
  for (size_t j = 0; j < s.theta.size(); ++j) s.theta[j] = 0.1 * std::sin(1.0 + static_cast<double>(j));
  for (size_t k = 1; k + 1 < s.ref_twist.size(); ++k) s.ref_twist[k] = 0.05 * std::cos(static_cast<double>(k));
  const double twist_before = twist_to_clamp(s, 3, 6);
  const std::vector<Eigen::Vector3d> x_bent(s.x.begin(), s.x.begin() + 6);
  // Push 12 cm in (0.32 → 0.44 m): the boundary edge would reach 19 cm, so grid points 6, 7, 8
  // (0.30, 0.35, 0.40) are inserted, leaving it 4 cm; the boundary vertex is material 0.44.
  rig.feeder.set_feed_speed(0.12);
  const double L = rig.feeder.feed_vertex_set(1.0);
  EXPECT_NEAR(L, 0.44, 1e-15);
  ASSERT_EQ(s.vertex_count(), 11);
  ASSERT_EQ(rig.feeder.first_clamped(), 9);
  const std::vector<double> u = {0.30, 0.35, 0.40, 0.44, 0.49};
  for (int k = 6; k < 11; ++k) EXPECT_NEAR(s.u[k], u[k - 6], 1e-15) << k;
  for (int k = 0; k < 6; ++k) EXPECT_EQ(s.x[k], x_bent[k]) << "free vertex " << k << " untouched";
  // Each new vertex where its material lay at 0.32 m inserted: 0.30 on the wire 2 cm inside the
  // entry (the circle, to the cubic's accuracy, 0.04 mm on these 5 and 7 cm edges, where the
  // chord from material 0.25 to the entry is 1.0 mm off it), the others and the clamp's vertices
  // on the insertion line.
  const Eigen::Vector3d on_chord = x_bent[5] + (5.0 / 7.0) * (pb - x_bent[5]);
  EXPECT_LT((s.x[6] - circle(0.02)).norm(), 0.05 * (on_chord - circle(0.02)).norm());
  for (int k = 7; k < 11; ++k) EXPECT_LT((s.x[k] - rig.on_line(s.u[k], 0.32)).norm(), 1e-14) << k;
  EXPECT_NEAR(twist_to_clamp(s, 3, 9), twist_before, 1e-15) << "the twist is carried, not made";
  s.inserted_length = L;
  rig.feeder.set_prescribed(L, 0.0, s.x, s.theta);
  EXPECT_LT((s.x[9] - pb).norm(), 1e-15) << "the boundary at the entry at the step's end";
  EXPECT_LT((s.x[10] - rig.on_line(0.49, L)).norm(), 1e-14);

  // Pull back 20 cm (0.44 → 0.24 m): grid points 8 … 5 leave (the boundary edge would be
  // shorter than half a segment), 4 (0.20) stays the last free one; the twist is kept.
  const double twist_in = twist_to_clamp(s, 3, 9);
  rig.feeder.set_feed_speed(-0.20);
  const double L2 = rig.feeder.feed_vertex_set(1.0);
  EXPECT_NEAR(L2, 0.24, 1e-15);
  ASSERT_EQ(s.vertex_count(), 7);
  ASSERT_EQ(rig.feeder.first_clamped(), 5);
  EXPECT_NEAR(s.u[5], 0.24, 1e-15);
  EXPECT_NEAR(s.u[6], 0.29, 1e-15);
  EXPECT_NEAR(rig.body.disc.rest_length[4], 0.04, 1e-15);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(s.x[k], x_bent[k]) << "free vertex " << k << " untouched";
  for (int k = 5; k < 7; ++k) EXPECT_LT((s.x[k] - rig.on_line(s.u[k], 0.44)).norm(), 1e-14) << k;
  EXPECT_NEAR(twist_to_clamp(s, 3, 5), twist_in, 1e-15);
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
  for (const double fed : {0.037, 0.12}) {  // within one segment, and past the tip by more than one
    rig.feeder.predict_feed(fed, 1e-3, x0, v0);
    for (int k = 0; k < rig.feeder.first_clamped(); ++k)
      EXPECT_LT((s.x[k] - rig.on_line(s.u[k], 0.32 + fed)).norm(), 1e-14) << k << ", fed " << fed;
  }
}

// A path that moves at a steady rate: a helix (radius 0.3 m, pitch 0.2 m per turn) leaving the
// entry along the insertion line, shifted by t·b at arc length σ > 0 from the entry (the
// insertion line behind it). A wire is inextensible, so σ stays its arc length at every t; of
// such paths, the shifted ones are those linear in t. Written from the helix's formula, not
// from the feeder's.
Eigen::Vector3d moving_path(double sigma, double t, const Eigen::Vector3d& pb, const Eigen::Vector3d& db) {
  if (sigma <= 0.0) return pb + db * sigma;
  const double r = 0.3, c = 0.2 / (2.0 * M_PI), rate = std::sqrt(r * r + c * c);
  const double th = sigma / rate;
  const Eigen::Vector3d p(r * std::cos(th) - r, r * std::sin(th), c * th);  // starts at 0 along (0, r, c)
  const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d(0.0, r, c).normalized(), db);
  return pb + q * p + t * Eigen::Vector3d(0.0, 0.01, -0.02);
}

// The slide's largest miss over the free vertices at least 0.1 m inside (the path's curvature
// and the shift jump at the entry, which only the segments next to it see) and behind the tip's
// blend (where the state's own guess is kept), for a wire of @p segments on a path sampled at
// t = −1 and 0 and fed @p fed a step; @p first_order: the path held still.
double slide_miss(int segments, double fed, bool first_order) {
  RodBody body{RodModel::from_spec(unit_rod_spec(segments)), {}, {}};
  body.state.reserve(body.max_vertices());
  Feeder feeder(body);
  const double L = 0.6;
  feeder.build(L);
  const Eigen::Vector3d pb = body.model.base_position, db = body.model.base_direction;
  const RodState& s = body.state;
  std::vector<Eigen::Vector3d> now(s.x.size()), before(s.x.size());
  for (size_t k = 0; k < now.size(); ++k) {
    now[k] = moving_path(L - s.u[k], 0.0, pb, db);
    before[k] = moving_path(L - fed - s.u[k], first_order ? 0.0 : -1.0, pb, db);
  }
  feeder.predict_slide(L + fed, {now, s.u, L}, {before, s.u, L - fed});
  double miss = 0.0;
  for (int k = 0; k < feeder.first_clamped(); ++k) {
    const double sigma = L + fed - s.u[k];
    if (sigma >= 0.1 && s.u[k] >= Feeder::kSlideBlend)
      miss = std::max(miss, (s.x[k] - moving_path(sigma, 1.0, pb, db)).norm());
  }
  return miss;
}

TEST(RodFeeder, TheSlideLandsOnAPathThatMovesSteadilyToTheCubicsOrder) {
  // 2·now(σ) − before(σ) is exact for a path moving linearly in time; what is left is the
  // cubic Hermite's between the vertices, whose tangents (the neighbouring chords) are O(h²)
  // off on a helix: O(h³).
  std::vector<double> h, miss;
  for (int n : {40, 80, 160, 320}) {
    h.push_back(1.0 / n);
    miss.push_back(slide_miss(n, 0.37 / n, false));  // the feed a fraction of a segment
  }
  const double slope = loglog_slope(h, miss);
  EXPECT_GT(slope, 2.7) << "misses " << miss[0] << " … " << miss.back();
  EXPECT_LT(miss.back(), 1e-6);
  // Held still in time (the first-order slide), the path's own motion is missed whatever h.
  EXPECT_GT(slide_miss(320, 0.37 / 320, true), 1e3 * miss.back());
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
  EXPECT_NEAR(p.voronoi_length, 0.5 * 0.07, 1e-15) << "half the boundary edge (7 cm)";
  rig.feeder.release_tip();
  EXPECT_EQ(rig.feeder.first_free_dof(), 0);
}

}  // namespace
}  // namespace flowire::rod
