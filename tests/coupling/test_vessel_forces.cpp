// Vessel forces (lookup, contact, friction, drag) on free point masses integrated by
// backward Euler with the forces' own Jacobians, against closed-form results.
#include "flowire/coupling/vessel_forces.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "flowire/vessels/generators.hpp"
#include "flowire_test.hpp"

using namespace flowire;
using namespace flowire::coupling;
using vessels::Vec3;

namespace {

/// A rigid straight wire: vertices each carrying the length ℓ_i they represent (half at the
/// two ends) and translating together at one velocity V; mass, load and damping are per
/// unit length. Backward Euler, Newton on V with the forces' own Jacobians.
struct RigidWire {
  std::vector<Vec3> x, v;
  std::vector<double> arc, radius, ell;
  double m;  ///< mass per unit length
  double length = 0;
  Vec3 V = Vec3::Zero();
  RigidWire(std::vector<Vec3> x0, double mass_per_length)
      : x(std::move(x0)), v(x.size(), Vec3::Zero()), m(mass_per_length) {
    const double h = (x[1] - x[0]).norm();
    ell.assign(x.size(), h);
    ell.front() = ell.back() = 0.5 * h;
    for (double e : ell) length += e;
    arc.resize(x.size());
    for (size_t i = 0; i < x.size(); ++i) arc[i] = static_cast<double>(x.size() - i);
    radius.assign(x.size() - 1, 0.0);
  }
  rod::RodView view(double dt, const std::vector<Vec3>& xs, const std::vector<Vec3>& vs) const {
    rod::RodView r;
    r.positions = xs;
    r.velocities = vs;
    r.arc_length = arc;
    r.radius = radius;
    r.first_clamped_vertex = static_cast<int>(xs.size());
    r.dt = dt;
    return r;
  }
  void step(rod::ExternalForce& f, double dt, const Vec3& load_per_length, double damping = 0.0) {
    rod::ForceAccumulator acc;
    Vec3 Vn = V;
    std::vector<Vec3> xn(x.size()), vn(x.size());
    for (int it = 0; it < 50; ++it) {
      for (size_t i = 0; i < x.size(); ++i) xn[i] = x[i] + dt * Vn, vn[i] = Vn;
      acc.reset(static_cast<int>(x.size()));
      f.evaluate(view(dt, xn, vn), acc);
      Vec3 F = Vec3::Zero();
      Eigen::Matrix3d J = (m * length / dt + damping * length) * Eigen::Matrix3d::Identity();
      for (size_t i = 0; i < x.size(); ++i) {
        F += acc.forces()[i];
        J -= acc.velocity_jacobians()[i] + dt * acc.position_jacobians()[i];
      }
      const Vec3 r = m * length * (Vn - V) / dt - F - load_per_length * length + damping * length * Vn;
      const Vec3 dV = J.ldlt().solve(-r);
      Vn += dV;
      if (dV.norm() < 1e-14) break;
    }
    V = Vn;
    for (size_t i = 0; i < x.size(); ++i) x[i] += dt * V, v[i] = V;
    std::vector<Vec3> xs = x, vs = v;
    f.end_step(view(dt, xs, vs));
  }
};

}  // namespace

TEST(VesselForces, SlenderBodyTerminalVelocityAlongTheAxis) {
  // A straight wire on the axis of a wide tube, blood at u along the axis, a load F per
  // vertex against the flow: the terminal velocity is u − F/(c∥ ℓ) with c∥ = 2πη/ln(L/r).
  const auto net =
      vessels::Network::build(vessels::straight_tube({.length = 1.0, .radius = 0.01}), {.max_segment_length = 0.01});
  const vessels::SpatialIndex index(net);
  const double a = 0.45e-3, ell = 1e-3, eta = 3.5e-3, L = 1.0, u = 0.3;
  std::vector<Vec3> x0;
  for (int i = 0; i < 20; ++i) x0.push_back(Vec3(0.4 + ell * i, 0, 0));
  RigidWire pm(x0, 1e-4);  // relaxation time ρA/c∥ ≈ 35 ms
  const double c_par = 2 * std::numbers::pi * eta / std::log(L / a);
  const double F = 0.5 * c_par * u;  // per unit length: halves the terminal velocity
  VesselForces f(index, a, ContactParams{.enabled = false},
                 DragModel{.law = DragLaw::SlenderBody, .viscosity = eta, .wire_length = L},
                 [&](int, const Vec3&) { return Vec3(u, 0, 0); });
  for (int k = 0; k < 2000; ++k) pm.step(f, 1e-3, Vec3(-F, 0, 0));
  EXPECT_NEAR(pm.V.x(), u - F / c_par, 1e-9 * u);
  // Sideways flow drags twice as hard: c⊥ = 2 c∥.
  RigidWire side(x0, 1e-4);
  VesselForces g(index, a, ContactParams{.enabled = false},
                 DragModel{.law = DragLaw::SlenderBody, .viscosity = eta, .wire_length = L},
                 [&](int, const Vec3&) { return Vec3(0, u, 0); });
  for (int k = 0; k < 2000; ++k) side.step(g, 1e-3, Vec3(0, -F, 0));
  EXPECT_NEAR(side.V.y(), u - F / (2 * c_par), 1e-9 * u);
}

TEST(VesselForces, VelocityOffsetIsTheImpulsePerStepOfThePublishedForm) {
  // Eq. 10 adds u to every velocity update. With linear damping c per vertex the terminal
  // velocity is ρA·u/(c·Δt) (c per unit length): the published form depends on the step size.
  const auto net =
      vessels::Network::build(vessels::straight_tube({.length = 1.0, .radius = 0.01}), {.max_segment_length = 0.01});
  const vessels::SpatialIndex index(net);
  const double ell = 1e-3, rhoA = 4.0e-3, u = 0.2, c = 4.0;
  std::vector<Vec3> x0;
  for (int i = 0; i < 10; ++i) x0.push_back(Vec3(0.4 + ell * i, 0, 0));
  for (double dt : {1e-3, 2e-3}) {
    RigidWire pm(x0, rhoA);
    VesselForces f(index, 0.45e-3, ContactParams{.enabled = false},
                   DragModel{.law = DragLaw::VelocityOffset, .mass_per_length = rhoA},
                   [&](int, const Vec3&) { return Vec3(u, 0, 0); });
    for (int k = 0; k < 4000; ++k) pm.step(f, dt, Vec3::Zero(), c);
    EXPECT_NEAR(pm.V.x(), rhoA * u / (c * dt), 1e-6 * u) << dt;
  }
}

TEST(VesselForces, CoulombFrictionOnTheWallNeedsMuTimesNToSlide) {
  // DisMech's case (reference README): a 1 kg wire, μ = 0.4, lying on the wall under
  // gravity, pulled along with a total force F for 1 s reaches ½(|F| − 3.92)² J.
  const double R = 1.0, a = 0.45e-3, g = 9.81, mu = 0.4;
  const auto net =
      vessels::Network::build(vessels::straight_tube({.length = 10.0, .radius = R}), {.max_segment_length = 0.5});
  const vessels::SpatialIndex index(net);
  const int n = 20;
  std::vector<Vec3> x0;
  const double k_wall = 1e6;
  const double sink = g / (n * k_wall);  // static penalty penetration under the weight
  for (int i = 0; i < n; ++i) x0.push_back(Vec3(4.0 + 0.01 * i, 0, -(R - a) - sink));  // resting on the bottom
  const double len = 0.01 * (n - 1);
  for (double F : {2.0, 3.0, 6.0, 10.0}) {
    RigidWire pm(x0, 1.0 / len);
    ContactParams cp{.stiffness = k_wall, .friction = mu, .tip_friction = mu, .slip_speed = 1e-5};
    VesselForces f(index, a, cp, DragModel{.law = DragLaw::None});
    const double dt = 1e-3;
    for (int k = 0; k < 1000; ++k) pm.step(f, dt, Vec3(F / len, 0, -g / len));
    const double ke = 0.5 * pm.m * pm.length * pm.V.squaredNorm();
    const double expected = F > mu * g ? 0.5 * std::pow(F - mu * g, 2) : 0.0;
    EXPECT_NEAR(ke, expected, 0.01 * expected + 1e-6) << "F = " << F;
    EXPECT_LT(f.stats().max_penetration, 0.1 * a);
  }
}

TEST(VesselForces, LookupUsesTheWindowForAMovingWire) {
  const auto net = vessels::Network::build(vessels::aortic_arch(), {.max_segment_length = 2e-3});
  const vessels::SpatialIndex index(net);
  const auto entry = vessels::aortic_arch_entry();
  std::vector<Vec3> x0;
  for (int i = 0; i < 30; ++i) x0.push_back(entry + Vec3(0, 0, 1e-3 * i));
  RigidWire pm(x0, 1e-2);
  VesselForces f(index, 0.45e-3, ContactParams{.stiffness = 1e4}, DragModel{.law = DragLaw::None});
  for (int k = 0; k < 50; ++k) pm.step(f, 1e-3, Vec3(0, 0, 0.1));
  EXPECT_GT(index.stats().window_hits, 10 * index.stats().fallbacks);
}

TEST(VesselForces, WallStiffnessScalesWithTheVertexEdgesOfARefinedWire) {
  // Two vertices pressed equally deep into the wall of a straight tube, one with grid
  // edges h, one with refined edges h/4: the wall pushes the refined one a quarter as
  // hard, so the wall stays equally stiff per unit length of wire.
  const auto net =
      vessels::Network::build(vessels::straight_tube({.length = 0.1, .radius = 2e-3}), {.max_segment_length = 5e-3});
  const vessels::SpatialIndex index(net);
  ContactParams cp;
  cp.stiffness = 1e4;
  cp.friction = 0.0;
  cp.tip_friction = 0.0;
  VesselForces forces(index, 0.3e-3, cp, DragModel{.law = DragLaw::None});
  const double h = 1e-3;
  // Vertices 0..4 along the wall (y = 1.8 mm: 0.1 mm into it with a 0.3 mm wire).
  std::vector<Vec3> x, v(5, Vec3::Zero());
  for (int i = 0; i < 5; ++i) x.emplace_back(0.05 + 0.001 * i, 1.8e-3, 0.0);
  const std::vector<double> arc{5, 4, 3, 2, 1}, radius(4, 0.3e-3);
  for (const double refined : {h, 0.25 * h}) {
    const std::vector<double> rest{h, refined, refined, h};
    rod::RodView view;
    view.positions = x;
    view.velocities = v;
    view.arc_length = arc;
    view.radius = radius;
    view.rest_lengths = rest;
    view.segment_length = h;
    view.first_clamped_vertex = 5;
    rod::ForceAccumulator acc;
    acc.reset(5);
    forces.evaluate(view, acc);
    const double f_grid = acc.forces()[0].norm();  // edges h
    const double f_mid = acc.forces()[2].norm();   // edges `refined`
    ASSERT_GT(f_grid, 0.0);
    EXPECT_NEAR(f_mid / f_grid, refined / h, 1e-9);
    EXPECT_NEAR(f_grid, cp.stiffness * 0.1e-3, 1e-9);  // k δ on the grid
  }
}

TEST(VesselForces, EachVertexTouchesTheWallAndFeelsTheBloodWithTheRodsOwnRadiusThere) {
  // A wire whose distal edges are thinner (0.15 mm, a tapered tip) than its shaft (0.45 mm)
  // lies along the wall of a 2 mm tube, every vertex centre 0.3 mm from the wall: the thin
  // tip vertex does not reach the wall, the shaft vertices press into it by 0.15 mm, the
  // vertex between them (radius 0.3 mm, the mean of its edges) just touches. The blood's
  // drag on each vertex is the law's at that vertex's radius. One radius for the whole wire
  // (the constructor's) would press every vertex alike.
  const auto net =
      vessels::Network::build(vessels::straight_tube({.length = 0.1, .radius = 2e-3}), {.max_segment_length = 5e-3});
  const vessels::SpatialIndex index(net);
  ContactParams cp;
  cp.stiffness = 1e4;
  cp.friction = 0.0;
  cp.tip_friction = 0.0;
  const DragModel drag{.law = DragLaw::Cylinder, .viscosity = 3.5e-3, .density = 1060.0};
  const Vec3 blood(0.0, 0.0, 0.2);  // across the wire
  VesselForces forces(index, 0.45e-3, cp, drag, [&](int, const Vec3&) { return blood; });
  std::vector<Vec3> x, v(5, Vec3::Zero());
  for (int i = 0; i < 5; ++i) x.emplace_back(0.05 + 0.001 * i, 1.7e-3, 0.0);
  const std::vector<double> arc{5, 4, 3, 2, 1}, radius{0.15e-3, 0.15e-3, 0.45e-3, 0.45e-3};
  rod::RodView view;
  view.positions = x;
  view.velocities = v;
  view.arc_length = arc;
  view.radius = radius;
  view.first_clamped_vertex = 5;
  view.dt = 1e-3;
  rod::ForceAccumulator acc;
  acc.reset(5);
  forces.evaluate(view, acc);
  const std::vector<double> a{0.15e-3, 0.15e-3, 0.3e-3, 0.45e-3, 0.45e-3};
  for (int i = 0; i < 5; ++i) {
    SCOPED_TRACE(i);
    const double push = std::max(0.0, a[i] - 0.3e-3);  // into the wall
    EXPECT_NEAR(-forces.contact_force()[i].y(), cp.stiffness * push, 1e-12);
    DragModel own = drag;
    own.wire_radius = a[i];
    DragInput in;
    in.u = blood;
    in.t = Vec3(-1, 0, 0);
    in.ell = i == 0 || i == 4 ? 0.5e-3 : 1e-3;
    in.vessel_radius = 2e-3;
    in.axis = Vec3(1, 0, 0);
    in.axis_offset = Vec3(0, 1.7e-3, 0);
    EXPECT_NEAR((forces.drag_force()[i] - blood_drag(own, in).force).norm(), 0.0,
                1e-12 * blood_drag(own, in).force.norm());
  }
  EXPECT_GT(forces.drag_force()[4].norm(), forces.drag_force()[1].norm() * 1.05) << "the radius would not show";
}

TEST(VesselForces, AStepsDragIsTheLawAtItsGuessLinearizedInTheWireVelocity) {
  // coupling.drag_update: step. The first evaluation of a step (Newton's initial guess)
  // evaluates the cylinder law; every later iterate of the same step gets that force plus
  // its velocity Jacobian times the change of velocity, exactly; the next step evaluates the
  // law again. The blood velocity here depends on the position, so that keeping the guess's
  // is visible too.
  const auto net =
      vessels::Network::build(vessels::straight_tube({.length = 0.2, .radius = 5e-3}), {.max_segment_length = 5e-3});
  const vessels::SpatialIndex index(net);
  const VelocityField u = [](int, const Vec3& p) { return Vec3(0.3 + 40.0 * p.y(), 0.05 - 20.0 * p.z(), 0.02); };
  const double a = 0.2e-3;
  DragModel law{.law = DragLaw::Cylinder};
  VesselForces per_step(index, a, ContactParams{.enabled = false}, law, u);
  law.once_per_step = false;
  VesselForces per_iterate(index, a, ContactParams{.enabled = false}, law, u);
  std::vector<Vec3> x0, v0, x1, v1;
  for (int i = 0; i < 6; ++i) {
    x0.push_back(Vec3(0.05 + 1e-3 * i, 1e-3 * std::sin(i), 0.5e-3 * std::cos(i)));
    v0.push_back(Vec3(0.01 * i, -0.02, 0.005 * i));
    x1.push_back(x0.back() + Vec3(2e-4, -1e-4 * i, 3e-5));
    v1.push_back(v0.back() + Vec3(0.03, 0.01 * i, -0.02));
  }
  RigidWire geometry(x0, 1e-4);
  auto evaluate = [&](VesselForces& f, double time, const std::vector<Vec3>& xs, const std::vector<Vec3>& vs) {
    rod::ForceAccumulator acc;
    acc.reset(static_cast<int>(xs.size()));
    auto view = geometry.view(1e-3, xs, vs);
    view.time = time;
    f.evaluate(view, acc);
    return acc;
  };
  const auto guess = evaluate(per_step, 0.01, x0, v0);
  const auto law_at_guess = evaluate(per_iterate, 0.01, x0, v0);
  const auto iterate = evaluate(per_step, 0.01, x1, v1);
  const auto law_at_iterate = evaluate(per_iterate, 0.01, x1, v1);
  for (size_t i = 0; i < x0.size(); ++i) {
    EXPECT_EQ(guess.forces()[i], law_at_guess.forces()[i]) << i;
    const Vec3 linear = guess.forces()[i] + guess.velocity_jacobians()[i] * (v1[i] - v0[i]);
    EXPECT_LT((iterate.forces()[i] - linear).norm(), 1e-14 * linear.norm()) << i;
    EXPECT_EQ(iterate.velocity_jacobians()[i], guess.velocity_jacobians()[i]) << i;
    // (The law itself is neither linear in the velocity nor blind to the position.)
    EXPECT_GT((law_at_iterate.forces()[i] - linear).norm(), 1e-3 * linear.norm()) << i;
  }
  // A new step (after end_step) evaluates the law again, at its own guess.
  per_step.end_step(geometry.view(1e-3, x1, v1));
  const auto next = evaluate(per_step, 0.011, x1, v1);
  for (size_t i = 0; i < x0.size(); ++i) EXPECT_EQ(next.forces()[i], law_at_iterate.forces()[i]) << i;
}

TEST(VesselForces, TheOncePerStepDragReachesTheSameTerminalVelocityAndErrsAtSecondOrderInTheStep) {
  // A straight wire across a Reynolds-dependent cross flow (cylinder law), pulled against it
  // by a load: the terminal velocity is the law's fixed point whether the law is linearized
  // once a step or iterated to convergence. On the way the two differ by the linearization's
  // O(Δv²) = O(Δt²) per step, i.e. at second order in Δt over a fixed time, below backward
  // Euler's own first-order error: halving Δt quarters the difference.
  const auto net =
      vessels::Network::build(vessels::straight_tube({.length = 1.0, .radius = 0.02}), {.max_segment_length = 0.01});
  const vessels::SpatialIndex index(net);
  std::vector<Vec3> x0;
  for (int i = 0; i < 10; ++i) x0.push_back(Vec3(0.4 + 1e-3 * i, 0, 0));
  const VelocityField u = [](int, const Vec3&) { return Vec3(0, 0.3, 0); };
  auto run = [&](bool once, double dt, double until) {
    DragModel law{.law = DragLaw::Cylinder};
    law.once_per_step = once;
    VesselForces f(index, 0.45e-3, ContactParams{.enabled = false}, law, u);
    RigidWire w(x0, 4e-3);
    const int n = static_cast<int>(std::lround(until / dt));
    for (int k = 0; k < n; ++k) w.step(f, dt, Vec3(0, -0.02, 0));
    return w.V.y();
  };
  EXPECT_NEAR(run(true, 1e-3, 2.0), run(false, 1e-3, 2.0), 1e-9);
  const double d1 = std::abs(run(true, 2e-3, 0.02) - run(false, 2e-3, 0.02));
  const double d2 = std::abs(run(true, 1e-3, 0.02) - run(false, 1e-3, 0.02));
  EXPECT_GT(d1, 0.0);
  EXPECT_NEAR(std::log2(d1 / d2), 2.0, 0.2);
}
