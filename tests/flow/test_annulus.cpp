// Annular Poiseuille flow (flow/annulus.hpp) against what it did not compute: the
// concentric closed form, and a finite-difference solution of the cross-section
// (η Δw = −G between the two circles, w = 0 on both) on a Cartesian grid with the
// Shortley–Weller stencil at the curved boundaries, solved here from scratch.
#include <gtest/gtest.h>

#include <Eigen/Sparse>
#include <Eigen/SparseLU>
#include <cmath>
#include <map>
#include <numbers>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/flow/annulus.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

using flowire::testing::tol;
constexpr double kPi = std::numbers::pi;

/// Distance from (x, y) along the unit direction (dx, dy) to where the segment of length h
/// leaves the domain {|p| < 1, |p − (c, 0)| > k}; h if it does not.
double boundary_distance(double x, double y, double dx, double dy, double k, double c, double h) {
  double best = h;
  const double b = x * dx + y * dy, cc = x * x + y * y - 1.0;
  const double t_out = -b + std::sqrt(b * b - cc);
  if (t_out > 0.0 && t_out < best) best = t_out;
  const double xs = x - c;
  const double bi = xs * dx + y * dy, ci = xs * xs + y * y - k * k, disc = bi * bi - ci;
  if (disc >= 0.0) {
    const double t_in = -bi - std::sqrt(disc);
    if (t_in > 0.0 && t_in < best) best = t_in;
  }
  return best;
}

/// Q/Q_tube of the cross-section by finite differences on an n × n grid over [−1, 1]²
/// (tube radius 1, wire radius k, wire axis at (c, 0)): −Δw = 1, Q = Σ w h², Q_tube = π/8.
double fd_flow_fraction(double k, double e, int n) {
  const double c = e * (1.0 - k), h = 2.0 / n;
  auto inside = [&](double x, double y) { return x * x + y * y < 1.0 && (x - c) * (x - c) + y * y > k * k; };
  std::vector<int> id(static_cast<size_t>((n + 1) * (n + 1)), -1);
  std::vector<std::pair<int, int>> pts;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      if (inside(-1.0 + h * i, -1.0 + h * j)) {
        id[static_cast<size_t>(i * (n + 1) + j)] = static_cast<int>(pts.size());
        pts.emplace_back(i, j);
      }
  const int m = static_cast<int>(pts.size());
  std::vector<Eigen::Triplet<double>> trip;
  for (int p = 0; p < m; ++p) {
    const auto [i, j] = pts[static_cast<size_t>(p)];
    const double x = -1.0 + h * i, y = -1.0 + h * j;
    double diag = 0.0;
    for (const auto& [di, dj] : {std::pair{1, 0}, std::pair{0, 1}}) {
      double arm[2];
      int nb[2];
      for (int side = 0; side < 2; ++side) {
        const int sgn = side == 0 ? 1 : -1;
        const int ii = i + sgn * di, jj = j + sgn * dj;
        nb[side] = id[static_cast<size_t>(ii * (n + 1) + jj)];
        arm[side] = nb[side] >= 0 ? h : boundary_distance(x, y, sgn * di, sgn * dj, k, c, h);
        if (nb[side] >= 0 && boundary_distance(x, y, sgn * di, sgn * dj, k, c, h) < h) {
          // The neighbour is inside but the wire lies between: the boundary is nearer.
          arm[side] = boundary_distance(x, y, sgn * di, sgn * dj, k, c, h);
          nb[side] = -1;
        }
      }
      const double f = 2.0 / (arm[0] + arm[1]);
      diag += f * (1.0 / arm[0] + 1.0 / arm[1]);
      for (int side = 0; side < 2; ++side)
        if (nb[side] >= 0) trip.emplace_back(p, nb[side], -f / arm[side]);
    }
    trip.emplace_back(p, p, diag);
  }
  Eigen::SparseMatrix<double> a(m, m);
  a.setFromTriplets(trip.begin(), trip.end());
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu(a);
  const Eigen::VectorXd w = lu.solve(Eigen::VectorXd::Ones(m));
  return w.sum() * h * h / (kPi / 8.0);
}

// A 0.014" wire in a 3 mm vessel.
constexpr double kRatio = 0.178 / 1.5;

TEST(Annulus, ConcentricClosedFormAndItsLimits) {
  const double k = kRatio, k2 = k * k;
  const double closed = 1.0 - k2 * k2 - (1.0 - k2) * (1.0 - k2) / std::log(1.0 / k);
  EXPECT_NEAR(annulus_flow_fraction(k, 0.0), closed, 1e-15);
  // The exact concentric annulus of a 0.014" wire in a 3 mm tube passes 54% of the flow.
  EXPECT_NEAR(annulus_flow_fraction(k, 0.0), 0.5438, 1e-4);
  EXPECT_EQ(annulus_flow_fraction(0.0, 0.3), 1.0);
  // A vanishing wire takes nothing; a wire filling the tube takes everything.
  // A wire that nearly fills the tube leaves a slot of gap δ = R − a: plane Poiseuille flow
  // Gδ³/(12η) per unit width around the circumference 2πR, i.e. Q/Q_tube → (4/3)(δ/R)³.
  for (double gap : {0.05, 0.01, 0.002}) {
    const double slot = 4.0 / 3.0 * gap * gap * gap;
    EXPECT_NEAR(annulus_flow_fraction(1.0 - gap, 0.0) / slot, 1.0, 0.6 * gap) << gap;
  }
  EXPECT_NEAR(annulus_resistance_factor(k, 0.0) * annulus_flow_fraction(k, 0.0), 1.0, 1e-15);
}

TEST(Annulus, EccentricSeriesMeetsTheConcentricClosedForm) {
  // The bipolar series at small offsets is a different formula from the logarithmic closed
  // form: they agree to the offset's second order (the flow is even in c).
  for (double k : {0.05, kRatio, 0.3, 0.6}) {
    const double q0 = annulus_flow_fraction(k, 0.0);
    for (double e : {1e-6, 1e-4, 1e-3}) EXPECT_NEAR(annulus_flow_fraction(k, e), q0, 10.0 * e * e) << k << " " << e;
  }
}

TEST(Annulus, FlowGrowsMonotonicallyAsTheWireMovesToTheWall) {
  for (double k : {0.05, kRatio, 0.3, 0.6}) {
    double prev = 0.0;
    for (int i = 0; i <= 100; ++i) {
      const double q = annulus_flow_fraction(k, i / 100.0);
      EXPECT_GT(q, prev) << k << " " << i;
      prev = q;
    }
    // Beyond the cap the value is that of the cap (clamped, not extrapolated).
    EXPECT_EQ(annulus_flow_fraction(k, 1.2), annulus_flow_fraction(k, kMaxAnnulusEccentricity));
  }
}

TEST(Annulus, AgreesWithAFiniteDifferenceCrossSection) {
  // For each case: the FD error on grids of 50..200 cells per diameter, its log-log slope
  // (second order or better), and the finest error. The error is not monotone (the grid
  // cuts the circles differently at each size), so the slope is a least-squares fit.
  for (double e : {0.0, 0.5, 0.99}) {
    const double exact = annulus_flow_fraction(kRatio, e);
    std::vector<double> lh, le;
    double finest = 0.0;
    for (int n : {50, 100, 200}) {
      const double err = std::abs(fd_flow_fraction(kRatio, e, n) - exact) / exact;
      lh.push_back(std::log(2.0 / n));
      le.push_back(std::log(std::max(err, 1e-14)));
      finest = err;
      std::printf("annulus a/R %.4f e %.2f: n %3d  FD/exact − 1 = %.2e\n", kRatio, e, n, err);
    }
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    const double m = static_cast<double>(lh.size());
    for (size_t i = 0; i < lh.size(); ++i) sx += lh[i], sy += le[i], sxx += lh[i] * lh[i], sxy += lh[i] * le[i];
    const double slope = (m * sxy - sx * sy) / (m * sxx - sx * sx);
    std::printf("annulus e %.2f: slope %.2f, finest error %.2e\n", e, slope, finest);
    EXPECT_GT(slope, 1.5) << e;
    EXPECT_LT(finest, tol(2e-5)) << e;
  }
}

TEST(Annulus, ThickWireAgainstFiniteDifferences) {
  for (double e : {0.0, 0.7}) {
    const double exact = annulus_flow_fraction(0.5, e);
    EXPECT_NEAR(fd_flow_fraction(0.5, e, 200) / exact, 1.0, tol(1e-4)) << e;
  }
}

TEST(Annulus, BadArgumentsAreRefused) {
  EXPECT_THROW((void)annulus_flow_fraction(1.0, 0.0), Error);
  EXPECT_THROW((void)annulus_flow_fraction(-0.1, 0.0), Error);
  EXPECT_THROW((void)annulus_flow_fraction(std::nan(""), 0.0), Error);
  EXPECT_THROW((void)annulus_flow_fraction(0.1, std::nan("")), Error);
}

}  // namespace
}  // namespace flowire::flow
