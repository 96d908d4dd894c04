// Blood drag on the wire against fluid mechanics: the cylinder drag curve against
// published solutions and measurements, the confinement across the vessel against Faxén's
// channel drag, Glauert's blockage and an independent quadrature of the Oseen channel, the tangential law against a
// numerical solution of the annulus between wire and wall, the whole chain (network flow → profile → drag on a wire)
// against the exact annular Poiseuille force, and every Jacobian against finite differences.
#include "flowire/coupling/drag.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include "flowire/common/error.hpp"
#include "flowire/coupling/vessel_forces.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/vessels/generators.hpp"
#include "flowire_test.hpp"

using namespace flowire;
using namespace flowire::coupling;
constexpr double kPi = std::numbers::pi;

namespace {

struct Reference {
  double re, cd;
  const char* source;
};

// Drag coefficients of an unconfined circular cylinder in steady or time-mean cross flow.
const Reference kReferences[] = {
    {10.0, 2.846, "Dennis & Chang 1970, steady Navier-Stokes"},
    {20.0, 2.045, "Dennis & Chang 1970, steady Navier-Stokes"},
    {20.0, 2.0001, "Fornberg 1980, steady Navier-Stokes"},
    {40.0, 1.522, "Dennis & Chang 1970, steady Navier-Stokes"},
    {40.0, 1.4980, "Fornberg 1980, steady Navier-Stokes"},
    {100.0, 1.35, "Henderson 1995, time-mean of the shedding wake"},
    {1000.0, 1.0, "Wieselsberger 1921, measured"},
    {10000.0, 1.15, "Wieselsberger 1921, measured"},
};

/// Lamb's (1911) Oseen drag, the leading term of the creeping-flow expansion.
double lamb(double re) { return 8.0 * kPi / (re * (0.5 - 0.5772156649 - std::log(re / 8.0))); }

/// Three vertices of a wire at rest, 1 mm apart, on the axis of a 2 mm tube.
struct ShortWire {
  vessels::Network net =
      vessels::Network::build(vessels::straight_tube({.length = 0.05, .radius = 2e-3}), {.max_segment_length = 5e-3});
  vessels::SpatialIndex index{net};
  Vec3 axis = (net.node(net.segment(net.num_segments() - 1).node_to) - net.node(net.segment(0).node_from)).normalized();
  std::vector<Vec3> x, v = std::vector<Vec3>(3, Vec3::Zero());
  std::vector<double> arc = {3e-3, 2e-3, 1e-3}, radius = std::vector<double>(2, 0.2e-3);
  rod::RodView view;
  ShortWire() {
    const Vec3 a = net.node(net.segment(0).node_from);
    x = {a + 0.02 * axis, a + 0.021 * axis, a + 0.022 * axis};
    view.positions = x;
    view.velocities = v;
    view.arc_length = arc;
    view.radius = radius;
    view.first_clamped_vertex = 3;
    view.dt = 1e-3;
  }
  ShortWire(const ShortWire&) = delete;
  ShortWire& operator=(const ShortWire&) = delete;
};

Mat3 fd_velocity_jacobian(const DragModel& m, DragInput in, double h) {
  Mat3 J;
  for (int k = 0; k < 3; ++k) {
    DragInput p = in, q = in;
    p.v[k] += h;
    q.v[k] -= h;
    J.col(k) = (blood_drag(m, p).force - blood_drag(m, q).force) / (2.0 * h);
  }
  return J;
}

}  // namespace

TEST(DragCurve, AgreesWithPublishedSolutionsAndMeasurements) {
  // The correlation is a fit to measurements, which scatter by about ±10% between Re 10 and
  // 100; its worst point is Re 40, 14–15% above the two steady solutions. 16% is asserted
  // (docs/blood-drag.md lists every ratio) and every point is printed.
  for (const auto& r : kReferences) {
    const double cd = cylinder_drag_coefficient(r.re);
    std::printf("  Re %8g  C_D %.4f  reference %.4f (%s)  ratio %.3f\n", r.re, cd, r.cd, r.source, cd / r.cd);
    EXPECT_NEAR(cd / r.cd, 1.0, flowire::testing::tol(0.16)) << r.source << " at Re " << r.re;
  }
}

TEST(DragCurve, TendsToTheOseenSolutionInCreepingFlow) {
  // Lamb's C_D is the leading order in ε = 1/ln(7.4/Re); the curve may differ from it by
  // the next order, O(ε²), and must approach it as Re → 0.
  double previous = 1.0;
  for (double re : {0.1, 1e-2, 1e-3, 1e-4, 1e-6}) {
    const double eps = 1.0 / std::log(7.406 / re);
    const double rel = std::abs(cylinder_drag_coefficient(re) / lamb(re) - 1.0);
    EXPECT_LT(rel, 1.5 * eps * eps) << re;
    EXPECT_LT(rel, previous) << re;
    previous = rel;
  }
}

TEST(DragCurve, IsContinuouslyDifferentiableWithTheExactDerivative) {
  for (double re = 1e-3; re < 3e5; re *= 1.13) {
    const auto c = cylinder_drag_curve(re);
    const double h = 1e-6 * re;
    const double fd = (cylinder_drag_coefficient(re + h) - cylinder_drag_coefficient(re - h)) / (2 * h);
    EXPECT_NEAR(c.dcd, fd, 1e-6 * std::abs(fd) + 1e-12) << re;
    // The force per length, η Re C_D/2 · U, grows with the speed (a monotone law).
    EXPECT_GT(c.cd + re * c.dcd, 0.0) << re;
  }
  // Across both ends of the blend, value and slope are continuous.
  for (double edge : {0.4, 1.0}) {
    const auto lo = cylinder_drag_curve(edge * (1 - 1e-9)), hi = cylinder_drag_curve(edge * (1 + 1e-9));
    EXPECT_NEAR(lo.cd, hi.cd, 1e-6 * lo.cd);
    EXPECT_NEAR(lo.dcd, hi.dcd, 1e-5 * std::abs(lo.dcd));
  }
  EXPECT_THROW(cylinder_drag_curve(0.0), Error);
  EXPECT_THROW(cylinder_drag_curve(std::nan("")), Error);
}

TEST(CylinderDrag, CrossFlowForceIsTheDragCurvesAtTheNormalReynoldsNumber) {
  // A 0.035" wire across aortic flow: f = ½ρ C_D d U² per length.
  const DragModel m{.law = DragLaw::Cylinder, .viscosity = 3.5e-3, .density = 1060, .wire_radius = 0.445e-3};
  for (double U : {1e-3, 0.01, 0.1, 0.5}) {
    DragInput in{.u = Vec3(0, U, 0), .t = Vec3::UnitX(), .ell = 2e-3, .vessel_radius = 0.1};
    const auto d = blood_drag(m, in);
    const double re = 1060 * U * 0.89e-3 / 3.5e-3;
    EXPECT_NEAR(d.reynolds_normal, re, 1e-12 * re);
    EXPECT_NEAR(d.force.y(), 0.5 * 1060 * cylinder_drag_coefficient(re) * 0.89e-3 * U * U * 2e-3,
                1e-12 * d.force.norm());
    EXPECT_NEAR(d.force.x(), 0.0, 1e-18);
  }
  // At Re ≈ 100 the law is about 50× the Stokes (slender-body) law the project used before.
  DragInput in{.u = Vec3(0, 0.4, 0), .t = Vec3::UnitX(), .ell = 1.0, .vessel_radius = 0.01};
  const double cyl = blood_drag(m, in).force.y();
  const double stokes = slender_body_drag(in.u, in.v, in.t, 3.5e-3, 1.7, 0.445e-3, 1.0).force.y();
  std::printf("  Re_d %.0f: cylinder law / slender-body law = %.1f\n", blood_drag(m, in).reynolds_normal, cyl / stokes);
  EXPECT_GT(cyl / stokes, 20.0);
}

TEST(CylinderDrag, SlowCrossFlowIsBoundedBelowByTheConfinedStokesDrag) {
  // In creeping flow an unbounded cylinder's drag vanishes (Stokes' paradox); in a vessel
  // of radius R the wall sets it: F' = 4πηU/(ln(R/a) − (R² − a²)/(R² + a²)).
  const double a = 0.178e-3, R = 1.5e-3, eta = 3.5e-3, U = 1e-5;
  const DragModel m{.law = DragLaw::Cylinder, .viscosity = eta, .density = 1060, .wire_radius = a};
  DragInput in{.u = Vec3(0, 0, U), .t = Vec3::UnitX(), .ell = 1.0, .vessel_radius = R};
  const double expected = 4 * kPi * eta * U / (std::log(R / a) - (R * R - a * a) / (R * R + a * a));
  EXPECT_NEAR(blood_drag(m, in).force.z(), expected, 1e-12 * expected);
}

TEST(CylinderDrag, AxialShearEqualsANumericalSolutionOfTheAnnulus) {
  // The annulus a < r < R between a coaxial wire sliding at v_w and the wall, pressure
  // gradient G: (1/r)(r u')' = −G/η, u(a) = v_w, u(R) = 0, solved by second-order finite
  // differences (uniform in ln r); the force per length on the wire, 2πaη u'(a), against
  // the law fed with the undisturbed centreline velocity GR²/(4η).
  const double a = 0.178e-3, R = 1.5e-3, eta = 3.5e-3, G = 2000.0;
  const DragModel m{.law = DragLaw::Cylinder, .viscosity = eta, .density = 1060, .wire_radius = a};
  for (double vw : {0.0, 0.05, -0.1}) {
    // In s = ln r: u'' = −(G/η) e^{2s}, second-order central differences, one-sided
    // second-order derivative at s = ln a.
    const int n = 4000;
    const double s0 = std::log(a), s1 = std::log(R), h = (s1 - s0) / n;
    Eigen::VectorXd diag = Eigen::VectorXd::Constant(n - 1, -2.0), rhs(n - 1);
    for (int i = 1; i < n; ++i) rhs[i - 1] = -(G / eta) * std::exp(2 * (s0 + i * h)) * h * h;
    rhs[0] -= vw;
    // Thomas algorithm on the constant tridiagonal (1, −2, 1).
    Eigen::VectorXd c(n - 1), d(n - 1);
    c[0] = 1.0 / diag[0], d[0] = rhs[0] / diag[0];
    for (int i = 1; i < n - 1; ++i) {
      const double den = diag[i] - c[i - 1];
      c[i] = 1.0 / den;
      d[i] = (rhs[i] - d[i - 1]) / den;
    }
    Eigen::VectorXd u(n + 1);
    u[0] = vw, u[n] = 0.0;
    u[n - 1] = d[n - 2];
    for (int i = n - 2; i >= 1; --i) u[i] = d[i - 1] - c[i - 1] * u[i + 1];
    const double dudr = (-3 * u[0] + 4 * u[1] - u[2]) / (2 * h) / a;  // du/ds / r
    const double numerical = 2 * kPi * a * eta * dudr;
    const double u0 = G * R * R / (4 * eta);
    DragInput in{.u = Vec3(u0, 0, 0), .v = Vec3(vw, 0, 0), .t = Vec3::UnitX(), .ell = 1.0, .vessel_radius = R};
    const double law = blood_drag(m, in).force.x();
    EXPECT_NEAR(law, numerical, 1e-5 * std::abs(numerical)) << vw;
  }
}

TEST(CylinderDrag, VelocityJacobianMatchesFiniteDifferences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uni(-1, 1);
  for (const double a : {0.178e-3, 0.445e-3}) {
    const DragModel m{.law = DragLaw::Cylinder, .viscosity = 3.5e-3, .density = 1060, .wire_radius = a, .scale = 1.3};
    for (int k = 0; k < 400; ++k) {
      const double speed = std::pow(10.0, -3.0 + 4.0 * (0.5 + 0.5 * uni(rng)));  // 1 mm/s .. 10 m/s
      DragInput in;
      in.u = speed * Vec3(uni(rng), uni(rng), uni(rng));
      in.v = 0.3 * speed * Vec3(uni(rng), uni(rng), uni(rng));
      in.t = Vec3(uni(rng), uni(rng), uni(rng)).normalized();
      in.ell = 1e-3;
      in.vessel_radius = a * (3.0 + 20.0 * (0.5 + 0.5 * uni(rng)));
      if (k % 2 == 1) {
        // The vessel's axis and the vertex's offset from it (the law across the vessel).
        in.axis = Vec3(uni(rng), uni(rng), uni(rng)).normalized();
        const Vec3 o = 0.9 * in.vessel_radius * Vec3(uni(rng), uni(rng), uni(rng)) / std::sqrt(3.0);
        in.axis_offset = o - o.dot(in.axis) * in.axis;
      }
      const auto d = blood_drag(m, in);
      const Mat3 fd = fd_velocity_jacobian(m, in, 1e-7 * speed);
      if ((d.dfdv - fd).norm() > 1e-5 * d.dfdv.norm()) {
        // Allowed only where the stencil straddles the switch between the confined and the
        // free law (a kink of the max): there the Jacobians on both sides differ.
        const Vec3 dir = ((Mat3::Identity() - in.t * in.t.transpose()) * (in.u - in.v)).normalized();
        DragInput lo = in, hi = in;
        lo.v += 1e-6 * speed * dir, hi.v -= 1e-6 * speed * dir;
        const bool kink = (blood_drag(m, lo).dfdv - blood_drag(m, hi).dfdv).norm() > 1e-3 * d.dfdv.norm();
        EXPECT_TRUE(kink) << "Jacobian off at speed " << speed << ": " << (d.dfdv - fd).norm() / d.dfdv.norm();
      }
      EXPECT_LT((d.dfdv - d.dfdv.transpose()).norm(), 1e-12 * d.dfdv.norm());
      EXPECT_LE(Eigen::SelfAdjointEigenSolver<Mat3>(d.dfdv).eigenvalues().maxCoeff(), 1e-15 * d.dfdv.norm());
    }
  }
}

TEST(SlenderBodyDrag, CoefficientsAndJacobian) {
  const double eta = 3.5e-3, L = 1.0, r = 0.45e-3, ell = 2e-3;
  const Vec3 t = Vec3(1, 2, 2).normalized(), side = t.unitOrthogonal();
  const double cn = slender_body_normal_coefficient(eta, L, r);
  EXPECT_NEAR(slender_body_drag(side, Vec3::Zero(), t, eta, L, r, ell).force.dot(side), cn * ell, 1e-15);
  EXPECT_NEAR(slender_body_drag(t, Vec3::Zero(), t, eta, L, r, ell).force.dot(t), 0.5 * cn * ell, 1e-15);
  const DragModel m{.law = DragLaw::SlenderBody, .viscosity = eta, .wire_radius = r, .wire_length = L};
  DragInput in{.u = Vec3(0.1, -0.2, 0.05), .v = Vec3(0.02, 0.01, -0.03), .t = t, .ell = ell};
  EXPECT_LT((blood_drag(m, in).dfdv - fd_velocity_jacobian(m, in, 1e-6)).norm(), 1e-12);
  EXPECT_THROW(slender_body_normal_coefficient(eta, 1e-4, r), Error);
}

TEST(CylinderDrag, CoaxialWireInATubeReceivesTheExactAnnularForce) {
  // The whole chain: a straight tube under a pressure drop (network flow, laminar profile),
  // a wire at rest on its axis, drag summed over the wire's vertices. The exact force of the
  // annular Poiseuille flow on the inner cylinder per length is
  //   F' = (πG/2)[(R² − a²)/ln(R/a) − 2a²]
  // (from u = (G/4η)[R² − r² − (R² − a²) ln(R/r)/ln(R/a)]).
  const double R = 1.5e-3, a = 0.178e-3, Ltube = 0.05, dp = 100.0, eta = 3.5e-3;
  const auto net =
      vessels::Network::build(vessels::straight_tube({.length = Ltube, .radius = R}), {.max_segment_length = 5e-3});
  const vessels::SpatialIndex index(net);
  auto spec = flow::default_spec(net, flow::Waveform::constant(dp));
  spec.viscosity = eta;
  auto fs = flow::make_solver(net, spec);
  fs->advance(0.0);
  const Vec3 A = net.node(net.segment(0).node_from);
  const Vec3 axis = (net.node(net.segment(net.num_segments() - 1).node_to) - A).normalized();
  const double G = dp / Ltube;
  // 31 vertices over 3 cm in the middle of the tube, at rest.
  std::vector<Vec3> x, v;
  std::vector<double> arc;
  const int nv = 31;
  const double span = 0.03, h = span / (nv - 1);
  for (int i = 0; i < nv; ++i) {
    x.push_back(A + (0.01 + h * i) * axis);
    v.push_back(Vec3::Zero());
    arc.push_back(h * (nv - i));
  }
  std::vector<double> radius(nv - 1, a);
  rod::RodView view;
  view.positions = x;
  view.velocities = v;
  view.arc_length = arc;
  view.radius = radius;
  view.first_clamped_vertex = nv;
  view.dt = 1e-3;
  VesselForces forces(index, a, ContactParams{.enabled = false},
                      DragModel{.law = DragLaw::Cylinder, .viscosity = eta, .density = 1060},
                      [&](int s, const Vec3& p) { return fs->velocity_at(s, p); });
  rod::ForceAccumulator acc;
  acc.reset(nv);
  forces.evaluate(view, acc);
  const double exact = 0.5 * kPi * G * ((R * R - a * a) / std::log(R / a) - 2 * a * a) * span;
  const double axial = forces.total_drag().dot(axis);
  std::printf("  coaxial wire: drag %.6e N, exact annulus %.6e N (ratio %.6f)\n", axial, exact, axial / exact);
  EXPECT_NEAR(axial, exact, 1e-9 * exact);
  EXPECT_LT((forces.total_drag() - axial * axis).norm(), 1e-9 * exact);
}

TEST(CylinderDrag, ANonFiniteBloodVelocityIsANumericalError) {
  const ShortWire w;
  const auto& index = w.index;
  const rod::RodView& view = w.view;
  VesselForces forces(index, 0.2e-3, ContactParams{.enabled = false}, DragModel{},
                      [](int, const Vec3&) { return Vec3(std::nan(""), 0, 0); });
  rod::ForceAccumulator acc;
  acc.reset(3);
  try {
    forces.evaluate(view, acc);
    FAIL() << "a NaN blood velocity was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Numerical);
    EXPECT_NE(std::string(e.what()).find("not finite"), std::string::npos) << e.what();
  }
}

TEST(CylinderDrag, TheLargestReynoldsNumberIsThatOfAcceptedStates) {
  // The runner warns when it passes the curve's range; what it reads is the largest normal
  // Reynolds number of the states the rod accepted (end_step), not of trial iterates.
  const ShortWire w;
  const auto& index = w.index;
  const Vec3& axis = w.axis;
  const rod::RodView& view = w.view;
  const Vec3 across = axis.unitOrthogonal();
  double speed = 0.5;
  // (The law at every evaluation: here the blood itself changes between the evaluations
  // of one step, which the once-a-step drag, linearized at the step's blood, does not see.)
  VesselForces forces(index, 0.2e-3, ContactParams{.enabled = false}, DragModel{.once_per_step = false},
                      [&](int, const Vec3&) { return Vec3(speed * across); });
  rod::ForceAccumulator acc;
  acc.reset(3);
  forces.evaluate(view, acc);
  forces.end_step(view);
  const double re = 1060 * 0.5 * 0.4e-3 / 3.5e-3;
  EXPECT_NEAR(forces.stats().max_reynolds, re, 1e-9 * re);
  speed = 5e3;  // a trial iterate far beyond the curve's range, then the accepted state again
  acc.reset(3);
  forces.evaluate(view, acc);
  speed = 0.5;
  acc.reset(3);
  forces.evaluate(view, acc);
  forces.end_step(view);
  EXPECT_NEAR(forces.stats().max_reynolds, re, 1e-9 * re);
  speed = 5e3;  // accepted: now beyond the range
  acc.reset(3);
  forces.evaluate(view, acc);
  forces.end_step(view);
  EXPECT_GT(forces.stats().max_reynolds, kCylinderDragMaxReynolds);
}

namespace {

/// The wall images' velocity at a two-dimensional Oseen point force midway in a channel of
/// half-width 1 (per unit force/η), W = 4π u_h with s = κ the Oseen parameter, by direct
/// quadrature of its Fourier integral (the derivation in docs/blood-drag.md, independent of
/// the law's table): for each wavenumber ξ the free-space stream function plus
/// A sinh(ξz) + B sinh(βz) vanishes with its slope at z = 1.
double oseen_wall_by_quadrature(double kappa) {
  using C = std::complex<double>;
  const auto integrand = [kappa](double xi) {
    const C al(xi, 0.0);
    const C be = std::sqrt(C(xi * xi, 2.0 * kappa * xi));
    const C den(0.0, 2.0 * kappa * xi);
    const C ea = std::exp(-al), eb = std::exp(-be);
    const C psi = (eb - ea) / (2.0 * den), dpsi = (al * ea - be * eb) / (2.0 * den);
    // Unknowns scaled by e^{−ξ}, e^{−β}: sinh → (1 − e^{−2·})/2, cosh → (1 + e^{−2·})/2.
    const C s1 = 0.5 * (1.0 - ea * ea), c1 = 0.5 * (1.0 + ea * ea);
    const C s2 = 0.5 * (1.0 - eb * eb), c2 = 0.5 * (1.0 + eb * eb);
    const C det = s1 * be * c2 - s2 * al * c1;
    const C A = (-psi * be * c2 + s2 * dpsi) / det;
    const C B = (-s1 * dpsi + al * c1 * psi) / det;
    return std::real(A * ea * al + B * eb * be);
  };
  // Simpson in ln ξ over [1e-8, 40].
  const int n = 20000;
  const double x0 = std::log(1e-8), x1 = std::log(40.0), hx = (x1 - x0) / n;
  double sum = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double xi = std::exp(x0 + i * hx);
    const double wgt = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
    sum += wgt * integrand(xi) * xi;
  }
  // Below ξ₀ = 1e-8 the integrand goes as ξ^{-1/2} (β ≈ √(2iκξ)): its integral is 2ξ₀ f(ξ₀).
  const double tail = 2.0 * 1e-8 * integrand(1e-8);
  return 4.0 * kPi * (sum * hx / 3.0 + tail) / kPi;
}

constexpr double kEulerGamma = 0.57721566490153286;

}  // namespace

TEST(ChannelDrag, OseenWallTableIsTheFourierSolution) {
  // The law's tabulated W(s) (nodes at ln s = −8, −7.75, …, 9, cubic interpolation) against
  // the Fourier integral evaluated here, at nodes and between them: within 10⁻⁴ of W (the
  // interpolation between nodes), which moves the drag by less than 10⁻⁵.
  for (double s : {0.01, 0.3, 1.0, 1.7, 4.2, 11.0, 60.0}) {
    const double quad = oseen_wall_by_quadrature(s);
    const double law = channel_oseen_wall(s).w;
    std::printf("  s %6.2f: W table %.7f, quadrature %.7f\n", s, law, quad);
    EXPECT_NEAR(law, quad, 1e-4 * std::max(1.0, std::abs(quad))) << s;
  }
}

TEST(ChannelDrag, CreepingFlowLimitIsFaxensChannelDrag) {
  // Faxén (1946), cylinder midway between plane walls 2h apart (as quoted by Happel &
  // Brenner 1965): F'/(ηU) = 4π/(ln(h/a) − 0.9157 + 1.7244 k² − …). With Lamb's Oseen drag
  // of the unbounded cylinder, 1/g = (ln(2/(κa)) − γ + ½)/(4π), the images' term must turn
  // the Oseen length into the wall distance: ln(2/s) − γ + ½ − W(s) → −0.9157 as s → 0.
  for (double s : {1e-2, 1e-4, 1e-6}) {
    const double constant = std::log(2.0 / s) - kEulerGamma + 0.5 - channel_oseen_wall(s).w;
    EXPECT_NEAR(constant, -0.9157, 1e-4) << s;
  }
  // The law's creeping-flow value across a channel is Faxén's.
  for (double k : {0.01, 0.05, 0.119, 0.2, 0.4}) {
    const auto c = channel_drag_coefficient(1e-6, k);
    EXPECT_TRUE(c.stokes) << k;
    EXPECT_DOUBLE_EQ(c.g, faxen_channel_coefficient(k)) << k;
  }
  // Faxén's series between its limits: the two-plane value is below the coaxial tube's of
  // the same gap (walls on two sides against all round), by the constants 0.9157 and 1 as k → 0.
  for (double k : {0.01, 0.05, 0.119, 0.2, 0.3}) {
    const double tube = 4 * kPi / (std::log(1 / k) - (1 - k * k) / (1 + k * k));
    EXPECT_LT(faxen_channel_coefficient(k), tube) << k;
  }
  const double k = 1e-4;
  EXPECT_NEAR(4 * kPi / faxen_channel_coefficient(k) - std::log(1 / k), -0.9157, 1e-6);
  EXPECT_THROW(faxen_channel_coefficient(0.6), Error);
  EXPECT_THROW(faxen_channel_coefficient(0.0), Error);
}

TEST(ChannelDrag, InertialLimitIsGlauertsBlockage) {
  // Far downstream of an Oseen point force the wake's displacement flux F'/(ρU) must pass
  // the walls: W s → π/2, i.e. the stream at the wire is faster by the wake blockage
  // ε = (C_D/4)(d/H), H = 2h (Glauert 1933; Allen & Vincenti 1944).
  EXPECT_NEAR(channel_oseen_wall(1e4).w * 1e4, kPi / 2, 1e-2);
  EXPECT_NEAR(channel_oseen_wall(1e8).w * 1e8, kPi / 2, 1e-4);
  for (double re : {200.0, 1e3, 1e4}) {
    for (double k : {0.05, 0.119, 0.2}) {
      const double cd = cylinder_drag_coefficient(re);
      const double eps = kPi * kPi / 12 * k * k + cd * k / 4;
      const double glauert = (1 + eps) * 0.5 * re * (1 + eps) * cylinder_drag_coefficient(re * (1 + eps));
      const auto c = channel_drag_coefficient(re, k);
      EXPECT_FALSE(c.stokes);
      EXPECT_NEAR(c.g / glauert, 1.0, 0.01) << re << " " << k;
    }
  }
}

TEST(ChannelDrag, FarWallsGiveTheUnconfinedLawAndTheLawIsAboveBothLimits) {
  const double a = 0.178e-3;
  const DragModel m{.law = DragLaw::Cylinder, .viscosity = 3.5e-3, .density = 1060, .wire_radius = a};
  for (double re : {1.0, 10.0, 100.0, 1000.0}) {
    const double U = re * 3.5e-3 / (1060 * 2 * a);
    // A wire across a vessel of radius 1 m, on its axis: k = 1.8·10⁻⁴.
    DragInput in{.u = Vec3(U, 0, 0), .t = Vec3::UnitY(), .ell = 1.0, .vessel_radius = 1.0};
    in.axis = Vec3::UnitX();
    const double unconfined = 0.5 * 1060 * cylinder_drag_coefficient(re) * 2 * a * U * U;
    EXPECT_NEAR(blood_drag(m, in).force.x() / unconfined, 1.0, 1e-3) << re;
  }
  for (double k : {0.01, 0.119, 0.3, 0.4}) {
    for (double re = 1e-4; re < 1e5; re *= 1.7) {
      const double g = channel_drag_coefficient(re, k).g;
      EXPECT_GE(g, faxen_channel_coefficient(k)) << re << " " << k;
      EXPECT_GE(g, 0.5 * re * cylinder_drag_coefficient(re)) << re << " " << k;
    }
  }
}

TEST(ChannelDrag, AlongTheVesselTheLawIsUnchanged) {
  // A wire along the vessel (t = A) keeps the coaxial-tube law, with or without the axis;
  // for any orientation the force along the wire (annular Poiseuille shear) does not
  // depend on the confinement across it.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uni(-1, 1);
  const double a = 0.178e-3, R = 1.5e-3;
  const DragModel m{.law = DragLaw::Cylinder, .viscosity = 3.5e-3, .density = 1060, .wire_radius = a};
  for (int i = 0; i < 100; ++i) {
    DragInput in;
    in.u = 0.3 * Vec3(uni(rng), uni(rng), uni(rng));
    in.v = 0.1 * Vec3(uni(rng), uni(rng), uni(rng));
    in.t = Vec3(uni(rng), uni(rng), uni(rng)).normalized();
    in.ell = 1e-3;
    in.vessel_radius = R;
    const auto bare = blood_drag(m, in);
    DragInput along = in;
    along.axis = in.t;
    EXPECT_LT((blood_drag(m, along).force - bare.force).norm(), 1e-12 * bare.force.norm());
    DragInput oblique = in;
    oblique.axis = Vec3(uni(rng), uni(rng), uni(rng)).normalized();
    oblique.axis_offset = 0.5 * R * oblique.axis.unitOrthogonal();
    EXPECT_NEAR(blood_drag(m, oblique).force.dot(in.t), bare.force.dot(in.t), 1e-12 * bare.force.norm());
  }
}

TEST(ChannelDrag, DerivativesMatchFiniteDifferences) {
  for (double s = 1e-5; s < 1e7; s *= 1.37) {
    const double h = 1e-6 * s;
    const double fd = (channel_oseen_wall(s + h).w - channel_oseen_wall(s - h).w) / (2 * h);
    // W = ln(2/s) − γ + ½ − C(s) loses its last digits to the cancellation at large s: 10⁻¹⁴/h.
    EXPECT_NEAR(channel_oseen_wall(s).dw, fd, 1e-5 * std::abs(fd) + 1e-14 / h) << s;
  }
  for (double k : {0.02, 0.119, 0.25, 0.4}) {
    for (double re = 1e-3; re < 1e5; re *= 1.23) {
      const double h = 1e-6 * re;
      const auto lo = channel_drag_coefficient(re - h, k), hi = channel_drag_coefficient(re + h, k);
      if (lo.stokes != hi.stokes) continue;  // the switch between Faxén's value and the inertial law
      const double fd = (hi.g - lo.g) / (2 * h);
      EXPECT_NEAR(channel_drag_coefficient(re, k).dg, fd, 1e-5 * std::abs(fd) + 1e-9) << re << " " << k;
      // The force per length η g U grows with the speed: a monotone law.
      EXPECT_GT(channel_drag_coefficient(re, k).g + re * channel_drag_coefficient(re, k).dg, 0.0) << re;
    }
  }
}
