// The wall's compliance between lumen points (solid/src/lumen_compliance.cpp): the nearest
// lumen point against a search of every face, Maxwell–Betti's reciprocity, and the condensed
// compliance against a full solve of the same loads.
#include "flowire/solid/lumen_compliance.hpp"

#include <gtest/gtest.h>

#include <sched.h>
#include <cmath>

#include <numbers>
#include <thread>
#include <vector>

#include "flowire/common/element.hpp"
#include "flowire/solid/tube_wall.hpp"
#include "flowire_test.hpp"

namespace flowire::solid {
namespace {

constexpr double kA = 2e-3, kB = 2.5e-3, kL = 12e-3;

ElasticSolid supported_tube() {
  ElasticSolid s{mesh_tube_wall({kA, kB, kL, 0.6e-3, false}), NeoHookean::from_young_poisson(1e6, 0.45)};
  s.hold(s.mesh().group_named("end_0"));
  s.hold(s.mesh().group_named("end_1"));
  s.support(s.mesh().group_named("outer"), 1e8);  // tissue around the vessel
  return s;
}

/// Points just inside the lumen at several angles and heights.
std::vector<Vec3> probe_points() {
  std::vector<Vec3> x;
  for (int k = 0; k < 5; ++k) {
    const double phi = 0.4 + 1.1 * k, r = kA - 0.1e-3, z = kL / 2 + (k - 2) * 1.3e-3;
    x.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
  }
  return x;
}

Vec3 interpolate(const ElasticSolid& s, const LumenPoint& p, const Eigen::VectorXd& u) {
  double w[6];
  element::tri_p2({p.bary[1], p.bary[2], 0.0}, w);
  Vec3 v = Vec3::Zero();
  for (int a = 0; a < 6; ++a)
    v += w[a] * u.segment<3>(3 * s.mesh().faces[static_cast<size_t>(p.face)][static_cast<size_t>(a)]);
  return v;
}

TEST(LumenCompliance, LocatesTheNearestLumenPointAsASearchOfEveryFaceDoes) {
  ElasticSolid s = supported_tube();
  s.linearize();
  LumenCompliance c(s, s.mesh().group_named("lumen"));
  for (const Vec3& x : probe_points()) {
    const LumenPoint p = c.locate(x);
    double best = 1e300;
    const auto& m = s.mesh();
    for (size_t f = 0; f < m.faces.size(); ++f) {
      if (m.face_group[f] != m.group_named("lumen")) continue;
      // The distance to the flat triangle, sampled finely: never below the located one.
      for (int i = 0; i <= 20; ++i)
        for (int j = 0; i + j <= 20; ++j) {
          const double b1 = i / 20.0, b2 = j / 20.0;
          const Vec3 q = (1 - b1 - b2) * m.nodes[static_cast<size_t>(m.faces[f][0])] +
                         b1 * m.nodes[static_cast<size_t>(m.faces[f][1])] +
                         b2 * m.nodes[static_cast<size_t>(m.faces[f][2])];
          best = std::min(best, (q - x).norm());
        }
    }
    EXPECT_LE((p.point - x).norm(), best + 1e-12);
    EXPECT_NEAR(std::hypot(p.point.x(), p.point.y()), kA, 0.02 * kA);  // a chord of the circle
    const Vec3 radial(x.x(), x.y(), 0.0);
    EXPECT_LT(p.normal.dot(radial.normalized()), -0.95);  // out of the solid: towards the axis
  }
}

TEST(LumenCompliance, APatchSharesAForceAsAUniformPressureOverTheDisc) {
  ElasticSolid s = supported_tube();
  s.linearize();
  LumenCompliance c(s, s.mesh().group_named("lumen"));
  const auto& m = s.mesh();
  for (const Vec3& x : probe_points()) {
    const LumenPoint point = c.locate(x), patch = c.locate_patch(x, 0.5e-3);
    EXPECT_EQ(point.weights.size(), 6u);
    EXPECT_EQ(c.locate_patch(x, 0.0).weights, point.weights);
    EXPECT_EQ(patch.face, point.face);
    EXPECT_GT(patch.weights.size(), 6u);
    double sum = 0.0;
    Vec3 centroid = Vec3::Zero();
    for (const auto& [node, w] : patch.weights) {
      sum += w;
      centroid += w * m.nodes[static_cast<size_t>(node)];
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
    // The pressure's resultant acts at the disc's centre (to the lumen's sagitta over the disc,
    // ρ²/2a = 0.06 mm here, along the normal).
    const Vec3 off = centroid - point.point;
    EXPECT_LT((off - off.dot(point.normal) * point.normal).norm(), 0.02e-3);
    EXPECT_LT(std::abs(off.dot(point.normal)), 0.07e-3);
    // Spread, it moves the wall less on the mean than at a point.
    const std::vector<Vec3> out{-point.normal};
    EXPECT_LT(c.compliance(std::vector<LumenPoint>{patch}, out)(0, 0),
              0.95 * c.compliance(std::vector<LumenPoint>{point}, out)(0, 0));
  }
}

TEST(LumenCompliance, IsReciprocalAndIsTheFullSolvesResponse) {
  // The compliance comes from sparse forward solves (C_ij = z_iᵀ z_j, z = L⁻¹ P W d), so it is
  // symmetric by construction; each entry is checked against a full back-substitution of the
  // same factorization (K⁻¹ W_j d_j read at point i), and the whole against a nonlinear solve.
  ElasticSolid s = supported_tube();
  s.linearize();
  LumenCompliance c(s, s.mesh().group_named("lumen"));
  std::vector<LumenPoint> points;
  std::vector<Vec3> directions;
  for (const Vec3& x : probe_points()) {
    points.push_back(c.locate(x));
    directions.push_back(-points.back().normal);  // pushing the wall outwards
  }
  const Eigen::MatrixXd compliance = c.compliance(points, directions);
  const double scale = compliance.cwiseAbs().maxCoeff();
  for (size_t j = 0; j < points.size(); ++j) {
    Eigen::MatrixXd x =
        c.nodal_forces(std::span<const LumenPoint>(&points[j], 1), std::span<const Vec3>(&directions[j], 1));
    s.tangent_solve(x);
    for (size_t i = 0; i < points.size(); ++i)
      EXPECT_NEAR(compliance(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)),
                  directions[i].dot(c.interpolate(points[i], x.col(0))), 1e-9 * scale)
          << i << ", " << j;
  }
  EXPECT_GT(compliance.selfadjointView<Eigen::Lower>().ldlt().vectorD().minCoeff(), 0.0);
  EXPECT_GT(c.solved_nodes(), 0);
  // The same loads through a full (nonlinear) solve: up to 20 µN at a point, which moves the
  // lumen 0.1 µm, 1e-4 of the wall's thickness, so the response is linear to about 1e-5
  // (2 mN gives 0.2% of nonlinearity under the loaded node).
  Eigen::VectorXd lambda(5);
  lambda << 1e-5, 0.5e-5, 2e-5, 0.0, 1.5e-5;
  std::vector<Vec3> forces;
  for (int j = 0; j < 5; ++j) forces.push_back(lambda[j] * directions[static_cast<size_t>(j)]);
  ElasticSolid full = supported_tube();
  full.nodal_forces() = c.nodal_forces(points, forces);
  ASSERT_TRUE(full.solve().converged);
  const Eigen::VectorXd predicted = compliance * lambda;
  // The displacements at the loaded points from the node blocks equal those read through a
  // response as long as the solid.
  const std::vector<Vec3> at_points = c.displacements(points, forces);
  for (int i = 0; i < 5; ++i) {
    const Vec3 through_response = c.displacement(points[static_cast<size_t>(i)], points, forces);
    EXPECT_LT((at_points[static_cast<size_t>(i)] - through_response).norm(), 1e-12 * through_response.norm()) << i;
  }
  for (int i = 0; i < 5; ++i) {
    const Vec3 u = interpolate(full, points[static_cast<size_t>(i)], full.displacement());
    EXPECT_NEAR(u.dot(directions[static_cast<size_t>(i)]), predicted[i], 1e-3 * predicted.cwiseAbs().maxCoeff()) << i;
    EXPECT_LT((c.displacement(points[static_cast<size_t>(i)], points, forces) - u).norm(), 1e-3 * u.norm()) << i;
  }
}

TEST(LumenCompliance, ColumnsDroppedForTheBudgetAreSolvedAgainAndGiveTheSameCompliance) {
  // A budget of one byte keeps the fewest columns allowed (256 lumen nodes' worth): a sweep of
  // patches along the tube asks for more, the oldest are dropped, and asking for the first
  // points again solves them anew, to the same compliance as an unbounded budget's.
  ElasticSolid s = supported_tube();
  s.linearize();
  LumenCompliance kept(s, s.mesh().group_named("lumen")), tight(s, s.mesh().group_named("lumen"), 1.0);
  auto patch_at = [&](LumenCompliance& c, double z, double phi) {
    return c.locate_patch(Vec3((kA - 0.05e-3) * std::cos(phi), (kA - 0.05e-3) * std::sin(phi), z), 0.445e-3);
  };
  auto compliance_at = [&](LumenCompliance& c, double z) {
    std::vector<LumenPoint> p = {patch_at(c, z, 0.3), patch_at(c, z + 0.4e-3, 2.0)};
    const std::vector<Vec3> d = {-p[0].normal, -p[1].normal};
    return c.compliance(p, d);
  };
  const Eigen::MatrixXd first = compliance_at(tight, 2e-3);
  for (int k = 0; k < 40; ++k) {  // a sweep along the tube and round it
    const double z = 1.5e-3 + 9e-3 * k / 39.0;
    for (int j = 0; j < 6; ++j) (void)compliance_at(tight, z + 0.1e-3 * j), (void)patch_at(tight, z, j);
    std::vector<LumenPoint> ring;
    std::vector<Vec3> d;
    for (int j = 0; j < 6; ++j) ring.push_back(patch_at(tight, z, 1.05 * j)), d.push_back(-ring.back().normal);
    (void)tight.compliance(ring, d);
  }
  EXPECT_GT(tight.dropped_nodes(), 0) << "the sweep went beyond the budget";
  const int solved_before = tight.solved_nodes();
  const Eigen::MatrixXd again = compliance_at(tight, 2e-3), unbounded = compliance_at(kept, 2e-3);
  EXPECT_GT(tight.solved_nodes(), solved_before) << "the first points' columns were dropped and solved again";
  EXPECT_LT((again - first).cwiseAbs().maxCoeff(), 1e-12 * first.cwiseAbs().maxCoeff());
  EXPECT_LT((again - unbounded).cwiseAbs().maxCoeff(), 1e-12 * first.cwiseAbs().maxCoeff());
  EXPECT_EQ(kept.dropped_nodes(), 0);
}

TEST(LumenCompliance, AColumnIsTheSameToTheBitAloneInABatchOrSolvedAheadOnASecondThread) {
  // What a run gives must not depend on which thread solved a column or with which others: a
  // node's column solved alone and in a batch of eight, and a sliding wire's compliance with its
  // columns solved ahead on the second thread (anticipate) and on the caller's, agree to the bit.
  ElasticSolid s = supported_tube();
  s.linearize();
  const int lumen = s.mesh().group_named("lumen");
  LumenCompliance probe(s, lumen);
  const std::vector<int> nodes = probe.nodes_near(probe_points(), 0.5e-3);
  ASSERT_GE(nodes.size(), ElasticSolid::kHalfSolveBatch);
  std::vector<std::vector<std::pair<int, double>>> loads(3 * ElasticSolid::kHalfSolveBatch);
  for (size_t k = 0; k < ElasticSolid::kHalfSolveBatch; ++k)
    for (int c = 0; c < 3; ++c) loads[3 * k + static_cast<size_t>(c)] = {{3 * nodes[k] + c, 1.0}};
  std::vector<HalfColumns> batch(ElasticSolid::kHalfSolveBatch);
  s.half_solve(loads, batch);
  for (size_t k = 0; k < ElasticSolid::kHalfSolveBatch; ++k) {
    HalfColumns alone;
    s.half_solve(std::span(loads).subspan(3 * k, 3), alone);
    EXPECT_EQ(alone.index, batch[k].index) << "node " << nodes[k];
    EXPECT_EQ(alone.value, batch[k].value) << "node " << nodes[k];
  }
  cpu_set_t cores;
  CPU_ZERO(&cores);
  if (sched_getaffinity(0, sizeof cores, &cores) != 0 || CPU_COUNT(&cores) < 2)
    GTEST_SKIP() << "one core: nothing is solved ahead";
  LumenCompliance caller(s, lumen), ahead(s, lumen);
  auto footprints = [&](LumenCompliance& c, double z0, std::vector<Vec3>* at = nullptr) {
    std::vector<LumenPoint> p;
    for (int k = 0; k < 8; ++k) {
      const double phi = 0.3 + 0.05 * k, z = z0 + 0.25e-3 * k;
      const Vec3 x((kA - 0.05e-3) * std::cos(phi), (kA - 0.05e-3) * std::sin(phi), z);
      p.push_back(c.locate_patch(x, 0.445e-3));
      if (at) at->push_back(x);
    }
    return p;
  };
  for (int step = 0; step < 6; ++step) {
    const double z0 = 3e-3 + 0.4e-3 * step;
    const auto p = footprints(caller, z0);
    std::vector<Vec3> at;
    const auto q = footprints(ahead, z0, &at);
    std::vector<Vec3> d;
    for (const auto& x : p) d.push_back(-x.normal);
    const Eigen::MatrixXd by_caller = caller.compliance(p, d), by_ahead = ahead.compliance(q, d);
    EXPECT_EQ(by_caller, by_ahead) << "step " << step;
    ahead.anticipate(at, 0.445e-3 + 1e-3);  // the next step's, a little further along
    ahead.wait_anticipated();
  }
  EXPECT_GT(ahead.anticipated_nodes(), 0);
  EXPECT_LT(ahead.solved_nodes() - ahead.anticipated_nodes(), caller.solved_nodes())
      << "the second thread solved none of what was asked for";
}

TEST(LumenCompliance, BlocksKeptFromTheLastCallGiveTheComplianceAFreshObjectGives) {
  // A wire sliding along the wall: each call's footprints a step further on. The node blocks kept
  // from the call before give the compliance that an object asked for the first time gives, and
  // that C = Zᵀ Z gives; only the blocks of nodes new to the call are formed; after a clear (a new
  // tangent) all are.
  ElasticSolid s = supported_tube();
  s.linearize();
  LumenCompliance sliding(s, s.mesh().group_named("lumen"));
  sliding.set_way(LumenCompliance::Way::blocks);
  auto footprints = [&](LumenCompliance& c, double z0) {
    std::vector<LumenPoint> p;
    for (int k = 0; k < 8; ++k) {
      const double phi = 0.3 + 0.05 * k, z = z0 + 0.25e-3 * k;
      p.push_back(c.locate_patch(Vec3((kA - 0.05e-3) * std::cos(phi), (kA - 0.05e-3) * std::sin(phi), z), 0.445e-3));
    }
    return p;
  };
  auto directions = [](const std::vector<LumenPoint>& p) {
    std::vector<Vec3> d;
    for (const auto& q : p) d.push_back(-q.normal);
    return d;
  };
  std::uint64_t fresh_products = 0, kept_products = 0;
  for (int step = 0; step < 6; ++step) {
    const double z0 = 3e-3 + 0.4e-3 * step;
    const auto p = footprints(sliding, z0);
    const std::uint64_t before = sliding.block_products();
    const Eigen::MatrixXd kept = sliding.compliance(p, directions(p));
    LumenCompliance fresh(s, s.mesh().group_named("lumen"));
    fresh.set_way(LumenCompliance::Way::blocks);
    const auto q = footprints(fresh, z0);
    const Eigen::MatrixXd first = fresh.compliance(q, directions(q));
    // The other way, C = Zᵀ Z from the points' forward-solved forces, to the same compliance.
    LumenCompliance columns(s, s.mesh().group_named("lumen"));
    columns.set_way(LumenCompliance::Way::columns);
    const auto r = footprints(columns, z0);
    const Eigen::MatrixXd by_columns = columns.compliance(r, directions(r));
    EXPECT_LT((by_columns - first).cwiseAbs().maxCoeff(), 1e-12 * first.cwiseAbs().maxCoeff()) << "step " << step;
    EXPECT_EQ(columns.block_products(), 0u);
    EXPECT_LT((kept - first).cwiseAbs().maxCoeff(), 1e-12 * first.cwiseAbs().maxCoeff()) << "step " << step;
    EXPECT_LT((kept - kept.transpose()).cwiseAbs().maxCoeff(), 1e-15 * first.cwiseAbs().maxCoeff());
    if (step > 0) kept_products += sliding.block_products() - before, fresh_products += fresh.block_products();
  }
  EXPECT_LT(kept_products, fresh_products / 2) << "the blocks of the nodes the footprints kept were formed again";
  // Another body's contacts on the other side of the tube keep their blocks in their own cache:
  // the first body's next call at its last footprints forms none, and both agree with a fresh
  // object's.
  auto opposite = [&](LumenCompliance& c) {
    std::vector<LumenPoint> p;
    for (int k = 0; k < 8; ++k) {
      const double phi = 3.4 + 0.05 * k, z = 5e-3 + 0.25e-3 * k;
      p.push_back(c.locate_patch(Vec3((kA - 0.05e-3) * std::cos(phi), (kA - 0.05e-3) * std::sin(phi), z), 0.445e-3));
    }
    return p;
  };
  {
    const auto mine = footprints(sliding, 3e-3 + 0.4e-3 * 5), theirs = opposite(sliding);
    const Eigen::MatrixXd c_theirs = sliding.compliance(theirs, directions(theirs), 1);
    const std::uint64_t before = sliding.block_products();
    const Eigen::MatrixXd c_mine = sliding.compliance(mine, directions(mine), 0);
    EXPECT_EQ(sliding.block_products(), before) << "the other body's call displaced this body's blocks";
    LumenCompliance fresh(s, s.mesh().group_named("lumen"));
    fresh.set_way(LumenCompliance::Way::blocks);
    const auto q_mine = footprints(fresh, 3e-3 + 0.4e-3 * 5), q_theirs = opposite(fresh);
    EXPECT_LT((c_mine - fresh.compliance(q_mine, directions(q_mine))).cwiseAbs().maxCoeff(),
              1e-12 * c_mine.cwiseAbs().maxCoeff());
    EXPECT_LT((c_theirs - fresh.compliance(q_theirs, directions(q_theirs))).cwiseAbs().maxCoeff(),
              1e-12 * c_theirs.cwiseAbs().maxCoeff());
  }
  // The same footprints after a new tangent: every block formed again, none from before.
  const auto p = footprints(sliding, 3e-3);
  (void)sliding.compliance(p, directions(p));
  const std::uint64_t before = sliding.block_products();
  sliding.clear();
  (void)sliding.compliance(p, directions(p));
  LumenCompliance fresh(s, s.mesh().group_named("lumen"));
  fresh.set_way(LumenCompliance::Way::blocks);
  const auto q = footprints(fresh, 3e-3);
  (void)fresh.compliance(q, directions(q));
  EXPECT_EQ(sliding.block_products() - before, fresh.block_products());
}

}  // namespace
}  // namespace flowire::solid
