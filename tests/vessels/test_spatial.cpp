// Spatial queries: the window search with its fallback against brute force, and the
// signed wall distance against its analytic value and its own gradient.
#include "flowire/vessels/spatial.hpp"

#include <gtest/gtest.h>

#include <random>

#include "flowire/vessels/generators.hpp"
#include "flowire_test.hpp"

using namespace flowire::vessels;

namespace {

bool holds(const Network& net, int s, const Vec3& p) {
  const auto& seg = net.segment(s);
  return project_on_axis(p, net.node(seg.node_from), net.node(seg.node_to)).distance <= seg.radius;
}

double wall_gap(const Network& net, int s, const Vec3& p) {
  const auto& seg = net.segment(s);
  return project_on_axis(p, net.node(seg.node_from), net.node(seg.node_to)).distance - seg.radius;
}

/// Random points near the network: on a random segment, offset up to `spread` radii.
std::vector<Vec3> random_points(const Network& net, int n, double spread, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pick(0, net.num_segments() - 1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Vec3> out;
  for (int i = 0; i < n; ++i) {
    const auto& s = net.segment(pick(rng));
    const Vec3 a = net.node(s.node_from), b = net.node(s.node_to);
    Vec3 dir(g(rng), g(rng), g(rng));
    dir.normalize();
    out.push_back(a + u(rng) * (b - a) + spread * s.radius * u(rng) * dir);
  }
  return out;
}

void check_against_brute_force(const Network& net, const std::vector<Vec3>& pts, bool chain_hints) {
  const SpatialIndex index(net, 4);
  int hint = -1;
  int inside = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    const auto& p = pts[i];
    const auto ref = index.locate_brute_force(p);
    const auto got =
        index.locate(p, chain_hints ? hint : static_cast<int>(i % static_cast<size_t>(net.num_segments())));
    ASSERT_EQ(got.inside, ref.inside) << "point " << i;
    if (ref.inside) {
      ++inside;
      EXPECT_TRUE(holds(net, got.segment, p)) << "point " << i;
    } else {
      EXPECT_NEAR(wall_gap(net, got.segment, p), wall_gap(net, ref.segment, p), 1e-15) << "point " << i;
    }
    hint = got.segment;
  }
  EXPECT_GT(inside, static_cast<int>(pts.size()) / 3);
  EXPECT_LT(inside, static_cast<int>(pts.size()));
  EXPECT_EQ(index.stats().window_hits + index.stats().fallbacks, pts.size());
}

/// Random walks of points that drift (as wire vertices between Newton iterates) and now and
/// then jump; each point's neighbourhood is kept across the walk. The fast path must give
/// the general path's answer to the last bit: same segment, same wall distance, normal and
/// Hessian.
void check_neighbourhood_against_general(const Network& net, unsigned seed) {
  const SpatialIndex index(net, 4);
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto starts = random_points(net, 60, 1.6, seed + 100);
  long queries = 0, outside = 0, blended = 0;
  for (const Vec3& start : starts) {
    Neighbourhood nb;
    int hint = -1;
    Vec3 p = start;
    for (int step = 0; step < 150; ++step) {
      const double r = net.segment(hint >= 0 ? hint : 0).radius;
      // Mostly drift; some jumps of up to about the neighbourhood's reach, so queries fall
      // both just inside and just beyond what it covers.
      const double scale = u(rng) < 0.3 ? 0.4 * u(rng) * r : 0.03 * r;
      p += scale * Vec3(g(rng), g(rng), g(rng));
      const auto ref = index.locate(p, hint);
      const auto got = index.locate(p, hint, nb);
      ASSERT_EQ(got.segment, ref.segment) << "query " << queries;
      ASSERT_EQ(got.inside, ref.inside);
      ASSERT_EQ(got.t, ref.t);
      ASSERT_EQ(got.axis_distance, ref.axis_distance);
      Vec3 g_ref, g_got;
      Eigen::Matrix3d H_ref, H_got;
      const double d_ref = index.wall_distance(p, ref.segment, &g_ref, &H_ref);
      const double d_got = index.wall_distance(p, got, nb, &g_got, &H_got);
      ASSERT_EQ(d_got, d_ref) << "query " << queries;
      ASSERT_EQ(g_got, g_ref);
      ASSERT_EQ(H_got, H_ref);
      outside += !ref.inside;
      blended += H_ref.norm() > 0.0 && std::abs(d_ref - wall_gap(net, ref.segment, p)) > 0.0;
      hint = got.segment;
      ++queries;
      // Now and then a neighbourhood of arbitrary centre and reach, which the next query may
      // find covering it, or not, by any margin.
      if (u(rng) < 0.2) index.gather(p + 0.5 * r * Vec3(g(rng), g(rng), g(rng)), 1.5 * r * u(rng), nb);
      // Pull the walk back towards the lumen so it stays near the walls.
      if (d_ref > r) p -= 0.5 * d_ref * g_ref;
    }
  }
  // The walks cover the cases that matter: outside the lumen, junction blends.
  EXPECT_GT(outside, queries / 20);
  EXPECT_GT(blended, 0);
}

}  // namespace

TEST(Spatial, WindowWithFallbackEqualsBruteForceOnTheAorta) {
  const auto net = Network::build(aortic_arch(), {.max_segment_length = 2e-3});
  check_against_brute_force(net, random_points(net, 4000, 1.6, 1), false);
}

TEST(Spatial, WindowWithFallbackEqualsBruteForceOnATree) {
  const auto net = binary_tree({.depth = 9});
  check_against_brute_force(net, random_points(net, 4000, 1.6, 2), false);
}

TEST(Spatial, AWireWalkMostlyHitsTheWindow) {
  // Points along the aortic centreline from the femoral entry up, hint = previous answer.
  const auto c = aortic_arch();
  const auto net = Network::build(c, {.max_segment_length = 2e-3});
  std::vector<Vec3> pts;
  for (const auto& b : c.branches)
    if (b.name == "right_iliac_femoral" || b.name == "descending_aorta")
      for (const auto& p : b.points) pts.push_back(p + Vec3(0.3e-3, 0, 0));
  const SpatialIndex index(net, 4);
  int hint = -1;
  for (const auto& p : pts) {
    const auto loc = index.locate(p, hint);
    ASSERT_TRUE(loc.inside);
    EXPECT_TRUE(holds(net, loc.segment, p));
    hint = loc.segment;
  }
  EXPECT_GE(index.stats().window_hits, pts.size() - 3);  // only jumps between branches miss
}

TEST(Spatial, WallDistanceIsExactInAStraightTube) {
  const auto net = Network::build(straight_tube({.length = 0.1, .radius = 2e-3}), {.max_segment_length = 5e-3});
  const SpatialIndex index(net);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 500; ++i) {
    const Vec3 p(0.005 + 0.09 * (0.5 + 0.5 * u(rng)), 3e-3 * u(rng), 3e-3 * u(rng));
    Vec3 g;
    const double d = index.wall_distance(p, -1, &g);
    const double rho = std::hypot(p.y(), p.z());
    EXPECT_NEAR(d, rho - 2e-3, 1e-15);
    EXPECT_NEAR(g.x(), 0.0, 1e-12);
    EXPECT_NEAR(g.y(), p.y() / rho, 1e-12);
  }
}

TEST(Spatial, WallDistanceGradientMatchesFiniteDifferencesAtAJunction) {
  const auto net = Network::build(y_bifurcation({}), {.max_segment_length = 5e-3});
  const SpatialIndex index(net);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1, 1);
  const Vec3 junction(0.04, 0, 0);
  const double h = 1e-8;
  int checked = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p = junction + 6e-3 * Vec3(u(rng), u(rng), u(rng));
    Vec3 g;
    const double d = index.wall_distance(p, -1, &g);
    Vec3 fd;
    for (int k = 0; k < 3; ++k) {
      Vec3 e = Vec3::Zero();
      e[k] = h;
      fd[k] = (index.wall_distance(p + e) - index.wall_distance(p - e)) / (2 * h);
    }
    // Skip points on the medial axis (distance to the axis ~ 0) where d is not differentiable.
    if (d < -0.9 * 5e-3 / std::cbrt(2.0)) continue;
    EXPECT_NEAR((g - fd).norm(), 0.0, 1e-5) << "at " << p.transpose() << " d=" << d;
    ++checked;
  }
  EXPECT_GT(checked, 1000);
}

TEST(Spatial, WallDistanceHessianMatchesFiniteDifferencesAtJunctionAndBends) {
  // At the Y junction and along the bent aorta (5 mm segments meeting at small angles,
  // where the blend's own term dominates), the Hessian is the derivative of the gradient.
  const auto y = Network::build(y_bifurcation({}), {.max_segment_length = 5e-3});
  const auto arch = Network::build(aortic_arch(), {.max_segment_length = 5e-3});
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  const double h = 1e-7;
  int checked = 0;
  for (const Network* net : {&y, &arch}) {
    const SpatialIndex index(*net);
    for (int i = 0; i < 1500; ++i) {
      // Near a node joining two segments, around the wall.
      const int seg = static_cast<int>((0.5 * (u(rng) + 1.0)) * (net->num_segments() - 1));
      const auto& sg = net->segment(seg);
      const Vec3 p = net->node(sg.node_to) + 1.2 * sg.radius * Vec3(u(rng), u(rng), u(rng));
      Vec3 g;
      Eigen::Matrix3d H;
      const double d = index.wall_distance(p, -1, &g, &H);
      if (d < -0.5 * sg.radius) continue;  // away from the medial axis (not differentiable)
      Eigen::Matrix3d fd;
      for (int k = 0; k < 3; ++k) {
        Vec3 e = Vec3::Zero();
        e[k] = h;
        Vec3 gp, gm;
        (void)index.wall_distance(p + e, -1, &gp);
        (void)index.wall_distance(p - e, -1, &gm);
        fd.col(k) = (gp - gm) / (2 * h);
      }
      // Kinks of the blend (|d − d_i| = k) and of the end caps are measure zero; skip the few
      // samples whose stencil straddles one (the FD matrix is then far from symmetric).
      if ((fd - fd.transpose()).norm() > 1e-3 * (1.0 + fd.norm())) continue;
      EXPECT_NEAR((H - fd).norm(), 0.0, 1e-4 * (1.0 + fd.norm())) << "at " << p.transpose() << " d=" << d;
      ++checked;
    }
  }
  EXPECT_GT(checked, 1500);
}

TEST(Spatial, WallDistanceIsContinuousAcrossTheJunction) {
  const auto net = Network::build(y_bifurcation({}), {.max_segment_length = 5e-3});
  const SpatialIndex index(net);
  // March across the crease between the daughters on a fine grid: no jumps.
  double prev = index.wall_distance(Vec3(0.035, -0.01, 0.002));
  double max_jump = 0;
  const int n = 4000;
  for (int i = 1; i <= n; ++i) {
    const Vec3 p(0.035 + 0.02 * i / n, -0.01 + 0.02 * i / n, 0.002);
    const double d = index.wall_distance(p);
    max_jump = std::max(max_jump, std::abs(d - prev));
    prev = d;
  }
  EXPECT_LT(max_jump, 2.0 * 0.02 * std::sqrt(2.0) / n);  // Lipschitz constant 1
}

TEST(Spatial, NeighbourhoodQueriesEqualTheGeneralPathOnTheAorta) {
  check_neighbourhood_against_general(Network::build(aortic_arch(), {.max_segment_length = 1e-3}), 11);
  check_neighbourhood_against_general(Network::build(aortic_arch(), {.max_segment_length = 5e-3}), 12);
}

TEST(Spatial, NeighbourhoodQueriesEqualTheGeneralPathOnATree) {
  check_neighbourhood_against_general(binary_tree({.depth = 7}), 13);
}

TEST(Spatial, NeighbourhoodsAreReusedByADriftingPoint) {
  // A point drifting by 0.2 % of the radius just outside the wall of the aorta: the tree is
  // descended once, then every query is answered from the neighbourhood.
  const auto net = Network::build(aortic_arch(), {.max_segment_length = 1e-3});
  const SpatialIndex index(net, 4);
  Neighbourhood nb;
  const auto& s = net.segment(net.num_segments() / 2);
  const Vec3 a = net.node(s.node_from), b = net.node(s.node_to);
  const Vec3 side = (b - a).unitOrthogonal();
  const Vec3 mid = 0.5 * (a + b);
  int hint = -1;
  for (int i = 0; i < 200; ++i) {
    const Vec3 p = mid + (1.02 + 0.002 * std::sin(0.1 * i)) * s.radius * side;
    const auto loc = index.locate(p, hint, nb);
    (void)index.wall_distance(p, loc, nb);
    hint = loc.segment;
  }
  EXPECT_EQ(index.stats().gathers, 1u);
}

TEST(Spatial, BothLocateOverloadsGiveTheSameAnswerAndCountsOnARandomCloud) {
  // Independent points (not a walk) over a generated network, each with a random hint (none
  // for some): locate(p, hint) and locate(p, hint, nb) must return the same Location, field
  // by field, and count the same window hits and fallbacks. Two indices keep the counts apart.
  const auto net = Network::build(aortic_arch(), {.max_segment_length = 2e-3});
  const SpatialIndex plain(net, 4), with_nb(net, 4);
  const auto pts = random_points(net, 3000, 2.0, 21);
  std::mt19937 rng(22);
  std::uniform_int_distribution<int> pick(-1, net.num_segments() - 1);
  Neighbourhood nb;
  long from_window = 0, outside = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    // Half the hints are the brute-force answer (a hit when the point is inside), half random.
    const int hint = i % 2 ? pick(rng) : plain.locate_brute_force(pts[i]).segment;
    const auto a = plain.locate(pts[i], hint);
    const auto b = with_nb.locate(pts[i], hint, nb);
    ASSERT_EQ(a.segment, b.segment) << "point " << i;
    ASSERT_EQ(a.inside, b.inside) << "point " << i;
    ASSERT_EQ(a.t, b.t) << "point " << i;
    ASSERT_EQ(a.axis_distance, b.axis_distance) << "point " << i;
    ASSERT_EQ(a.from_window, b.from_window) << "point " << i;
    from_window += a.from_window;
    outside += !a.inside;
  }
  EXPECT_EQ(plain.stats().window_hits, with_nb.stats().window_hits);
  EXPECT_EQ(plain.stats().fallbacks, with_nb.stats().fallbacks);
  EXPECT_EQ(plain.stats().window_hits, static_cast<std::uint64_t>(from_window));
  EXPECT_EQ(plain.stats().window_hits + plain.stats().fallbacks, pts.size());
  // The cloud exercises both stages and points outside the lumen.
  EXPECT_GT(from_window, static_cast<long>(pts.size()) / 5);
  EXPECT_GT(static_cast<long>(pts.size()) - from_window, static_cast<long>(pts.size()) / 5);
  EXPECT_GT(outside, static_cast<long>(pts.size()) / 10);
}
