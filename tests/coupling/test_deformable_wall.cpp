// A wire pressed against a wall that yields (coupling/src/deformable_wall.cpp and the
// compliant branch of wall_contact.cpp): the static equilibrium of a cantilevered wire pushed
// by a tip load onto the wall of a straight vessel, against the same wire on the rigid wall,
// against a full (nonlinear) solve of the wall under the wire's final forces, and in the limit
// of a stiff wall; the forces on the wall are the opposites of those on the wire.
#include "flowire/coupling/deformable_wall.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "flowire/common/element.hpp"
#include "flowire/common/error.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/coupling/vessel_forces.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire/solid/elastic_solid.hpp"
#include "flowire/solid/lumen_compliance.hpp"
#include "flowire/solid/tube_wall.hpp"
#include "flowire/vessels/generators.hpp"
#include "flowire_test.hpp"
#include "scene_config_test.hpp"

namespace flowire::coupling {
namespace {

constexpr double kR = 2e-3, kLength = 30e-3, kThickness = 0.5e-3;

struct Pressed {
  std::vector<Vec3> positions;
  std::vector<Vec3> contact_force;  ///< the wall's force on each vertex
  bool converged = false;
  int newton = 0;
};

/// The wire of every case here: 25 mm long, clamped at x = 28 mm (on the axis, or 0.3 mm from
/// the wall at y = R − 0.3 mm) and fed towards x = 3 mm, no friction, no drag, against the
/// rigid wall or @p wall.
struct Rig {
  std::unique_ptr<vessels::SpatialIndex> index;
  std::unique_ptr<rod::RodSimulator> sim;
  std::shared_ptr<VesselForces> forces;
  Rig(const vessels::Network& net, CompliantWall* wall, double base_y = 0.0) {
    rod::WireSpec spec;
    spec.length = 25e-3;
    spec.radius = 0.2e-3;
    spec.youngs_modulus = 60e9;
    spec.segments = 50;
    spec.inserted_length = spec.length;
    spec.tip.length = 0.0;
    spec.base_position = Vec3(28e-3, base_y, 0);
    spec.base_direction = -Vec3::UnitX();
    spec.base_normal = Vec3::UnitZ();
    sim = std::make_unique<rod::RodSimulator>(spec);
    index = std::make_unique<vessels::SpatialIndex>(net, 4);
    ContactParams contact;
    contact.stiffness = 3e4;
    contact.friction = 0.0;
    contact.tip_friction = 0.0;
    DragModel drag;
    drag.law = DragLaw::None;
    forces = std::make_shared<VesselForces>(*index, spec.radius, contact, drag);
    if (wall) forces->set_deformable(wall);
    sim->add_external(forces);
  }
};

/// A 50 mN tip load towards +y: without a wall the tip would move 3.5 mm sideways, the lumen
/// leaves it 1.8 mm. With @p lying, the wire clamped near the wall and a body load of 10 N/m
/// towards it instead (gravity ×1000): it lies along the wall with many contacts, each moving
/// the wall under the others.
Pressed press(const vessels::Network& net, CompliantWall* wall, bool lying = false) {
  Rig rig(net, wall, lying ? kR - 0.3e-3 : 0.0);
  rod::RodSimulator& sim = *rig.sim;
  const auto& forces = rig.forces;
  if (lying) {
    sim.set_gravity({0.0, 9810.0, 0.0});
  } else {
    sim.set_tip_force({0.0, 0.05, 0.0});
  }
  const rod::StepReport rep = sim.solve_static();
  Pressed p;
  p.converged = rep.converged();
  p.newton = rep.newton_iterations;
  p.positions.assign(sim.positions().begin(), sim.positions().end());
  p.contact_force = forces->contact_force();
  p.contact_force.resize(p.positions.size(), Vec3::Zero());
  return p;
}

vessels::Network tube() {
  return vessels::Network::build(vessels::straight_tube({.length = kLength, .radius = kR}),
                                 {.max_segment_length = 1e-3});
}

WallSpec soft_wall(double E) { return {kThickness, 0.0, E, 0.45, 0.0, 1e-3, {}, {}}; }

double tip_offset(const Pressed& p) { return p.positions.front().y(); }

TEST(DeformableWall, AWallTurnedInsideOutIsANumericalFailure) {
  // The linear wall under a point force far beyond its range: its field inverts the elements
  // under the force, which is reported, not drawn. A force 10⁴ times smaller is carried.
  DeformableWall wall(Vec3::Zero(), Vec3(kLength, 0, 0), kR, soft_wall(0.5e6));
  const std::vector<Vec3> at = {Vec3(0.5 * kLength, kR, 0)};
  wall.load(&wall, at, std::vector<Vec3>{Vec3(0, 1e-4, 0)});
  EXPECT_GT(wall.max_displacement(), 0.0);
  wall.load(&wall, at, std::vector<Vec3>{Vec3(0, 1.0, 0)});
  try {
    (void)wall.displacement();
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Numerical);
    EXPECT_NE(std::string(e.what()).find("inside out"), std::string::npos) << e.what();
  }
}

TEST(DeformableWall, TheWirePushesTheWallOutAndTheWallPushesBack) {
  const vessels::Network net = tube();
  const Pressed rigid = press(net, nullptr);
  DeformableWall wall(Vec3::Zero(), Vec3(kLength, 0, 0), kR, soft_wall(0.5e6));
  const Pressed soft = press(net, &wall);
  ASSERT_TRUE(rigid.converged);
  ASSERT_TRUE(soft.converged);
  std::printf("wall: %d nodes, %d tets, %d compliance columns, %.2f s (mesh %.2f s)\n", wall.mesh().num_nodes(),
              wall.mesh().num_tets(), wall.compliance_columns(), wall.seconds(), wall.mesh_seconds());
  std::printf("tip offset: rigid wall %.4f mm, 0.5 MPa wall %.4f mm; wall displaced %.4f mm; Newton %d vs %d\n",
              tip_offset(rigid) * 1e3, tip_offset(soft) * 1e3, wall.max_displacement() * 1e3, rigid.newton,
              soft.newton);
  // The rigid lumen stops the tip at R − a (less the penalty's sink).
  EXPECT_NEAR(tip_offset(rigid), kR - 0.2e-3, 0.1e-3);
  // The soft wall lets it go farther, by about what the wall moved.
  EXPECT_GT(tip_offset(soft), tip_offset(rigid) + 0.5 * wall.max_displacement());
  EXPECT_GT(wall.max_displacement(), 20e-6);
  // Newton's third law: the wall carries the opposite of every wall force on the wire.
  Vec3 on_wire = Vec3::Zero();
  for (const Vec3& f : soft.contact_force) on_wire += f;
  EXPECT_LT((wall.load_total() + on_wire).norm(), 1e-12 + 1e-9 * on_wire.norm());
  EXPECT_GT(on_wire.norm(), 0.01);
}

/// The wall's solid held at both ends of the straight vessel, as DeformableWall holds it.
void hold_ends(solid::ElasticSolid& s) {
  s.hold(s.mesh().group_named("end_0"));
  s.hold(s.mesh().group_named("end_1"));
}

/// Where a pressed wire's contacts put the wall, as the contact assumed it: for each vertex in
/// contact, its lumen point (radially out from the axis), the force on the wall there, the
/// radial direction, and the wall's radial displacement the contact assumed (the wire's distance
/// from the axis + its radius − R − the penalty's sink λ/k).
struct ContactSites {
  std::vector<solid::LumenPoint> points;
  std::vector<Vec3> loads, along;
  std::vector<double> expected;
  ContactSites(const Pressed& p, const solid::LumenCompliance& lumen) {
    for (size_t i = 0; i < p.positions.size(); ++i) {
      if (p.contact_force[i].norm() == 0.0) continue;
      const Vec3& x = p.positions[i];
      const double r = std::hypot(x.y(), x.z());
      const Vec3 radial(0.0, x.y() / r, x.z() / r);
      // (the wire, of radius 0.2 mm, presses over its footprint: the mean displacement there)
      points.push_back(lumen.locate_patch(Vec3(x.x(), kR * radial.y(), kR * radial.z()), 0.2e-3));
      loads.push_back(-p.contact_force[i]);
      along.push_back(radial);
      expected.push_back(r + 0.2e-3 - kR - p.contact_force[i].norm() / 3e4);
    }
  }
};

class DeformableWallAgainstFullSolve : public ::testing::TestWithParam<bool> {};

TEST_P(DeformableWallAgainstFullSolve, TheContactsWallIsTheFullSolidsUnderTheWiresForces) {
  // The contact assumes the wall's linear response condensed onto its contacts; solve the
  // wall again, in full and nonlinear, under the opposites of the wire's final forces, and
  // compare where the lumen went under each contact vertex. The tip pressing (one contact),
  // and the wire lying along the wall (many, coupled through the wall).
  const vessels::Network net = tube();
  const WallSpec spec = soft_wall(2e6);
  DeformableWall wall(Vec3::Zero(), Vec3(kLength, 0, 0), kR, spec);
  const Pressed soft = press(net, &wall, GetParam());
  ASSERT_TRUE(soft.converged);
  solid::ElasticSolid full(wall.mesh(), solid::NeoHookean::from_young_poisson(spec.youngs_modulus, spec.poisson_ratio));
  hold_ends(full);
  full.linearize();
  solid::LumenCompliance lumen(full, full.mesh().group_named("lumen"));
  const ContactSites sites(soft, lumen);
  const auto& points = sites.points;
  const auto& loads = sites.loads;
  const auto& along = sites.along;
  const auto& expected = sites.expected;
  ASSERT_FALSE(points.empty());
  // The same wall linear (what the contact condenses) and nonlinear (neo-Hookean, large
  // displacements): the first checks the condensation, the second what linearizing costs.
  Eigen::MatrixXd linear = lumen.nodal_forces(points, loads);
  full.tangent_solve(linear);
  full.nodal_forces() = lumen.nodal_forces(points, loads);
  ASSERT_TRUE(full.solve().converged);
  // (The contact condenses the wall's compliance along its own normal, the capsule's radial
  // direction, not the flat face's normal: a face of the lumen's triangulation can lean a few
  // degrees from it, and the friction's axial load moves the wall axially.)
  auto radial_at = [&](const solid::LumenPoint& p, const Vec3& n, const Eigen::VectorXd& u_all) {
    return lumen.interpolate(p, u_all).dot(n);  // outwards
  };
  double worst_linear = 0.0, worst_nonlinear = 0.0, largest = 0.0;
  for (size_t j = 0; j < points.size(); ++j) {
    worst_linear = std::max(worst_linear, std::abs(radial_at(points[j], along[j], linear.col(0)) - expected[j]));
    worst_nonlinear =
        std::max(worst_nonlinear, std::abs(radial_at(points[j], along[j], full.displacement()) - expected[j]));
    largest = std::max(largest, std::abs(expected[j]));
  }
  std::printf(
      "%zu contacts: wall displacement assumed by the contact up to %.4g mm; the full linear solve differs "
      "by %.3g mm, the nonlinear one by %.3g mm\n",
      points.size(), largest * 1e3, worst_linear * 1e3, worst_nonlinear * 1e3);
  // One concentrated contact (the tip) reads the compliance where the contact was anchored,
  // which the tip has slid from within the solve (measured 1.9% over the wire's footprint, 2.0%
  // as a point load); many contacts agree to 1% (0.1%).
  EXPECT_LT(worst_linear, (GetParam() ? 0.01 : 0.03) * largest);
  EXPECT_LT(worst_nonlinear, 0.1 * largest);  // displacements of half the wall's thickness
  if (GetParam()) {
    EXPECT_GT(points.size(), 10u);
  }
}

INSTANTIATE_TEST_SUITE_P(TipOrLying, DeformableWallAgainstFullSolve, ::testing::Values(false, true));

TEST(DeformableWall, APushAndReleaseWithoutFrictionGainsNoEnergy) {
  // The tip pressed 20 ms into the soft wall by 50 mN, then let go: from then on the rod's
  // kinetic and elastic energy and the contact's (penalty and wall strain) may only fall
  // (backward Euler dissipates, nothing else works on the system), although the contacts are
  // anchored and their compliance condensed anew every step.
  const vessels::Network net = tube();
  DeformableWall wall(Vec3::Zero(), Vec3(kLength, 0, 0), kR, soft_wall(0.5e6));
  Rig rig(net, &wall);
  rod::RodSimulator& sim = *rig.sim;
  const auto& forces = rig.forces;
  sim.set_tip_force({0.0, 0.05, 0.0});
  for (int n = 0; n < 20; ++n) ASSERT_TRUE(sim.step(1e-3).converged());
  sim.set_tip_force(Vec3::Zero());
  double previous = std::numeric_limits<double>::infinity(), first = 0.0, largest_rise = 0.0;
  for (int n = 0; n < 60; ++n) {
    ASSERT_TRUE(sim.step(1e-3).converged());
    const double e = sim.energy().total() + forces->contact_energy();
    if (n == 0) first = e;
    largest_rise = std::max(largest_rise, e - previous);
    previous = e;
  }
  std::printf("push and release: energy %.4g J after the release, %.4g J 60 ms later; largest rise in a step %.3g J\n",
              first, previous, largest_rise);
  EXPECT_GT(first, 0.0);
  EXPECT_LE(largest_rise, 1e-9 * first);
  EXPECT_LT(previous, first);
}

TEST(DeformableWall, AStiffWallIsTheRigidWall) {
  const vessels::Network net = tube();
  const Pressed rigid = press(net, nullptr);
  DeformableWall wall(Vec3::Zero(), Vec3(kLength, 0, 0), kR, soft_wall(1e12));
  const Pressed stiff = press(net, &wall);
  ASSERT_TRUE(stiff.converged);
  double worst = 0.0;
  for (size_t i = 0; i < rigid.positions.size(); ++i)
    worst = std::max(worst, (rigid.positions[i] - stiff.positions[i]).norm());
  EXPECT_LT(worst, 1e-7);
}

TEST(DeformableWall, TheBloodPressureInflatesTheWallAndTheWireLiesWhereItWent) {
  // A uniform 2 kPa inflates the tube (held ends: plane strain away from them) by Lamé's radial
  // displacement at the lumen; the wire lying along the wall under a body load then sits that
  // much farther out, its total contact force the same (it balances the same load).
  const vessels::Network net = tube();
  const WallSpec spec = soft_wall(2e6);
  const double p = 2e3, a = kR, b = kR + kThickness, nu = spec.poisson_ratio, E = spec.youngs_modulus;
  const double lame = (1 + nu) * p * a * a / (E * (b * b - a * a)) * ((1 - 2 * nu) * a + b * b / a);
  DeformableWall dry(Vec3::Zero(), Vec3(kLength, 0, 0), kR, spec);
  DeformableWall wet(Vec3::Zero(), Vec3(kLength, 0, 0), kR, spec);
  const std::vector<double> pressures(2, p);  // the wall's own straight network: two nodes
  wet.set_blood_pressure(pressures, 0.0);
  // The lumen at mid-length, all round: its radial displacement against Lamé's.
  double worst = 0.0;
  int seen = 0;
  const auto& m = wet.mesh();
  const Eigen::VectorXd& u = wet.displacement();
  for (int n = 0; n < m.num_nodes(); ++n) {
    const Vec3& x = m.nodes[static_cast<size_t>(n)];
    const double r = std::hypot(x.y(), x.z());
    if (std::abs(x.x() - 0.5 * kLength) > 2e-3 || std::abs(r - a) > 1e-7) continue;
    const double ur = (u[3 * n + 1] * x.y() + u[3 * n + 2] * x.z()) / r;
    worst = std::max(worst, std::abs(ur - lame));
    ++seen;
  }
  ASSERT_GT(seen, 8);
  EXPECT_LT(worst, 0.05 * lame) << "Lamé " << lame * 1e6 << " um";
  EXPECT_EQ(wet.summary()["blood_pressure_max_lumen_displacement"].get<double>() > 0.9 * lame, true);

  // The wire lying along the inflated wall meets it where the pressure and its own forces put it:
  // solve the same wall, linear, under the pressure and the opposites of the wire's final forces,
  // and compare the lumen's radial displacement under each contact with the one the contact
  // assumed (the wire's distance from the axis + its radius − R − the penalty's sink λ/k).
  const Pressed at_rest = press(net, &dry, true), inflated = press(net, &wet, true);
  ASSERT_TRUE(at_rest.converged);
  ASSERT_TRUE(inflated.converged);
  solid::ElasticSolid full(wet.mesh(), solid::NeoHookean::from_young_poisson(E, nu));
  hold_ends(full);
  full.set_pressure(full.mesh().group_named("lumen"), p);
  full.linearize();
  solid::LumenCompliance lumen(full, full.mesh().group_named("lumen"));
  const ContactSites sites(inflated, lumen);
  const auto& points = sites.points;
  const auto& along = sites.along;
  const auto& expected = sites.expected;
  ASSERT_GT(points.size(), 10u);
  Eigen::MatrixXd field = lumen.nodal_forces(points, sites.loads) + full.loads();
  full.tangent_solve(field);
  double off = 0.0, largest = 0.0;
  for (size_t j = 0; j < points.size(); ++j) {
    off = std::max(off, std::abs(along[j].dot(lumen.interpolate(points[j], field.col(0))) - expected[j]));
    largest = std::max(largest, std::abs(expected[j]));
  }
  EXPECT_LT(off, 0.01 * largest) << "largest " << largest * 1e6 << " um";
  // And the inflation is seen: the wire lies farther out than against the dry wall.
  double moved = 0.0;
  for (size_t i = 0; i < at_rest.positions.size(); ++i)
    moved = std::max(moved, inflated.positions[i].y() - at_rest.positions[i].y());
  EXPECT_GT(moved, 0.3 * lame);
}

TEST(DeformableWall, TwoBodiesLoadOneWallAndEachMeetsWhereTheOtherMovedIt) {
  // A wire and a catheter on one wall: each body's forces replace only its own, the wall carries
  // both, and a body's anchors are offset by the wall's displacement under the other's forces
  // (the same as the wall's full field there), not under its own.
  DeformableWall wall(Vec3::Zero(), Vec3(kLength, 0, 0), kR, soft_wall(2e6));
  const int wire = 0, catheter = 0;  // two identities
  const void* a = &wire;
  const void* b = &catheter;
  const std::vector<Vec3> pa = {Vec3(10e-3, kR, 0)}, fa = {Vec3(0, 0.02, 0)};
  const std::vector<Vec3> pb = {Vec3(20e-3, 0, -kR)}, fb = {Vec3(0, 0, -0.03)};
  wall.load(a, pa, fa);
  wall.load(b, pb, fb);
  wall.load(a, pa, fa);  // replaces a's, keeps b's
  EXPECT_LT((wall.load_total() - Vec3(0, 0.02, -0.03)).norm(), 1e-15);
  // b's anchors near a's load: offset by a's displacement only.
  const std::vector<Vec3> near = {Vec3(11e-3, kR, 0), Vec3(9e-3, 0.7 * kR, 0.714 * kR)};
  std::vector<Vec3> normals;
  for (const Vec3& x : near) normals.push_back(Vec3(0, x.y(), x.z()).normalized());
  const auto at_b = wall.anchor(b, near, normals);
  DeformableWall only_a(Vec3::Zero(), Vec3(kLength, 0, 0), kR, soft_wall(2e6));
  only_a.load(a, pa, fa);
  solid::ElasticSolid probe(only_a.mesh(), solid::NeoHookean::from_young_poisson(2e6, 0.45));
  solid::LumenCompliance lumen(probe, probe.mesh().group_named("lumen"));
  ASSERT_EQ(at_b.offsets.size(), 2);
  for (int j = 0; j < 2; ++j) {
    const double full = normals[static_cast<size_t>(j)].dot(
        lumen.interpolate(lumen.locate(near[static_cast<size_t>(j)]), only_a.displacement()));
    EXPECT_NEAR(at_b.offsets[j], full, 1e-6 * std::abs(full) + 1e-12) << j;
    EXPECT_GT(std::abs(full), 1e-7);
  }
  // a's own anchors are not offset by a's own forces (it solves them in its step): by b's only.
  const auto at_a = wall.anchor(a, near, normals);
  ASSERT_EQ(at_a.offsets.size(), 2);
  EXPECT_LT(std::abs(at_a.offsets[0]), 0.1 * std::abs(at_b.offsets[0]));
}

TEST(DeformableWall, RefusesAWallThatCannotBe) {
  auto build = [](double thickness, double E, double nu, double support) {
    const WallSpec spec{thickness, 0.0, E, nu, support, 0.5e-3, {}, {}};
    DeformableWall wall(Vec3::Zero(), Vec3(kLength, 0, 0), kR, spec);
  };
  EXPECT_THROW(build(0.0, 1e6, 0.45, 0.0), Error);
  EXPECT_THROW(build(kThickness, -1e6, 0.45, 0.0), Error);
  EXPECT_THROW(build(kThickness, 1e6, 0.5, 0.0), Error);
  EXPECT_THROW(build(kThickness, 1e6, 0.45, -1.0), Error);
}

TEST(DeformableWall, LoadsTooLargeForOneLinearStepAreReachedInIncrements) {
  // The footprint's whole load at once on a wall at rest, 0.4 N (five thicknesses), which the
  // wall's Newton does not reach in one go from the linear estimate (42% off at half of it, the
  // test above). The wall is linearized again under it in increments and
  // lands where the same load reached in 20 steps (each solved from the last equilibrium) leaves
  // it: the nonlinear solid's equilibrium under a dead load does not depend on the way there.
  const double force = 0.4, radius = 0.445e-3, length = 16e-3;
  const Vec3 at(0.5 * length, kR, 0.0);
  const std::vector<Vec3> points = {at};
  const std::vector<double> radii = {radius};
  auto nearest_node = [&](const DeformableWall& wall) {
    const auto& m = wall.mesh();
    int nearest = 0;
    for (int n = 1; n < m.num_nodes(); ++n)
      if ((m.nodes[static_cast<size_t>(n)] - at).norm() < (m.nodes[static_cast<size_t>(nearest)] - at).norm())
        nearest = n;
    return nearest;
  };
  WallSpec spec = soft_wall(1e6);
  spec.relinearize = 0.0;
  DeformableWall stepped(Vec3::Zero(), Vec3(length, 0, 0), kR, spec);
  for (int k = 1; k <= 20; ++k) {
    stepped.load(&stepped, points, std::vector<Vec3>{Vec3(0, force * k / 20, 0)}, radii);
    stepped.relinearize();
  }
  DeformableWall at_once(Vec3::Zero(), Vec3(length, 0, 0), kR, spec);
  at_once.load(&at_once, points, std::vector<Vec3>{Vec3(0, force, 0)}, radii);
  at_once.relinearize();
  const int n = nearest_node(at_once);
  const double u_stepped = stepped.displacement()[3 * n + 1], u_once = at_once.displacement()[3 * n + 1];
  std::printf("footprint pushed out %.4g mm (%.2f thicknesses) at once in %d increments, %.4g mm in 20 steps\n",
              u_once * 1e3, u_once / kThickness, at_once.relinearize_load_increments(), u_stepped * 1e3);
  EXPECT_GT(at_once.relinearize_load_increments(), 1) << "the load was reached in one go: no increments tested";
  EXPECT_GT(u_once, 2.0 * kThickness);
  EXPECT_NEAR(u_once, u_stepped, 1e-6 * u_stepped);
}
}  // namespace
}  // namespace flowire::coupling

namespace flowire::coupling {
namespace {

/// The flow through a straight 120 mm tube (r = 3 mm) whose wall (0.6 mm, 1 MPa) the blood
/// pressure widens (8 kPa in, 7.9 kPa out), with `wall.flow_radii` on or off.
double distensible_tube_flow(bool flow_radii, const std::vector<std::string>& sets = {}) {
  const auto dir = flowire::testing::scratch_dir(std::string("distensible_") + (flow_radii ? "on" : "off"));
  std::ofstream(dir / "tube.yml") << "length_unit: mm\nbranches:\n  - name: tube\n    points:\n"
                                     "      - [0, 0, 0, 3.0]\n      - [120, 0, 0, 3.0]\n";
  std::ofstream(dir / "scene.yaml")
      << "name: distensible\nvessels: {file: tube.yml, max_segment_length: 2 mm}\n"
         "flow:\n  solver: superposition\n  inlet: {pressure: 8 kPa}\n  outlets: {pressure: 7.9 kPa}\n"
         "wire: {entry: 0, length: 0.05, radius: 0.2 mm, youngs_modulus: 60 GPa, segment_length: 2 mm}\n"
         "insertion: {speed: 0, initial_length: 5 mm}\ncontact: {friction: 0}\n"
         "coupling: {drag: none, occlusion: none}\n"
         "wall:\n  thickness: 0.6 mm\n  youngs_modulus: 1 MPa\n  poisson_ratio: 0.45\n  blood_pressure: true\n"
         "  flow_radii: "
      << (flow_radii ? "true" : "false") << "\n  mesh_size: 1 mm\n"
      << "solve: {dt: 10 ms, duration: 0.2 s}\noutput: {vtk: false, csv: true, png: false}\n";
  auto cfg = load_scene((dir / "scene.yaml").string(), sets, (dir / "out").string());
  const auto r = run_scene(cfg);
  EXPECT_EQ(r.summary["status"], "ok");
  std::ifstream in(dir / "out" / "segments.csv");
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  std::stringstream ss(last);
  std::string field;
  std::vector<std::string> f;
  while (std::getline(ss, field, ',')) f.push_back(field);
  return std::stod(f.at(7));  // flow_rate
}

TEST(DeformableWall, TheFlowThroughATubeItsPressureWidensIsTheDistensibleTubes) {
  // A linear wall widens the lumen by c p (Lamé, plane strain: c = (1+ν)a²((1−2ν)a + b²/a)/(E(b²−a²)));
  // Poiseuille's law over r(p) = a + c p integrates to Q = π((a + c p₁)⁵ − (a + c p₂)⁵)/(40 η L c),
  // against the rigid tube's πa⁴(p₁ − p₂)/(8ηL): their ratio, without η or L. The widening is the
  // wall's own (its field's mean over each segment), the flow sees the last step's.
  const double a = 3e-3, b = 3.6e-3, E = 1e6, nu = 0.45, p1 = 8e3, p2 = 7.9e3;
  const double c = (1 + nu) * a * a / (E * (b * b - a * a)) * ((1 - 2 * nu) * a + b * b / a);
  const double exact = (std::pow(a + c * p1, 5) - std::pow(a + c * p2, 5)) / (5 * c * std::pow(a, 4) * (p1 - p2));
  const double rigid = distensible_tube_flow(false), widened = distensible_tube_flow(true);
  std::printf("flow widened / rigid %.5f, the distensible tube's %.5f\n", widened / rigid, exact);
  // The held ends do not widen (a few millimetres at each of the 120): within 5% of the change.
  EXPECT_NEAR(widened / rigid - 1.0, exact - 1.0, 0.05 * (exact - 1.0));
}

TEST(DeformableWall, TheFlowsRadiiNeedAQuasiSteadyFlow) {
  EXPECT_NE(test::input_error([] { (void)distensible_tube_flow(true, {"flow.model=rlc"}); }).find("wall.flow_radii"),
            std::string::npos);
}

}  // namespace
}  // namespace flowire::coupling

namespace flowire::coupling {
namespace {
/// A straight vessel along x of two branches, "proximal" and "distal", meeting at its middle.
vessels::Network two_branch_vessel() {
  vessels::Centerlines c;
  const double mid = 0.5 * kLength;
  c.branches.push_back({"proximal", {Vec3::Zero(), Vec3(mid, 0, 0)}, {kR, kR}});
  c.branches.push_back({"distal", {Vec3(mid, 0, 0), Vec3(kLength, 0, 0)}, {kR, kR}});
  return vessels::Network::build(c, {.max_segment_length = 2e-3});
}

/// The mean radial displacement of the lumen's nodes within 1.5 mm of x = @p x0.
double lumen_radial_displacement(const mesh::TetMesh& m, const Eigen::VectorXd& u, double x0) {
  double sum = 0.0;
  int seen = 0;
  for (int n = 0; n < m.num_nodes(); ++n) {
    const Vec3& x = m.nodes[static_cast<size_t>(n)];
    const double r = std::hypot(x.y(), x.z());
    if (std::abs(x.x() - x0) > 1.5e-3 || std::abs(r - kR) > 1e-6) continue;
    sum += (u[3 * n + 1] * x.y() + u[3 * n + 2] * x.z()) / r;
    ++seen;
  }
  EXPECT_GT(seen, 8) << x0;
  return sum / std::max(seen, 1);
}

/// Lamé's radial displacement of the bore of a tube (plane strain) of bore @p a and wall
/// thickness @p t under an internal pressure @p p.
double lame_bore_displacement(double p, double a, double t, double E, double nu) {
  const double b = a + t;
  return (1 + nu) * p * a * a / (E * (b * b - a * a)) * ((1 - 2 * nu) * a + b * b / a);
}

TEST(DeformableWall, EachBranchsWallHasItsOwnModulus) {
  // A straight vessel of two branches, the distal one's wall three times as stiff: a uniform
  // 2 kPa inflates each half by Lamé's displacement with its own modulus (away from the joint
  // and the held ends), and nothing changes where no branch is given a modulus of its own.
  const vessels::Network net = two_branch_vessel();
  ASSERT_EQ(net.num_branches(), 2);
  WallSpec spec = soft_wall(1e6);
  const int distal = net.branches()[0].name == "distal" ? 0 : 1;
  spec.branch_youngs_modulus = {{distal, 3e6}};
  DeformableWall wall(net, spec);
  const double p = 2e3;
  auto lame = [&](double E) { return lame_bore_displacement(p, kR, kThickness, E, spec.poisson_ratio); };
  wall.set_blood_pressure(std::vector<double>(static_cast<size_t>(net.num_nodes()), p), 0.0);
  auto radial_at = [&](double x0) { return lumen_radial_displacement(wall.mesh(), wall.displacement(), x0); };
  const double soft = radial_at(0.25 * kLength), stiff = radial_at(0.75 * kLength);  // proximal, distal
  EXPECT_NEAR(soft, lame(1e6), 0.05 * lame(1e6));
  EXPECT_NEAR(stiff, lame(3e6), 0.05 * lame(3e6));
  EXPECT_NEAR(soft / stiff, 3.0, 0.15);
  std::printf("proximal %.4g um (Lame %.4g), distal %.4g um (Lame %.4g)\n", soft * 1e6, lame(1e6) * 1e6, stiff * 1e6,
              lame(3e6) * 1e6);
  EXPECT_THROW(DeformableWall(net,
                              [&] {
                                WallSpec bad = spec;
                                bad.branch_youngs_modulus = {{5, 3e6}};
                                return bad;
                              }()),
               Error);
}

TEST(DeformableWall, EachBranchsWallHasItsOwnThickness) {
  // A straight vessel of two branches, the distal one's wall twice as thick: its outer surface
  // steps at the joint, and a uniform 2 kPa inflates each half by Lamé's displacement of its own
  // thickness (away from the joint and the held ends). The proximal branch keeps the wall's.
  const vessels::Network net = two_branch_vessel();
  ASSERT_EQ(net.num_branches(), 2);
  WallSpec spec = soft_wall(1e6);
  const int distal = net.branches()[0].name == "distal" ? 0 : 1;
  spec.branch_thickness = {{distal, 2.0 * kThickness, 0.0}};
  DeformableWall wall(net, spec);
  const double p = 2e3;
  auto lame = [&](double t) { return lame_bore_displacement(p, kR, t, spec.youngs_modulus, spec.poisson_ratio); };
  const auto& m = wall.mesh();
  // The outer surface: kR + t on each side of the joint, the step between them outer surface
  // too (were it lumen, the blood pressure would push the thick half along its axis).
  const int outer = m.group_named("outer"), lumen = m.group_named("lumen");
  double outer_proximal = 0.0, outer_distal = 0.0;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (m.face_group[f] == lumen) {
      for (int node : m.faces[f])
        EXPECT_NEAR(std::hypot(m.nodes[static_cast<size_t>(node)].y(), m.nodes[static_cast<size_t>(node)].z()), kR,
                    1e-6);
    }
    if (m.face_group[f] != outer) continue;
    for (int node : m.faces[f]) {
      const Vec3& x = m.nodes[static_cast<size_t>(node)];
      const double r = std::hypot(x.y(), x.z());
      if (x.x() < 0.4 * kLength) outer_proximal = std::max(outer_proximal, r);
      if (x.x() > 0.6 * kLength) outer_distal = std::max(outer_distal, r);
    }
  }
  EXPECT_NEAR(outer_proximal, kR + kThickness, 1e-3 * kR);
  EXPECT_NEAR(outer_distal, kR + 2.0 * kThickness, 1e-3 * kR);
  wall.set_blood_pressure(std::vector<double>(static_cast<size_t>(net.num_nodes()), p), 0.0);
  auto radial_at = [&](double x0) { return lumen_radial_displacement(m, wall.displacement(), x0); };
  const double thin = radial_at(0.25 * kLength), thick = radial_at(0.75 * kLength);
  EXPECT_NEAR(thin, lame(kThickness), 0.03 * lame(kThickness));
  EXPECT_NEAR(thick, lame(2.0 * kThickness), 0.03 * lame(2.0 * kThickness));
  std::printf("proximal %.4g um (Lame %.4g), distal %.4g um (Lame %.4g)\n", thin * 1e6, lame(kThickness) * 1e6,
              thick * 1e6, lame(2.0 * kThickness) * 1e6);
  EXPECT_THROW(DeformableWall(net,
                              [&] {
                                WallSpec bad = spec;
                                bad.branch_thickness = {{distal, 0.0, 0.0}};
                                return bad;
                              }()),
               Error);
}

TEST(DeformableWall, ARelinearizedWallFollowsTheNonlinearSolidBeyondItsThickness) {
  // A wire's footprint pushes a tube's wall outwards with a force that grows in 20 steps until
  // the wall has moved two and a half times its thickness. The reference: the same wall solved
  // (neo-Hookean, Newton) under every step's load, each from the last equilibrium. A wall linear
  // about rest departs from it; one linearized again whenever the footprint has moved a quarter of
  // its thickness from its last linearization follows it, at every step, within a small fraction
  // of that departure.
  const double force = 0.15, radius = 0.445e-3, length = 16e-3;
  const int steps = 20;
  const Vec3 at(0.5 * length, kR, 0.0);
  auto run = [&](double relinearize, bool reference) {
    WallSpec spec = soft_wall(1e6);
    spec.relinearize = relinearize;
    DeformableWall wall(Vec3::Zero(), Vec3(length, 0, 0), kR, spec);
    const auto& m = wall.mesh();
    int nearest = 0;  // the footprint's centre: the lumen node nearest to it
    for (int n = 1; n < m.num_nodes(); ++n)
      if ((m.nodes[static_cast<size_t>(n)] - at).norm() < (m.nodes[static_cast<size_t>(nearest)] - at).norm())
        nearest = n;
    const std::vector<Vec3> points = {at};
    const std::vector<double> radii = {radius};
    std::vector<double> path;
    for (int k = 1; k <= steps; ++k) {
      wall.load(&wall, points, std::vector<Vec3>{Vec3(0, force * k / steps, 0)}, radii);
      if (reference) wall.relinearize();
      path.push_back(wall.displacement()[3 * nearest + 1]);
    }
    return std::pair{path, wall.relinearizations()};
  };
  const auto [exact, solves] = run(0.0, true);
  const auto [linear, none] = run(0.0, false);
  const auto [relinearized, count] = run(0.25, false);
  const auto [finer, finer_count] = run(0.1, false);
  auto largest_error = [&](const std::vector<double>& path) {
    double e = 0.0;
    for (int k = 0; k < steps; ++k) e = std::max(e, std::abs(path[k] - exact[k]) / exact[k]);
    return e;
  };
  const double linear_error = largest_error(linear), error = largest_error(relinearized),
               finer_error = largest_error(finer);
  std::printf(
      "footprint displacement at the last step: nonlinear %.4g mm, linear about rest %.4g mm, relinearized "
      "at 0.25 t %.4g mm (%d linearizations), at 0.1 t %.4g mm (%d); largest error over the steps: linear "
      "%.1f%%, relinearized %.2f%% and %.2f%%\n",
      exact.back() * 1e3, linear.back() * 1e3, relinearized.back() * 1e3, count, finer.back() * 1e3, finer_count,
      100 * linear_error, 100 * error, 100 * finer_error);
  EXPECT_EQ(solves, steps);
  EXPECT_EQ(none, 0);
  EXPECT_GT(exact.back(), 2.0 * kThickness) << "the case is beyond the wall's thickness";
  EXPECT_GT(count, 2);
  EXPECT_LT(count, finer_count);
  EXPECT_GT(linear_error, 0.3) << "the linear wall's departure is what is measured";
  EXPECT_LT(error, 0.2 * linear_error);
  EXPECT_LT(std::abs(relinearized.back() - exact.back()), 0.01 * exact.back());
  // The departure between linearizations shrinks with the distance allowed, at least in proportion
  // to it: the slope of the largest error against the fraction of the thickness.
  const double slope = std::log(error / finer_error) / std::log(0.25 / 0.1);
  std::printf("slope of the error against wall.relinearize: %.2f\n", slope);
  EXPECT_GT(slope, 0.7);
}
}  // namespace
}  // namespace flowire::coupling
