// The catheter over the wire: the lumen penalty's gradients and Hessian blocks against
// central differences of its energy; action and reaction between the two rods; and the
// composite bending of an overlapping pair against the Euler–Bernoulli cantilever with
// EI_wire + EI_catheter (tip deflection P L³ / (3 EI)), converging in the segment length.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>

#include "flowire/common/config.hpp"
#include "flowire/coupling/catheter.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/flow/annulus.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire_test.hpp"

using namespace flowire;
using namespace flowire::coupling;

namespace {

using V3 = Eigen::Vector3d;

// ∂E/∂y and ∂²E/∂y² (diagonal block) of the penalty w.r.t. y ∈ {x, a, b} by central differences.
void check_block(const V3& x, const V3& a, const V3& b, double c, double k, bool open, int which, double onset = 0.0) {
  const LumenPenalty p = lumen_penalty(x, a, b, c, k, open, onset);
  ASSERT_GT(p.energy, 0.0);
  const V3& grad = which == 0 ? p.grad_x : which == 1 ? p.grad_a : p.grad_b;
  const Eigen::Matrix3d& hess = which == 0 ? p.hess_xx : which == 1 ? p.hess_aa : p.hess_bb;
  const double h = 1e-7;
  auto at = [&](int m, double s) {
    V3 xs = x, as = a, bs = b;
    (which == 0 ? xs : which == 1 ? as : bs)[m] += s;
    return lumen_penalty(xs, as, bs, c, k, open, onset);
  };
  for (int m = 0; m < 3; ++m) {
    const LumenPenalty plus = at(m, h), minus = at(m, -h);
    const double fd = (plus.energy - minus.energy) / (2 * h);
    EXPECT_NEAR(grad[m], fd, 1e-6 * (std::abs(fd) + k * 1e-4)) << "grad, block " << which << ", m " << m;
    const V3& gp = which == 0 ? plus.grad_x : which == 1 ? plus.grad_a : plus.grad_b;
    const V3& gm = which == 0 ? minus.grad_x : which == 1 ? minus.grad_a : minus.grad_b;
    const V3 col = (gp - gm) / (2 * h);
    for (int l = 0; l < 3; ++l)
      EXPECT_NEAR(hess(l, m), col[l], 1e-5 * k) << "hessian, block " << which << ", (" << l << "," << m << ")";
    if (which == 2) {  // the cross block ∂²E/∂a∂b: column m of ∂(∂E/∂a)/∂b
      const V3 cross = (plus.grad_a - minus.grad_a) / (2 * h);
      for (int l = 0; l < 3; ++l)
        EXPECT_NEAR(p.hess_ab(l, m), cross[l], 1e-5 * k) << "hessian a-b, (" << l << "," << m << ")";
    }
    if (which > 0) {  // the cross blocks ∂²E/∂x∂a, ∂²E/∂x∂b: column m of ∂(∂E/∂x)/∂a or /∂b
      const V3 cross = (plus.grad_x - minus.grad_x) / (2 * h);
      const Eigen::Matrix3d& hx = which == 1 ? p.hess_xa : p.hess_xb;
      for (int l = 0; l < 3; ++l)
        EXPECT_NEAR(hx(l, m), cross[l], 1e-5 * k)
            << "hessian x-" << (which == 1 ? "a" : "b") << ", (" << l << "," << m << ")";
    }
  }
}

}  // namespace

TEST(LumenPenalty, DerivativesMatchCentralDifferences) {
  const V3 a(0.0, 0.0, 0.0), b(1e-3, 0.2e-3, -0.1e-3);
  const double c = 5e-5, k = 3e4;
  // interior projection, near each end, and the open tip end (before a, on the line)
  for (const V3& x : {V3(0.4e-3, 0.3e-3, 0.15e-3), V3(0.9e-3, -0.25e-3, 0.2e-3), V3(0.1e-3, 0.1e-3, -0.3e-3)})
    for (int which = 0; which < 3; ++which) check_block(x, a, b, c, k, false, which);
  const V3 before(-0.2e-3, 0.2e-3, 0.1e-3), behind(1.3e-3, 0.3e-3, 0.1e-3);
  for (int which = 0; which < 3; ++which) check_block(before, a, b, c, k, true, which);
  check_block(before, a, b, c, k, false, 0);  // the closed end: distance to the point a
  check_block(before, a, b, c, k, false, 1);
  check_block(behind, a, b, c, k, false, 0);  // beyond b: distance to b
  check_block(behind, a, b, c, k, false, 2);
  // the open tip end, where the penalty is tapered (tip_weight): half an edge inside the tip
  // to half an edge beyond it, the weight's ramp, its ends and the plain part past it
  const V3 e = b - a, lateral = e.cross(V3::UnitZ()).normalized() * 2.5 * c + V3(0, 0, 1.5 * c);
  for (const double alpha : {-0.45, -0.3, -0.12, 0.0, 0.2, 0.45, 0.7})
    for (int which = 0; which < 3; ++which) check_block(a + alpha * e + lateral, a, b, c, k, true, which);
  // inside the clearance: no force
  const V3 side = (b - a).cross(V3::UnitZ()).normalized();
  EXPECT_EQ(lumen_penalty(0.5 * (a + b) + 0.6 * c * side, a, b, c, k).energy, 0.0);
  EXPECT_GT(lumen_penalty(0.5 * (a + b) + 1.4 * c * side, a, b, c, k).energy, 0.0);
}

TEST(LumenPenalty, SmoothedOnsetDerivativesMatchCentralDifferences) {
  // The penalty k φ(d − c) with its onset smoothed over |d − c| < δ/2 (onset_quadratic), a wide
  // band (δ = 0.4 c) so that each point below sits well inside it or past it: every gradient
  // and Hessian block against central differences of E, at an interior projection, at a closed
  // end, at the open tip end (distance to the line) and across the tip's taper.
  const V3 a(0.0, 0.0, 0.0), b(1e-3, 0.2e-3, -0.1e-3);
  const double c = 5e-5, k = 3e4, onset = 0.4 * c;
  const V3 e = b - a, side = e.cross(V3::UnitZ()).normalized();
  const V3 up = side.cross(e).normalized();
  // d − c = s δ/2: below the band's middle, above it, near its top, and past it
  for (const double s : {-0.7, -0.2, 0.3, 0.9, 1.6}) {
    const double d = c + 0.5 * s * onset;
    const V3 off = d * (0.6 * side + 0.8 * up);  // |off| = d, perpendicular to e
    for (int which = 0; which < 3; ++which) {
      check_block(a + 0.4 * e + off, a, b, c, k, false, which, onset);  // interior
      check_block(a + 0.7 * e + off, a, b, c, k, true, which, onset);   // tip edge, full weight
      for (const double alpha : {-0.3, 0.1})                            // the taper
        check_block(a + alpha * e + off, a, b, c, k, true, which, onset);
    }
    check_block(b + d * e.normalized(), a, b, c, k, false, 0, onset);  // beyond b: distance to the end point
    check_block(b + d * e.normalized(), a, b, c, k, false, 2, onset);
  }
  // Below the band: no force; past it the force is that of ½ k (d − c)² exactly.
  EXPECT_EQ(lumen_penalty(a + 0.5 * e + (c - 0.51 * onset) * side, a, b, c, k, false, onset).energy, 0.0);
  EXPECT_GT(lumen_penalty(a + 0.5 * e + (c - 0.49 * onset) * side, a, b, c, k, false, onset).energy, 0.0);
  const V3 x = a + 0.5 * e + (c + 2.0 * onset) * side;
  EXPECT_NEAR(lumen_penalty(x, a, b, c, k, false, onset).grad_x.norm(), lumen_penalty(x, a, b, c, k).grad_x.norm(),
              1e-12 * k * onset);
}

TEST(LumenPenalty, OnsetQuadraticIsTwiceContinuouslyDifferentiable) {
  // φ(g): 0 below −δ/2, the cubic (g + δ/2)³/(6δ) over the band, ½ g² + δ²/24 past it. Its φ′ and
  // φ″ are those of φ (central differences), φ, φ′ and φ″ are continuous at both ends of the band
  // (φ″ = 0 and 1 there: the stiffness k φ″ of the penalty has no jump, which ½ g₊² has at
  // g = 0), and δ = 0 is the plain ½ g₊².
  const double delta = 2e-6, h = 1e-11;
  for (double g = -1.2 * delta; g <= 1.2 * delta; g += 0.01 * delta) {
    double d1 = 0.0, d2 = 0.0, d1p = 0.0, d1m = 0.0;
    (void)onset_quadratic(g, delta, &d1, &d2);
    const double fp = onset_quadratic(g + h, delta, &d1p), fm = onset_quadratic(g - h, delta, &d1m);
    EXPECT_NEAR(d1, (fp - fm) / (2 * h), 1e-6 * delta) << "g / delta " << g / delta;
    EXPECT_NEAR(d2, (d1p - d1m) / (2 * h), 1e-4) << "g / delta " << g / delta;
  }
  for (const double end : {-0.5 * delta, 0.5 * delta}) {
    double f[2], d1[2], d2[2];
    for (int side = 0; side < 2; ++side)
      f[side] = onset_quadratic(end + (side ? 1e-13 : -1e-13), delta, &d1[side], &d2[side]);
    // (a jump would be δ²/24, δ/2 and 1; 2e-13 apart they differ by the slope times 2e-13)
    EXPECT_NEAR(f[0], f[1], 1e-6 * delta * delta);
    EXPECT_NEAR(d1[0], d1[1], 1e-6 * delta);
    EXPECT_NEAR(d2[0], d2[1], 1e-6);
  }
  double d2 = 0.0;
  (void)onset_quadratic(0.5 * delta + 1e-13, delta, nullptr, &d2);
  EXPECT_NEAR(d2, 1.0, 1e-6);
  (void)onset_quadratic(-0.5 * delta + 1e-13, delta, nullptr, &d2);
  EXPECT_NEAR(d2, 0.0, 1e-6);
  double d1 = 0.0;
  EXPECT_EQ(onset_quadratic(3e-6, 0.0, &d1, &d2), 0.5 * 3e-6 * 3e-6);
  EXPECT_EQ(d1, 3e-6);
  EXPECT_EQ(onset_quadratic(-1e-9, 0.0, &d1, &d2), 0.0);
  EXPECT_EQ(d2, 0.0);
}

TEST(LumenPenalty, TipWeightIsTheSmoothedShareOfTheCellInsideTheLumen) {
  // w(α) = s(α + ½), s the quintic smoothstep: 0 half an edge beyond the tip, ½ at the tip
  // end (half the vertex's cell inside), 1 half an edge inside; w′ and w″ continuous (0 at
  // both ends of the ramp) and the derivatives those of w (central differences).
  EXPECT_EQ(tip_weight(-0.5), 0.0);
  EXPECT_EQ(tip_weight(-0.9), 0.0);
  EXPECT_DOUBLE_EQ(tip_weight(0.0), 0.5);
  EXPECT_EQ(tip_weight(0.5), 1.0);
  EXPECT_EQ(tip_weight(3.0), 1.0);
  const double h = 1e-5;
  for (double alpha = -0.6; alpha <= 0.6; alpha += 0.01) {
    double dw = 0.0, d2w = 0.0;
    (void)tip_weight(alpha, &dw, &d2w);
    double dp = 0.0, dm = 0.0;
    const double wp = tip_weight(alpha + h, &dp), wm = tip_weight(alpha - h, &dm);
    EXPECT_NEAR(dw, (wp - wm) / (2 * h), 1e-8) << "alpha " << alpha;
    EXPECT_NEAR(d2w, (dp - dm) / (2 * h), 5e-4) << "alpha " << alpha;  // (w‴ jumps at the ramp's ends: O(h) there)
  }
  for (const double end : {-0.5, 0.5}) {  // the ramp's ends: w′ and w″ go to 0 (C²)
    double dw = 1.0, d2w = 1.0;
    (void)tip_weight(end + 1e-6, &dw, &d2w);
    EXPECT_LT(std::abs(dw), 1e-9);
    EXPECT_LT(std::abs(d2w), 1e-3);
    (void)tip_weight(end - 1e-6, &dw, &d2w);
    EXPECT_LT(std::abs(dw), 1e-9);
    EXPECT_LT(std::abs(d2w), 1e-3);
  }
}

namespace {
/// A straight catheter of `n` edges of length h, its tip at the origin and its entry at
/// x = n h (vertices tip first), and one wire vertex held at α edges from the tip end along
/// the tip edge (α < 0: beyond the tip), y off the axis; its edge assigned.
LumenContact straight_lumen(double alpha, double y, double c, double k, int n = 6, double h = 2e-3) {
  LumenContact lc(c, k);
  for (int j = 0; j <= n; ++j) {
    lc.catheter_snapshot.emplace_back(j * h, 0.0, 0.0);
    lc.catheter_arc.push_back((n - j) * h);
  }
  lc.wire_snapshot = {V3(alpha * h, y, 0.0)};
  lc.wire_arc = {(n - alpha) * h};
  lc.assign_edges();
  return lc;
}
/// The lumen force on that wire vertex (LumenContact::evaluate_wire) and its energy.
std::pair<V3, double> wire_force(const LumenContact& lc) {
  rod::RodView v;
  const std::vector<double> arc = lc.wire_arc;
  v.positions = lc.wire_snapshot;
  v.arc_length = arc;
  v.first_clamped_vertex = 1;
  rod::ForceAccumulator out;
  out.reset(1);
  lc.evaluate_wire(v, out);
  return {out.forces()[0], out.energy()};
}
}  // namespace

TEST(LumenContact, WireLeavesTheTipWithAContinuousForce) {
  // A wire vertex held 2.5 clearances off the axis walks out of the catheter's tip, from two
  // edges inside to one beyond. The contact's energy and force are continuous all the way (no
  // jump where the vertex leaves the lumen, half an edge beyond the tip) and the force is
  // −∂E/∂x by central differences of the whole contact (edge choice included), near the tip
  // end and across the taper.
  const double c = 1e-4, k = 3e4, y = 2.5 * c, full = k * onset_quadratic(y - c, lumen_onset_fraction * c);
  double last_e = full;
  V3 last_f = wire_force(straight_lumen(2.0, y, c, k)).first;
  double max_de = 0.0, max_df = 0.0;
  const double step = 1e-3;  // in edges
  for (double alpha = 2.0 - step; alpha >= -1.0; alpha -= step) {
    const auto [f, e] = wire_force(straight_lumen(alpha, y, c, k));
    EXPECT_NEAR(e, straight_lumen(alpha, y, c, k).energy(), 1e-15);
    if (alpha > 0.5 + step) {
      EXPECT_NEAR(e, full, 1e-12 * full) << "alpha " << alpha;
    }
    if (alpha < -0.5 - step) {
      EXPECT_EQ(e, 0.0) << "alpha " << alpha;
    }
    max_de = std::max(max_de, std::abs(e - last_e));
    max_df = std::max(max_df, (f - last_f).norm());
    last_e = e, last_f = f;
  }
  // Steps of 1e-3 edge: the energy changes by at most |E′| Δα ≈ 1.9 E Δα per step, the force
  // by |F′| Δα; a vertex switched off at once would jump by E (and k (y − c)).
  EXPECT_LT(max_de, 5e-3 * full);
  EXPECT_LT(max_df, 5e-3 * k * (y - c));
  for (const double alpha : {-0.45, -0.3, -0.05, 0.0, 0.05, 0.3, 0.45}) {
    const auto [f, e] = wire_force(straight_lumen(alpha, y, c, k));
    ASSERT_GT(e, 0.0);
    const double h = 1e-9;
    for (int m = 0; m < 3; ++m) {
      auto at = [&](double s) {
        LumenContact lc = straight_lumen(alpha, y, c, k);
        lc.wire_snapshot[0][m] += s;
        lc.assign_edges();
        return lc.energy();
      };
      const double fd = -(at(h) - at(-h)) / (2 * h);
      EXPECT_NEAR(f[m], fd, 1e-6 * k * (y - c)) << "alpha " << alpha << ", component " << m;
    }
  }
}

namespace {
/// A straight catheter along x (tip at the origin, 6 edges of 2 mm, entry at x = 12 mm) and a
/// three-vertex wire leaving it at an angle: vertex 0 beyond the tip, 1 and 2 inside and off the
/// axis by more than the clearance, so that both press on the lumen. Velocities
/// v = (x − x₀)/Δt from the given positions of the step's start.
struct FrictionScene {
  LumenContact lc{1e-4, 3e4};
  std::vector<V3> wire_x0, cath_x0;
  std::vector<double> wire_arc, cath_arc;
  double dt = 1e-3;
  FrictionScene() {
    for (int j = 0; j <= 6; ++j) cath_x0.emplace_back(j * 2e-3, 0.0, 0.0), cath_arc.push_back((6 - j) * 2e-3);
    wire_x0 = {V3(-1.5e-3, 1.2e-3, 0.1e-3), V3(0.5e-3, 0.25e-3, 0.05e-3), V3(2.5e-3, -0.22e-3, 0.03e-3)};
    wire_arc = {13.5e-3, 11.5e-3, 9.5e-3};
    lc.set_friction(0.3, 1e-4);
    lc.catheter_snapshot = cath_x0, lc.catheter_arc = cath_arc;
    lc.wire_snapshot = wire_x0, lc.wire_arc = wire_arc;
    lc.assign_edges();
    lc.lag_friction();  // N and normals of these states
  }
  /// The forces and energy on the wire at positions @p x (the catheter held at @p cx moving
  /// with @p cv), or on the catheter at @p cx (the wire held at @p x moving with @p wv).
  rod::ForceAccumulator on_wire(const std::vector<V3>& x, const std::vector<V3>& cv) {
    lc.catheter_velocity = cv;
    std::vector<V3> v(x.size());
    for (size_t i = 0; i < x.size(); ++i) v[i] = (x[i] - wire_x0[i]) / dt;
    return evaluate(x, v, wire_arc, true);
  }
  rod::ForceAccumulator on_catheter(const std::vector<V3>& cx, const std::vector<V3>& wv) {
    lc.wire_velocity = wv;
    std::vector<V3> v(cx.size());
    for (size_t i = 0; i < cx.size(); ++i) v[i] = (cx[i] - cath_x0[i]) / dt;
    return evaluate(cx, v, cath_arc, false);
  }
  rod::ForceAccumulator evaluate(const std::vector<V3>& x, const std::vector<V3>& v, const std::vector<double>& arc,
                                 bool wire) {
    rod::RodView view;
    view.positions = x, view.velocities = v, view.arc_length = arc;
    view.first_clamped_vertex = static_cast<int>(x.size());
    view.dt = dt;
    rod::ForceAccumulator out;
    out.reset(static_cast<int>(x.size()));
    if (wire)
      lc.evaluate_wire(view, out);
    else
      lc.evaluate_catheter(view, out);
    return out;
  }
};
}  // namespace

// Friction in the lumen: every force on either rod is −∂E/∂x of the energy
// it reports (penalties plus the incremental potential Δt·D of friction, v = (x − x₀)/Δt), the
// Jacobians entered (vertex, velocity over Δt, edge blocks) are ∂f/∂x by central differences,
// and the forces on wire and catheter add up to zero (Newton's third law) when each side is
// evaluated at the other's held state.
TEST(LumenContact, FrictionForcesAreGradientsWithExactJacobiansAndActBothWays) {
  FrictionScene fs;
  for (int i : {1, 2}) ASSERT_GT(fs.lc.friction_contact[static_cast<size_t>(i)].normal, 0.0) << i;
  // The end of step: the wire moved (sliding back into the catheter and sideways), the catheter
  // too (more slowly).
  std::vector<V3> wx = fs.wire_x0, cx = fs.cath_x0;
  const V3 dw(2e-6, -0.3e-6, 0.4e-6), dc(-0.5e-6, 0.2e-6, -0.1e-6);
  for (auto& x : wx) x += dw;
  for (size_t j = 0; j < cx.size(); ++j) cx[j] += (0.5 + 0.1 * static_cast<double>(j)) * dc;
  std::vector<V3> wv(wx.size()), cv(cx.size());
  for (size_t i = 0; i < wx.size(); ++i) wv[i] = (wx[i] - fs.wire_x0[i]) / fs.dt;
  for (size_t j = 0; j < cx.size(); ++j) cv[j] = (cx[j] - fs.cath_x0[j]) / fs.dt;
  // Hold each rod at its end of step (the vertices keep their edges).
  fs.lc.catheter_snapshot = cx, fs.lc.wire_snapshot = wx;
  const rod::ForceAccumulator fw = fs.on_wire(wx, cv), fc = fs.on_catheter(cx, wv);
  V3 total = V3::Zero();
  double scale = 0.0;
  for (const V3& f : fw.forces()) total += f, scale = std::max(scale, f.norm());
  for (const V3& f : fc.forces()) total += f;
  EXPECT_LT(total.norm(), 1e-12 * scale) << "the two sides do not balance";
  EXPECT_NEAR(fw.energy(), fc.energy(), 1e-12 * fw.energy());
  const double h = 1e-10;
  auto check = [&](bool wire) {
    std::vector<V3>& x = wire ? wx : cx;
    auto eval = [&]() { return wire ? fs.on_wire(wx, cv) : fs.on_catheter(cx, wv); };
    const rod::ForceAccumulator base = eval();
    const int n = static_cast<int>(x.size());
    for (int i = 0; i < n; ++i) {
      for (int m = 0; m < 3; ++m) {
        x[static_cast<size_t>(i)][m] += h;
        const rod::ForceAccumulator plus = eval();
        x[static_cast<size_t>(i)][m] -= 2 * h;
        const rod::ForceAccumulator minus = eval();
        x[static_cast<size_t>(i)][m] += h;
        const double fd = -(plus.energy() - minus.energy()) / (2 * h);
        EXPECT_NEAR(base.forces()[static_cast<size_t>(i)][m], fd, 1e-6 * scale)
            << (wire ? "wire" : "catheter") << " vertex " << i << " component " << m;
        // Column (i, m) of ∂f/∂x against the assembled blocks.
        for (int r = 0; r < n; ++r) {
          const V3 col = (plus.forces()[static_cast<size_t>(r)] - minus.forces()[static_cast<size_t>(r)]) / (2 * h);
          V3 jac = V3::Zero();
          if (r == i)
            jac += (base.position_jacobians()[static_cast<size_t>(i)] +
                    base.velocity_jacobians()[static_cast<size_t>(i)] / fs.dt)
                       .col(m);
          for (int e : {r - 1, r}) {  // edge e joins vertices e and e + 1
            if (e < 0 || e + 1 >= n || !base.has_edge_jacobians()) continue;
            const auto& J = base.edge_jacobians()[static_cast<size_t>(e)];
            const int ri = r - e, ci = i - e;
            if (ci == 0 || ci == 1) jac += J.block<3, 3>(3 * ri, 3 * ci).col(m);
          }
          for (int l = 0; l < 3; ++l)
            EXPECT_NEAR(jac[l], col[l], 1e-5 * 3e4 + 1e-4 * col.norm())
                << (wire ? "wire" : "catheter") << " df" << r << "/dx" << i << " (" << l << "," << m << ")";
        }
      }
    }
  };
  check(true);
  check(false);
}

// The coupling blocks of the pair's joint Newton matrix (LumenContact::cross_matrix) against
// central differences of the forces on the wire as the catheter moves (its velocities
// (x − x₀)/Δt moving with it): penalty and friction, every pair of vertices.
TEST(LumenContact, TheJointMatrixCouplingBlocksAreTheForcesDerivatives) {
  FrictionScene fs;
  std::vector<V3> wx = fs.wire_x0, cx = fs.cath_x0;
  for (auto& x : wx) x += V3(2e-6, -0.3e-6, 0.4e-6);
  for (size_t j = 0; j < cx.size(); ++j) cx[j] += (0.5 + 0.1 * static_cast<double>(j)) * V3(-0.5e-6, 0.2e-6, -0.1e-6);
  auto velocities = [&](const std::vector<V3>& x, const std::vector<V3>& x0) {
    std::vector<V3> v(x.size());
    for (size_t i = 0; i < x.size(); ++i) v[i] = (x[i] - x0[i]) / fs.dt;
    return v;
  };
  fs.lc.wire_snapshot = wx, fs.lc.wire_velocity = velocities(wx, fs.wire_x0);
  fs.lc.catheter_snapshot = cx, fs.lc.catheter_velocity = velocities(cx, fs.cath_x0);
  const int nw = 4 * static_cast<int>(wx.size()) - 1, nc = static_cast<int>(cx.size());
  std::vector<Eigen::Triplet<double>> trip;
  fs.lc.cross_matrix(trip, std::vector<char>(wx.size(), 1), std::vector<char>(cx.size(), 1), nw, fs.dt);
  ASSERT_FALSE(trip.empty());
  Eigen::MatrixXd cross = Eigen::MatrixXd::Zero(4 * nc, nw);  // catheter rows, wire columns
  for (const auto& t : trip) cross(t.row() - nw, t.col()) += t.value();
  const double h = 1e-10;
  double largest = 0.0;
  for (int c = 0; c < nc; ++c)
    for (int r = 0; r < 3; ++r) {
      auto forces = [&](double s) {
        std::vector<V3> moved = cx;
        moved[static_cast<size_t>(c)][r] += s;
        fs.lc.catheter_snapshot = moved;
        const auto f = fs.on_wire(wx, velocities(moved, fs.cath_x0));
        fs.lc.catheter_snapshot = cx;
        return f.forces();
      };
      const auto plus = forces(h), minus = forces(-h);
      for (size_t i = 0; i < wx.size(); ++i)
        for (int q = 0; q < 3; ++q) {
          const double fd = -(plus[i][q] - minus[i][q]) / (2 * h);  // ∂²E/∂x_i,q ∂a_c,r
          largest = std::max(largest, std::abs(fd));
          EXPECT_NEAR(cross(4 * c + r, 4 * static_cast<int>(i) + q), fd, 1e-5 * 3e4 + 1e-4 * std::abs(fd))
              << "catheter vertex " << c << " (" << r << "), wire vertex " << i << " (" << q << ")";
        }
    }
  EXPECT_GT(largest, 1e3);  // the blocks are not all zero
}

TEST(CatheterPair, AnAngledWirePushedOutOfTheCatheterConvergesEveryStep) {
  // A 45°-angled wire tip, 1 cm inside a straight cantilevered catheter, fed 2 cm out of it
  // at 1 cm/s in 5 ms steps (staggered as in the scene runner). Every step of both rods
  // converges, and the contact energy changes smoothly while the pre-shaped tip leaves the
  // lumen: no step changes it by more than a fifth of its largest value.
  rod::WireSpec wire;
  wire.length = 0.1;
  wire.radius = 0.445e-3;
  wire.youngs_modulus = 60e9;
  wire.density = 6450;
  wire.segments = 50;
  wire.inserted_length = 0.04;
  wire.tip.length = 0.03;
  wire.tip.youngs_modulus = 10e9;
  wire.tip.shape = rod::TipShape::Angled;
  wire.tip.angle = std::numbers::pi / 4;
  wire.tip.bend_radius = 5e-3;
  CatheterSpec cat;
  cat.length = 0.1;
  cat.outer_radius = 1e-3;
  cat.inner_radius = 0.55e-3;
  cat.initial_length = 0.05;
  rod::RodSimulator w(wire);
  rod::RodSimulator k(catheter_rod_spec(cat, wire));
  auto contact = std::make_shared<LumenContact>(cat.inner_radius - wire.radius, cat.stiffness);
  w.add_external(std::make_shared<LumenContactSide>(contact, LumenContactSide::Side::Wire));
  k.add_external(std::make_shared<LumenContactSide>(contact, LumenContactSide::Side::Catheter));
  contact->hold_catheter(k);
  contact->hold_wire(w);
  w.set_insertion_speed(0.01);
  const double dt = 5e-3;
  std::vector<double> energy;
  int unconverged = 0;
  for (int n = 0; n < 600; ++n) {
    if (!w.step(dt).converged()) ++unconverged;
    contact->hold_wire(w);
    if (!k.step(dt).converged()) ++unconverged;
    contact->hold_catheter(k);
    energy.push_back(contact->energy());
  }
  EXPECT_EQ(unconverged, 0);
  EXPECT_GT(w.tip_position().x(), k.tip_position().x() + 0.015);  // 2 cm out: the angled part is free
  const double e_max = *std::max_element(energy.begin(), energy.end());
  double jump = 0.0;
  for (size_t n = 1; n < energy.size(); ++n) jump = std::max(jump, std::abs(energy[n] - energy[n - 1]));
  std::printf("contact energy: largest %.3e J, largest change in a step %.3e J\n", e_max, jump);
  ASSERT_GT(e_max, 0.0);
  EXPECT_LT(jump, 0.2 * e_max);
}

namespace {
struct Pair {
  rod::WireSpec wire;
  CatheterSpec cat;
  double ei_wire = 0.0, ei_cath = 0.0;
};
Pair cantilever_pair(double length, int segments) {
  Pair p;
  p.wire.length = length;
  p.wire.radius = 0.2e-3;
  p.wire.youngs_modulus = 60e9;
  p.wire.segments = segments;
  p.wire.inserted_length = length;
  p.cat.length = length;
  p.cat.outer_radius = 0.6e-3;
  p.cat.inner_radius = 0.2e-3;  // clearance 0: the wire's axis held on the catheter's
  p.cat.youngs_modulus = 2e9;
  p.cat.initial_length = length;
  p.cat.stiffness = 1e5;
  const double pi = std::numbers::pi;
  p.ei_wire = p.wire.youngs_modulus * pi * std::pow(p.wire.radius, 4) / 4;
  p.ei_cath = p.cat.youngs_modulus * pi * (std::pow(p.cat.outer_radius, 4) - std::pow(p.cat.inner_radius, 4)) / 4;
  return p;
}
}  // namespace

TEST(LumenContact, ReactionOnTheCatheterIsMinusTheForceOnTheWire) {
  Pair p = cantilever_pair(0.03, 15);
  rod::RodSimulator wire(p.wire);
  rod::RodSimulator cath(catheter_rod_spec(p.cat, p.wire));
  // bend the wire off the catheter's axis by a tip load, catheter held straight
  LumenContact contact(p.cat.inner_radius - p.wire.radius, p.cat.stiffness);
  contact.hold_catheter(cath);
  wire.set_tip_force({0.0, 5e-3, 0.0});
  (void)wire.solve_static();
  contact.hold_wire(wire);
  rod::ForceAccumulator on_wire, on_cath;
  on_wire.reset(wire.vertex_count());
  on_cath.reset(cath.vertex_count());
  const auto view = [](const rod::RodSimulator& s) {
    rod::RodView v;
    v.positions = s.positions();
    v.velocities = s.velocities();
    v.arc_length = s.arc_lengths();
    v.first_clamped_vertex = s.first_clamped_vertex();
    return v;
  };
  contact.evaluate_wire(view(wire), on_wire);
  contact.evaluate_catheter(view(cath), on_cath);
  V3 fw = V3::Zero(), fc = V3::Zero();
  for (const V3& f : on_wire.forces()) fw += f;
  for (const V3& f : on_cath.forces()) fc += f;
  ASSERT_GT(fw.norm(), 1e-3);  // the catheter carries a real part of the load
  EXPECT_LT((fw + fc).norm(), 1e-9 * fw.norm() + 1e-12);
  EXPECT_NEAR(on_wire.energy(), on_cath.energy(), 1e-12 * on_wire.energy());
}

// Cantilevered overlapping pair, tip load P on the wire: δ → P L³ / (3 (EI_w + EI_c)). The
// discrete rod's error shrinks with the segment length h; the slope of log error vs log h
// is asserted (the shear-free rod converges at first order or better in h).
TEST(CatheterPair, CantileverBendsWithTheSumOfBothStiffnesses) {
  const double length = 0.04, load = 1e-4;
  std::vector<double> hs, errs;
  for (int n : {10, 20, 40}) {
    Pair p = cantilever_pair(length, n);
    rod::RodSimulator wire(p.wire);
    rod::RodSimulator cath(catheter_rod_spec(p.cat, p.wire));
    auto contact = std::make_shared<LumenContact>(p.cat.inner_radius - p.wire.radius, p.cat.stiffness);
    contact->hold_catheter(cath);
    contact->hold_wire(wire);
    wire.add_external(std::make_shared<LumenContactSide>(contact, LumenContactSide::Side::Wire));
    cath.add_external(std::make_shared<LumenContactSide>(contact, LumenContactSide::Side::Catheter));
    wire.set_tip_force({0.0, load, 0.0});
    const PairStaticReport rep = solve_static_pair(wire, cath, *contact, 300, 1e-12);
    ASSERT_TRUE(rep.converged) << "n " << n << " sweeps " << rep.sweeps << " correction " << rep.correction;
    const double exact = load * std::pow(length, 3) / (3 * (p.ei_wire + p.ei_cath));
    const double wire_alone = load * std::pow(length, 3) / (3 * p.ei_wire);
    const double deflection = wire.tip_position().y();
    const double err = std::abs(deflection / exact - 1.0);
    std::printf("n %d sweeps %d: tip %.6e m, composite EB %.6e m (wire alone %.6e), rel. error %.3e\n", n, rep.sweeps,
                deflection, exact, wire_alone, err);
    EXPECT_LT(err, 0.05);
    EXPECT_NEAR(cath.tip_position().y(), deflection, 0.02 * exact);  // the pair bends as one
    hs.push_back(length / n), errs.push_back(err);
  }
  const double slope = std::log(errs.front() / errs.back()) / std::log(hs.front() / hs.back());
  std::printf("convergence slope %.2f\n", slope);
  EXPECT_GT(slope, 0.8);
}

// The static pair as a scene runs it (solve.mode: static, the scene's own tolerances): a wire
// in a catheter held at one end, a lateral load P on the wire's tip. Euler–Bernoulli with the
// moment P (L − x) over EI(x): EI_w + EI_c where the catheter covers the wire (x < a), EI_w
// beyond, so δ = P [(L³ − (L − a)³) / (3 (EI_w + EI_c)) + (L − a)³ / (3 EI_w)] (a = L: the
// composite cantilever, asserted at 2%). The clamps' reactions together balance the load. The
// solve once stopped after one sweep, its catheter hardly moved by the stiff lumen penalty,
// and reported ok with the wire bent alone (86 µm instead of 5 mm) and 0.5% of the load at the
// clamps. With the catheter over half the wire the formula holds only without play in the
// lumen: the wire leaving the catheter crosses its clearance c = 0.1 mm, from one wall to the
// other over ℓ ≈ (4c / κ_w)^½ = 2.5 cm at the curvature κ_w = P (L − a) / EI_w, and tilts by
// about (κ_w − κ_pair) ℓ more than the composite would, some 1.2 mm at the tip: there the tip
// must lie between the play-free formula and the wire alone.
// The joint step's two linear solvers give the same steps: a tip-loaded overlapping pair stepped
// for 50 ms with its joint matrix factorized as a band (the default) and by the sparse LDLᵀ that
// takes bands wider than step_pair_newton's max_band (forced with max_band 0): the same Newton
// iterations and the same positions to round-off.
TEST(CatheterPair, TheJointStepsBandedAndSparseSolversAgree) {
  std::vector<std::vector<V3>> tips;
  std::vector<int> iterations;
  for (const int max_band : {96, 0}) {
    Pair p = cantilever_pair(0.04, 20);
    p.cat.inner_radius = 0.3e-3;  // clearance 0.1 mm
    rod::RodSimulator wire(p.wire);
    rod::RodSimulator cath(catheter_rod_spec(p.cat, p.wire));
    auto contact = std::make_shared<LumenContact>(p.cat.inner_radius - p.wire.radius, p.cat.stiffness);
    contact->set_friction(0.2, 1e-4);
    contact->hold_catheter(cath);
    contact->hold_wire(wire);
    wire.add_external(std::make_shared<LumenContactSide>(contact, LumenContactSide::Side::Wire));
    cath.add_external(std::make_shared<LumenContactSide>(contact, LumenContactSide::Side::Catheter));
    wire.set_tip_force({0.0, 2e-3, 0.0});
    int its = 0;
    for (int n = 0; n < 10; ++n) {
      const PairStepReport r = step_pair_newton(wire, cath, *contact, 5e-3, max_band);
      ASSERT_TRUE(r.converged) << "max_band " << max_band << " step " << n;
      its += r.wire.newton_iterations;
    }
    iterations.push_back(its);
    tips.push_back({wire.tip_position(), cath.tip_position()});
  }
  EXPECT_EQ(iterations[0], iterations[1]);
  ASSERT_GT(std::abs(tips[0][0].y()), 1e-5);  // the pair has bent
  for (int k = 0; k < 2; ++k) EXPECT_LT((tips[0][k] - tips[1][k]).norm(), 1e-12) << k;
}

TEST(CatheterPair, AStaticSceneBendsThePairAsOneBeamAndBalancesTheLoad) {
  const double pi = std::numbers::pi, L = 0.2, P = 5e-4;
  const double ei_w = 60e9 * pi * std::pow(0.2e-3, 4) / 4.0;
  const double ei_c = 2e9 * pi * (std::pow(0.6e-3, 4) - std::pow(0.3e-3, 4)) / 4.0;
  for (const double a : {0.2, 0.1}) {
    const auto dir = flowire::testing::scratch_dir("catheter-static-scene");
    const std::string yaml = R"(
wire: {length: 0.4, radius: 0.2 mm, youngs_modulus: 60 GPa, density: 6450, segment_length: 2 mm,
       base: {position: [0, 0, 0], direction: [1, 0, 0]}}
insertion: {initial_length: 0.2}
catheter: {length: 0.4, outer_radius: 0.6 mm, inner_radius: 0.3 mm, youngs_modulus: 2 GPa, density: 1200,
           initial_length: )" +
                             std::to_string(a) +
                             R"(}
loads: [{type: tip_force, value: [0, 0.0005, 0]}]
solve: {mode: static}
output: {csv: false, vtk: false}
)";
    const auto cfg = config::load_config_text(yaml, "scene.yaml", scene_schema(), {"output.dir=" + dir.string()});
    const auto s = run_scene(cfg).summary;
    ASSERT_EQ(s["status"], "ok");
    EXPECT_TRUE(s["catheter"]["static_pair"]["converged"].get<bool>());
    const double exact =
        P * ((std::pow(L, 3) - std::pow(L - a, 3)) / (3.0 * (ei_w + ei_c)) + std::pow(L - a, 3) / (3.0 * ei_w));
    const double alone = P * std::pow(L, 3) / (3.0 * ei_w);
    const double tip = s["wire"]["tip"][1].get<double>();
    const double reaction = s["wire"]["base_force"][1].get<double>() + s["catheter"]["base_force"][1].get<double>();
    std::printf(
        "catheter over %.2f of %.2f m (%d sweeps): tip %.4e m, Euler-Bernoulli %.4e m (ratio %.4f), wire "
        "alone %.4e m; clamps %.4e N of %.1e\n",
        a, L, s["catheter"]["static_pair"]["sweeps"].get<int>(), tip, exact, tip / exact, alone, -reaction, P);
    EXPECT_NEAR(-reaction, P, 1e-3 * P) << "catheter over " << a;
    if (a == L) {
      EXPECT_NEAR(tip / exact, 1.0, 0.02);
    } else {
      EXPECT_GT(tip, exact);
      EXPECT_LT(tip, exact + 0.5 * (alone - exact));
    }
  }
}

// The same composite cantilever stepped in time (dt 1 ms, mass-proportional damping 20/s):
// it must ring about the composite beam's static deflection with the pair's own period and
// settle within the damping's time, e^(−ζ t / 2) = e^(−10 t) at 0.5 s well under 1%. The
// catheter held at its last step's shape (one sweep a step) let the pair creep towards it
// by a micrometre a step: 0.2 mm after 0.1 s, 1 mm after 1 s, where it should be 5 mm.
TEST(CatheterPair, ADynamicPairSettlesOnTheCompositeBeamInPhysicalTime) {
  const double pi = std::numbers::pi, L = 0.2, P = 5e-4;
  const double ei =
      60e9 * pi * std::pow(0.2e-3, 4) / 4.0 + 2e9 * pi * (std::pow(0.6e-3, 4) - std::pow(0.3e-3, 4)) / 4.0;
  const double exact = P * std::pow(L, 3) / (3.0 * ei);
  const auto dir = flowire::testing::scratch_dir("catheter-dynamic-scene");
  const std::string yaml = R"(
wire: {length: 0.4, radius: 0.2 mm, youngs_modulus: 60 GPa, density: 6450, segment_length: 2 mm, damping: 20,
       base: {position: [0, 0, 0], direction: [1, 0, 0]}}
insertion: {initial_length: 0.2}
catheter: {length: 0.4, outer_radius: 0.6 mm, inner_radius: 0.3 mm, youngs_modulus: 2 GPa, density: 1200,
           initial_length: 0.2}
loads: [{type: tip_force, value: [0, 0.0005, 0]}]
solve: {dt: 1 ms, duration: 0.5 s}
output: {csv: false, vtk: false}
)";
  const auto cfg = config::load_config_text(yaml, "scene.yaml", scene_schema(), {"output.dir=" + dir.string()});
  const auto s = run_scene(cfg).summary;
  ASSERT_EQ(s["status"], "ok");
  const double tip = s["wire"]["tip"][1].get<double>();
  const double cath_tip = s["catheter"]["tip"][1].get<double>();
  std::printf(
      "t = 0.5 s: wire tip %.5e m, catheter tip %.5e m, composite beam %.5e m (ratio %.4f); %.2f sweeps a "
      "step, %d unbalanced\n",
      tip, cath_tip, exact, tip / exact, s["catheter"]["pair"]["sweeps_per_step"].get<double>(),
      s["catheter"]["pair"]["unbalanced_steps"].get<int>());
  EXPECT_NEAR(tip / exact, 1.0, 0.02);  // the discrete beam's 1.2% (the static test) and the ringing's rest
  EXPECT_NEAR(cath_tip, tip, 0.02 * exact);
  EXPECT_EQ(s["wire"]["unconverged_steps"].get<int>(), 0);
  EXPECT_EQ(s["catheter"]["unconverged_steps"].get<int>(), 0);
}

TEST(CatheterPair, ACatheterSlidesOnTheWallWhenPushedWithMuTimesItsWeight) {
  // Coulomb's law for the catheter on the vessel wall, through a scene: a catheter lies along
  // the bottom of a horizontal tube under gravity and is fed at 1 cm/s. Sliding takes an axial
  // push of μ m g, m the mass inserted: the clamp's axial force over m g is μ (0.1 and 0.3),
  // and 0 without friction. The catheter's wall friction is the wire's (VesselForces, the same
  // contact: keys). The 1 cm of wire inside hangs from its own clamp (its sag, 1e-9 m, is far
  // within the lumen's clearance), and the clamp carries the catheter's weight over a boundary
  // layer of about (EI / k)^¼ ≈ 2 cm on the soft penalty foundation: 25 cm are inserted. The
  // clamp holds the catheter exactly on the wall (δ = 0), so the wall's onset is sharp here: a
  // smoothed one already presses there with k·onset/8, a hundred times the weight.
  const double g = 9.81, pi = std::numbers::pi, rho = 1200, ro = 1e-3, ri = 0.55e-3;
  for (const double mu : {0.0, 0.1, 0.3}) {
    const auto dir = flowire::testing::scratch_dir("catheter-coulomb");
    const std::string yaml = R"(
vessels: {generator: {type: straight_tube, length: 0.4, radius: 3 mm}, max_segment_length: 5 mm}
wire: {length: 0.3, radius: 0.3 mm, youngs_modulus: 60 GPa, density: 6450, segment_length: 2 mm,
       base: {position: [0.01, 0, -0.002], direction: [1, 0, 0]}}
insertion: {speed: 0, initial_length: 1 cm}
catheter: {length: 0.4, outer_radius: 1 mm, inner_radius: 0.55 mm, youngs_modulus: 2 GPa, density: 1200,
           initial_length: 24 cm, insertion: {speed: 1 cm/s}}
loads: [{type: gravity, value: [0, 0, -9.81]}]
contact: {onset: 0, friction: )" +
                             std::to_string(mu) +
                             R"(}
solve: {dt: 5 ms, duration: 1 s}
output: {csv: false, vtk: false}
)";
    const auto cfg = config::load_config_text(yaml, "scene.yaml", scene_schema(), {"output.dir=" + dir.string()});
    const auto s = run_scene(cfg).summary;
    ASSERT_EQ(s["status"], "ok");
    const auto& c = s["catheter"];
    EXPECT_EQ(c["unconverged_steps"].get<int>(), 0);
    const double inserted = c["inserted_length"].get<double>();
    ASSERT_NEAR(inserted, 0.25, 1e-9);
    const double weight = g * rho * pi * (ro * ro - ri * ri) * inserted;
    const double push = std::abs(c["base_force"][0].get<double>());
    std::printf("mu %.1f: push %.4e N, mu m g %.4e N, push / m g %.4f\n", mu, push, mu * weight, push / weight);
    EXPECT_NEAR(push / weight, mu, 0.03 * mu + 1e-6) << "mu " << mu;
    EXPECT_LT(c["contact"]["max_penetration"].get<double>(), 1e-6);
  }
}

namespace {
/// A vessel along +x for `lead` from the origin, bending by `turn` on a centerline radius
/// `bend` (in the xy plane, towards +y), then straight for `tail`: a flowire .yaml network.
std::string bent_vessel(double lead, double bend, double turn, double tail, double radius) {
  std::string pts = fmt::format("[[0, 0, 0, {0}], [{1}, 0, 0, {0}]", radius, lead);
  const int n = std::max(4, static_cast<int>(std::ceil(bend * turn / 1e-3)));
  for (int k = 1; k <= n; ++k) {
    const double a = turn * k / n;
    pts += fmt::format(", [{}, {}, 0, {}]", lead + bend * std::sin(a), bend * (1.0 - std::cos(a)), radius);
  }
  const double xe = lead + bend * std::sin(turn), ye = bend * (1.0 - std::cos(turn));
  pts += fmt::format(", [{}, {}, 0, {}]]", xe + tail * std::cos(turn), ye + tail * std::sin(turn), radius);
  return "branches:\n  - name: bend\n    points: " + pts + "\n";
}
}  // namespace

// The capstan law through a scene: a wire runs through a catheter laid in a vessel that turns
// by θ (the catheter ends 1 cm past the bend), a tension T pulls its tip on along the vessel,
// and the wire is pulled back at 1 cm/s. Sliding on the lumen with friction μ, the tension grows
// along the bend as dT/dθ = μ T (the normal force per unit length is T/R, the friction μ T/R),
// so the clamp pulls with T e^(μθ) (Euler–Eytelwein). Checked for θ = π/2 and π and μ = 0, 0.1,
// 0.3, on the clamp's force averaged over the last edge fed (0.2 s): wire and catheter share the
// feeding grid, so their vertices pass each other once per edge and the force ripples with that
// period (-3% to +8% here, where the wire's bending length √(EI/T) ≈ 0.9 mm is below the 2 mm edge).
// The wire's own bending adds forces where it enters and leaves the bend, about √(EI T)/R each
// (1% of T θ μ here: a soft 0.3 mm wire); the walls are frictionless so that only the lumen rubs.
// The tension comes on at once at t = 0 (a scene's loads have no ramp): with one Newton over
// both rods every step converges (also at dt 2.5 and 1 ms; with the block sweeps a few of the
// start's sub-steps stayed at the Newton limit there, docs/catheter.md).
TEST(CatheterPair, AWirePulledThroughABentCatheterFollowsTheCapstanLaw) {
  const double pi = std::numbers::pi, T = 0.5, bend = 0.025, v = 0.01, h = 2e-3, duration = 0.5, dt = 5e-3;
  for (const double turn : {0.5 * pi, pi}) {
    const auto dir = flowire::testing::scratch_dir("catheter-capstan");
    const std::string net = (dir / "bend.yaml").string();
    {
      std::ofstream f(net);
      f << bent_vessel(0.03, bend, turn, 0.06, 0.003);
    }
    const double arc = 0.03 + bend * turn;  // the vessel's length to the end of the bend
    const V3 out_dir(std::cos(turn), std::sin(turn), 0.0);
    for (const double mu : {0.0, 0.1, 0.3}) {
      const std::string yaml =
          fmt::format(R"(
vessels: {{file: {net}}}
wire: {{length: 0.3, radius: 0.15 mm, youngs_modulus: 1 GPa, density: 6450, segment_length: {h}, damping: 200,
       entry: 0}}
insertion: {{speed: {speed}, initial_length: {wire_in}}}
catheter: {{length: 0.3, outer_radius: 1 mm, inner_radius: 0.55 mm, initial_length: {cath_in},
           inner_friction: {mu}}}
loads: [{{type: tip_force, value: [{fx}, {fy}, 0]}}]
contact: {{friction: 0, settle: false}}
solve: {{dt: {dt}, duration: {duration}}}
output: {{csv: true, vtk: false}}
)",
                      fmt::arg("net", net), fmt::arg("h", h), fmt::arg("speed", -v), fmt::arg("wire_in", arc + 0.03),
                      fmt::arg("cath_in", arc + 0.01), fmt::arg("mu", mu), fmt::arg("fx", T * out_dir.x()),
                      fmt::arg("fy", T * out_dir.y()), fmt::arg("dt", dt), fmt::arg("duration", duration));
      const auto cfg = config::load_config_text(yaml, "scene.yaml", scene_schema(), {"output.dir=" + dir.string()});
      const auto s = run_scene(cfg).summary;
      ASSERT_EQ(s["status"], "ok") << s.dump();
      // The clamp's force along the entry (−x: it holds the wire against the pull) over the last
      // edge fed.
      std::ifstream in(dir / "base_force.csv");
      std::string line;
      std::getline(in, line);
      double sum = 0.0, lo = 1e300, hi = -1e300;
      int count = 0;
      while (std::getline(in, line)) {
        double t = 0.0, fx = 0.0;
        ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf", &t, &fx), 2) << line;
        if (t <= duration - h / v + 1e-9) continue;
        sum += -fx, ++count, lo = std::min(lo, -fx), hi = std::max(hi, -fx);
      }
      ASSERT_EQ(count, static_cast<int>(std::lround(h / v / dt)));
      const double pull = sum / count, capstan = T * std::exp(mu * turn);
      std::printf(
          "turn %.3f mu %.1f: clamp %.4f N (%.4f-%.4f over the edge), T e^(mu turn) %.4f N, ratio %.4f; %.2f "
          "sweeps a step, %d unbalanced\n",
          turn, mu, pull, lo, hi, capstan, pull / capstan, s["catheter"]["pair"]["sweeps_per_step"].get<double>(),
          s["catheter"]["pair"]["unbalanced_steps"].get<int>());
      EXPECT_NEAR(pull / capstan, 1.0, 0.02) << "turn " << turn << " mu " << mu;
      EXPECT_EQ(s["wire"]["unconverged_steps"].get<int>(), 0);
      EXPECT_EQ(s["catheter"]["unconverged_steps"].get<int>(), 0);
    }
  }
}

// The catheter in the blood, through a scene: a 1 mm catheter lies 4 cm along the axis of a
// 3 mm tube carrying a steady flow, the 0.2 mm wire runs 2 cm on beyond its tip. A segment the
// catheter fills is occluded as a concentric annulus of the catheter's outer radius: its
// resistance factor is the exact one for κ = 1/3 (flow/annulus.hpp), not the wire's κ = 1/15.
// The wire inside the catheter feels no blood drag (zero at every vertex behind its tip), the
// wire beyond the tip and the catheter do.
TEST(CatheterPair, TheCatheterOccludesTheVesselAndShieldsTheWireFromTheBlood) {
  const auto dir = flowire::testing::scratch_dir("catheter-blood");
  const std::string yaml = R"(
vessels: {generator: {type: straight_tube, length: 0.1, radius: 3 mm}, max_segment_length: 5 mm}
flow: {solver: superposition, inlet: {pressure: 100 Pa}, outlets: {pressure: 0 Pa}}
wire: {length: 0.3, radius: 0.2 mm, youngs_modulus: 60 GPa, density: 6450, segment_length: 2 mm}
insertion: {speed: 0, initial_length: 6 cm}
catheter: {length: 0.3, outer_radius: 1 mm, inner_radius: 0.55 mm, initial_length: 4 cm}
solve: {dt: 5 ms, duration: 0.02 s}
output: {csv: true, vtk: false}
)";
  const auto cfg = config::load_config_text(yaml, "scene.yaml", scene_schema(), {"output.dir=" + dir.string()});
  const auto s = run_scene(cfg).summary;
  ASSERT_EQ(s["status"], "ok") << s.dump();
  ASSERT_EQ(s["occlusion"]["model"], "annulus");
  const double f_cath = flow::annulus_resistance_factor(1.0 / 3.0, 0.0);
  const double f_wire = flow::annulus_resistance_factor(0.2 / 3.0, 0.0);
  const double f = s["occlusion"]["max_resistance_factor"].get<double>();
  std::printf("largest resistance factor %.5f; concentric annulus of the catheter %.5f, of the wire %.5f\n", f, f_cath,
              f_wire);
  EXPECT_NEAR(f / f_cath, 1.0, 2e-3);
  // Drag per vertex (arc length s from the base, |drag|), the wire's and the catheter's.
  auto drag_of = [&](const char* file) {
    std::vector<std::pair<double, double>> out;
    std::ifstream in(dir / file);
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      double t, vertex, arc, x, y, z, dx, dy, dz;
      if (std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &t, &vertex, &arc, &x, &y, &z, &dx, &dy,
                      &dz) == 9)
        out.emplace_back(arc, std::sqrt(dx * dx + dy * dy + dz * dz));
    }
    return out;
  };
  double inside_max = 0.0, outside_min = 1e300, cath_min = 1e300;
  int inside = 0, outside = 0, cath = 0;
  for (const auto& [arc, drag] : drag_of("wire.csv")) {
    if (arc <= 0.0 || arc >= 0.06) continue;  // the clamp and the tip
    if (arc < 0.04 - 2e-3)
      inside_max = std::max(inside_max, drag), ++inside;
    else if (arc > 0.04 + 2e-3)
      outside_min = std::min(outside_min, drag), ++outside;
  }
  for (const auto& [arc, drag] : drag_of("catheter.csv"))
    if (arc > 0.0 && arc < 0.04 - 2e-3) cath_min = std::min(cath_min, drag), ++cath;
  ASSERT_GT(inside, 10);
  ASSERT_GT(outside, 5);
  ASSERT_GT(cath, 10);
  std::printf(
      "drag: largest on the wire behind the catheter's tip %.3e N, smallest beyond it %.3e N, on the "
      "catheter %.3e N\n",
      inside_max, outside_min, cath_min);
  EXPECT_EQ(inside_max, 0.0);
  EXPECT_GT(outside_min, 0.0);
  EXPECT_GT(cath_min, 0.0);
}
