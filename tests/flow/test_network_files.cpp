// Network flow on networks read from files as other programs write them: one polyline per
// branch (a VTK writer, VMTK's branch export), each branch with its own radius and the
// junction point repeated in each, against the closed-form Poiseuille answers; and the
// resistance of a tapered segment against a numerical quadrature of 8η/(π r(x)⁴).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "flow_test_networks.hpp"
#include "flowire/flow/rlc.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/vessels/io.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

using flowire::testing::scratch_dir;
using flowire::testing::tol;
using namespace flowire::flow::test;
constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------
// Composite 8-point Gauss–Legendre quadrature of f over [a, b] in n panels.
template <class F>
double quadrature(F&& f, double a, double b, int n) {
  static constexpr std::array<double, 4> x = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                                              0.9602898564975363};
  static constexpr std::array<double, 4> w = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                              0.1012285362903763};
  const double h = (b - a) / n;
  double sum = 0.0;
  for (int p = 0; p < n; ++p) {
    const double c = a + (p + 0.5) * h;
    for (size_t k = 0; k < x.size(); ++k) sum += w[k] * (f(c - 0.5 * h * x[k]) + f(c + 0.5 * h * x[k]));
  }
  return 0.5 * h * sum;
}

/// ∫₀ˡ 8η/(π r(x)⁴) dx with r linear from r1 to r2, by quadrature.
double taper_resistance_quadrature(double eta, double l, double r1, double r2) {
  return quadrature([&](double s) { return 8.0 * eta / (kPi * std::pow(r1 + (r2 - r1) * s / l, 4)); }, 0.0, l, 400);
}

TEST(FrustumResistance, EqualsTheQuadratureOfTheLinearTaper) {
  const double eta = 3.5e-3, l = 0.03;
  for (const auto& [r1, r2] : std::vector<std::pair<double, double>>{
           {2e-3, 2e-3}, {2e-3, 1e-3}, {1e-3, 2e-3}, {4e-3, 0.4e-3}, {1.5e-3, 1.4999e-3}}) {
    const double exact = frustum_resistance(eta, l, r1, r2);
    EXPECT_NEAR(exact / taper_resistance_quadrature(eta, l, r1, r2), 1.0, 1e-12) << r1 << " -> " << r2;
    // Symmetric in its ends, and the mean radius would be wrong for a real taper.
    EXPECT_NEAR(frustum_resistance(eta, l, r2, r1) / exact, 1.0, 1e-14);
  }
  EXPECT_NEAR(frustum_resistance(eta, l, 2e-3, 2e-3) / poiseuille_resistance(eta, l, 2e-3), 1.0, 1e-15);
  // A segment's resistance is its frustum's times its sections' shape factor.
  vessels::Segment seg{0, 1, 1.5e-3, l, 0, 2e-3, 1e-3};
  EXPECT_DOUBLE_EQ(segment_resistance(eta, seg), frustum_resistance(eta, l, 2e-3, 1e-3));
  seg.shape = 1.0833;
  EXPECT_NEAR(segment_resistance(eta, seg) / frustum_resistance(eta, l, 2e-3, 1e-3), 1.0833, 1e-14);
  EXPECT_GT(frustum_resistance(eta, l, 2e-3, 1e-3) / poiseuille_resistance(eta, l, 1.5e-3), 1.1);
  // Inertance ∫ρ/(π r²) and compliance ∫ 3π r² /(2 E h/r) over the same taper.
  const double rho = 1060.0, e = 4e5, h = 0.1, r1 = 3e-3, r2 = 1.2e-3;
  auto r = [&](double s) { return r1 + (r2 - r1) * s / l; };
  EXPECT_NEAR(segment_inertance(Inertance::Poiseuille, rho, l, r1, r2) /
                  quadrature([&](double s) { return rho / (kPi * r(s) * r(s)); }, 0.0, l, 200),
              1.0, 1e-12);
  EXPECT_NEAR(segment_compliance(e, h, l, r1, r2) /
                  quadrature([&](double s) { return 3.0 * kPi * r(s) * r(s) / (2.0 * e * h); }, 0.0, l, 200),
              1.0, 1e-12);
}

// ---------------------------------------------------------------------------------------
// Legacy ASCII VTK poly data, one line cell per branch with its own point ids, a point
// array "radius"; numbers written to round trip.

struct Poly {
  std::vector<Vec3> points;
  std::vector<double> radius;
  std::vector<std::vector<long long>> lines;
  /// Adds the branch a → b with n + 1 points a + (b − a)·i/n and the radius r(i/n).
  template <class R>
  void branch(const Vec3& a, const Vec3& b, int n, R&& r) {
    std::vector<long long> ids;
    for (int i = 0; i <= n; ++i) {
      const double t = static_cast<double>(i) / n;
      ids.push_back(static_cast<long long>(points.size()));
      points.push_back(a + (b - a) * t);
      radius.push_back(r(t));
    }
    lines.push_back(std::move(ids));
  }
  [[nodiscard]] std::string legacy_vtk() const {
    std::string s = "# vtk DataFile Version 3.0\nbranches\nASCII\nDATASET POLYDATA\n";
    s += fmt::format("POINTS {} double\n", points.size());
    for (const auto& x : points) s += fmt::format("{} {} {}\n", x.x(), x.y(), x.z());
    size_t size = 0;
    for (const auto& l : lines) size += l.size() + 1;
    s += fmt::format("LINES {} {}\n", lines.size(), size);
    for (const auto& l : lines) {
      s += fmt::format("{}", l.size());
      for (const long long id : l) s += fmt::format(" {}", id);
      s += "\n";
    }
    s += fmt::format("POINT_DATA {}\nSCALARS radius double\nLOOKUP_TABLE default\n", points.size());
    for (const double r : radius) s += fmt::format("{}\n", r);
    return s;
  }
};

std::string write(const std::string& dir, const std::string& name, const std::string& text) {
  const auto path = (scratch_dir(dir) / name).string();
  std::ofstream(path) << text;
  return path;
}

/// Distance from x to the segment [a, b] and the parameter of the closest point.
std::pair<double, double> on_segment(const Vec3& x, const Vec3& a, const Vec3& b) {
  const double t = std::clamp((x - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
  return {(a + t * (b - a) - x).norm(), t};
}

// ---------------------------------------------------------------------------------------
// Reference 2 of ../shared/reference: the Murray tree, generations k = 0..5,
// r_k = 2 mm·2^(−k/3), L_k = 20 mm·2^(−k/3), inlet 1000 Pa, outlets 0 Pa. Every generation
// has the same equivalent resistance R0, so the pressure falls by 1000/6 Pa per generation
// (linearly along each vessel) and Q_k = 1000/(6 R0)/2^k.

struct MurrayFile {
  Poly poly;
  struct Edge {
    Vec3 a, b;
    int gen;
  };
  std::vector<Edge> edges;
};

/// `nudge`: each daughter starts one unit in the last place away from its parent's end.
MurrayFile murray_file(bool nudge) {
  MurrayFile m;
  std::vector<Vec3> ends = {Vec3::Zero()};
  std::vector<Vec3> dirs = {Vec3(1, 0, 0)};
  for (int v = 0; v < 63; ++v) {
    const int gen = static_cast<int>(std::floor(std::log2(v + 1)));
    const double f = std::pow(2.0, -gen / 3.0);
    const Vec3 from = v == 0 ? Vec3::Zero() : ends[static_cast<size_t>((v - 1) / 2 + 1)];
    const Vec3 dir = v == 0 ? dirs[0]
                            : Eigen::AngleAxisd((v % 2 ? 0.45 : -0.45), Vec3(0.1 * gen, 0.2, 1).normalized()) *
                                  dirs[static_cast<size_t>((v - 1) / 2)];
    const Vec3 to = from + 20e-3 * f * dir;
    Vec3 start = from;
    if (nudge && v > 0) start = Vec3(std::nextafter(from.x(), 1.0), std::nextafter(from.y(), -1.0), from.z());
    m.poly.branch(start, to, 3 + v % 4, [&](double) { return 2e-3 * f; });
    m.edges.push_back({from, to, gen});
    ends.push_back(to);
    dirs.push_back(dir);
  }
  return m;
}

void check_murray(const std::string& file) {
  vessels::ReadOptions opt;
  opt.build.max_segment_length = 4e-3;
  const Network net = vessels::read_network(file, opt);
  const auto c = net.counts();
  ASSERT_EQ(c.branches, 63);
  ASSERT_EQ(c.ends, 33);
  ASSERT_EQ(c.junctions, 31);
  const MurrayFile m = murray_file(false);
  const int inlet = net.widest_end();
  ASSERT_LT(net.node(inlet).norm(), 1e-15);
  std::vector<std::pair<int, double>> outlets;
  for (int e : net.ends())
    if (e != inlet) outlets.emplace_back(e, 0.0);
  const double r0 = 8.0 * 3.5e-3 * 20e-3 / (kPi * std::pow(2e-3, 4));  // every generation's resistance
  const double q0 = 1000.0 / (6.0 * r0);
  for (const auto kind : {SolverKind::Superposition, SolverKind::Sparse}) {
    FlowSpec spec = pressure_spec(net, inlet, Waveform::constant(1000.0), outlets);
    spec.solver = kind;
    auto s = make_solver(net, spec);
    s->advance(0.0);
    // Every node: on vessel (a, b) of generation k at fraction t, p = 1000 (1 − (k + t)/6).
    for (int i = 0; i < net.num_nodes(); ++i) {
      double best = 1.0, expected = 0.0;
      for (const auto& e : m.edges) {
        const auto [d, t] = on_segment(net.node(i), e.a, e.b);
        if (d < best) best = d, expected = 1000.0 * (1.0 - (e.gen + t) / 6.0);
      }
      ASSERT_LT(best, 1e-12) << "node " << i;
      EXPECT_NEAR(s->node_pressure(i), expected, tol(1e-10) * 1000.0) << "node " << i;
    }
    for (int seg = 0; seg < net.num_segments(); ++seg) {
      const auto& sg = net.segment(seg);
      const Vec3 mid = 0.5 * (net.node(sg.node_from) + net.node(sg.node_to));
      int gen = -1;
      for (const auto& e : m.edges)
        if (on_segment(mid, e.a, e.b).first < 1e-12) gen = e.gen;
      ASSERT_GE(gen, 0);
      EXPECT_NEAR(std::abs(s->segment_flow(seg)) / (q0 / std::pow(2.0, gen)), 1.0, tol(1e-10)) << "segment " << seg;
    }
  }
}

TEST(FlowFromFiles, MurrayTreeAsOnePolylinePerBranchIsExact) {
  check_murray(write("flow_murray_split", "murray.vtk", murray_file(false).poly.legacy_vtk()));
}

TEST(FlowFromFiles, MurrayTreeWithRoundingGapsAtTheJunctionsIsExact) {
  check_murray(write("flow_murray_rounding", "murray.vtk", murray_file(true).poly.legacy_vtk()));
}

TEST(FlowFromFiles, LinearTaperHasTheFrustumResistance) {
  // A 6 cm vessel narrowing linearly from 4 mm to 1.5 mm, written with 13 points and read
  // into segments of at most 5 mm: Q = Δp / ∫8η/(π r⁴), the integral by quadrature.
  const double l = 0.06, ra = 4e-3, rb = 1.5e-3, dp = 200.0, eta = 3.5e-3;
  Poly p;
  p.branch(Vec3(0, 0, 0), Vec3(l * 0.6, l * 0.8, 0.0), 12, [&](double t) { return ra + (rb - ra) * t; });
  const Network net = vessels::read_network(write("flow_taper", "taper.vtk", p.legacy_vtk()));
  ASSERT_GE(net.num_segments(), 12);
  const int in = net.widest_end();
  int out = -1;
  for (int e : net.ends())
    if (e != in) out = e;
  FlowSpec spec = pressure_spec(net, in, Waveform::constant(dp), {{out, 0.0}});
  auto s = make_solver(net, spec);
  s->advance(0.0);
  const double q = dp / taper_resistance_quadrature(eta, l, ra, rb);
  for (int seg = 0; seg < net.num_segments(); ++seg)
    EXPECT_NEAR(std::abs(s->segment_flow(seg)) / q, 1.0, tol(1e-10)) << "segment " << seg;
  // The pressure at distance x along the taper: Δp (1 − R(0, x)/R(0, l)).
  for (int i = 0; i < net.num_nodes(); ++i) {
    const double x = net.node(i).norm();
    const double rx = ra + (rb - ra) * x / l;
    const double expected = x > 0.0 ? dp - q * taper_resistance_quadrature(eta, x, ra, rx) : dp;
    EXPECT_NEAR(s->node_pressure(i), expected, tol(1e-10) * dp) << "node " << i;
  }
}

}  // namespace
}  // namespace flowire::flow
