// Segments occluded by a wire (FlowSolver::set_occlusion): the network's flows against
// the annular Poiseuille flow and against resistances combined by hand, the solvers
// against each other, and the Womersley harmonics of the fast path against resampling.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "flow_test_networks.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/annulus.hpp"
#include "flowire/flow/solver.hpp"

namespace flowire::flow {
namespace {

using namespace flowire::flow::test;
constexpr double kPi = std::numbers::pi;
constexpr double kEta = 3.5e-3;

FlowSpec pressure_drop_spec(const Network& net, double dp) {
  FlowSpec spec = default_spec(net, Waveform::constant(dp));
  spec.viscosity = kEta;
  return spec;
}

std::vector<SegmentOcclusion> uniform(const Network& net, double factor, double fraction = 1.0) {
  SegmentOcclusion o;
  o.occupied_fraction = fraction;
  o.resistance_factor = o.gradient_factor = factor;
  return std::vector<SegmentOcclusion>(static_cast<size_t>(net.num_segments()), o);
}

TEST(FlowOcclusion, AWireThroughATubeCarriesTheAnnularPoiseuilleFlow) {
  // A 3 mm tube, 5 cm long, 100 Pa across, with a 0.014" wire along its whole length.
  const double r = 1.5e-3, a = 0.178e-3, l = 0.05, dp = 100.0;
  const Network net = tube(l, r, 5);
  for (SolverKind kind : {SolverKind::Superposition, SolverKind::Sparse}) {
    FlowSpec spec = pressure_drop_spec(net, dp);
    spec.solver = kind;
    auto solver = make_solver(net, spec);
    solver->advance(0.0);
    const double empty = solver->segment_flow(2);
    EXPECT_NEAR(empty, kPi * dp * r * r * r * r / (8.0 * kEta * l), 1e-12 * empty);
    for (double e : {0.0, 0.6, 1.0}) {
      solver->set_occlusion(uniform(net, annulus_resistance_factor(a / r, e)));
      // The annulus, integrated here from its own definition: Q = πG/(8η)·R⁴·fraction,
      // with the concentric fraction in closed form (Bird, Stewart & Lightfoot) at e = 0.
      const double k = a / r;
      const double fraction =
          e == 0.0 ? 1.0 - std::pow(k, 4) - std::pow(1.0 - k * k, 2) / std::log(1.0 / k) : annulus_flow_fraction(k, e);
      const double exact = kPi * dp / (8.0 * kEta * l) * std::pow(r, 4) * fraction;
      for (int s = 0; s < net.num_segments(); ++s) EXPECT_NEAR(solver->segment_flow(s), exact, 1e-12 * exact) << e;
      // Pressure falls linearly along the uniformly occluded tube.
      EXPECT_NEAR(solver->node_pressure(2), dp * 3.0 / 5.0, 1e-9 * dp);
    }
    // Concentric: 46% less flow; on the wall: 8% less.
    solver->set_occlusion(uniform(net, annulus_resistance_factor(a / r, 0.0)));
    EXPECT_NEAR(solver->segment_flow(0) / empty, 0.544, 0.001);
    // Taking the wire out restores the empty tube exactly.
    solver->set_occlusion(uniform(net, 1.0, 0.0));
    EXPECT_NEAR(solver->segment_flow(0), empty, 1e-13 * empty);
    // A tube widened by 2% (a wall that yields: factor (1/1.02)^4 < 1) carries 1.02^4 the flow.
    std::vector<SegmentOcclusion> widened(static_cast<size_t>(net.num_segments()));
    for (auto& w : widened) w.resistance_factor = std::pow(1.0 / 1.02, 4);
    solver->set_occlusion(widened);
    EXPECT_NEAR(solver->segment_flow(0), empty * std::pow(1.02, 4), 1e-12 * empty);
    solver->set_occlusion(uniform(net, 1.0, 0.0));
  }
}

TEST(FlowOcclusion, OccludingOneBranchShiftsTheSplitAsItsResistancesSay) {
  // Wheatstone network of unit resistances (R = length with kUnitViscosity): occlude the
  // branch S–A by 3× and compare with the node equations solved by hand for the new
  // resistances (the network's Kirchhoff system in 2 unknowns, p_A and p_B).
  const Network net = wheatstone();
  FlowSpec spec = pressure_spec(net, kS, Waveform::constant(1.0), {{kT, 0.0}});
  spec.viscosity = kUnitViscosity;
  auto solver = make_solver(net, spec);
  std::vector<SegmentOcclusion> occ(5);
  occ[0].resistance_factor = 3.0;
  occ[0].occupied_fraction = 1.0;
  solver->set_occlusion(occ);
  // Resistances: SA 3, SB 2, AT 2, BT 1, AB 1; p_S = 1, p_T = 0.
  //   A: (1 − pA)/3 = pA/2 + (pA − pB)/1
  //   B: (1 − pB)/2 + (pA − pB)/1 = pB/1
  const double m00 = 1.0 / 3 + 0.5 + 1.0, m01 = -1.0, m10 = -1.0, m11 = 0.5 + 1.0 + 1.0;
  const double b0 = 1.0 / 3, b1 = 0.5, det = m00 * m11 - m01 * m10;
  const double pa = (b0 * m11 - m01 * b1) / det, pb = (m00 * b1 - m10 * b0) / det;
  EXPECT_NEAR(solver->node_pressure(kA), pa, 1e-13);
  EXPECT_NEAR(solver->node_pressure(kB), pb, 1e-13);
  EXPECT_NEAR(solver->segment_flow(0), (1.0 - pa) / 3.0, 1e-13);
  EXPECT_NEAR(solver->effective_resistance(0), 3.0, 1e-13);
}

TEST(FlowOcclusion, SuperpositionEqualsSparseWithPeriodicSourcesAndTheWomersleyProfile) {
  // A Murray tree driven by a sine pressure, the Womersley profile on, random occlusions:
  // the superposition solver (refactored, its harmonics from the sources' harmonics) and
  // the sparse solver (refactored, its harmonics resampled from the flows) agree.
  const Network net = murray_tree(3);
  FlowSpec spec = default_spec(net, Waveform::sine(16000.0, 10000.0, 0.8));
  spec.profile = Profile::Womersley;
  FlowSpec sparse_spec = spec;
  sparse_spec.solver = SolverKind::Sparse;
  auto sup = make_solver(net, spec);
  auto ref = make_solver(net, sparse_spec);
  std::vector<SegmentOcclusion> occ(static_cast<size_t>(net.num_segments()));
  for (int round = 0; round < 3; ++round) {
    for (size_t s = 0; s < occ.size(); ++s) {
      const double f = 1.0 + 0.37 * static_cast<double>((s * 7 + static_cast<size_t>(round) * 3) % 5);
      occ[s].resistance_factor = occ[s].gradient_factor = f;
      occ[s].occupied_fraction = f > 1.0 ? 1.0 : 0.0;
    }
    sup->set_occlusion(occ);
    ref->set_occlusion(occ);
    for (double t : {0.05, 0.31, 0.62}) {
      sup->advance(t);
      ref->advance(t);
      for (int s = 0; s < net.num_segments(); ++s) {
        const double q = ref->segment_flow(s);
        EXPECT_NEAR(sup->segment_flow(s), q, 1e-10 * std::abs(q) + 1e-18) << s;
        const auto& seg = net.segment(s);
        const Vec3 p = 0.5 * (net.node(seg.node_from) + net.node(seg.node_to)) + Vec3(0, 0, 0.3 * seg.radius);
        const double u = ref->axial_velocity_at(s, p);
        EXPECT_NEAR(sup->axial_velocity_at(s, p), u, 1e-9 * std::abs(u) + 1e-12) << s << " t " << t;
      }
    }
  }
  EXPECT_EQ(sup->timings().occlusion_updates, 3);
}

TEST(FlowOcclusion, TheDragSeesTheOccupiedPartsPressureGradient) {
  // In the occupied part of a segment, the undisturbed velocity at the wire is the empty
  // tube's profile under that part's gradient: gradient_factor times the parabola of Q.
  const Network net = tube(0.05, 1.5e-3, 1);
  auto solver = make_solver(net, pressure_drop_spec(net, 100.0));
  solver->advance(0.0);
  const Vec3 p(0.02, 0.4e-3, 0.0);
  const double u_empty = solver->axial_velocity_at(0, p);
  std::vector<SegmentOcclusion> occ(1);
  occ[0].occupied_fraction = 0.5;
  occ[0].gradient_factor = 1.8;
  occ[0].resistance_factor = 1.4;  // half of the length at 1.8×
  solver->set_occlusion(occ);
  const double q_ratio = 1.0 / 1.4;
  EXPECT_NEAR(solver->axial_velocity_at(0, p), u_empty * q_ratio * 1.8, 1e-12 * u_empty);
}

TEST(FlowOcclusion, RlcTubeRelaxesWithTheOccludedResistanceAndInertance) {
  // A rigid tube (no compliance) is an R–L circuit: after the wire goes in at t0 the flow
  // relaxes from Q0 to Q∞ = Δp/(F_R R) with the time constant F_L L/(F_R R), exactly
  // Q(t) = Q∞ + (Q0 − Q∞) exp(−(t − t0) F_R R/(F_L L)). The integrator's error falls with
  // its step (the slope is asserted; the jump in the parameters costs the restart its
  // second order).
  const double r = 1.5e-3, l = 0.05, dp = 100.0;
  const Network net = tube(l, r, 1);
  std::vector<double> log_dt, log_err;
  for (double dt : {8e-4, 4e-4, 2e-4, 1e-4}) {
    FlowSpec spec = pressure_drop_spec(net, dp);
    spec.model = Model::Rlc;
    spec.wall_youngs_modulus = 0.0;  // rigid
    spec.dt = dt;
    auto solver = make_solver(net, spec);
    solver->advance(0.008);
    const double big_r = 8.0 * kEta * l / (kPi * std::pow(r, 4)), big_l = spec.density * l / (kPi * r * r);
    const double q0 = solver->segment_flow(0);
    EXPECT_NEAR(q0, dp / big_r, 1e-9 * q0);
    std::vector<SegmentOcclusion> occ(1);
    occ[0].occupied_fraction = 1.0;
    occ[0].resistance_factor = occ[0].gradient_factor = 1.84;
    occ[0].inertance_factor = 1.016;
    solver->set_occlusion(occ);
    const double q_inf = dp / (1.84 * big_r), tau = 1.016 * big_l / (1.84 * big_r);
    double err = 0.0;
    for (int k = 1; k <= 100; ++k) {  // every step over 0.8 s (17 time constants)
      const double t = k * 0.008;
      solver->advance(0.008 + t);
      err = std::max(err, std::abs(solver->segment_flow(0) - (q_inf + (q0 - q_inf) * std::exp(-t / tau))) / q0);
    }
    std::printf("rlc tube, dt %.0e s (tau %.3f s): max |Q - exact|/Q0 = %.2e\n", dt, tau, err);
    log_dt.push_back(std::log(dt));
    log_err.push_back(std::log(err));
    if (dt == 1e-4) {
      EXPECT_LT(err, 2e-4);
    }
  }
  const double slope = (log_err.back() - log_err.front()) / (log_dt.back() - log_dt.front());
  std::printf("rlc tube: error slope %.2f\n", slope);
  EXPECT_GT(slope, 0.9);
}

TEST(FlowOcclusion, SolversThatKeepTheirMatrixAndBadFactorsAreRefused) {
  const Network net = tube(0.05, 1.5e-3, 2);
  FlowSpec spec = pressure_drop_spec(net, 100.0);
  spec.solver = SolverKind::DenseInverse;
  auto dense = make_solver(net, spec);
  EXPECT_FALSE(dense->supports_occlusion());
  EXPECT_THROW(dense->set_occlusion(uniform(net, 2.0)), Error);
  spec.solver = SolverKind::Superposition;
  auto sup = make_solver(net, spec);
  EXPECT_THROW(sup->set_occlusion(uniform(net, 0.5)), Error);  // (a gradient factor below 1)
  EXPECT_THROW(sup->set_occlusion(uniform(net, 0.0)), Error);
  EXPECT_THROW(sup->set_occlusion(uniform(net, std::nan(""))), Error);
  EXPECT_THROW(sup->set_occlusion(std::vector<SegmentOcclusion>(1)), Error);
  // An unchanged occlusion costs nothing.
  sup->set_occlusion(uniform(net, 2.0));
  sup->set_occlusion(uniform(net, 2.0));
  EXPECT_EQ(sup->timings().occlusion_updates, 1);
}

}  // namespace
}  // namespace flowire::flow
