// Curvature-adaptive resampling: the refined rod is more accurate per vertex than the
// uniform one against analytic references (elastica, exact J-tip geometry) and against a
// fine uniform run (free vibration); resampling keeps the material, the energy and the
// feeding consistent.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "flowire/rod/simulator.hpp"
#include "flowire_test.hpp"
#include "rod_test_util.hpp"

namespace flowire::rod {
namespace {

WireSpec adaptive(WireSpec spec) {
  spec.adapt.enabled = true;
  return spec;
}

double free_rest_length(const RodSimulator& sim) {
  double l = 0.0;
  for (int j = 0; j < sim.first_clamped_vertex(); ++j) l += sim.discretization().rest_length[j];
  return l;
}

struct TipResult {
  Eigen::Vector2d tip;
  int vertices;
};

TipResult elastica_tip(const WireSpec& spec, double alpha) {
  RodSimulator sim(spec);
  sim.set_tip_force({0.0, alpha, 0.0});
  sim.settings().static_load_steps = 2;
  const StepReport r = sim.solve_static();
  EXPECT_TRUE(r.converged()) << to_string(r.status);
  return {{sim.tip_position().x(), sim.tip_position().y()}, sim.vertex_count()};
}

TEST(RodAdapt, ElasticaRefinedWhereBentBeatsUniformPerVertex) {
  // Bisshopp–Drucker α = 5 (shared reference table): δ/L = 0.71379, (L − x)/L = 0.38763.
  const Eigen::Vector2d ref{1.0 - 0.38763, 0.71379};
  const TipResult coarse = elastica_tip(unit_rod_spec(10), 5.0);
  const TipResult fine = elastica_tip(unit_rod_spec(40), 5.0);
  const TipResult adapt = elastica_tip(adaptive(unit_rod_spec(10)), 5.0);
  const double e_coarse = (coarse.tip - ref).norm();
  const double e_fine = (fine.tip - ref).norm();
  const double e_adapt = (adapt.tip - ref).norm();
  RecordProperty("error_uniform10", std::to_string(e_coarse));
  RecordProperty("error_uniform40", std::to_string(e_fine));
  RecordProperty("error_adaptive", std::to_string(e_adapt));
  std::printf("elastica a=5: uniform 10: %.3e (%d v), uniform 40: %.3e (%d v), adaptive: %.3e (%d v)\n", e_coarse,
              coarse.vertices, e_fine, fine.vertices, e_adapt, adapt.vertices);
  EXPECT_LT(e_adapt, 0.2 * e_coarse);
  EXPECT_LT(adapt.vertices, fine.vertices);
  // The reference error times vertices² (the O(h²) work measure) is smaller adaptively.
  EXPECT_LT(e_adapt * adapt.vertices * adapt.vertices, e_fine * fine.vertices * fine.vertices);
}

TEST(RodAdapt, ResamplingKeepsTheMaterial) {
  WireSpec spec = adaptive(unit_rod_spec(10));
  RodSimulator sim(spec);
  sim.set_tip_force({0.0, 5.0, 0.0});
  sim.settings().static_load_steps = 2;
  ASSERT_TRUE(sim.solve_static().converged());
  EXPECT_GT(sim.adapt_splits(), 0);
  // The free rest lengths still add up to the inserted length, masses to ρA times the
  // simulated length, and every rest length is a dyadic multiple of the grid.
  EXPECT_NEAR(free_rest_length(sim), 1.0, 1e-12);
  double mass = 0.0, rest = 0.0;
  for (int k = 0; k < sim.vertex_count(); ++k) mass += sim.discretization().mass[k];
  for (double l : sim.discretization().rest_length) {
    rest += l;
    const double levels = std::log2(0.1 / l);
    EXPECT_NEAR(levels, std::round(levels), 1e-9);
    EXPECT_GE(l, 0.025 - 1e-12);
    EXPECT_LE(l, 0.4 + 1e-12);
  }
  EXPECT_NEAR(mass, rest * 1.0, 1e-12);
  // Neighbouring rest lengths of the free part within a factor 2 (the clamped stub behind
  // the entry is a rigid grid edge).
  const auto& l = sim.discretization().rest_length;
  for (size_t j = 1; j < static_cast<size_t>(sim.first_clamped_vertex()); ++j)
    EXPECT_LE(std::max(l[j] / l[j - 1], l[j - 1] / l[j]), 2.0 + 1e-9) << j << " of " << l.size();
}

/// A J tip with a straight distal piece: the exact shape is a straight shaft, a half
/// circle of radius R and a straight piece of length `offset`.
WireSpec j_tip(double h) {
  WireSpec spec;
  spec.length = 0.1;
  spec.segment_length = h;
  spec.radius = 3e-4;
  spec.youngs_modulus = 60e9;
  spec.tip.length = 0.03;
  spec.tip.youngs_modulus = 10e9;
  spec.tip.shape = TipShape::J;
  spec.tip.bend_radius = 0.003;
  spec.tip.bend_offset = 0.0025;
  spec.base_normal = Eigen::Vector3d::UnitZ();
  return spec;
}

double j_tip_error(const RodSimulator& sim) {
  const double R = 0.003, offset = 0.0025, L = 0.1;
  const double arc_end = offset + std::numbers::pi * R;
  // Along the insertion direction (x): L − arc_end forward, back by offset; across: 2R.
  const Eigen::Vector3d tip = sim.tip_position();
  return std::hypot(tip.x() - (L - arc_end - offset), std::hypot(tip.y(), tip.z()) - 2.0 * R);
}

TEST(RodAdapt, JTipShapeConvergesWithRefinement) {
  RodSimulator uniform(j_tip(1e-3));
  RodSimulator uniform_fine(j_tip(0.25e-3));
  RodSimulator refined(adaptive(j_tip(1e-3)));
  const double e_u = j_tip_error(uniform), e_f = j_tip_error(uniform_fine), e_a = j_tip_error(refined);
  std::printf("J tip: uniform 1 mm %.3e m (%d v), 0.25 mm %.3e m (%d v), adaptive %.3e m (%d v)\n", e_u,
              uniform.vertex_count(), e_f, uniform_fine.vertex_count(), e_a, refined.vertex_count());
  // The arc is resolved at the finest level: as accurate as the fine uniform wire.
  EXPECT_LT(e_a, 1.5 * e_f + 1e-9);
  EXPECT_LT(e_a, 0.25 * e_u);
  EXPECT_LT(refined.vertex_count(), uniform_fine.vertex_count() / 2);
  // The refined rest shape is stress free too.
  EXPECT_LT(refined.energy().total(), 1e-15);
}

/// Free vibration of the unit cantilever released from its static deflection under a tip
/// load: tip trajectory over about one period with the energy-conserving integrator.
struct Swing {
  std::vector<Eigen::Vector3d> tip;
  double energy_drift = 0.0;
  int vertices = 0;
};

Swing swing(WireSpec spec) {
  RodSimulator sim(spec);
  sim.set_tip_force({0.0, 3.0, 0.0});
  sim.settings().static_load_steps = 2;
  EXPECT_TRUE(sim.solve_static().converged());
  sim.set_tip_force(Eigen::Vector3d::Zero());
  sim.set_integrator(Integrator::ImplicitMidpoint);
  Swing out;
  const double e0 = sim.energy().total();
  for (int i = 0; i < 200; ++i) {
    const StepReport r = sim.step(2e-3);
    EXPECT_TRUE(r.converged()) << i;
    out.tip.push_back(sim.tip_position());
    out.energy_drift = std::max(out.energy_drift, std::abs(sim.energy().total() / e0 - 1.0));
    out.vertices = std::max(out.vertices, sim.vertex_count());
  }
  return out;
}

double trajectory_error(const Swing& a, const Swing& ref) {
  double e = 0.0;
  for (size_t i = 0; i < a.tip.size(); ++i) e = std::max(e, (a.tip[i] - ref.tip[i]).norm());
  return e;
}

TEST(RodAdapt, FreeVibrationFollowsTheFineRunAndKeepsTheEnergy) {
  const Swing ref = swing(unit_rod_spec(80));
  const Swing coarse = swing(unit_rod_spec(10));
  const Swing adapt = swing(adaptive(unit_rod_spec(10)));
  const double e_c = trajectory_error(coarse, ref), e_a = trajectory_error(adapt, ref);
  std::printf("swing: uniform 10 %.3e, adaptive %.3e (max %d v); energy drift uniform %.2e adaptive %.2e\n", e_c, e_a,
              adapt.vertices, coarse.energy_drift, adapt.energy_drift);
  // Refining the bent part near the clamp helps the trajectory; the resampling (splits
  // as it bends, merges only where that does not change the kinetic energy) adds no
  // energy beyond the integrator's own error.
  EXPECT_LT(e_a, 0.85 * e_c);
  EXPECT_LT(adapt.energy_drift, 2.0 * coarse.energy_drift + 1e-4);
}

TEST(RodAdapt, FeedingInAndOutKeepsTheGridAtTheClampAndTheLength) {
  WireSpec spec = j_tip(1e-3);
  spec.length = 0.2;
  spec.inserted_length = 0.02;
  spec.damping = 1e-3;
  RodSimulator plain(spec);
  RodSimulator refined(adaptive(spec));
  double max_diff = 0.0, max_drift = 0.0;
  for (RodSimulator* sim : {&plain, &refined}) sim->set_gravity({0.0, 0.0, -9.81});
  // In to 4 cm, then back to 6 mm: the refined J arc is pulled into the clamp.
  for (int i = 0; i < 540; ++i) {
    const double speed = i < 200 ? 0.1 : -0.1;
    for (RodSimulator* sim : {&plain, &refined}) {
      sim->set_insertion_speed(speed);
      ASSERT_TRUE(sim->step(1e-3).converged()) << i;
    }
    max_diff = std::max(max_diff, (plain.tip_position() - refined.tip_position()).norm());
    max_drift = std::max(max_drift, refined.length_drift());
    // The boundary vertex is the material at the entry, the one behind it a segment further;
    // the boundary edge is within [ℓ/2, 3ℓ/2) of the edge before it, ℓ a dyadic level.
    const auto u = refined.material_coordinates();
    const int fc = refined.first_clamped_vertex();
    EXPECT_NEAR(u[fc], refined.inserted_length(), 1e-15);
    EXPECT_NEAR(u[fc + 1] - u[fc], 1e-3, 1e-12);
    const double l = u[fc - 1] - u[fc - 2], b = u[fc] - u[fc - 1];
    EXPECT_NEAR(std::log2(1e-3 / l), std::round(std::log2(1e-3 / l)), 1e-9) << i;
    EXPECT_GE(b, 0.5 * l - 1e-12) << i;
    EXPECT_LT(b, 1.5 * l + 1e-12) << i;
  }
  std::printf("feeding: max tip difference %.3e m, max length drift %.2e, splits %ld merges %ld\n", max_diff, max_drift,
              refined.adapt_splits(), refined.adapt_merges());
  EXPECT_GT(refined.adapt_splits(), 0);
  EXPECT_GT(refined.adapt_merges(), 0);
  EXPECT_LT(max_drift, 1e-3);
  EXPECT_LT(max_diff, 1e-3);  // the same wire: the J tip is resolved better, not moved
  EXPECT_NEAR(refined.inserted_length(), 0.006, 1e-9);
}

}  // namespace
}  // namespace flowire::rod

namespace flowire::rod {
namespace {

TEST(RodFeeding, ForceLimitHoldsTheFeedAgainstALargerResistance) {
  // A guidewire fed at 2 cm/s against a dead tip load opposing the feed, with a 0.2 N force
  // limit: below the limit it is fed the whole way; above it the feed holds as soon as
  // the clamp pushes harder than the limit, which then carries the load statically.
  for (const double load : {0.05, 0.5}) {
    WireSpec spec;
    spec.length = 0.4;
    spec.segment_length = 4e-3;
    spec.radius = 3e-4;
    spec.youngs_modulus = 60e9;
    spec.tip.length = 0.0;
    spec.inserted_length = 0.2;
    spec.damping = 0.05;
    RodSimulator sim(spec);
    sim.set_max_insertion_force(0.2);
    sim.set_tip_force({-load, 0.0, 0.0});
    sim.set_insertion_speed(0.02);
    for (int i = 0; i < 1000; ++i) ASSERT_TRUE(sim.step(1e-3).converged()) << i;
    if (load < 0.2) {
      EXPECT_EQ(sim.held_steps(), 0);
      EXPECT_NEAR(sim.inserted_length(), 0.22, 1e-9);
      EXPECT_NEAR(sim.base_force().x(), load, 0.1 * load);
    } else {
      EXPECT_GT(sim.held_steps(), 900);
      EXPECT_LT(sim.inserted_length(), 0.202);
      EXPECT_NEAR(sim.base_force().x(), load, 0.02 * load);
    }
  }
}

}  // namespace
}  // namespace flowire::rod
