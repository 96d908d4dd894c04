// WireLocation: each free vertex's segment from the window search seeded by its previous one,
// against the index's brute-force answer, while the wire moves and after a resampling.
#include "flowire/coupling/wire_location.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "flowire/vessels/generators.hpp"
#include "flowire_test.hpp"

using namespace flowire;
using namespace flowire::coupling;
using vessels::Vec3;

namespace {

rod::RodView view_of(const std::vector<Vec3>& x, int free) {
  rod::RodView v;
  v.positions = x;
  v.first_clamped_vertex = free;
  return v;
}

/// A wire of n vertices 1 mm apart up the arch from its entry, drifting sideways by @p shift.
std::vector<Vec3> wire_up_the_arch(int n, double along, const Vec3& shift) {
  std::vector<Vec3> x;
  const Vec3 entry = vessels::aortic_arch_entry();
  for (int i = 0; i < n; ++i) x.push_back(entry + Vec3(0, 0, along + 1e-3 * (n - 1 - i)) + shift);
  return x;
}

/// Vertex i's segment holds it wherever some segment does (the window keeps the hint while it
/// holds the point: any holding segment is an answer), and is the brute-force answer's kind.
void expect_holds(const vessels::SpatialIndex& index, const WireLocation& where, int i, const Vec3& p) {
  const auto brute = index.locate_brute_force(p);
  const auto& loc = where.location(i);
  ASSERT_EQ(where.segment(i), loc.segment);
  ASSERT_GE(loc.segment, 0) << "vertex " << i;
  EXPECT_EQ(loc.inside, brute.inside) << "vertex " << i;
  const auto& seg = index.network().segment(loc.segment);
  const Vec3 a = index.network().node(seg.node_from), b = index.network().node(seg.node_to);
  const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
  if (brute.inside) {
    EXPECT_LE((p - (a + t * (b - a))).norm(), seg.radius * (1 + 1e-12)) << "vertex " << i;
  }
}

}  // namespace

TEST(WireLocation, EachFreeVertexInASegmentThatHoldsItAsTheBruteForceSearchSays) {
  const auto net = vessels::Network::build(vessels::aortic_arch(), {.max_segment_length = 2e-3});
  const vessels::SpatialIndex index(net);
  WireLocation where(index);
  InteractionStats stats;
  const int n = 24, free = 20;  // the last four held by the clamp: not looked up
  for (int step = 0; step < 30; ++step) {
    const auto x = wire_up_the_arch(n, 0.3e-3 * step, Vec3(0.1e-3 * std::sin(step), 0, 0));
    where.locate(view_of(x, free), free, stats);
    for (int i = 0; i < free; ++i) {
      expect_holds(index, where, i, x[static_cast<size_t>(i)]);
    }
    for (int i = free; i < n; ++i) EXPECT_EQ(where.segment(i), -1) << "held vertex " << i << " was looked up";
  }
  EXPECT_EQ(stats.lookups, static_cast<std::uint64_t>(30 * free));
}

TEST(WireLocation, AWireMovingAlongAVesselIsFoundInItsLastSegmentsWindowNotByTheTree) {
  const auto net =
      vessels::Network::build(vessels::straight_tube({.length = 0.1, .radius = 3e-3}), {.max_segment_length = 1e-3});
  const vessels::SpatialIndex index(net);
  WireLocation where(index);
  InteractionStats stats;
  for (int step = 0; step < 50; ++step) {
    std::vector<Vec3> x;
    for (int i = 0; i < 30; ++i) x.emplace_back(0.02 + 0.2e-3 * step + 1e-3 * (29 - i), 1e-3 * std::sin(0.3 * i), 0.0);
    where.locate(view_of(x, 30), 30, stats);
    for (int i = 0; i < 30; ++i) expect_holds(index, where, i, x[static_cast<size_t>(i)]);
  }
  // Only the first step's vertices go to the tree.
  EXPECT_LE(index.stats().fallbacks, 30u);
  EXPECT_GT(index.stats().window_hits, 40u * 30u);
}

TEST(WireLocation, AResampledWireKeepsItsHintsAndLooksUpOnlyItsNewVertices) {
  const auto net = vessels::Network::build(vessels::aortic_arch(), {.max_segment_length = 2e-3});
  const vessels::SpatialIndex index(net);
  WireLocation where(index);
  InteractionStats stats;
  const auto x = wire_up_the_arch(20, 0.02, Vec3::Zero());
  where.locate(view_of(x, 20), 20, stats);
  const auto before = where.segments();
  // Every other edge split: vertex 2j continues old vertex j, odd vertices are new.
  std::vector<Vec3> y;
  std::vector<int> source;
  for (int j = 0; j < 20; ++j) {
    y.push_back(x[static_cast<size_t>(j)]);
    source.push_back(j);
    if (j + 1 < 20) {
      y.push_back(0.5 * (x[static_cast<size_t>(j)] + x[static_cast<size_t>(j + 1)]));
      source.push_back(-1);
    }
  }
  const int n = static_cast<int>(y.size());
  const auto lookups = stats.lookups;
  where.remap(view_of(y, n), source, stats);
  EXPECT_EQ(stats.lookups - lookups, 19u);  // the new vertices only
  for (int i = 0; i < n; ++i) {
    if (i % 2 == 0) {
      EXPECT_EQ(where.segment(i), before[static_cast<size_t>(i / 2)]) << i;
    } else {
      expect_holds(index, where, i, y[static_cast<size_t>(i)]);
    }
  }
}
