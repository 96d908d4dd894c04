// The vessel path an initially inserted wire is laid on: it follows the aorta from the
// femoral entry to the aortic root, stays inside the lumen by more than the wire radius
// (also on the way back after its turn), and is parametrized by arc length.
#include "flowire/coupling/vessel_path.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

#include "flowire/vessels/generators.hpp"
#include "flowire/vessels/spatial.hpp"

using namespace flowire;
using vessels::Vec3;

namespace {

int entry_node(const vessels::Network& net) {
  const Vec3 entry = vessels::aortic_arch_entry();
  for (int e : net.ends())
    if ((net.node(e) - entry).norm() < 1e-9) return e;
  return -1;
}

}  // namespace

TEST(VesselPath, FollowsTheAortaFromTheFemoralEntryToTheRoot) {
  for (double h : {5e-3, 1e-3}) {
    const auto net = vessels::Network::build(vessels::aortic_arch(), {.max_segment_length = h});
    const int entry = entry_node(net);
    ASSERT_GE(entry, 0);
    const coupling::VesselPath path(net, entry);
    // Its end is the end of the network farthest along the widest vessels: the aortic root,
    // the widest end (the inlet of the flow).
    EXPECT_LT((path.at(path.length()) - net.node(net.widest_end())).norm(), 1e-12);
    // Arc length: the path's own polyline length, independent of how finely it is sampled.
    double sum = 0.0;
    const int n = 20000;
    for (int i = 0; i < n; ++i) sum += (path.at((i + 1) * path.length() / n) - path.at(i * path.length() / n)).norm();
    EXPECT_NEAR(sum, path.length(), 1e-5 * path.length());  // chords cut the corners
  }
}

TEST(VesselPath, TheWireCurveStaysInsideTheLumenThereAndBack) {
  const double wire_radius = 0.445e-3;
  for (double h : {5e-3, 1e-3}) {
    const auto net = vessels::Network::build(vessels::aortic_arch(), {.max_segment_length = h});
    const vessels::SpatialIndex index(net, 4);
    const coupling::VesselPath path(net, entry_node(net));
    const double L = path.max_wire_length();
    // Room for the 0.78 m wire of the aortic-arch runs: into the root and back up the arch.
    EXPECT_GT(L, 0.8);
    const double ds = 2e-4;
    Vec3 prev = path.wire_point(0.0);
    for (double s = ds; s <= L; s += ds) {
      const Vec3 p = path.wire_point(s);
      EXPECT_LT(index.wall_distance(p) + wire_radius, 0.0) << "s = " << s << " of " << L;
      // Unit speed: a chord is never longer than its arc, and shorter only at the corners
      // of the centerline polyline.
      const double chord = (p - prev).norm();
      EXPECT_LE(chord, ds * (1.0 + 1e-9));
      EXPECT_GE(chord, 0.95 * ds) << "s = " << s;
      prev = p;
    }
    EXPECT_THROW((void)path.wire_point(L + 1e-3), std::invalid_argument);
  }
}
