// BloodDrag: at a step's first evaluation the drag law itself; at the step's later iterates
// the law linearized in the wire velocity at that guess, whose error against the law shrinks
// as the square of the velocity change (slope 2) and whose velocity Jacobian is the one it
// adds; a new solve evaluates the law again; shielded vertices feel nothing.
#include "flowire/coupling/blood_drag.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "flowire/vessels/generators.hpp"
#include "flowire_test.hpp"

using namespace flowire;
using namespace flowire::coupling;
using vessels::Vec3;

namespace {

struct TubeFlow {
  vessels::Network net =
      vessels::Network::build(vessels::straight_tube({.length = 0.1, .radius = 3e-3}), {.max_segment_length = 5e-3});
  vessels::SpatialIndex index{net};
  WireLocation where{index};
  std::vector<Vec3> x;
  std::vector<double> arc;
  TubeFlow() {
    // Across the tube and off its axis: the confined cylinder law's cross-flow branch.
    for (int i = 0; i < 8; ++i) x.emplace_back(0.05 + 0.3e-3 * i, -1e-3 + 0.25e-3 * i, 0.4e-3);
    for (int i = 0; i < 8; ++i) arc.push_back(1e-3 * (8 - i));
  }
  rod::ForceAccumulator drag(BloodDrag& d, const std::vector<Vec3>& v, long serial,
                             std::vector<Vec3>* tally = nullptr) {
    rod::RodView r;
    r.positions = x;
    r.velocities = v;
    r.arc_length = arc;
    r.first_clamped_vertex = static_cast<int>(x.size());
    r.time = 1.0;
    r.dt = 1e-2;
    r.solve_serial = serial;
    InteractionStats s;
    where.locate(r, r.vertex_count(), s);
    rod::ForceAccumulator acc;
    acc.reset(r.vertex_count());
    std::vector<Vec3> own(x.size(), Vec3::Zero());
    d.evaluate(r, r.vertex_count(), where, acc, tally ? *tally : own, s);
    return acc;
  }
};

VelocityField blood() {
  return [](int, const Vec3& p) { return Vec3(0.3 + 10.0 * p.y(), 0.05, 0.0); };
}

}  // namespace

TEST(BloodDrag, ALaterIterateOfTheStepTakesTheLawLinearizedAtTheGuessWithASecondOrderError) {
  TubeFlow tube;
  const double a = 0.2e-3;
  BloodDrag once({.law = DragLaw::Cylinder}, a, blood());
  BloodDrag every({.law = DragLaw::Cylinder, .once_per_step = false}, a, blood());
  std::vector<Vec3> v0(tube.x.size());
  for (size_t i = 0; i < v0.size(); ++i) v0[i] = Vec3(0.01 * static_cast<double>(i), -0.02, 0.005);
  const auto guess = tube.drag(once, v0, 1);
  const auto law0 = tube.drag(every, v0, 1);
  for (size_t i = 0; i < v0.size(); ++i) {
    ASSERT_GT(law0.forces()[i].norm(), 0.0);
    EXPECT_EQ(guess.forces()[i], law0.forces()[i]);  // the step's first evaluation: the law
    EXPECT_EQ(guess.velocity_jacobians()[i], law0.velocity_jacobians()[i]);
  }
  std::vector<double> dv, err;
  for (double s : {0.04, 0.02, 0.01, 0.005}) {
    std::vector<Vec3> v = v0;
    for (auto& vi : v) vi += s * Vec3(0.6, -0.3, 0.75);
    const auto lin = tube.drag(once, v, 1);
    const auto law = tube.drag(every, v, 1);
    double e = 0.0;
    for (size_t i = 0; i < v.size(); ++i) {
      // Exactly linear in v, with the Jacobian it reports.
      EXPECT_LT((lin.forces()[i] - guess.forces()[i] - guess.velocity_jacobians()[i] * (v[i] - v0[i])).norm(),
                1e-15 + 1e-12 * lin.forces()[i].norm());
      EXPECT_EQ(lin.velocity_jacobians()[i], guess.velocity_jacobians()[i]);
      e = std::max(e, (lin.forces()[i] - law.forces()[i]).norm() / law.forces()[i].norm());
    }
    dv.push_back(s);
    err.push_back(e);
  }
  EXPECT_NEAR(flowire::testing::loglog_slope(dv, err), 2.0, 0.15);
  // A new solve (a step begun or taken again) evaluates the law anew.
  std::vector<Vec3> v = v0;
  for (auto& vi : v) vi += Vec3(0.01, 0.0, 0.0);
  const auto fresh = tube.drag(once, v, 2);
  const auto law = tube.drag(every, v, 2);
  for (size_t i = 0; i < v.size(); ++i) EXPECT_EQ(fresh.forces()[i], law.forces()[i]);
}

TEST(BloodDrag, AShieldedVertexFeelsNoBloodAndTheTallyIsEachVertexsDrag) {
  TubeFlow tube;
  BloodDrag drag({.law = DragLaw::Cylinder}, 0.2e-3, blood());
  std::vector<char> shielded(tube.x.size(), 0);
  shielded[2] = shielded[5] = 1;
  drag.set_shielded(shielded);
  std::vector<Vec3> v(tube.x.size(), Vec3::Zero());
  std::vector<Vec3> tally(tube.x.size(), Vec3::Constant(7.0));
  const auto acc = tube.drag(drag, v, 1, &tally);
  for (size_t i = 0; i < v.size(); ++i) {
    if (shielded[i]) {
      EXPECT_EQ(acc.forces()[i], Vec3::Zero());
      EXPECT_EQ(drag.fluid_velocity()[i], Vec3::Zero());
      EXPECT_EQ(tally[i], Vec3::Constant(7.0));  // untouched: the caller's to set
    } else {
      EXPECT_GT(acc.forces()[i].norm(), 0.0);
      EXPECT_EQ(tally[i], acc.forces()[i]);
      EXPECT_EQ(drag.fluid_velocity()[i], blood()(0, tube.x[i]));
    }
  }
  EXPECT_FALSE(BloodDrag({.law = DragLaw::None}, 0.2e-3, blood()).active());
  EXPECT_FALSE(BloodDrag({.law = DragLaw::Cylinder}, 0.2e-3, {}).active());
}
