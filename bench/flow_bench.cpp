// Flow solver benchmarks.
//
// 1. Per-frame cost on a network of the published size (2,477 vessels, 2,478 nodes,
//    2,488 edges: 11 loops): the published dense K⁻¹ product against superposition
//    (full frame, and the lazy frame that evaluates only the 100 segments a wire touches)
//    and a sparse direct solve per frame. BM_FrameRatio measures both in one run.
// 2. Setup (assembly + CHOLMOD factorization + per-source solves) of binary trees from
//    10³ to 10⁶ segments with superposition: time, retained memory, full-frame cost.
// 3. A calibrated network (quadratic segment laws, the newton solver) against Poiseuille,
//    full frames in one run (BM_CalibratedFrameRatio).
// 4. flow.model: rlc on binary trees of 2^(depth+1) − 1 segments: one time step, and one
//    change of the occlusion (refactorization of the step matrix) followed by a step.
//
// Run: build-flow/bench/bench_flow --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <unistd.h>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <random>

#include "flowire/common/units.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/vessels/generators.hpp"

namespace {

using namespace flowire;
using flow::FlowSpec;
using flow::Network;
using flow::Vec3;

/// A random tree of `vessels` segments plus `loops` segments closing loops (fixed seed).
Network published_size_network(int vessels = 2477, int loops = 11) {
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> nodes = {Vec3::Zero(), Vec3(0.01, 0, 0)};
  std::vector<int> degree = {1, 1};
  std::vector<vessels::Segment> segs = {{0, 1, 12e-3, 0.0, -1}};
  std::vector<double> radius_at = {12e-3, 12e-3};
  for (int i = 1; i < vessels; ++i) {
    int parent = 0;
    do parent = 1 + static_cast<int>(u(rng) * static_cast<double>(nodes.size() - 1));
    while (parent >= static_cast<int>(nodes.size()) || degree[static_cast<size_t>(parent)] >= 3);
    const double r = std::max(0.4e-3, radius_at[static_cast<size_t>(parent)] * (0.75 + 0.2 * u(rng)));
    nodes.push_back(nodes[static_cast<size_t>(parent)] + 5e-3 * Vec3(u(rng) - 0.3, u(rng) - 0.5, u(rng) - 0.5));
    degree.push_back(1);
    radius_at.push_back(r);
    ++degree[static_cast<size_t>(parent)];
    segs.push_back({parent, static_cast<int>(nodes.size()) - 1, r, 0.0, -1});
  }
  for (int k = 0; k < loops; ++k) {
    int a = 0, b = 0;
    do {
      a = 1 + static_cast<int>(u(rng) * static_cast<double>(nodes.size() - 2));
      b = 1 + static_cast<int>(u(rng) * static_cast<double>(nodes.size() - 2));
    } while (a == b || degree[static_cast<size_t>(a)] < 2 || degree[static_cast<size_t>(b)] < 2);
    segs.push_back({a, b, 1e-3, 0.0, -1});
  }
  return Network::from_graph(nodes, segs, {}, "published-size benchmark network");
}

FlowSpec spec_for(const Network& net, flow::SolverKind kind) {
  FlowSpec s = flow::default_spec(net, flow::Waveform::sine(120 * units::mmHg, 80 * units::mmHg, 60.0 / 72.0));
  for (auto& o : s.outlets) {
    o.type = flow::OutletBC::Type::Resistance;
    o.resistance = 5e9;
  }
  s.solver = kind;
  return s;
}

const Network& published() {
  static const Network net = published_size_network();
  return net;
}

flow::FlowSolver& solver(flow::SolverKind kind) {
  static std::unique_ptr<flow::FlowSolver> cache[4];
  auto& s = cache[static_cast<int>(kind)];
  if (!s) s = flow::make_solver(published(), spec_for(published(), kind));
  return *s;
}

/// The segments a 100-vertex wire would touch: a path of consecutive segments.
std::vector<int> wire_segments() {
  std::vector<int> s;
  for (int i = 0; i < 100; ++i) s.push_back((i * 7) % published().num_segments());
  return s;
}

void full_frame(flow::FlowSolver& s, double t, std::vector<double>& p, std::vector<double>& q) {
  s.solve_at(t, p, q);
  benchmark::DoNotOptimize(p.data());
  benchmark::DoNotOptimize(q.data());
}

void BM_Frame(benchmark::State& state) {
  const auto kind = static_cast<flow::SolverKind>(state.range(0));
  auto& s = solver(kind);
  std::vector<double> p(static_cast<size_t>(published().num_nodes())),
      q(static_cast<size_t>(published().num_segments()));
  double t = 0.0;
  for (auto _ : state) {
    full_frame(s, t, p, q);
    t += 1e-3;
  }
  state.SetLabel(std::string(s.name()) + " (all pressures and flows)");
  state.counters["setup_s"] = s.timings().assemble + s.timings().factor;
  state.counters["segments"] = published().num_segments();
}
BENCHMARK(BM_Frame)
    ->Arg(static_cast<int>(flow::SolverKind::DenseInverse))
    ->Arg(static_cast<int>(flow::SolverKind::Superposition))
    ->Arg(static_cast<int>(flow::SolverKind::Sparse))
    ->Unit(benchmark::kMicrosecond);

void BM_FrameLazy100Segments(benchmark::State& state) {
  auto& s = solver(flow::SolverKind::Superposition);
  const auto segs = wire_segments();
  double t = 0.0, sum = 0.0;
  for (auto _ : state) {
    s.advance(t);
    for (int k : segs) sum += s.segment_flow(k);
    benchmark::DoNotOptimize(sum);
    t += 1e-3;
  }
  state.SetLabel("superposition, advance + 100 segment flows");
}
BENCHMARK(BM_FrameLazy100Segments)->Unit(benchmark::kMicrosecond);

void BM_VelocityQuery(benchmark::State& state) {
  auto& s = solver(flow::SolverKind::Superposition);
  s.advance(0.1);
  const auto& net = published();
  double sum = 0.0;
  int k = 0;
  for (auto _ : state) {
    const auto& seg = net.segment(k);
    const Vec3 p = 0.5 * (net.node(seg.node_from) + net.node(seg.node_to));
    sum += s.velocity_at(k, p).x();
    benchmark::DoNotOptimize(sum);
    k = (k + 1) % net.num_segments();
  }
  state.SetLabel("velocity_at(segment, point), laminar");
}
BENCHMARK(BM_VelocityQuery);

/// Thread CPU time (s): robust to other processes sharing the machine.
double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// Both methods timed in the same run (thread CPU time): dense_inverse frame vs
/// superposition frame.
void BM_FrameRatio(benchmark::State& state) {
  auto& dense = solver(flow::SolverKind::DenseInverse);
  auto& sup = solver(flow::SolverKind::Superposition);
  const auto segs = wire_segments();
  std::vector<double> p(static_cast<size_t>(published().num_nodes())),
      q(static_cast<size_t>(published().num_segments()));
  double dense_s = 0.0, full_s = 0.0, lazy_s = 0.0, sum = 0.0;
  long n = 0;
  for (auto _ : state) {
    const double t = 1e-3 * static_cast<double>(n);
    const double a = cpu_seconds();
    full_frame(dense, t, p, q);
    const double b = cpu_seconds();
    for (int r = 0; r < 100; ++r) full_frame(sup, t + r * 1e-6, p, q);
    const double c = cpu_seconds();
    for (int r = 0; r < 1000; ++r) {
      sup.advance(t + r * 1e-7);
      for (int k : segs) sum += sup.segment_flow(k);
    }
    const double d = cpu_seconds();
    benchmark::DoNotOptimize(sum);
    dense_s += b - a;
    full_s += (c - b) / 100.0;
    lazy_s += (d - c) / 1000.0;
    ++n;
  }
  state.counters["dense_ms"] = 1e3 * dense_s / static_cast<double>(n);
  state.counters["superposition_full_us"] = 1e6 * full_s / static_cast<double>(n);
  state.counters["superposition_100seg_us"] = 1e6 * lazy_s / static_cast<double>(n);
  state.counters["ratio_full"] = dense_s / full_s;
  state.counters["ratio_100seg"] = dense_s / lazy_s;
}
BENCHMARK(BM_FrameRatio)->Unit(benchmark::kMillisecond)->Iterations(20);

/// A calibrated network (vessels.calibration, the newton solver) against Poiseuille
/// (superposition), full frames, in one run: every segment's quadratic term equal to its linear
/// one at its mean Poiseuille flow (K = R/|Q̄|), a strongly nonlinear network; frames 1 ms apart
/// over the pulsatile inlet (each Newton starts from the last frame).
void BM_CalibratedFrameRatio(benchmark::State& state) {
  auto& sup = solver(flow::SolverKind::Superposition);
  static std::unique_ptr<flow::FlowSolver> cal;
  if (!cal) {
    FlowSpec spec = spec_for(published(), flow::SolverKind::Superposition);
    std::vector<double> p(static_cast<size_t>(published().num_nodes())),
        q(static_cast<size_t>(published().num_segments()));
    sup.solve_at(0.25, p, q);
    for (int k = 0; k < published().num_segments(); ++k)
      spec.segment_laws.push_back({1.0, sup.resistance(k) / std::max(std::abs(q[static_cast<size_t>(k)]), 1e-12)});
    cal = flow::make_solver(published(), spec);
  }
  std::vector<double> p(static_cast<size_t>(published().num_nodes())),
      q(static_cast<size_t>(published().num_segments()));
  double poiseuille_s = 0.0, calibrated_s = 0.0, t = 0.0;
  long n = 0;
  for (auto _ : state) {
    const double a = cpu_seconds();
    for (int r = 0; r < 20; ++r) full_frame(sup, t + 1e-3 * r, p, q);
    const double b = cpu_seconds();
    for (int r = 0; r < 20; ++r) full_frame(*cal, t + 1e-3 * r, p, q);
    const double c = cpu_seconds();
    poiseuille_s += (b - a) / 20.0;
    calibrated_s += (c - b) / 20.0;
    t += 0.02;
    ++n;
  }
  state.SetLabel(std::string(cal->name()) + " vs " + std::string(sup.name()));
  state.counters["poiseuille_us"] = 1e6 * poiseuille_s / static_cast<double>(n);
  state.counters["calibrated_us"] = 1e6 * calibrated_s / static_cast<double>(n);
  state.counters["ratio"] = calibrated_s / poiseuille_s;
}
BENCHMARK(BM_CalibratedFrameRatio)->Unit(benchmark::kMillisecond)->Iterations(10);

double rss_mb() {
  std::ifstream in("/proc/self/statm");
  long pages = 0, resident = 0;
  in >> pages >> resident;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / 1e6;
}

/// Setup and frame cost of superposition on binary trees of 2^(depth+1) − 1 segments.
void BM_TreeSetup(benchmark::State& state) {
  vessels::BinaryTreeParams bp;
  bp.depth = static_cast<int>(state.range(0));
  const Network net = vessels::binary_tree(bp);
  FlowSpec spec = flow::default_spec(net, flow::Waveform::sine(16000.0, 10666.0, 0.8));
  double setup = 0.0, mem = 0.0, frame = 0.0;
  long n = 0;
  for (auto _ : state) {
    const double before = rss_mb();
    const auto t0 = std::chrono::steady_clock::now();
    auto s = flow::make_solver(net, spec);
    const auto t1 = std::chrono::steady_clock::now();
    mem = rss_mb() - before;
    std::vector<double> p(static_cast<size_t>(net.num_nodes())), q(static_cast<size_t>(net.num_segments()));
    const auto t2 = std::chrono::steady_clock::now();
    s->solve_at(0.2, p, q);
    const auto t3 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(q.data());
    setup += std::chrono::duration<double>(t1 - t0).count();
    frame += std::chrono::duration<double>(t3 - t2).count();
    ++n;
  }
  state.SetComplexityN(net.num_segments());
  state.counters["segments"] = net.num_segments();
  state.counters["setup_s"] = setup / static_cast<double>(n);
  state.counters["full_frame_ms"] = 1e3 * frame / static_cast<double>(n);
  state.counters["retained_MB"] = mem;
}
BENCHMARK(BM_TreeSetup)->DenseRange(9, 19, 1)->Unit(benchmark::kMillisecond)->Iterations(1)->Complexity(benchmark::oN);

/// The rlc model on a binary tree: one generalized-α step (BM_RlcStep) and one occlusion
/// change with its refactorization plus a step (BM_RlcOcclusion).
std::unique_ptr<flow::FlowSolver> rlc_tree(int depth, Network& net) {
  vessels::BinaryTreeParams bp;
  bp.depth = depth;
  net = vessels::binary_tree(bp);
  FlowSpec spec = flow::default_spec(net, flow::Waveform::sine(16000.0, 10666.0, 0.8));
  spec.model = flow::Model::Rlc;
  spec.max_cycles = 2;  // setup is not measured
  return flow::make_solver(net, spec);
}

void BM_RlcStep(benchmark::State& state) {
  Network net;
  auto s = rlc_tree(static_cast<int>(state.range(0)), net);
  double t = 0.0;
  for (auto _ : state) {
    t += 1e-3;
    s->advance(t);
    benchmark::DoNotOptimize(s->segment_flow(0));
  }
  state.counters["segments"] = net.num_segments();
}
BENCHMARK(BM_RlcStep)->Arg(8)->Arg(11)->Arg(14)->Unit(benchmark::kMicrosecond);

void BM_RlcOcclusion(benchmark::State& state) {
  Network net;
  auto s = rlc_tree(static_cast<int>(state.range(0)), net);
  std::vector<flow::SegmentOcclusion> occ(static_cast<size_t>(net.num_segments()));
  double t = 0.0;
  long k = 0;
  for (auto _ : state) {
    occ[1].resistance_factor = occ[1].inertance_factor = (++k % 2) ? 1.5 : 1.2;
    s->set_occlusion(occ);
    t += 1e-3;
    s->advance(t);
    benchmark::DoNotOptimize(s->segment_flow(0));
  }
  state.counters["segments"] = net.num_segments();
}
BENCHMARK(BM_RlcOcclusion)->Arg(8)->Arg(11)->Arg(14)->Unit(benchmark::kMicrosecond);

}  // namespace
