// Blood drag on the wire against fluid mechanics: the cylinder drag curve against
// published solutions and measurements, the tangential law against a numerical solution of
// the annulus between wire and wall, the whole chain (network flow → profile → drag on a
// wire) against the exact annular Poiseuille force, and every Jacobian against finite
// differences.
#include "flowire/coupling/drag.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
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
  VesselForces forces(index, 0.2e-3, ContactParams{.enabled = false}, DragModel{},
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
