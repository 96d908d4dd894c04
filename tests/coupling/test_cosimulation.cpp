// The wire in vessels with blood: the real rod driven through the vessel forces, against
// beam theory, force balance, and the published qualitative result.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "flowire/coupling/scene.hpp"
#include "flowire/coupling/trace_compare.hpp"
#include "flowire/coupling/vessel_forces.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire/vessels/generators.hpp"
#include "flowire_test.hpp"

using namespace flowire;
using namespace flowire::coupling;
using vessels::Vec3;

TEST(CoSim, UniformCrossFlowBendsAClampedWireLikeABeamUnderUniformLoad) {
  // Small deflection: w_tip = q L⁴ / (8 EI) with q = c⊥ u (the flow is normal to the wire).
  const auto net =
      vessels::Network::build(vessels::straight_tube({.length = 2.0, .radius = 0.5}), {.max_segment_length = 0.1});
  const vessels::SpatialIndex index(net);
  rod::WireSpec spec;
  spec.length = 0.2;
  spec.radius = 0.2e-3;
  spec.youngs_modulus = 5e9;
  spec.segments = 100;
  spec.tip.length = 0.0;
  spec.base_position = Vec3(0.5, 0, 0);
  spec.base_direction = Vec3::UnitX();
  spec.inserted_length = spec.length - 2 * spec.length / spec.segments;
  rod::RodSimulator sim(spec);
  const double eta = 3.5e-3, u = 0.01;
  auto forces = std::make_shared<VesselForces>(
      index, spec.radius, ContactParams{.enabled = false},
      DragModel{.law = DragLaw::SlenderBody, .viscosity = eta, .wire_length = spec.length},
      [&](int, const Vec3&) { return Vec3(0, u, 0); });
  sim.add_external(forces);
  const auto rep = sim.solve_static();
  ASSERT_TRUE(rep.converged());
  const double L = sim.inserted_length();
  const double EI = spec.youngs_modulus * std::numbers::pi * std::pow(spec.radius, 4) / 4;
  const double q = 4 * std::numbers::pi * eta / std::log(spec.length / spec.radius) * u;
  const double w = q * std::pow(L, 4) / (8 * EI);
  ASSERT_LT(w / L, 0.02);  // small deflection regime
  EXPECT_NEAR(sim.tip_position().y(), w, 0.01 * w);
}

TEST(CoSim, ContactForcesBalanceThePushInAStaticCheck) {
  // A wire pushed by a tip force into the closed end of a tube: at equilibrium the wall's
  // forces, the clamp's reaction and the load sum to zero.
  const auto net =
      vessels::Network::build(vessels::straight_tube({.length = 0.1, .radius = 3e-3}), {.max_segment_length = 5e-3});
  const vessels::SpatialIndex index(net);
  rod::WireSpec spec;
  spec.length = 0.2;
  spec.radius = 0.3e-3;
  spec.youngs_modulus = 20e9;
  spec.segment_length = 2e-3;
  spec.tip.length = 0.0;
  spec.base_position = Vec3(0.1, 0, 0);
  spec.base_direction = Vec3(-1, 0.02, 0).normalized();
  spec.inserted_length = 0.104;
  rod::RodSimulator sim(spec);
  ContactParams cp;
  cp.stiffness = 1e5;
  cp.friction = 0.0;
  cp.tip_friction = 0.0;
  auto forces = std::make_shared<VesselForces>(index, spec.radius, cp, DragModel{.law = DragLaw::None});
  sim.add_external(forces);
  const Vec3 F(-0.05, 0.0, 0.0);
  sim.set_tip_force(F);
  const auto rep = sim.solve_static();
  ASSERT_TRUE(rep.converged()) << rod::to_string(rep.status);
  Vec3 wall = Vec3::Zero();
  for (int i = 0; i < sim.first_clamped_vertex(); ++i) wall += forces->force()[static_cast<size_t>(i)];
  EXPECT_GT(wall.norm(), 0.5 * F.norm());  // the end wall takes the push
  EXPECT_LT((wall + sim.base_force() + F).norm(), 1e-6 * F.norm())
      << "wall " << wall.transpose() << " base " << sim.base_force().transpose();
}

namespace {
nlohmann::json run_text(const std::string& yaml, const std::string& dir) {
  const auto cfg = config::load_config_text(yaml, "scene.yaml", scene_schema(), {"output.dir=" + dir});
  return run_scene(cfg).summary;
}
}  // namespace

TEST(CoSim, AWirePushedThroughTheAorticArchStaysInside) {
  const auto dir = flowire::testing::scratch_dir("cosim-inside");
  const auto s = run_text(R"(
vessels: {generator: {type: aortic_arch}, max_segment_length: 5 mm}
wire: {length: 0.6, radius: 0.445 mm, youngs_modulus: 60 GPa, segment_length: 2 mm}
insertion: {speed: 5 cm/s, initial_length: 2 cm}
contact: {friction: 0.2}
solve: {dt: 5 ms, duration: 3 s}
output: {csv: false, vtk: false}
)",
                          dir.string());
  ASSERT_EQ(s["status"], "ok");
  EXPECT_NEAR(s["wire"]["inserted_length"].get<double>(), 0.17, 1e-9);
  EXPECT_LE(s["contact"]["max_outside_over_wire_radius"].get<double>(), 0.1);
  EXPECT_GT(s["contact"]["contact_evaluations"].get<long>(), 0);
  EXPECT_LT(s["wire"]["length_drift"].get<double>(), 1e-3);
  EXPECT_GT(s["lookup"]["window_hits"].get<long>(), 20 * s["lookup"]["fallbacks"].get<long>());
}

TEST(CoSim, AnAdaptiveJTipWirePushedThroughTheArchStaysInside) {
  // The same push with a J tip, on the uniform wire and on a curvature-adaptive one: the
  // tip arc is refined, the contact carries over the resampling, the wire never leaves the
  // lumen, and Newton fails no more often than on the uniform wire (a J tip fed at 5 cm/s
  // with 5 ms steps leaves a few steps at the iteration limit, reported as warnings).
  const std::string scene = R"(
vessels: {generator: {type: aortic_arch}, max_segment_length: 5 mm}
wire:
  length: 0.6
  radius: 0.445 mm
  youngs_modulus: 60 GPa
  segment_length: 2 mm
  tip: {length: 3 cm, youngs_modulus: 10 GPa, shape: j, angle: 180 deg, bend_radius: 4 mm}
insertion: {speed: 5 cm/s, initial_length: 2 cm}
contact: {friction: 0.2}
solve: {dt: 5 ms, duration: 3 s}
output: {csv: false, vtk: false}
)";
  const flowire::testing::ExpectWarnings allowed;
  const auto uniform = run_text(scene, flowire::testing::scratch_dir("cosim-jtip").string());
  std::string adaptive_scene = scene;
  const std::string tip_line = "bend_radius: 4 mm}\n";
  adaptive_scene.insert(adaptive_scene.find(tip_line) + tip_line.size(), "  adapt: {split_angle: 0.15 rad}\n");
  const auto adaptive = run_text(adaptive_scene, flowire::testing::scratch_dir("cosim-adaptive").string());
  for (const auto* s : {&uniform, &adaptive}) {
    ASSERT_EQ((*s)["status"], "ok");
    EXPECT_NEAR((*s)["wire"]["inserted_length"].get<double>(), 0.17, 1e-9);
    EXPECT_LE((*s)["contact"]["max_outside_over_wire_radius"].get<double>(), 0.1);
    EXPECT_LT((*s)["wire"]["length_drift"].get<double>(), 1e-3);
  }
  EXPECT_GT(adaptive["wire"]["adapt"]["splits"].get<long>(), 0);
  EXPECT_GT(adaptive["wire"]["vertices"].get<long>(), uniform["wire"]["vertices"].get<long>());
  EXPECT_LE(adaptive["wire"]["unconverged_steps"].get<long>(), uniform["wire"]["unconverged_steps"].get<long>());
}

TEST(CoSim, BloodFlowPushesTheWireDownstream) {
  // A wire with an angled tip pushed against the flow up a straight artery, flow on vs
  // off: the traces differ, and with the flow the tip sits further downstream (+x).
  const auto dir = flowire::testing::scratch_dir("cosim-flow");
  const std::string scene = R"(
vessels: {generator: {type: straight_tube, length: 0.2, radius: 4 mm}, max_segment_length: 5 mm}
flow:
  inlet: {pressure: {waveform: sine, systolic: 120 mmHg, diastolic: 80 mmHg, period: 0.833 s}}
  outlets: {resistance: 1 mmHg*s/mL}
wire: {length: 0.3, radius: 0.3 mm, youngs_modulus: 5 GPa, segment_length: 2 mm,
       tip: {length: 3 cm, youngs_modulus: 1 GPa, shape: angled, angle: 45 deg, bend_radius: 5 mm}}
insertion: {speed: 2 cm/s, initial_length: 2 cm}
contact: {friction: 0.1}
coupling: {drag: slender_body, drag_scale: 20}
solve: {dt: 10 ms, duration: 4 s}
output: {vtk: false}
)";
  auto run_with = [&](const std::string& name, const std::string& drag) {
    const std::vector<std::string> sets{"output.dir=" + (dir / name).string(), "coupling.drag=" + drag};
    const auto s = run_scene(config::load_config_text(scene, "scene.yaml", scene_schema(), sets)).summary;
    EXPECT_EQ(s["status"], "ok");
    return read_tip_trace((dir / name / "tip_trace.csv").string());
  };
  const auto a = run_with("on", "slender_body");
  const auto b = run_with("off", "none");
  const auto cmp = compare_traces(a, b);
  EXPECT_GT(cmp.rms_total, 1e-4);
  double dx = 0;
  int n = 0;
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i)
    if (a[i].inserted_length > 0.04) dx += a[i].x.x() - b[i].x.x(), ++n;
  ASSERT_GT(n, 10);
  EXPECT_GT(dx / n, 0.0) << "mean x(on) - x(off) = " << dx / n;
}

TEST(CoSim, SteeringChoosesTheBranch) {
  const auto dir = flowire::testing::scratch_dir("cosim-steer");
  const std::string scene = R"(
vessels: {generator: {type: y_bifurcation, parent_radius: 4 mm, parent_length: 60 mm, child_length: 50 mm}, max_segment_length: 4 mm}
wire: {length: 0.3, radius: 0.3 mm, youngs_modulus: 20 GPa, segment_length: 2 mm, entry: 0,
       base: {position: [0.002, 0, 0], direction: [1, 0, 0]}}
insertion: {speed: 2 cm/s, initial_length: 1 cm}
contact: {friction: 0.1}
coupling: {steering: {branch: daughter_1, force: 10 mN}}
solve: {dt: 5 ms, duration: 4 s}
output: {csv: false, vtk: false}
)";
  // The tip pressed into the junction's crease leaves a few of the 800 steps at the Newton
  // limit with residuals of ~1e-6 N (the contact's round-off level there); they are
  // reported as warnings and counted, and bounded here.
  const flowire::testing::ExpectWarnings reported;
  for (const char* branch : {"daughter_1", "daughter_2"}) {
    const std::vector<std::string> sets{"output.dir=" + (dir / branch).string(),
                                        std::string("coupling.steering.branch=") + branch};
    const auto s = run_scene(config::load_config_text(scene, "scene.yaml", scene_schema(), sets)).summary;
    ASSERT_EQ(s["status"], "ok");
    EXPECT_LE(s["wire"]["unconverged_steps"].get<long>(), 12) << branch;
    const double y = s["wire"]["tip"][1].get<double>();
    // daughter_1 leaves towards +y, daughter_2 towards −y; the tip is well inside it.
    EXPECT_GT(std::string(branch) == "daughter_1" ? y : -y, 0.01) << branch;
    EXPECT_GT(s["tip_forces"]["steering_steps"].get<long>(), 0);
  }
}

TEST(CoSim, AnObstacleHoldsTheTipBackWithItsForce) {
  // Quasi-static push into a resisting region, no friction: the clamp supplies the obstacle's
  // resistance along the insertion direction.
  const auto dir = flowire::testing::scratch_dir("cosim-obstacle");
  const auto s = run_text(R"(
vessels: {generator: {type: straight_tube, length: 0.2, radius: 3 mm}, max_segment_length: 5 mm}
wire: {length: 0.3, radius: 0.3 mm, youngs_modulus: 20 GPa, segment_length: 2 mm}
obstacles: [{center: [0.105, 0, 0], radius: 10 mm, force: 20 mN}]
insertion: {speed: 2 mm/s, initial_length: 9 cm}
contact: {friction: 0}
solve: {dt: 10 ms, duration: 1 s}
output: {csv: false, vtk: false}
)",
                          dir.string());
  ASSERT_EQ(s["status"], "ok");
  EXPECT_GT(s["tip_forces"]["obstacle_steps"].get<long>(), 50);
  // The wire enters at x = 0.2 going −x; the clamp pushes it towards −x with the obstacle's force.
  EXPECT_NEAR(s["wire"]["base_force"][0].get<double>(), -0.02, 0.002);
}

namespace {
/// The example's scene (J tip, flow, friction) with `initial_length` inserted at t = 0.
std::string long_wire_scene(double initial_length, const std::string& extra) {
  std::ostringstream o;
  o.precision(17);
  o << R"(
vessels: {generator: {type: aortic_arch}, max_segment_length: 5 mm}
flow:
  solver: superposition
  inlet: {pressure: {waveform: sine, systolic: 120 mmHg, diastolic: 80 mmHg, period: 0.833 s}}
  outlets: {resistance: 1 mmHg*s/mL, scaling: murray}
wire:
  length: 0.8
  radius: 0.445 mm
  youngs_modulus: 60 GPa
  density: 6450
  segment_length: 2 mm
  tip: {length: 3 cm, youngs_modulus: 10 GPa, shape: j, angle: 180 deg, bend_radius: 4 mm}
)" << extra
    << "insertion: {speed: 1 cm/s, initial_length: " << initial_length << R"(}
contact: {friction: 0.2, tip_friction: 0.05}
coupling: {drag: slender_body}
solve: {dt: 10 ms, duration: 0.1 s}
output: {csv: false, vtk: false}
)";
  return o.str();
}
}  // namespace

TEST(CoSim, AStraightLongWireThroughTheWallsSettlesAndEveryStepConverges) {
  // 0.78 m laid straight from the femoral entry (wire.base given: no vessel path), so most
  // of the shaft starts centimetres outside the lumen and its vertices cross junction
  // blends, whose wall curvature is indefinite, on the way back in: the settle and every
  // step must still converge at the scene's dt.
  const auto net = vessels::Network::build(vessels::aortic_arch(), {.max_segment_length = 5e-3});
  const Vec3 entry = vessels::aortic_arch_entry();
  int end = -1;
  for (int e : net.ends())
    if ((net.node(e) - entry).norm() < 1e-9) end = e;
  ASSERT_GE(end, 0);
  const auto& seg = net.segment(*net.node_segments(end).first);
  const Vec3 dir = (net.node(seg.node_from == end ? seg.node_to : seg.node_from) - entry).normalized();
  std::ostringstream base;
  base.precision(17);
  base << "  base: {position: [" << entry.x() << ", " << entry.y() << ", " << entry.z() << "], direction: [" << dir.x()
       << ", " << dir.y() << ", " << dir.z() << "]}\n";
  const auto s =
      run_text(long_wire_scene(0.78, base.str()), flowire::testing::scratch_dir("cosim-long-straight").string());
  ASSERT_EQ(s["status"], "ok");
  EXPECT_EQ(s["wire"]["initial_layout"], "straight");
  EXPECT_TRUE(s["wire"]["settle"]["converged"].get<bool>());
  EXPECT_EQ(s["wire"]["unconverged_steps"].get<int>(), 0);
}

TEST(CoSim, ALongWireStartsOnTheVesselPathInsideTheLumen) {
  for (double initial : {0.5, 0.78}) {  // 0.78 m: longer than the path, turned at the root
    const auto s = run_text(long_wire_scene(initial, ""), flowire::testing::scratch_dir("cosim-long-path").string());
    ASSERT_EQ(s["status"], "ok");
    EXPECT_EQ(s["wire"]["initial_layout"], "vessel_path");
    EXPECT_TRUE(s["wire"]["settle"]["converged"].get<bool>());
    EXPECT_EQ(s["wire"]["unconverged_steps"].get<int>(), 0);
    EXPECT_LE(s["contact"]["max_outside_over_wire_radius"].get<double>(), 0.5);
  }
}

TEST(SceneWire, TheTipAngleDefaultsToTheShapesOwn) {
  // A J tip of the published experiment is a 180° J; an angled tip bends 45°; an angle given
  // wins. The total turn of the rest shape, summed over the wire, is the angle.
  auto turn = [](const std::string& tip) {
    const auto cfg = config::load_config_text("wire:\n  length: 0.2\n  segment_length: 0.5 mm\n  tip: " + tip + "\n",
                                              "tip.yaml", scene_schema());
    const rod::RodModel m = rod::RodModel::from_spec(scene_wire_spec(cfg));
    double sum = 0.0;
    for (double k : m.rest_kappa1) sum += 2.0 * std::atan(0.5 * k);
    return sum;
  };
  EXPECT_NEAR(turn("{shape: j}"), std::numbers::pi, 1e-12);
  EXPECT_NEAR(turn("{shape: angled}"), std::numbers::pi / 4.0, 1e-12);
  EXPECT_NEAR(turn("{shape: j, angle: 120 deg}"), 2.0 * std::numbers::pi / 3.0, 1e-12);
  EXPECT_NEAR(turn("{shape: angled, angle: 30 deg}"), std::numbers::pi / 6.0, 1e-12);
  EXPECT_NEAR(turn("{shape: straight}"), 0.0, 1e-15);
}

TEST(CoSim, TheDragTakenOnceAStepMovesTheTipAsTheDragIteratedEveryNewtonStep) {
  // coupling.drag_update: step (the law once a step at Newton's guess, linearized in the
  // wire velocity) against iterate (the law at every iterate), where the drag is what moves
  // the wire: examples/flow_bends_wire, whose soft angled tip the systole swings 2–3 mm
  // across the artery. The two tip traces agree to within 1% of the flow's own effect (the
  // distance between the traces with and without drag); measured over 2.4 s: RMS 0.26 µm
  // against 1.4 mm.
  const std::string scene = std::string(FLOWIRE_SOURCE_DIR) + "/examples/flow_bends_wire/scene.yaml";
  std::ifstream in(scene);
  std::stringstream text;
  text << in.rdbuf();
  auto trace = [&](const std::string& name, const std::string& set) {
    const auto dir = flowire::testing::scratch_dir("cosim-drag-update-" + name);
    const auto cfg = config::load_config_text(
        text.str(), scene, scene_schema(),
        {"output.dir=" + dir.string(), "output.vtk=false", "output.png=false", "solve.duration=2.4 s", set});
    const auto s = run_scene(cfg).summary;
    EXPECT_EQ(s["wire"]["unconverged_steps"].get<int>(), 0) << name;
    return read_tip_trace((dir / "tip_trace.csv").string());
  };
  const auto step = trace("step", "coupling.drag_update=step");
  const auto iterate = trace("iterate", "coupling.drag_update=iterate");
  const auto off = trace("off", "coupling.drag=none");
  ASSERT_EQ(step.size(), iterate.size());
  ASSERT_EQ(step.size(), off.size());
  double linearization = 0, flow = 0;
  for (size_t i = 0; i < step.size(); ++i) {
    linearization += (step[i].x - iterate[i].x).squaredNorm();
    flow += (iterate[i].x - off[i].x).squaredNorm();
  }
  EXPECT_GT(flow, 0.0);
  EXPECT_LT(std::sqrt(linearization), 0.01 * std::sqrt(flow));
}

TEST(CoSim, APushedWireEndsWhereTheSameWireLaidThereSettles) {
  // The feed's consistency at the published scale (400 vertices of 1 mm on the arch): a wire
  // pushed from 36 to 40 cm at 2 cm/s and then held, and the same wire laid at 40 cm along the
  // vessel path and held, end in the same state. Without friction and drag the equilibrium
  // against the walls is one, so any difference is the feed's (vertices added at the base, their
  // rest lengths, material coordinates and frames, the last step's stop at insertion.max_length).
  auto scene = [](double initial, const char* speed, const char* duration) {
    return fmt::format(R"(
vessels: {{generator: {{type: aortic_arch}}, max_segment_length: 5 mm}}
wire:
  length: 0.8
  radius: 0.445 mm
  youngs_modulus: 60 GPa
  density: 6450
  segment_length: 1 mm
  tip: {{length: 3 cm, youngs_modulus: 10 GPa, shape: j, angle: 180 deg, bend_radius: 4 mm}}
insertion: {{speed: {}, initial_length: {}, max_length: 0.40}}
contact: {{friction: 0, tip_friction: 0}}
solve: {{dt: 10 ms, duration: {}}}
output: {{csv: false, vtk: false}}
)",
                       speed, initial, duration);
  };
  const auto pushed =
      run_text(scene(0.36, "2 cm/s", "3 s"), flowire::testing::scratch_dir("cosim-feed-pushed").string());
  const auto laid = run_text(scene(0.40, "0", "1 s"), flowire::testing::scratch_dir("cosim-feed-laid").string());
  ASSERT_EQ(pushed["status"], "ok");
  ASSERT_EQ(laid["status"], "ok");
  EXPECT_EQ(pushed["wire"]["unconverged_steps"].get<int>(), 0);
  EXPECT_EQ(laid["wire"]["unconverged_steps"].get<int>(), 0);
  EXPECT_GE(pushed["wire"]["vertices"].get<int>(), 400);
  // The feed stops on insertion.max_length, not a step's feed beyond it.
  EXPECT_NEAR(pushed["wire"]["inserted_length"].get<double>(), 0.40, 1e-12);
  const auto tp = pushed["wire"]["tip"].get<std::vector<double>>(), tl = laid["wire"]["tip"].get<std::vector<double>>();
  const auto fp = pushed["wire"]["base_force"].get<std::vector<double>>(),
             fl = laid["wire"]["base_force"].get<std::vector<double>>();
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(tp[static_cast<size_t>(i)], tl[static_cast<size_t>(i)], 1e-8) << i;  // measured 5e-12 m
    EXPECT_NEAR(fp[static_cast<size_t>(i)], fl[static_cast<size_t>(i)], 1e-6) << i;  // measured 1e-9 N
  }
}
