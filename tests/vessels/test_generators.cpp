// Synthetic anatomies (vessels/src/generators.cpp): the straight tube, the Y bifurcation and
// the binary tree against their defining geometry (Murray's law r_p³ = Σ r_d³, branching
// angles, lengths), the aortic arch's layout, and its exact scaling with `scale`.
#include "flowire/vessels/generators.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "flowire/common/error.hpp"
#include "flowire_test.hpp"

using namespace flowire::vessels;

namespace {

TEST(Generators, YBifurcationObeysMurray) {
  const auto net = Network::build(y_bifurcation({}), {.max_segment_length = 5e-3});
  const auto n = net.counts();
  EXPECT_EQ(n.branches, 3);
  EXPECT_EQ(n.junctions, 1);
  EXPECT_EQ(n.ends, 3);
  EXPECT_EQ(n.loops, 0);
  const double rp = net.segment(net.branch(0).segments[0]).radius;
  const double r1 = net.segment(net.branch(1).segments[0]).radius;
  const double r2 = net.segment(net.branch(2).segments[0]).radius;
  EXPECT_NEAR(std::pow(r1, 3) + std::pow(r2, 3), std::pow(rp, 3), 1e-20);
  EXPECT_NEAR(n.total_length, 0.12, 1e-12);
}

TEST(Generators, AorticArchIsAnAdultAortaWithThreeSupraAorticBranches) {
  const auto c = aortic_arch();
  const auto net = Network::build(c, {.max_segment_length = 5e-3});
  const auto n = net.counts();
  EXPECT_EQ(n.branches, 9);
  EXPECT_EQ(n.junctions, 4);  // brachiocephalic, carotid, subclavian, iliac bifurcation
  EXPECT_EQ(n.ends, 6);       // root, three supra-aortic, two femoral
  EXPECT_EQ(n.loops, 0);
  EXPECT_NEAR(n.radius_max, 0.014, 0.001);
  EXPECT_GT(n.radius_min, 3e-3);
  // The root is the widest end (flow inlet) and sits at the origin.
  EXPECT_LT(net.node(net.widest_end()).norm(), 1e-12);
  // The femoral entry is well below the root: a realistic insertion path of 60–80 cm.
  double path = 0;
  for (const auto& b : c.branches)
    if (b.name == "ascending_aorta" || b.name == "arch_1" || b.name == "arch_2" || b.name == "descending_aorta" ||
        b.name == "right_iliac_femoral")
      for (size_t i = 1; i < b.points.size(); ++i) path += (b.points[i] - b.points[i - 1]).norm();
  EXPECT_GT(path, 0.60);
  EXPECT_LT(path, 0.80);
  EXPECT_LT(aortic_arch_entry().z(), -0.4);
}

TEST(Generators, BinaryTreeCountsAndMurrayScaling) {
  const auto net = binary_tree({.depth = 5});
  const auto n = net.counts();
  EXPECT_EQ(n.segments, 63);
  EXPECT_EQ(n.ends, 33);
  EXPECT_EQ(n.junctions, 31);
  EXPECT_EQ(n.loops, 0);
  EXPECT_NEAR(net.segment(62).radius, 2e-3 * std::pow(2.0, -5.0 / 3.0), 1e-15);
  EXPECT_NEAR(net.segment(62).length, 20e-3 * std::pow(2.0, -5.0 / 3.0), 1e-15);
}

TEST(Generators, RejectBadParameters) {
  EXPECT_THROW(straight_tube({.length = 0.0}), flowire::Error);
  EXPECT_THROW(y_bifurcation({.parent_radius = -1.0}), flowire::Error);
  EXPECT_THROW(binary_tree({.depth = 40}), flowire::Error);
}

TEST(Generators, StraightTubeRunsAlongItsDirectionFromItsOrigin) {
  const auto c = straight_tube({.length = 0.07, .radius = 1.5e-3, .origin = Vec3(1, 2, 3), .direction = Vec3(0, 3, 4)});
  ASSERT_EQ(c.branches.size(), 1u);
  const auto& b = c.branches[0];
  EXPECT_EQ(b.points.front(), Vec3(1, 2, 3));
  EXPECT_LT((b.points.back() - Vec3(1, 2 + 0.07 * 0.6, 3 + 0.07 * 0.8)).norm(), 1e-15);  // direction normalized
  for (double r : b.radii) EXPECT_EQ(r, 1.5e-3);
  EXPECT_THROW(straight_tube({.direction = Vec3::Zero()}), flowire::Error);
  EXPECT_THROW(straight_tube({.radius = std::nan("")}), flowire::Error);
}

TEST(Generators, YBifurcationDaughtersMakeTheHalfAngleAndSplitByMurray) {
  const double rp = 4e-3, a = 0.4, theta = 0.5;
  const auto c =
      y_bifurcation({.parent_radius = rp, .parent_length = 0.03, .child_length = 0.02, .angle = theta, .asymmetry = a});
  ASSERT_EQ(c.branches.size(), 3u);
  const auto& parent = c.branches[0];
  const auto& d1 = c.branches[1];
  const auto& d2 = c.branches[2];
  EXPECT_EQ(parent.points.back(), d1.points.front());  // the daughters start at the junction
  EXPECT_EQ(parent.points.back(), d2.points.front());
  const Vec3 axis = (parent.points.back() - parent.points.front()).normalized();
  const Vec3 u1 = d1.points.back() - d1.points.front(), u2 = d2.points.back() - d2.points.front();
  EXPECT_NEAR(u1.norm(), 0.02, 1e-15);
  EXPECT_NEAR(u2.norm(), 0.02, 1e-15);
  EXPECT_NEAR(std::acos(axis.dot(u1.normalized())), theta, 1e-12);
  EXPECT_NEAR(std::acos(axis.dot(u2.normalized())), theta, 1e-12);
  EXPECT_NEAR(std::acos(u1.normalized().dot(u2.normalized())), 2 * theta, 1e-12);
  // r_1³ = (1 + a)/2 · r_p³, r_2³ = (1 − a)/2 · r_p³.
  EXPECT_NEAR(std::pow(d1.radii[0], 3), 0.7 * std::pow(rp, 3), 1e-20);
  EXPECT_NEAR(std::pow(d2.radii[0], 3), 0.3 * std::pow(rp, 3), 1e-20);
  EXPECT_THROW(y_bifurcation({.asymmetry = 1.0}), flowire::Error);
  EXPECT_THROW(y_bifurcation({.angle = 1.6}), flowire::Error);
}

TEST(Generators, AorticArchScalesExactlyAndNamesItsBranches) {
  const auto one = aortic_arch();
  const auto two = aortic_arch({.scale = 2.0});
  std::set<std::string> names;
  ASSERT_EQ(one.branches.size(), two.branches.size());
  for (size_t b = 0; b < one.branches.size(); ++b) {
    names.insert(one.branches[b].name);
    ASSERT_EQ(one.branches[b].points.size(), two.branches[b].points.size());
    for (size_t i = 0; i < one.branches[b].points.size(); ++i) {
      EXPECT_LT((two.branches[b].points[i] - 2.0 * one.branches[b].points[i]).norm(), 1e-15) << one.branches[b].name;
      EXPECT_NEAR(two.branches[b].radii[i], 2.0 * one.branches[b].radii[i], 1e-17);
    }
  }
  EXPECT_EQ(names, (std::set<std::string>{"ascending_aorta", "arch_1", "arch_2", "descending_aorta", "brachiocephalic",
                                          "left_common_carotid", "left_subclavian", "right_iliac_femoral",
                                          "left_iliac_femoral"}));
  EXPECT_LT((aortic_arch_entry({.scale = 2.0}) - 2.0 * aortic_arch_entry()).norm(), 1e-15);
  // The right femoral entry lies on the patient's right (−x) and the left one on the left.
  for (const auto& b : one.branches) {
    if (b.name == "right_iliac_femoral") {
      EXPECT_EQ(b.points.back(), aortic_arch_entry());
      EXPECT_LT(b.points.back().x(), 0.0);
    }
    if (b.name == "left_iliac_femoral") {
      EXPECT_GT(b.points.back().x(), 0.0);
    }
  }
  // Finer sampling traces the same curves between the same ends.
  const auto fine = aortic_arch({.points_per_cm = 16});
  for (size_t b = 0; b < one.branches.size(); ++b) {
    EXPECT_LT((fine.branches[b].points.front() - one.branches[b].points.front()).norm(), 1e-12);
    EXPECT_LT((fine.branches[b].points.back() - one.branches[b].points.back()).norm(), 1e-12);
  }
  EXPECT_THROW(aortic_arch({.points_per_cm = 0}), flowire::Error);
}

TEST(Generators, BinaryTreeBranchesAtItsAngleInAlternatingPlanes) {
  const double angle = 0.45;
  const auto net = binary_tree(
      {.depth = 4, .root_radius = 3e-3, .root_length = 0.02, .radius_ratio = 0.8, .length_ratio = 0.7, .angle = angle});
  ASSERT_EQ(net.num_segments(), 31);
  EXPECT_EQ(net.node(0), Vec3::Zero());
  auto dir = [&](int s) {
    const auto& seg = net.segment(s);
    return Vec3((net.node(seg.node_to) - net.node(seg.node_from)).normalized());
  };
  EXPECT_LT((dir(0) - Vec3::UnitX()).norm(), 1e-15);
  for (int s = 0; s < net.num_segments(); ++s) {
    const auto& seg = net.segment(s);
    const int gen = static_cast<int>(std::floor(std::log2(s + 1)));
    EXPECT_NEAR(seg.length, 0.02 * std::pow(0.7, gen), 1e-15);
    EXPECT_NEAR((net.node(seg.node_to) - net.node(seg.node_from)).norm(), seg.length, 1e-15);
    EXPECT_NEAR(seg.radius, 3e-3 * std::pow(0.8, gen), 1e-17);
    if (s == 0) continue;
    const int parent = (s - 1) / 2;
    EXPECT_EQ(seg.node_from, net.segment(parent).node_to);
    EXPECT_NEAR(std::acos(std::clamp(dir(s).dot(dir(parent)), -1.0, 1.0)), angle, 1e-12) << s;
  }
  // The plane of each bifurcation is perpendicular to its parent's: the normals of the
  // planes through (parent, daughters) at consecutive generations are orthogonal.
  auto plane_normal = [&](int s) {  // the plane of segment s's two daughters
    return Vec3(dir(2 * s + 1).cross(dir(2 * s + 2)).normalized());
  };
  for (int s = 1; s < 15; ++s) EXPECT_NEAR(plane_normal(s).dot(plane_normal((s - 1) / 2)), 0.0, 1e-12) << s;
  EXPECT_EQ(binary_tree({.depth = 0}).num_segments(), 1);
}

}  // namespace
