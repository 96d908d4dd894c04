// Losses beyond Poiseuille taken from the network's geometry (flow/losses.hpp): which narrowings
// of a branch are stenoses and against which shoulder, and a stenosed vessel's pressure drop
// through a whole scene (flow.losses) against Young & Tsai's law written out here term by term.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "flow_test_networks.hpp"
#include "flowire/common/config.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/losses.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/flow/spec.hpp"
#include "flowire/vessels/generators.hpp"

namespace flowire::flow {
namespace {

using test::flow_schema;
constexpr double kPi = std::numbers::pi;
constexpr double r0 = 2e-3;

/// A vessel of radius r0 along x (or bent on a circle of radius bend_radius), sampled every 0.5 mm
/// over [0, 80] mm of arc length, with a cosine
/// stenosis of depth δ (throat radius (1 − δ) r0) and half-length 4 mm centred at each given x,
/// a ripple of ±ripple·r0 everywhere, and (if taper) the last 6 mm narrowing to 0.6 r0.
Network stenosed_vessel(const std::vector<std::pair<double, double>>& stenoses, double ripple, bool taper,
                        double bend_radius = 0.0) {
  vessels::Centerlines c;
  vessels::Polyline p;
  p.name = "stenosed";
  for (int i = 0; i <= 160; ++i) {
    const double x = 0.5e-3 * i;
    double r = r0 * (1.0 + ripple * std::sin(2.0 * kPi * x / 3.1e-3));
    for (const auto& [xc, delta] : stenoses)
      if (std::abs(x - xc) <= 4e-3) r -= r0 * delta / 2.0 * (1.0 + std::cos(kPi * (x - xc) / 4e-3));
    if (taper && x > 74e-3) r *= 1.0 - 0.4 * (x - 74e-3) / 6e-3;
    if (bend_radius > 0.0)  // the same arc length along a circle in the xy plane
      p.points.emplace_back(bend_radius * std::sin(x / bend_radius), bend_radius * (1.0 - std::cos(x / bend_radius)),
                            0.0);
    else
      p.points.emplace_back(x, 0.0, 0.0);
    p.radii.push_back(r);
  }
  c.branches.push_back(p);
  vessels::BuildOptions opt;
  opt.max_segment_length = 0.5e-3;
  opt.radius_change = 1e-3;  // every sample a node
  return Network::build(c, opt);
}

TEST(FlowLosses, EachNarrowingPastTheThresholdIsOneStenosisMeasuredAgainstItsLowerShoulder) {
  // 75% and 51% area reductions, a ±1% ripple (4% of area: no stenosis) and a tapering end
  // (its minimum is the end node: no stenosis either).
  const Network net = stenosed_vessel({{20e-3, 0.5}, {50e-3, 0.3}}, 0.01, true);
  ASSERT_EQ(net.num_segments(), 160);
  const std::vector<Stenosis> found = find_stenoses(net, 1060.0, 0.2);
  ASSERT_EQ(found.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const double delta = i == 0 ? 0.5 : 0.3, xc = i == 0 ? 20e-3 : 50e-3;
    const Stenosis& st = found[i];
    EXPECT_NEAR(st.s, xc, 0.51e-3) << i;
    // The throat: the sampled minimum, within the ripple of (1 − δ) r0; the shoulder within the ripple of r0.
    EXPECT_NEAR(st.throat_radius, (1.0 - delta) * r0, 0.011 * r0) << i;
    EXPECT_NEAR(st.reference_radius, r0, 0.011 * r0) << i;
    const double ratio = std::pow(st.reference_radius / st.throat_radius, 2);
    EXPECT_NEAR(st.area_reduction, 1.0 - 1.0 / ratio, 1e-14) << i;
    // K = K_t ρ / (2 A0²) (A0/As − 1)², written out.
    const double a0 = kPi * st.reference_radius * st.reference_radius;
    EXPECT_NEAR(st.coefficient, 1.52 * 1060.0 / (2.0 * a0 * a0) * (ratio - 1.0) * (ratio - 1.0), 1e-9 * st.coefficient);
    // Spread from the throat to where the lumen has widened 90% of the way to the shoulder: the distal half.
    double spread = 0.0;
    for (int seg : st.segments) spread += net.segment(seg).length;
    EXPECT_GT(spread, 2.5e-3) << i;
    EXPECT_LT(spread, 4.1e-3) << i;
  }
  EXPECT_GT(found[0].area_reduction, 0.73);
  EXPECT_LT(found[1].area_reduction, 0.53);
  // A higher threshold keeps the 75% one only; no threshold also counts the ripple's dips.
  EXPECT_EQ(find_stenoses(net, 1060.0, 0.6).size(), 1u);
  EXPECT_GT(find_stenoses(net, 1060.0, 0.0).size(), 10u);
  EXPECT_THROW((void)find_stenoses(net, 1060.0, 1.0), Error);
}

TEST(FlowLosses, AStenosedVesselsDropThroughASceneIsPoiseuillePlusYoungAndTsaisExpansionLoss) {
  const Network net = stenosed_vessel({{30e-3, 0.5}}, 0.0, false);
  const double q = 2e-6;  // 2 mL/s: U0 = 0.16 m/s, Re 190 in the vessel
  const auto scene = [&](const std::string& losses) {
    return config::load_config_text("flow:\n  inlet: {node: 0, flow: 2 mL/s}\n  outlets: {pressure: 0}\n" + losses,
                                    "stenosis.yaml", flow_schema());
  };
  const FlowSpec with = from_config(scene("  losses: {stenosis: young_tsai}\n"), net);
  const FlowSpec without = from_config(scene(""), net);
  ASSERT_EQ(with.stenoses.size(), 1u);
  EXPECT_TRUE(without.stenoses.empty());
  // Borda–Carnot's sudden expansion is the same law with K_t = 1; a K_t given replaces the model's.
  const FlowSpec borda = from_config(scene("  losses: {stenosis: borda_carnot}\n"), net);
  const FlowSpec given = from_config(scene("  losses: {stenosis: young_tsai, expansion_coefficient: 0.8}\n"), net);
  EXPECT_NEAR(borda.stenoses.at(0).coefficient, with.stenoses[0].coefficient / 1.52,
              1e-12 * borda.stenoses[0].coefficient);
  EXPECT_NEAR(given.stenoses.at(0).coefficient, with.stenoses[0].coefficient * 0.8 / 1.52,
              1e-12 * given.stenoses[0].coefficient);
  const auto s_with = make_solver(net, with);
  const auto s_without = make_solver(net, without);
  EXPECT_EQ(s_with->name(), "newton");
  // Poiseuille: the frusta in series.
  double poiseuille = 0.0;
  for (const auto& seg : net.segments()) poiseuille += segment_resistance(with.viscosity, seg) * q;
  // Young & Tsai: K_t ρ/2 (A0/As − 1)² U0², U0 = Q/A0, with the sampled throat (the minimum node) and r0.
  double rs = r0;
  for (const auto& seg : net.segments()) rs = std::min({rs, seg.radius_from, seg.radius_to});
  const double u0 = q / (kPi * r0 * r0);
  const double expansion = 1.52 * 1060.0 / 2.0 * std::pow(r0 * r0 / (rs * rs) - 1.0, 2) * u0 * u0;
  const std::vector<int> ends = net.ends();
  ASSERT_EQ(ends.size(), 2u);
  const int inlet = 0, outlet = ends[0] == 0 ? ends[1] : ends[0];
  ASSERT_TRUE(ends[0] == 0 || ends[1] == 0);
  ASSERT_NEAR(s_without->segment_flow(0), q, 1e-12 * q);
  EXPECT_NEAR(s_without->node_pressure(inlet) - s_without->node_pressure(outlet), poiseuille, 1e-9 * poiseuille);
  EXPECT_NEAR(s_with->node_pressure(inlet) - s_with->node_pressure(outlet), poiseuille + expansion,
              1e-8 * (poiseuille + expansion));
  // At this flow the expansion loss is about the whole viscous drop of the 80 mm vessel.
  EXPECT_GT(expansion, 0.5 * poiseuille);
  // The throat's pressure carries the whole loss: it is spread over the segments distal to it.
  const Stenosis& st = with.stenoses[0];
  EXPECT_NEAR(s_with->node_pressure(st.throat_node) - s_without->node_pressure(st.throat_node), expansion,
              1e-8 * expansion);
}

TEST(FlowLosses, TheRlcModelCarriesTheLossesWithSecondOrderInTime) {
  // A rigid stenosed vessel bent on a circle under a pulsatile pressure that reverses the flow:
  // one flow Q(t) through every segment, L Q̇ + Σ (R Q φ(De) + K|Q|Q) = Δp(t), against the periodic
  // solution of that ODE by RK4 at 50 µs (written here), the rlc model at 10 and 5 ms.
  const Network net = stenosed_vessel({{30e-3, 0.5}}, 0.0, false, 30e-3);  // bent on R = 30 mm as well
  const double period = 0.8, p1 = 300.0, p2 = -60.0;
  FlowSpec spec = default_spec(net, Waveform::sine(p1, p2, period));
  spec.model = Model::Rlc;
  spec.wall_youngs_modulus = 0.0;  // rigid: no compliance
  spec.periodic_tolerance = 1e-10;
  spec.stenoses = find_stenoses(net, spec.density, 0.2);
  ASSERT_EQ(spec.stenoses.size(), 1u);
  add_stenosis_losses(net, spec.stenoses, spec.segment_laws);
  ASSERT_EQ(add_curvature_losses(net, spec.density, spec.viscosity, spec.segment_laws), net.num_segments());
  const int inlet = spec.inlets[0].node;
  ASSERT_EQ(net.degree(inlet), 1);
  double l = 0.0;
  for (int s = 0; s < net.num_segments(); ++s) {
    const auto& seg = net.segment(s);
    l += spec.density * seg.length / (kPi * seg.radius_from * seg.radius_to);
  }
  const auto drop = [&](double q) {  // Σ over the segments of R Q φ(De) + K|Q|Q
    double sum = 0.0;
    for (int s = 0; s < net.num_segments(); ++s)
      sum += spec.segment_laws[static_cast<size_t>(s)].pressure_drop(
          q, segment_resistance(spec.viscosity, net.segment(s)));
    return sum;
  };
  // Δp(t) = (p1 − p2)/2 sin(2πt/T) + (p1 + p2)/2 from the inlet to the outlet at 0 Pa.
  const auto rhs = [&](double t, double q) {
    const double dp = (p1 - p2) / 2.0 * std::sin(2.0 * kPi * t / period) + (p1 + p2) / 2.0;
    return (dp - drop(q)) / l;
  };
  const int n_ref = 16000;  // 50 µs
  const double h = period / n_ref;
  double q = 0.0;
  std::vector<double> ref(static_cast<size_t>(n_ref) + 1);
  for (int cycle = 0; cycle < 12; ++cycle) {
    for (int i = 0; i < n_ref; ++i) {
      const double t = i * h;
      ref[static_cast<size_t>(i)] = q;
      const double k1 = rhs(t, q), k2 = rhs(t + h / 2, q + h / 2 * k1), k3 = rhs(t + h / 2, q + h / 2 * k2),
                   k4 = rhs(t + h, q + h * k3);
      q += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
  }
  ref.back() = q;
  double qmin = 0.0;
  for (double v : ref) qmin = std::min(qmin, v);
  ASSERT_LT(qmin, 0.0);  // the flow reverses
  std::vector<double> errors;
  for (const double dt : {0.01, 0.005}) {
    FlowSpec sp = spec;
    sp.dt = dt;
    const auto solver = make_solver(net, sp);
    EXPECT_EQ(solver->name(), "rlc");
    double worst = 0.0, scale = 0.0;
    const int steps = static_cast<int>(std::lround(period / dt));
    for (int i = 1; i <= steps; ++i) {
      solver->advance(i * dt);
      const double qr = ref[static_cast<size_t>(i * n_ref / steps)];
      worst = std::max(worst, std::abs(solver->segment_flow(0) - qr));
      scale = std::max(scale, std::abs(qr));
    }
    errors.push_back(worst / scale);
    std::printf("rlc with losses, dt %.3g s: largest flow error over a period %.3e of the largest flow\n", dt,
                worst / scale);
  }
  const double slope = std::log(errors[0] / errors[1]) / std::log(2.0);
  std::printf("order in time %.2f\n", slope);
  EXPECT_LT(errors[1], 2e-3);
  EXPECT_GT(slope, 1.7);
  EXPECT_LT(slope, 2.5);
}

TEST(FlowLosses, WhitesRatioIsContinuousAndItsSlopeAndTheCurvedLawsInverseAreExact) {
  EXPECT_DOUBLE_EQ(dean_resistance_ratio(5.0), 1.0);
  EXPECT_NEAR(dean_resistance_ratio(11.6 * (1.0 + 1e-9)), 1.0, 1e-12);  // continuous at the onset
  // Rises monotonically, about √De at large De (White's data: about 1.5 at De 100).
  double last = 1.0;
  for (double de = 12.0; de < 3000.0; de *= 1.3) {
    const double phi = dean_resistance_ratio(de);
    EXPECT_GT(phi, last) << de;
    last = phi;
    const double h = 1e-6 * de;
    const double fd = (dean_resistance_ratio(de + h) - dean_resistance_ratio(de - h)) / (2.0 * h);
    EXPECT_NEAR(dean_resistance_ratio_slope(de), fd, 1e-6 * std::abs(fd) + 1e-12) << de;
  }
  EXPECT_GT(dean_resistance_ratio(100.0), 1.45);
  EXPECT_LT(dean_resistance_ratio(100.0), 1.6);
  // A curved segment's flow is the root of its law, and its conductance the inverse slope.
  const SegmentLaw law{1.3, 2e9, 4e7};  // f, K, De per unit |Q| (De 40 at 1 mL/s)
  const double r = 5e7;
  for (const double dp : {-300.0, -2.0, -1e-4, 1e-4, 0.7, 25.0, 900.0}) {
    const double q = law.flow(dp, r);
    EXPECT_NEAR(law.pressure_drop(q, r), dp, 1e-12 * std::abs(dp)) << dp;
    const double h = 1e-6 * std::abs(dp);
    const double fd = (law.flow(dp + h, r) - law.flow(dp - h, r)) / (2.0 * h);
    EXPECT_NEAR(law.conductance(dp, r), fd, 1e-6 * std::abs(fd)) << dp;
  }
}

TEST(FlowLosses, ASampledArcsCurvatureConvergesToOneOverItsRadiusAtSecondOrder) {
  // A circle of radius R sampled at chords h: the turning angle over h is (1/R)(1 + θ²/24 + ...).
  const double bend = 25e-3;
  std::vector<double> errors;
  for (const double h : {2e-3, 1e-3, 0.5e-3}) {
    vessels::Centerlines c;
    vessels::Polyline p;
    p.name = "arc";
    const int n = static_cast<int>(std::lround(0.06 / h));
    for (int i = 0; i <= n; ++i) {
      const double s = i * h;
      p.points.emplace_back(bend * std::sin(s / bend), bend * (1.0 - std::cos(s / bend)), 0.0);
      p.radii.push_back(r0);
    }
    c.branches.push_back(p);
    vessels::BuildOptions opt;
    opt.max_segment_length = h;
    opt.max_chord_deviation = 1e-6;
    const Network net = Network::build(c, opt);
    double worst = 0.0;
    for (double k : segment_curvatures(net)) worst = std::max(worst, std::abs(k * bend - 1.0));
    errors.push_back(worst);
  }
  const double slope = std::log(errors[0] / errors[2]) / std::log(4.0);
  EXPECT_LT(errors[2], 1e-3);
  EXPECT_GT(slope, 1.8);
  EXPECT_LT(slope, 2.2);
  // A straight vessel has none.
  for (double k : segment_curvatures(stenosed_vessel({}, 0.0, false))) EXPECT_EQ(k, 0.0);
}

TEST(FlowLosses, ABentVesselsDropThroughASceneIsPoiseuilleTimesWhitesRatio) {
  const double bend = 20e-3;
  const Network net = stenosed_vessel({}, 0.0, false, bend);
  const FlowSpec spec =
      from_config(config::load_config_text("flow:\n  inlet: {node: 0, flow: 4 mL/s}\n  outlets: {pressure: 0}\n"
                                           "  losses: {curvature: white}\n",
                                           "bend.yaml", flow_schema()),
                  net);
  EXPECT_EQ(spec.curved_segments, net.num_segments());
  const auto solver = make_solver(net, spec);
  EXPECT_EQ(solver->name(), "newton");
  // Re = 2ρQ/(πaμ), De = Re √(a/R): written out here.
  const double q = 4e-6, re = 2.0 * 1060.0 * q / (kPi * r0 * 3.5e-3), de = re * std::sqrt(r0 / bend);
  const double poiseuille = 8.0 * 3.5e-3 * 80e-3 / (kPi * std::pow(r0, 4)) * q;
  const std::vector<int> ends = net.ends();
  const int outlet = ends[0] == 0 ? ends[1] : ends[0];
  const double got = solver->node_pressure(0) - solver->node_pressure(outlet);
  // The chords are 0.5 mm: their length is the arc's to 1e-5 and their curvature 1/R to 1e-4.
  EXPECT_NEAR(got, poiseuille * dean_resistance_ratio(de), 2e-4 * got);
  EXPECT_GT(got, 1.5 * poiseuille);  // De 122 at 4 mL/s (Re 386)
  EXPECT_GT(de, 120.0);
}

TEST(FlowLosses, AWomersleyProfileResamplesANonlinearPeriodOnlyWhenTheOcclusionMovesByOnePercent) {
  // A period of a nonlinear network is 128 Newton solves: a wire moving every step would resample
  // one every step. The harmonics follow an occlusion that moved by more than 1% since they were
  // sampled; the flow the profile carries is always the current one.
  const Network net = stenosed_vessel({}, 0.0, false, 20e-3);
  FlowSpec spec = default_spec(net, Waveform::sine(2000.0, 400.0, 0.8));
  spec.profile = Profile::Womersley;
  ASSERT_GT(add_curvature_losses(net, spec.density, spec.viscosity, spec.segment_laws), 0);
  const auto lagged = make_solver(net, spec);
  ASSERT_EQ(lagged->name(), "newton");
  std::vector<SegmentOcclusion> occ(static_cast<size_t>(net.num_segments()));
  const auto occlude = [&](FlowSolver& solver, double factor) {
    for (int s = 40; s < 60; ++s) occ[static_cast<size_t>(s)].resistance_factor = factor;
    solver.set_occlusion(occ);
  };
  occlude(*lagged, 1.004);
  EXPECT_EQ(lagged->timings().harmonic_updates, 1);
  occlude(*lagged, 1.009);  // 0.5% from the sampled 1.004: kept
  EXPECT_EQ(lagged->timings().harmonic_updates, 1);
  EXPECT_EQ(lagged->timings().occlusion_updates, 2);
  const auto fresh = make_solver(net, spec);
  occlude(*fresh, 1.009);
  // Velocities on the axis and off it over a beat: the lagged harmonics within 0.2% of the fresh.
  const int seg = 50;
  const Vec3 centre = 0.5 * (net.node(net.segment(seg).node_from) + net.node(net.segment(seg).node_to));
  double worst = 0.0, scale = 0.0;
  for (int i = 0; i < 16; ++i) {
    const double t = 0.05 * i;
    lagged->advance(t);
    fresh->advance(t);
    EXPECT_NEAR(lagged->segment_flow(seg), fresh->segment_flow(seg), 1e-9 * std::abs(fresh->segment_flow(seg)));
    for (const double off : {0.0, 0.5e-3, 1.5e-3}) {
      const Vec3 p = centre + Vec3(0.0, 0.0, off);
      worst = std::max(worst, std::abs(lagged->axial_velocity_at(seg, p, t) - fresh->axial_velocity_at(seg, p, t)));
      scale = std::max(scale, std::abs(fresh->axial_velocity_at(seg, p, t)));
    }
  }
  EXPECT_LT(worst, 2e-3 * scale);
  EXPECT_GT(worst, 0.0);   // the harmonics did lag
  occlude(*lagged, 1.03);  // 2% beyond: resampled
  EXPECT_EQ(lagged->timings().harmonic_updates, 2);
}

/// Shah's correlation as he printed it: the apparent Fanning friction factor times Re at x⁺.
double shah_fapp_re(double x) {
  return 3.44 / std::sqrt(x) + (1.25 / (4.0 * x) + 16.0 - 3.44 / std::sqrt(x)) / (1.0 + 0.00021 / (x * x));
}

TEST(FlowLosses, ShahsIncrementalDropIsHisCorrelationLessPoiseuilleAndItsSlopeIsExact) {
  EXPECT_EQ(shah_incremental_drop(0.0), 0.0);
  EXPECT_EQ(shah_incremental_drop(std::numeric_limits<double>::infinity()), 1.25);
  double last = 0.0;
  for (double x = 1e-7; x < 1e3; x *= 1.2) {
    // The drop over ½ρū² is 4 f_app Re x⁺, Poiseuille's 64 x⁺: the code's rearranged form against
    // the printed one (whose large terms cancel far downstream: compared where they do not).
    const double k = shah_incremental_drop(x);
    if (x < 10.0) {
      EXPECT_NEAR(k, 4.0 * shah_fapp_re(x) * x - 64.0 * x, 1e-12 * (1.0 + 64.0 * x)) << x;
    }
    EXPECT_GT(k, last) << x;  // increasing: every segment after an entrance adds a positive drop
    EXPECT_LT(k, 1.25) << x;
    last = k;
    const double h = 1e-6 * x;
    const double fd = (shah_incremental_drop(x + h) - shah_incremental_drop(x - h)) / (2.0 * h);
    EXPECT_NEAR(shah_incremental_drop_slope(x), fd, 1e-6 * std::abs(fd) + 1e-15 / h) << x;  // K's round-off / h
  }
  // Developed flow: from x⁺ = 0.1 on, the apparent friction is that of Poiseuille's profile plus
  // K(∞) = 1.25 to 1% (the correlation's own tail, K − 1.25 ≈ −0.0134/x⁺, is within its ±2.4%).
  for (const double x : {0.1, 0.3, 1.0, 10.0}) EXPECT_NEAR(shah_fapp_re(x) / (16.0 + 1.25 / (4.0 * x)), 1.0, 0.01) << x;
  EXPECT_NEAR(shah_incremental_drop(100.0), 1.25, 2e-4);
  EXPECT_LT(shah_incremental_drop(0.01), 0.95);
}

TEST(FlowLosses, ADevelopingSegmentsLawHasTheExactSlopeAndInverseInBothDirections) {
  SegmentLaw first{1.0, 0.0, 0.0};  // from the entrance itself
  first.entry = 1060.0 / (2.0 * std::pow(kPi * r0 * r0, 2));
  const double per_length = 3.5e-3 * kPi / (4.0 * 1060.0);
  first.entry_forward = {0.0, 2e-3 * per_length};
  first.entry_backward = {30e-3 * per_length, 32e-3 * per_length};
  SegmentLaw later{1.3, 2e9, 4e7};  // with a quadratic term and a bend
  later.entry = first.entry;
  later.entry_forward = {12e-3 * per_length, 14e-3 * per_length};
  const double r = 8.0 * 3.5e-3 * 2e-3 / (kPi * std::pow(r0, 4));
  for (const SegmentLaw& law : {first, later}) {
    ASSERT_TRUE(law.nonlinear());
    for (double q = -20e-6; q <= 20e-6; q += 0.37e-6) {
      const double h = 1e-6 * std::max(std::abs(q), 1e-7);
      const double fd = (law.pressure_drop(q + h, r) - law.pressure_drop(q - h, r)) / (2.0 * h);
      EXPECT_NEAR(law.slope(q, r), fd, 1e-6 * std::abs(fd)) << q;
      EXPECT_GT(law.slope(q, r), 0.0) << q;
      const double dp = law.pressure_drop(q, r);
      EXPECT_NEAR(law.flow(dp, r), q, 1e-12 * std::abs(q) + 1e-20) << q;
      EXPECT_GE(law.entrance_drop(q) * q, 0.0) << q;  // never a gain
    }
  }
  // The excess tends to zero with the flow (Poiseuille's law at small Re) and, for the first
  // segment, to K(x⁺) ½ρū² at its far end.
  const double q = 8e-6;
  EXPECT_NEAR(first.entrance_drop(q), first.entry * q * q * shah_incremental_drop(2e-3 * per_length / q), 1e-12);
  EXPECT_LT(std::abs(later.entrance_drop(1e-9)), 1e-6 * later.pressure_drop(1e-9, r));
  EXPECT_EQ(later.entrance_drop(-q), 0.0);  // no entrance at its far end
}

TEST(FlowLosses, AVesselEnteredFlatLosesPoiseuillePlusShahsIncrementalDropThroughAScene) {
  const Network net = stenosed_vessel({}, 0.0, false);  // 80 mm, r 2 mm, 160 segments
  for (const std::string profile : {"flat", "developed"}) {
    const FlowSpec spec =
        from_config(config::load_config_text("flow:\n  inlet: {node: 0, flow: 4 mL/s}\n  outlets: {pressure: 0}\n"
                                             "  losses: {entrance: shah, inlet_profile: " +
                                                 profile + "}\n",
                                             "tube.yaml", flow_schema()),
                    net);
    const auto solver = make_solver(net, spec);
    // Written out here: U = Q/A, Re = ρUD/μ, x⁺ = L/(D Re).
    const double q = 4e-6, u = q / (kPi * r0 * r0), re = 1060.0 * u * 2.0 * r0 / 3.5e-3;
    const double xl = 80e-3 / (2.0 * r0 * re);
    const double poiseuille = 8.0 * 3.5e-3 * 80e-3 / (kPi * std::pow(r0, 4)) * q;
    const double shah = (4.0 * shah_fapp_re(xl) * xl - 64.0 * xl) * 0.5 * 1060.0 * u * u;
    const std::vector<int> ends = net.ends();
    const int outlet = ends[0] == 0 ? ends[1] : ends[0];
    const double got = solver->node_pressure(0) - solver->node_pressure(outlet);
    if (profile == "flat") {
      EXPECT_EQ(spec.entrances, 1);
      EXPECT_EQ(solver->name(), "newton");
      EXPECT_NEAR(got, poiseuille + shah, 1e-9 * got);
      EXPECT_GT(shah, 0.3 * poiseuille);  // Re 386: the entrance is a third of an 80 mm vessel's drop
    } else {
      EXPECT_EQ(spec.entrances, 0);  // one branch, no junction: nothing develops
      EXPECT_NEAR(got, poiseuille, 1e-9 * got);
    }
  }
}

/// An asymmetric Y of straight branches, parent radius 4 mm (Re about 1000 at 20 mL/s).
Network wide_y() {
  vessels::YBifurcationParams yp;
  yp.parent_radius = 4e-3;
  yp.asymmetry = 0.4;
  return Network::build(vessels::y_bifurcation(yp));
}

/// A solver for @p net with the scene's `flow:` section @p flow (its body, indented).
std::unique_ptr<FlowSolver> solver_from(const Network& net, const std::string& flow) {
  return make_solver(net, from_config(config::load_config_text("flow:\n" + flow, "y.yaml", flow_schema()), net));
}

TEST(FlowLosses, EveryBranchLeavingAJunctionDevelopsAgainAndTheFlowSplitFollows) {
  const Network net = wide_y();
  auto solve = [&](const std::string& losses) {
    const std::string flow = "  inlet: {flow: 20 mL/s}\n  outlets: {pressure: 0}\n" + losses;
    const FlowSpec spec = from_config(config::load_config_text("flow:\n" + flow, "y.yaml", flow_schema()), net);
    return std::make_pair(spec.entrances, solver_from(net, flow));
  };
  const auto [none, plain] = solve("");
  const auto [three, shah] = solve("  losses: {entrance: shah}\n");
  EXPECT_EQ(none, 0);
  EXPECT_EQ(three, 3);  // the junction's three branch ends (the parent's for a flow reversed into it)
  // Every segment's flow satisfies its law.
  for (int s = 0; s < net.num_segments(); ++s) {
    const auto& seg = net.segment(s);
    const double dp = shah->node_pressure(seg.node_from) - shah->node_pressure(seg.node_to);
    EXPECT_NEAR(
        shah->spec().segment_laws[static_cast<size_t>(s)].pressure_drop(shah->segment_flow(s), shah->resistance(s)), dp,
        1e-8 * std::abs(dp) + 1e-12)
        << s;
  }
  // The entrance's excess over Poiseuille's drop is ρQK/(16πμL) of it: larger in the daughter that
  // carries more flow, which therefore takes less than Poiseuille's law gives it.
  const std::vector<int> ends = net.ends();
  std::vector<std::pair<double, double>> outlets;  // (Poiseuille, with the entrance)
  for (int e : ends) {
    if (e == net.widest_end()) continue;
    const auto [b, end] = net.node_segments(e);
    outlets.emplace_back(std::abs(plain->segment_flow(*b)), std::abs(shah->segment_flow(*b)));
  }
  ASSERT_EQ(outlets.size(), 2u);
  std::sort(outlets.begin(), outlets.end());
  EXPECT_GT(outlets[0].second, outlets[0].first);
  EXPECT_LT(outlets[1].second, outlets[1].first);
  EXPECT_NEAR(outlets[0].second + outlets[1].second, 20e-6, 1e-15);
  EXPECT_GT(shah->node_pressure(net.widest_end()), 1.2 * plain->node_pressure(net.widest_end()));
}

TEST(FlowLosses, TheRlcModelsSteadyStateWithTheEntranceIsTheQuasiSteadyNetworks) {
  // The rlc model carries the entrance law in its nonlinear block: under a constant inlet flow its
  // state settles on the quasi-steady network's solution (Newton on the node balances).
  const Network net = wide_y();
  auto solver_for = [&](const std::string& model) {
    return solver_from(net, "  model: " + model +
                                "\n  inlet: {flow: 20 mL/s}\n  outlets: {pressure: 0}\n  losses: {entrance: shah}\n");
  };
  const auto quasi = solver_for("poiseuille");
  const auto rlc = solver_for("rlc");
  rlc->advance(2.0);
  const int inlet = net.widest_end();
  EXPECT_NEAR(rlc->node_pressure(inlet), quasi->node_pressure(inlet), 1e-6 * quasi->node_pressure(inlet));
  for (int s = 0; s < net.num_segments(); ++s)
    EXPECT_NEAR(rlc->segment_flow(s), quasi->segment_flow(s), 1e-6 * 20e-6) << s;
}

TEST(FlowLosses, BadLossKeysAreRefusedNamingTheKey) {
  const Network net = stenosed_vessel({{30e-3, 0.5}}, 0.0, false);
  for (const auto& [text, fragment] : std::vector<std::pair<std::string, std::string>>{
           {"  losses: {stenosis: yes}\n", "flow.losses.stenosis"},
           {"  losses: {stenosis: young_tsai, stenosis_threshold: 1.0}\n", "flow.losses.stenosis_threshold"},
           {"  losses: {stenosis: young_tsai, expansion_coefficient: -1}\n", "flow.losses.expansion_coefficient"},
           {"  losses: {curvature: dean}\n", "flow.losses.curvature"},
           {"  losses: {junctions: mynard}\n", "flow.losses.junctions"},
           {"  losses: {entrance: langhaar}\n", "flow.losses.entrance"},
           {"  losses: {entrance: shah, inlet_profile: plug}\n", "flow.losses.inlet_profile"}}) {
    try {
      (void)from_config(config::load_config_text("flow:\n  outlets: {pressure: 0}\n" + text, "s.yaml", flow_schema()),
                        net);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("s.yaml"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace flowire::flow
