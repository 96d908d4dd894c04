// Whole co-simulation step of a 400-vertex wire in a ~2,500-segment aortic network with
// contact, friction and blood drag (the published frame: 24.6 ms without rendering), and
// the same step with each feature off. Per-phase times are reported as counters.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <sstream>

#include "flowire/common/config.hpp"
#include "flowire/coupling/occlusion.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/coupling/vessel_forces.hpp"
#include "flowire/coupling/vessel_path.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/flow/spec.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire/vessels/generators.hpp"

using namespace flowire;
using vessels::Vec3;

namespace {

struct Scene {
  vessels::Network net;
  std::unique_ptr<vessels::SpatialIndex> index;
  std::unique_ptr<flow::FlowSolver> flow;
  std::unique_ptr<rod::RodSimulator> rod;
  std::shared_ptr<coupling::VesselForces> forces;
  double t = 0;

  Scene(bool contact, bool drag, double friction) {
    const auto c = vessels::aortic_arch();
    const double total = vessels::Network::build(c, {.max_segment_length = 1.0}).counts().total_length;
    net = vessels::Network::build(c, {.max_segment_length = total / 2500.0});
    index = std::make_unique<vessels::SpatialIndex>(net, 4);
    flow::FlowSpec spec = flow::default_spec(net, flow::Waveform::sine(16000, 10670, 0.833));
    flow = flow::make_solver(net, spec);
    rod::WireSpec w;
    w.length = 0.6;
    w.radius = 0.445e-3;
    w.youngs_modulus = 60e9;
    w.segment_length = 1e-3;
    w.tip.length = 0.03;
    w.tip.youngs_modulus = 10e9;
    const Vec3 entry = vessels::aortic_arch_entry();
    int end = -1;
    for (int e : net.ends())
      if ((net.node(e) - entry).norm() < 1e-9) end = e;
    const auto& seg = net.segment(*net.node_segments(end).first);
    const int other = seg.node_from == end ? seg.node_to : seg.node_from;
    w.base_position = entry;
    w.base_direction = (net.node(other) - entry).normalized();
    w.inserted_length = 0.02;
    rod = std::make_unique<rod::RodSimulator>(w);
    coupling::ContactParams cp;
    cp.enabled = contact;
    cp.stiffness = 3e4;
    cp.friction = cp.tip_friction = friction;
    coupling::DragModel dp;
    dp.law = drag ? coupling::DragLaw::SlenderBody : coupling::DragLaw::None;
    dp.wire_length = w.length;
    flow::FlowSolver* fs = flow.get();
    forces = std::make_shared<coupling::VesselForces>(*index, w.radius, cp, dp,
                                                      [fs](int s, const Vec3& p) { return fs->velocity_at(s, p); });
    rod->add_external(forces);
    // Feed 38 cm (about 400 vertices inside), then hold.
    rod->set_insertion_speed(0.1);
    while (rod->inserted_length() < 0.399) step(0.01);
    rod->set_insertion_speed(0.0);
    for (int i = 0; i < 20; ++i) step(0.01);
  }
  void step(double dt) {
    t += dt;
    flow->advance(t);
    rod->step(dt);
  }
};

void run(benchmark::State& state, bool contact, bool drag, double friction) {
  Scene s(contact, drag, friction);
  const auto before = s.forces->stats();
  for (auto _ : state) s.step(0.01);
  const auto& st = s.forces->stats();
  const double n = static_cast<double>(state.iterations());
  state.counters["vertices"] = s.rod->vertex_count();
  state.counters["segments"] = s.net.num_segments();
  state.counters["lookup_us"] = 1e6 * (st.seconds_lookup - before.seconds_lookup) / n;
  state.counters["contact_us"] = 1e6 * (st.seconds_contact - before.seconds_contact) / n;
  state.counters["drag_us"] = 1e6 * (st.seconds_drag - before.seconds_drag) / n;
  state.counters["newton_its"] = s.rod->last_report().newton_iterations;
}

/// The aortic-arch example (J tip, 2 mm segments, friction 0.2/0.05, cylinder drag,
/// pulsatile flow, dt = 10 ms) with `inserted` metres of wire laid on the vessel path and
/// settled against the walls, held there; the network sampled at `network_h`. With
/// `two_way` the wire occludes the segments it lies in (coupling.occlusion: annulus): the
/// flow is refactored and re-solved before every flow evaluation.
struct ArchExample {
  vessels::Network net;
  std::unique_ptr<vessels::SpatialIndex> index;
  std::unique_ptr<flow::FlowSolver> flow;
  std::unique_ptr<rod::RodSimulator> rod;
  std::shared_ptr<coupling::VesselForces> forces;
  std::unique_ptr<coupling::WireOcclusion> occlusion;
  double t = 0;

  ArchExample(double network_h, double inserted, bool two_way = false, double segment = 2e-3) {
    net = vessels::Network::build(vessels::aortic_arch(), {.max_segment_length = network_h});
    index = std::make_unique<vessels::SpatialIndex>(net, 4);
    // The example's flow: 120/80 mmHg at 72 bpm, 1 mmHg·s/mL split over the outlets by r³.
    const auto cfg = config::load_config_text(R"(
flow:
  solver: superposition
  inlet: {pressure: {waveform: sine, systolic: 120 mmHg, diastolic: 80 mmHg, period: 0.833 s}}
  outlets: {resistance: 1 mmHg*s/mL, scaling: murray}
)",
                                              "scene.yaml", coupling::scene_schema(), {});
    flow = flow::make_solver(net, flow::from_config(cfg, net));
    rod::WireSpec w;
    w.length = 0.8;
    w.radius = 0.445e-3;
    w.youngs_modulus = 60e9;
    w.density = 6450;
    w.segment_length = segment;
    w.tip.length = 0.03;
    w.tip.youngs_modulus = 10e9;
    w.tip.shape = rod::TipShape::J;
    w.tip.angle = std::numbers::pi;
    w.tip.bend_radius = 4e-3;
    const Vec3 entry = vessels::aortic_arch_entry();
    int end = -1;
    for (int e : net.ends())
      if ((net.node(e) - entry).norm() < 1e-9) end = e;
    const auto& seg = net.segment(*net.node_segments(end).first);
    const int other = seg.node_from == end ? seg.node_to : seg.node_from;
    w.base_position = entry;
    w.base_direction = (net.node(other) - entry).normalized();
    w.inserted_length = inserted;
    rod = std::make_unique<rod::RodSimulator>(w);
    const coupling::VesselPath path(net, end);
    rod->lay_along([&path](double s) { return path.wire_point(s); });
    coupling::ContactParams cp;
    cp.stiffness = 3e4;
    cp.friction = 0.2;
    cp.tip_friction = 0.05;
    cp.onset = 0.2 * w.radius;  // the scene's default (contact.onset)
    coupling::DragModel dp;     // the example's law: cylinder cross-flow drag + annular shear
    dp.law = coupling::DragLaw::Cylinder;
    dp.wire_radius = w.radius;
    dp.wire_length = w.length;
    flow::FlowSolver* fs = flow.get();
    forces = std::make_shared<coupling::VesselForces>(*index, w.radius, cp, dp,
                                                      [fs](int s, const Vec3& p) { return fs->velocity_at(s, p); });
    rod->add_external(forces);
    if (two_way) occlusion = std::make_unique<coupling::WireOcclusion>(*flow);
    (void)rod->solve_static();  // settle against the walls, as a scene does
    for (int i = 0; i < 20; ++i) step(0.01);
  }
  void step(double dt) {
    t += dt;
    if (occlusion)
      flow->set_occlusion(occlusion->update(rod->positions(), rod->first_clamped_vertex(), forces->segments(),
                                            rod->discretization().edge_radius));
    flow->advance(t);
    rod->step(dt);
  }
};

void run_arch(benchmark::State& state, double network_h, bool two_way = false, double inserted = 0.78) {
  ArchExample s(network_h, inserted, two_way);
  const auto flow_before = s.flow->timings();
  const auto before = s.forces->stats();
  const auto rod_before = s.rod->phase_seconds();
  long newton = 0, unconverged = 0;
  for (auto _ : state) {
    s.step(0.01);
    newton += s.rod->last_report().newton_iterations;
    unconverged += !s.rod->last_report().converged();
  }
  const auto& st = s.forces->stats();
  const auto& ph = s.rod->phase_seconds();
  const double n = static_cast<double>(state.iterations());
  state.counters["vertices"] = s.rod->vertex_count();
  state.counters["segments"] = s.net.num_segments();
  state.counters["lookup_us"] = 1e6 * (st.seconds_lookup - before.seconds_lookup) / n;
  state.counters["contact_us"] = 1e6 * (st.seconds_contact - before.seconds_contact) / n;
  state.counters["drag_us"] = 1e6 * (st.seconds_drag - before.seconds_drag) / n;
  state.counters["assembly_us"] = 1e6 * (ph.assembly - rod_before.assembly) / n;
  state.counters["factorize_us"] = 1e6 * (ph.factorize - rod_before.factorize) / n;
  state.counters["line_search_us"] = 1e6 * (ph.line_search - rod_before.line_search) / n;
  state.counters["newton_per_step"] = static_cast<double>(newton) / n;
  state.counters["unconverged"] = static_cast<double>(unconverged);
  state.counters["flow_us"] = 1e6 * (s.flow->timings().frames - flow_before.frames) / n;
  state.counters["occlusion_us"] = 1e6 * (s.flow->timings().occlusion - flow_before.occlusion) / n;
  if (s.occlusion) state.counters["occupied_segments"] = s.occlusion->stats().occupied_segments;
}

void BM_ArchExample78cm_5mmNetwork(benchmark::State& st) { run_arch(st, 5e-3); }
void BM_ArchExample78cm_1mmNetwork(benchmark::State& st) { run_arch(st, 1e-3); }
BENCHMARK(BM_ArchExample78cm_5mmNetwork)->Unit(benchmark::kMillisecond)->Iterations(200);
BENCHMARK(BM_ArchExample78cm_1mmNetwork)->Unit(benchmark::kMillisecond)->Iterations(200);
// Two-way coupling (the wire occludes the flow) against the one-way case above.
void BM_ArchExample78cm_5mmNetwork_TwoWay(benchmark::State& st) { run_arch(st, 5e-3, true); }
void BM_ArchExample78cm_1mmNetwork_TwoWay(benchmark::State& st) { run_arch(st, 1e-3, true); }
BENCHMARK(BM_ArchExample78cm_5mmNetwork_TwoWay)->Unit(benchmark::kMillisecond)->Iterations(200);
BENCHMARK(BM_ArchExample78cm_1mmNetwork_TwoWay)->Unit(benchmark::kMillisecond)->Iterations(200);

/// The wire as every study moves it: held, pushed or pulled at 2 cm/s, or pushed while
/// turned at π rad/s, with `inserted` metres in the arch at `segment` metres a vertex
/// (about inserted/segment vertices in contact), everything on (friction, cylinder drag,
/// pulsatile flow, 5 mm network). Counters: Newton iterations and unconverged steps.
/// `slide`: Newton starts from the slide while the wire is fed (rod::SolverSettings::slide_guess);
/// without it, from the inertial guess (the baseline of BM_ArchPushedInertialGuess).
/// `Forced`: pushed by a constant force at the base (insertion.force) instead of a speed.
enum class Drive { Held, Pushed, Pulled, Turned, Forced };
void run_driven(benchmark::State& state, Drive drive, bool slide = true) {
  const double inserted = 1e-3 * static_cast<double>(state.range(0));
  const double segment = 1e-6 * static_cast<double>(state.range(1));
  ArchExample s(5e-3, inserted, false, segment);
  s.rod->settings().slide_guess = slide;
  if (drive == Drive::Pushed || drive == Drive::Turned) s.rod->set_insertion_speed(0.02);
  if (drive == Drive::Pulled) s.rod->set_insertion_speed(-0.02);
  if (drive == Drive::Turned) s.rod->set_rotation_speed(std::numbers::pi);
  if (drive == Drive::Forced) s.rod->set_push_force(0.1);
  for (int i = 0; i < 5; ++i) s.step(0.01);  // past the start of the feed
  const auto before = s.rod->solver_totals();
  const double fed_before = s.rod->inserted_length();
  for (auto _ : state) s.step(0.01);
  const auto& after = s.rod->solver_totals();
  const double n = static_cast<double>(state.iterations());
  state.counters["vertices"] = s.rod->vertex_count();
  state.counters["newton_per_step"] = static_cast<double>(after.newton_iterations - before.newton_iterations) / n;
  state.counters["factorizations_per_step"] = static_cast<double>(after.factorizations - before.factorizations) / n;
  state.counters["unconverged"] = static_cast<double>(after.unconverged_steps - before.unconverged_steps);
  state.counters["fed_mm_per_step"] = 1e3 * (s.rod->inserted_length() - fed_before) / n;
}
void BM_ArchHeld(benchmark::State& st) { run_driven(st, Drive::Held); }
void BM_ArchPushed(benchmark::State& st) { run_driven(st, Drive::Pushed); }
void BM_ArchPulled(benchmark::State& st) { run_driven(st, Drive::Pulled); }
void BM_ArchTurned(benchmark::State& st) { run_driven(st, Drive::Turned); }
void BM_ArchPushedInertialGuess(benchmark::State& st) { run_driven(st, Drive::Pushed, false); }
void BM_ArchForced(benchmark::State& st) { run_driven(st, Drive::Forced); }
#define FLOWIRE_DRIVEN_ARGS               \
  ArgNames({"inserted_mm", "segment_um"}) \
      ->Args({200, 1000})                 \
      ->Args({400, 1000})                 \
      ->Args({425, 250})                  \
      ->Unit(benchmark::kMillisecond)     \
      ->Iterations(100)
BENCHMARK(BM_ArchHeld)->FLOWIRE_DRIVEN_ARGS;
BENCHMARK(BM_ArchPushed)->FLOWIRE_DRIVEN_ARGS;
BENCHMARK(BM_ArchPulled)->FLOWIRE_DRIVEN_ARGS;
BENCHMARK(BM_ArchTurned)->FLOWIRE_DRIVEN_ARGS;
BENCHMARK(BM_ArchPushedInertialGuess)->FLOWIRE_DRIVEN_ARGS;
BENCHMARK(BM_ArchForced)->FLOWIRE_DRIVEN_ARGS;

// Scaling of each phase: against the inserted length (args: cm inserted, network 5 mm) and
// against the network's sampling (args: 78 cm, network in tenths of a mm).
void BM_ArchScaling(benchmark::State& st) {
  run_arch(st, 1e-4 * static_cast<double>(st.range(1)), false, 0.01 * static_cast<double>(st.range(0)));
}
BENCHMARK(BM_ArchScaling)
    ->Args({20, 50})
    ->Args({39, 50})
    ->Args({78, 50})
    ->Args({78, 20})
    ->Args({78, 10})
    ->Args({78, 5})
    ->ArgNames({"inserted_cm", "network_tenth_mm"})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(200);

void BM_CoSimStep_All(benchmark::State& st) { run(st, true, true, 0.1); }
void BM_CoSimStep_NoFriction(benchmark::State& st) { run(st, true, true, 0.0); }
void BM_CoSimStep_NoDrag(benchmark::State& st) { run(st, true, false, 0.1); }
void BM_CoSimStep_NoContact(benchmark::State& st) { run(st, false, true, 0.0); }
BENCHMARK(BM_CoSimStep_All)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_CoSimStep_NoFriction)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_CoSimStep_NoDrag)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_CoSimStep_NoContact)->Unit(benchmark::kMillisecond)->MinTime(2.0);

/// The Feel++ arch's folder in FLOWIRE_SHARED_DIR or ../shared next to the source tree;
/// empty (and the benchmark marked skipped, saying where it looked) when it is absent.
std::filesystem::path feelpp_arch_data(benchmark::State& state) {
  const char* env = std::getenv("FLOWIRE_SHARED_DIR");
  const std::filesystem::path shared =
      env ? std::filesystem::path(env) : std::filesystem::path(FLOWIRE_BENCH_SOURCE_DIR).parent_path() / "shared";
  const auto data = shared / "data/real/feelpp-aortic-arch";
  if (std::filesystem::exists(data / "aorta2.stl")) return data;
  state.SkipWithError(("shared data not found at " + data.string()).c_str());
  return {};
}

/// Surface contact against cylinder contact per step on the Feel++ aortic arch
/// (examples/real/feelpp_arch.yaml as it is: the J tip pushed from 2 to 12 cm over the arch
/// against the flow): the same scene run once with its lumen surface as the wall and once with
/// the network's cylinders; contact = lookup + wall distance + penalty + friction, per step.
void BM_RealArch_SurfaceVsCylinderContact(benchmark::State& state) {
  const auto data = feelpp_arch_data(state);
  if (data.empty()) return;
  const auto scene = std::filesystem::path(FLOWIRE_BENCH_SOURCE_DIR) / "examples/real/feelpp_arch.yaml";
  const auto out = std::filesystem::temp_directory_path() / "flowire-bench-real-arch";
  auto contact_per_step = [&](bool surface) {
    std::vector<std::string> sets = {"vessels.file=" + (data / "centerlinesAORTA.vtk").string(), "output.vtk=false",
                                     "output.csv=false", "output.dir=" + out.string()};
    std::ifstream in(scene);
    std::string text, line;
    while (std::getline(in, line))
      if (line.find("  surface:") != 0) text += line + "\n";  // the scene without its surface
    if (surface) sets.push_back("vessels.surface=" + (data / "aorta2.stl").string());
    const auto cfg = config::load_config_text(text, scene.string(), coupling::scene_schema(), sets);
    const auto r = coupling::run_scene(cfg);
    return r.summary["timings"]["contact"].get<double>() / r.summary["steps"].get<double>();
  };
  double s_surface = 0, s_cyl = 0;
  for (auto _ : state) {
    s_surface = contact_per_step(true);
    s_cyl = contact_per_step(false);
  }
  state.counters["surface_contact_us_per_step"] = 1e6 * s_surface;
  state.counters["cylinder_contact_us_per_step"] = 1e6 * s_cyl;
  state.counters["surface_over_cylinder"] = s_surface / s_cyl;
}
BENCHMARK(BM_RealArch_SurfaceVsCylinderContact)->Unit(benchmark::kSecond)->Iterations(1);

/// A scene run's counters: ms a step (the steps alone: without the setup, the start's settling
/// and first flow frame, and the outputs), Newton iterations a step, unconverged steps.
void run_counters(benchmark::State& state, const nlohmann::json& summary) {
  const double steps = summary["steps"].get<double>();
  const auto& t = summary["timings"];
  state.counters["ms_per_step"] = 1e3 * t["stepping"].get<double>() / steps;
  state.counters["newton_per_step"] = summary["wire"]["solver"]["newton_iterations_per_step"].get<double>();
  state.counters["unconverged"] = summary["wire"]["unconverged_steps"].get<double>();
  if (summary.contains("wall")) {
    state.counters["wall_seconds"] = summary["wall"]["seconds"].get<double>();
    state.counters["compliance_columns"] = summary["wall"]["compliance_columns"].get<double>();
    state.counters["columns_ahead"] = summary["wall"]["compliance_columns_ahead"].get<double>();
    state.counters["ms_per_step_ahead"] = 1e3 * summary["wall"]["seconds_ahead"].get<double>() / steps;
  }
}

/// Run the scene @p text (read from @p scene) with @p sets through the scene runner in the
/// benchmark's loop, and record run_counters of its summary.
void run_scene_text(benchmark::State& state, const std::string& text, const std::filesystem::path& scene,
                    const std::vector<std::string>& sets) {
  nlohmann::json summary;
  for (auto _ : state) {
    const auto cfg = config::load_config_text(text, scene.string(), coupling::scene_schema(), sets);
    summary = coupling::run_scene(cfg).summary;
  }
  run_counters(state, summary);
}

/// The same for the scene file @p scene.
void run_scene_file(benchmark::State& state, const std::filesystem::path& scene, const std::vector<std::string>& sets) {
  std::ifstream in(scene);
  std::stringstream text;
  text << in.rdbuf();
  run_scene_text(state, text.str(), scene, sets);
}

/// The driven variants on a real lumen: the Feel++ aortic arch with its own surface as the
/// wall (examples/real/feelpp_arch.yaml), 10 cm of the J-tipped wire inside at 1 mm a
/// vertex, held, pushed or pulled at 2 cm/s, or pushed while turned at π rad/s, for 100
/// steps of 10 ms through the scene runner (flow, drag, friction on). Counters: ms a step
/// (the steps alone), Newton iterations a step, unconverged steps.
void BM_RealArchDriven(benchmark::State& state) {
  const auto data = feelpp_arch_data(state);
  if (data.empty()) return;
  const auto scene = std::filesystem::path(FLOWIRE_BENCH_SOURCE_DIR) / "examples/real/feelpp_arch.yaml";
  const auto drive = static_cast<Drive>(state.range(0));
  std::vector<std::string> sets = {
      "vessels.file=" + (data / "centerlinesAORTA.vtk").string(),
      "vessels.surface=" + (data / "aorta2.stl").string(),
      "wire.segment_length=1mm",
      "insertion.initial_length=10cm",
      "insertion.max_length=14cm",
      "solve.duration=1s",
      "output.vtk=false",
      "output.csv=false",
      "output.png=false",
      "output.dir=" + (std::filesystem::temp_directory_path() / "flowire-bench-real-driven").string()};
  sets.push_back(drive == Drive::Held     ? "insertion.speed=0"
                 : drive == Drive::Pulled ? "insertion.speed=-2cm/s"
                                          : "insertion.speed=2cm/s");
  if (drive == Drive::Turned) sets.push_back("insertion.rotation_speed=3.14159");
  run_scene_file(state, scene, sets);
}
BENCHMARK(BM_RealArchDriven)
    ->ArgName("drive")
    ->Arg(static_cast<int>(Drive::Held))
    ->Arg(static_cast<int>(Drive::Pushed))
    ->Arg(static_cast<int>(Drive::Pulled))
    ->Arg(static_cast<int>(Drive::Turned))
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

/// The wire inside a catheter (examples/catheter_arch/scene.yaml: a 6 F catheter parked in the
/// arch, the 0.035" wire 58 cm in, steered into the left subclavian), held (arg 0) or pushed out of
/// the catheter at the example's 1 cm/s (arg 1), 200 steps of 5 ms through the scene runner.
/// Counters as BM_RealArchDriven's (the wire and the catheter are one Newton solve: its iterations).
void BM_CatheterArchDriven(benchmark::State& state) {
  const auto scene = std::filesystem::path(FLOWIRE_BENCH_SOURCE_DIR) / "examples/catheter_arch/scene.yaml";
  const std::vector<std::string> sets = {
      state.range(0) == 0 ? "insertion.speed=0" : "insertion.speed=1cm/s",
      "solve.duration=1s",
      "output.vtk=false",
      "output.csv=false",
      "output.png=false",
      "output.dir=" + (std::filesystem::temp_directory_path() / "flowire-bench-catheter-driven").string()};
  run_scene_file(state, scene, sets);
}
BENCHMARK(BM_CatheterArchDriven)->ArgName("pushed")->Arg(0)->Arg(1)->Unit(benchmark::kSecond)->Iterations(1);

/// A wall that yields against the rigid one: examples/deformable_wall/scene.yaml (a J tip
/// pushed at 1 cm/s along a soft straight artery, 200 vertices) for 100 steps of 10 ms through
/// the scene runner, its wall: section removed for the rigid run (arg 0) or kept (arg 1).
/// Counters: ms a step (the steps alone), Newton iterations a step,
/// unconverged steps, the wall's seconds and its compliance columns.
void BM_DeformableWallPush(benchmark::State& state) {
  const auto scene = std::filesystem::path(FLOWIRE_BENCH_SOURCE_DIR) / "examples/deformable_wall/scene.yaml";
  std::ifstream in(scene);
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string text = buffer.str();
  if (state.range(0) == 0) {
    const auto a = text.find("\nwall:\n"), b = text.find("\nsolve:");
    if (a == std::string::npos || b == std::string::npos || b < a) {
      state.SkipWithError("examples/deformable_wall/scene.yaml has no wall: section before solve:");
      return;
    }
    text.erase(a, b - a);
  }
  run_scene_text(state, text, scene,
                 {"solve.duration=1s", "output.vtk=false", "output.csv=false", "output.png=false",
                  "output.dir=" + (std::filesystem::temp_directory_path() / "flowire-bench-wall").string()});
}
BENCHMARK(BM_DeformableWallPush)->ArgName("deformable")->Arg(0)->Arg(1)->Unit(benchmark::kSecond)->Iterations(1);

/// The wall of a real anatomy against its rigid surface: the Feel++ arch with a 400-vertex wire
/// (0.25 mm segments, 10 cm inside) pushed at 2 cm/s for 100 steps of 10 ms through the scene
/// runner, examples/real/feelpp_arch.yaml (arg 0, the rigid surface) or feelpp_arch_wall.yaml
/// (arg 1: the wall grown around the same surface, the blood pressure on it, the flow's radii
/// from it). Counters as BM_DeformableWallPush's.
void BM_RealArchWall(benchmark::State& state) {
  const auto data = feelpp_arch_data(state);
  if (data.empty()) return;
  const auto scene = std::filesystem::path(FLOWIRE_BENCH_SOURCE_DIR) /
                     (state.range(0) == 0 ? "examples/real/feelpp_arch.yaml" : "examples/real/feelpp_arch_wall.yaml");
  const std::vector<std::string> sets = {
      "vessels.file=" + (data / "centerlinesAORTA.vtk").string(),
      "vessels.surface=" + (data / "aorta2.stl").string(),
      "wire.segment_length=0.25mm",
      "insertion.initial_length=10cm",
      "insertion.max_length=14cm",
      "insertion.speed=2cm/s",
      "solve.duration=1s",
      "output.vtk=false",
      "output.csv=false",
      "output.png=false",
      "output.dir=" + (std::filesystem::temp_directory_path() / "flowire-bench-real-wall").string()};
  run_scene_file(state, scene, sets);
}
BENCHMARK(BM_RealArchWall)->ArgName("deformable")->Arg(0)->Arg(1)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace
