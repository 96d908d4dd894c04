// Whole co-simulation step of a 400-vertex wire in a ~2,500-segment aortic network with
// contact, friction and blood drag (the published frame: 24.6 ms without rendering), and
// the same step with each feature off. Per-phase times are reported as counters.
#include <benchmark/benchmark.h>

#include <memory>

#include "flowire/coupling/vessel_forces.hpp"
#include "flowire/flow/solver.hpp"
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

void BM_CoSimStep_All(benchmark::State& st) { run(st, true, true, 0.1); }
void BM_CoSimStep_NoFriction(benchmark::State& st) { run(st, true, true, 0.0); }
void BM_CoSimStep_NoDrag(benchmark::State& st) { run(st, true, false, 0.1); }
void BM_CoSimStep_NoContact(benchmark::State& st) { run(st, false, true, 0.0); }
BENCHMARK(BM_CoSimStep_All)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_CoSimStep_NoFriction)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_CoSimStep_NoDrag)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_CoSimStep_NoContact)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace
