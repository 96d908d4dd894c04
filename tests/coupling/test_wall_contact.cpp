// WallContact: the wall penalty and the introducer against a Wall. Its reported energy, forces
// and position Jacobians against central differences on the arch's blended junction walls
// (smoothed onset on); what it records at the end of a step (the lagged normal forces the
// friction presses with, the "outside" record) against the penalty law at the accepted state;
// and its checkpoint.
#include "flowire/coupling/wall_contact.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "flowire/vessels/generators.hpp"
#include "flowire_test.hpp"

using namespace flowire;
using namespace flowire::coupling;
using vessels::Vec3;

namespace {

struct ArchWall {
  vessels::Network net = vessels::Network::build(vessels::aortic_arch(), {.max_segment_length = 2e-3});
  vessels::SpatialIndex index{net};
  WireLocation where{index};
  NetworkWall wall{where};
  std::vector<double> arc, radius;
  rod::RodView view(const std::vector<Vec3>& x) {
    arc.resize(x.size());
    for (size_t i = 0; i < x.size(); ++i) arc[i] = 1e-3 * static_cast<double>(x.size() - i);
    radius.assign(x.size() - 1, 0.45e-3);
    rod::RodView v;
    v.positions = x;
    v.velocities = x;  // unused by the contact
    v.arc_length = arc;
    v.radius = radius;
    v.first_clamped_vertex = static_cast<int>(x.size());
    v.dt = 1e-2;
    return v;
  }
  /// Energy, forces and Jacobians of @p contact at @p x.
  rod::ForceAccumulator evaluate(WallContact& contact, const std::vector<Vec3>& x) {
    const auto v = view(x);
    InteractionStats stats;
    where.locate(v, v.vertex_count(), stats);
    rod::ForceAccumulator acc;
    acc.reset(v.vertex_count());
    std::vector<Vec3> tally(x.size(), Vec3::Zero());
    contact.evaluate(v, v.vertex_count(), wall, acc, tally, stats);
    for (size_t i = 0; i < x.size(); ++i) EXPECT_LT((tally[i] - acc.forces()[i]).norm(), 1e-15) << i;
    return acc;
  }
  /// Vertices pressed into the walls near the arch's junctions: each a random point of a
  /// random segment pushed out to the wall, give or take a wire radius.
  std::vector<Vec3> pressed_vertices(int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> seg(0, net.num_segments() - 1);
    std::uniform_real_distribution<double> u(0.0, 1.0), depth(-0.6e-3, 0.2e-3);
    std::vector<Vec3> x;
    while (static_cast<int>(x.size()) < n) {
      const auto& s = net.segment(seg(rng));
      const Vec3 a0 = net.node(s.node_from), a1 = net.node(s.node_to);
      const Vec3 axis = (a1 - a0).normalized();
      const Vec3 side = Eigen::AngleAxisd(6.283 * u(rng), axis) * axis.unitOrthogonal();
      x.push_back(a0 + u(rng) * (a1 - a0) + (s.radius + depth(rng)) * side);
    }
    return x;
  }
};

/// What @p contact presses with is the force of @p forces: −k φ′(δ) ∇d per vertex (∇d is not a
/// unit vector in a junction's blend).
void expect_presses_with(const WallContact& contact, const rod::ForceAccumulator& forces) {
  for (size_t i = 0; i < forces.forces().size(); ++i) {
    const int k = static_cast<int>(i);
    if (contact.normal_force(k) > 0.0) {
      EXPECT_LT((contact.normal(k) * contact.normal_force(k) + forces.forces()[i]).norm(), 1e-12) << i;
    } else {
      EXPECT_EQ(forces.forces()[i], Vec3::Zero()) << i;
    }
  }
}

}  // namespace

TEST(WallContact, EnergyForcesAndJacobiansMatchCentralDifferencesAtJunctionsWithTheOnset) {
  ArchWall arch;
  ContactParams p{.stiffness = 3e4, .onset = 0.09e-3};
  WallContact contact(p, 0.45e-3);
  const auto x = arch.pressed_vertices(300, 11);
  const auto acc = arch.evaluate(contact, x);
  int active = 0;
  const double h = 1e-8;
  for (size_t i = 0; i < x.size(); ++i) {
    if (acc.forces()[i].norm() == 0.0) continue;
    ++active;
    for (int c = 0; c < 3; ++c) {
      auto xp = x, xm = x;
      xp[i][c] += h;
      xm[i][c] -= h;
      const auto ap = arch.evaluate(contact, xp), am = arch.evaluate(contact, xm);
      const double f = acc.forces()[i].norm();
      EXPECT_NEAR(-(ap.energy() - am.energy()) / (2 * h), acc.forces()[i][c], 1e-5 * f + 1e-9) << i;
      const Vec3 col = (ap.forces()[i] - am.forces()[i]) / (2 * h);
      EXPECT_LT((col - acc.position_jacobians()[i].col(c)).norm(),
                1e-4 * (p.stiffness + acc.position_jacobians()[i].norm()))
          << "vertex " << i << " column " << c;
    }
    // Every force is conservative: the rod's line search measures it by the energy.
    EXPECT_EQ(acc.forces()[i], acc.conservative_forces()[i]);
  }
  EXPECT_GT(active, 100);
}

TEST(WallContact, TheIntroducerPushesAVertexBehindTheEntryBackAlongTheAxisWithItsEnergysGradient) {
  ArchWall arch;
  ContactParams p{.stiffness = 3e4};
  WallContact contact(p, 0.45e-3);
  const Vec3 entry = vessels::aortic_arch_entry();
  const Vec3 into(0, 0, 1);  // the arch's femoral entry points up the iliac
  contact.set_introducer(entry, into, 2e-3);
  const double a = 0.45e-3;
  // One vertex 0.3 mm behind the plane a wire radius behind the entry, one in front of the entry.
  const std::vector<Vec3> x = {entry + Vec3(0, 0, 1e-3), entry - (a + 0.3e-3) * into};
  const auto acc = arch.evaluate(contact, x);
  EXPECT_EQ(contact.introducer_contacts(), 1u);
  EXPECT_LT((acc.forces()[1] - p.stiffness * 0.3e-3 * into).norm(), 1e-9);
  EXPECT_NEAR(acc.energy() - 0.5 * p.stiffness * 0.3e-3 * 0.3e-3, 0.0, 1e-12);
}

TEST(WallContact, AtTheEndOfAStepItRecordsThePenaltysNormalForceAndHowFarOutsideTheWireWent) {
  ArchWall arch;
  ContactParams p{.stiffness = 3e4, .onset = 0.05e-3};
  WallContact contact(p, 0.45e-3);
  const auto x = arch.pressed_vertices(200, 5);
  auto acc = arch.evaluate(contact, x);
  // Before any step ends, the friction would press with this evaluation's forces.
  EXPECT_FALSE(contact.lagged());
  expect_presses_with(contact, acc);
  InteractionStats stats;
  contact.end_step(arch.view(x), arch.wall, stats);
  ASSERT_TRUE(contact.lagged());
  contact.save_checkpoint();
  double deepest = -1.0;
  expect_presses_with(contact, acc);
  for (size_t i = 0; i < x.size(); ++i) deepest = std::max(deepest, arch.index.wall_distance(x[i]) + 0.45e-3);
  EXPECT_NEAR(stats.max_penetration, deepest, 1e-12);
  // Vertices up to 0.2 mm beyond the wall: less than a wire radius, never recorded as outside.
  EXPECT_LT(stats.outside_time, 0.0);
  // The next evaluation (another state) does not change what the step presses with …
  const auto y = arch.pressed_vertices(200, 6);
  (void)arch.evaluate(contact, y);
  expect_presses_with(contact, acc);
  // … nor does another end of step once the checkpoint is restored.
  contact.end_step(arch.view(y), arch.wall, stats);
  contact.restore_checkpoint();
  expect_presses_with(contact, acc);
  // A vertex 1.5 wire radii outside is recorded, with when and where.
  Vec3 g;
  const double d0 = arch.index.wall_distance(x[0], -1, &g);
  std::vector<Vec3> out = {x[0] + (1.5 * 0.45e-3 - d0) * g, x[1]};
  auto v = arch.view(out);
  v.time = 0.25;
  InteractionStats located, recorded;
  arch.where.locate(v, 2, located);
  contact.end_step(v, arch.wall, recorded);
  const double d = arch.index.wall_distance(out[0]);
  ASSERT_GT(d, 0.45e-3);
  EXPECT_EQ(recorded.outside_time, 0.25);
  EXPECT_EQ(recorded.outside_distance, d);
  EXPECT_EQ(recorded.outside_position, out[0]);
  EXPECT_NEAR(recorded.max_outside, d, 1e-15);
}
