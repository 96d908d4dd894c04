// Network construction: splitting, joining, counting, bad input; on the real centerlines of
// ../shared/data/real, segments that follow the bends (BuildOptions::max_chord_deviation).
#include "flowire/vessels/network.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "flowire/common/error.hpp"
#include "flowire/vessels/generators.hpp"
#include "flowire/vessels/io.hpp"
#include "flowire/vessels/spatial.hpp"
#include "flowire_test.hpp"

using namespace flowire::vessels;

namespace {

Polyline line(std::string name, Vec3 a, Vec3 b, double ra, double rb, int n = 1) {
  Polyline p;
  p.name = std::move(name);
  for (int i = 0; i <= n; ++i) {
    const double w = static_cast<double>(i) / n;
    p.points.push_back((1 - w) * a + w * b);
    p.radii.push_back((1 - w) * ra + w * rb);
  }
  return p;
}

std::string build_error(const Centerlines& c) {
  try {
    (void)Network::build(c);
  } catch (const flowire::Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Network, SplitsBranchesUniformlyNoLongerThanTheLimit) {
  Centerlines c;
  c.branches.push_back(line("a", Vec3::Zero(), Vec3(0.01, 0, 0), 1e-3, 1e-3, 7));
  BuildOptions opt;
  opt.max_segment_length = 3e-3;
  const auto net = Network::build(c, opt);
  EXPECT_EQ(net.num_segments(), 4);  // ceil(10 / 3)
  for (const auto& s : net.segments()) {
    EXPECT_LE(s.length, 3e-3 + 1e-15);
    EXPECT_NEAR(s.length, 2.5e-3, 1e-15);
    EXPECT_NEAR(s.radius, 1e-3, 1e-15);
  }
  EXPECT_NEAR(net.counts().total_length, 0.01, 1e-15);
  EXPECT_EQ(net.counts().ends, 2);
}

TEST(Network, SplitsWhereTheRadiusChangesAndAveragesTheRadius) {
  Centerlines c;
  c.branches.push_back(line("taper", Vec3::Zero(), Vec3(0.01, 0, 0), 2e-3, 1e-3, 10));
  BuildOptions opt;
  opt.max_segment_length = 1.0;
  opt.radius_change = 0.2;
  const auto net = Network::build(c, opt);
  EXPECT_GT(net.num_segments(), 2);
  double mean = 0;
  for (const auto& s : net.segments()) {
    const double r0 = 2e-3 - 1e-3 * net.node(s.node_from).x() / 0.01;
    const double r1 = 2e-3 - 1e-3 * net.node(s.node_to).x() / 0.01;
    EXPECT_NEAR(s.radius, 0.5 * (r0 + r1), 1e-15);  // exact mean of a linear taper
    EXPECT_LE(std::abs(r1 - r0), 0.2 * r0 + 1e-4 + 1e-15);
    mean += s.radius * s.length;
  }
  EXPECT_NEAR(mean / 0.01, 1.5e-3, 1e-15);
}

TEST(Network, JoinsBranchEndsIntoJunctionsAndCountsLoops) {
  // A diamond: S→A, S→B, A→T, B→T, plus A→B: two independent loops.
  const Vec3 S(0, 0, 0), A(0.01, 0.01, 0), B(0.01, -0.01, 0), T(0.02, 0, 0);
  Centerlines c;
  c.branches = {line("SA", S, A, 1e-3, 1e-3), line("SB", S, B, 1e-3, 1e-3), line("AT", A, T, 1e-3, 1e-3),
                line("BT", B, T, 1e-3, 1e-3), line("AB", A, B, 1e-3, 1e-3)};
  const auto n = Network::build(c, {.max_segment_length = 1.0, .radius_change = 0.1, .join_tolerance = 0}).counts();
  EXPECT_EQ(n.nodes, 4);
  EXPECT_EQ(n.segments, 5);
  EXPECT_EQ(n.loops, 2);
  EXPECT_EQ(n.junctions, 2);
  EXPECT_EQ(n.ends, 0);
  EXPECT_EQ(n.components, 1);
}

TEST(Network, CountsComponentsAndKeepsOne) {
  Centerlines c;
  c.branches = {line("a", Vec3::Zero(), Vec3(0.01, 0, 0), 2e-3, 2e-3),
                line("b", Vec3(0, 1, 0), Vec3(0.01, 1, 0), 1e-3, 1e-3)};
  const auto net = Network::build(c);
  EXPECT_EQ(net.counts().components, 2);
  EXPECT_EQ(net.widest_end(), 0);
  const auto kept = net.keep_component(net.widest_end());
  EXPECT_EQ(kept.counts().components, 1);
  EXPECT_NEAR(kept.counts().radius_max, 2e-3, 1e-15);
  EXPECT_NEAR(kept.counts().radius_min, 2e-3, 1e-15);
}

TEST(Network, BadInputNamesBranchAndPoint) {
  auto c = Centerlines{{line("ok", Vec3::Zero(), Vec3(0.01, 0, 0), 1e-3, 1e-3, 4)}, "file.vtp"};
  auto bad = c;
  bad.branches[0].radii[2] = 0.0;
  EXPECT_NE(build_error(bad).find("file.vtp: branch 0 ('ok'), point 2: radius 0 is not positive"), std::string::npos)
      << build_error(bad);
  bad = c;
  bad.branches[0].radii[3] = std::nan("");
  EXPECT_NE(build_error(bad).find("point 3: radius is not finite"), std::string::npos);
  bad = c;
  bad.branches[0].points[1].y() = INFINITY;
  EXPECT_NE(build_error(bad).find("point 1: coordinate is not finite"), std::string::npos);
  bad = c;
  bad.branches[0].points[2] = bad.branches[0].points[1];
  EXPECT_NE(build_error(bad).find("points 1 and 2 coincide"), std::string::npos);
  bad = c;
  bad.branches[0].points.resize(1);
  bad.branches[0].radii.resize(1);
  EXPECT_NE(build_error(bad).find("needs at least 2"), std::string::npos);
  // A branch that closes on itself in one segment is a self-loop.
  Centerlines loop{{line("loop", Vec3::Zero(), Vec3(1e-9, 0, 0), 1e-3, 1e-3)}, "f"};
  loop.branches[0].points[1] = Vec3(2e-7, 0, 0);
  EXPECT_NE(build_error(loop).find("self-loop"), std::string::npos) << build_error(loop);
  EXPECT_NE(build_error(Centerlines{{}, "empty.vtp"}).find("empty.vtp: no centerline branches"), std::string::npos);
}

TEST(Network, FarthestEndFollowsTheVessels) {
  const auto net = Network::build(aortic_arch(), {.max_segment_length = 5e-3});
  const int root = net.widest_end();
  const int far = net.farthest_end(root);
  // A femoral end: farther along the vessels than any supra-aortic end.
  EXPECT_LT(net.node(far).z(), -0.4);
  const auto d = net.path_lengths_from(root);
  EXPECT_GT(d[static_cast<size_t>(far)], 0.6);
  EXPECT_NEAR(d[static_cast<size_t>(root)], 0.0, 0.0);
}

// Bends are not cut: on every real centerline, no centerline point lies farther than 0.1 of
// its radius from the axis of the nearest segment of its own branch (measured here against the
// file's points), while the uniform 5 mm sampling alone cuts the carotid siphon's bends by more.
TEST(RealCenterlines, SegmentsFollowTheBendsWithinATenthOfTheRadius) {
  struct F {
    const char* path;
    const char* unit;
  };
  for (const F f :
       {F{"aneurisk-c0015-ica-vampy/artery_centerlines.vtp", "mm"}, F{"feelpp-aortic-arch/centerlinesAORTA.vtk", "cm"},
        F{"vmtk-abdominal-aorta-bifurcation/aorta-centerline-branches.vtp", "mm"},
        F{"simvascular-demo-aorta-iliac/rom-centerlines.vtp", "cm"}}) {
    FLOWIRE_REQUIRE_SHARED(std::string("data/real/") + f.path);
    const auto file = (flowire::testing::shared_dir() / "data/real" / f.path).string();
    auto deviation = [&](double max_chord) {
      flowire::vessels::ReadOptions ro;
      ro.length_unit = f.unit;
      ro.build.max_chord_deviation = max_chord;
      const auto net = flowire::vessels::read_network(file, ro);
      // Each network branch's polyline is the file branch cut into segments: measure every
      // node-to-node piece against the points of the file's branches that project into it.
      const auto cl = flowire::vessels::read_centerlines(file, ro);
      double worst = 0.0;
      for (const auto& b : cl.branches)
        for (size_t i = 1; i + 1 < b.points.size(); ++i) {
          double best = 1e300;
          for (const auto& s : net.segments()) {
            const auto pr = flowire::vessels::project_on_axis(b.points[i], net.node(s.node_from), net.node(s.node_to));
            best = std::min(best, pr.distance);
          }
          worst = std::max(worst, best / b.radii[i]);
        }
      return worst;
    };
    const double with = deviation(0.1), without = deviation(0.0);
    std::printf("%s: largest chord deviation / radius %.3f (uniform 5 mm sampling alone: %.3f)\n", f.path, with,
                without);
    EXPECT_LE(with, 0.1 + 1e-9) << f.path;
  }
}
