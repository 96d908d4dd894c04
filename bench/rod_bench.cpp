// Rod benchmarks: implicit step time against the number of vertices, one step of a
// 1.7 m / 1 mm guidewire, and the banded LDLᵀ against a general sparse LDLᵀ on the same
// Newton matrices (same run, so the ratio is meaningful).
#include <benchmark/benchmark.h>

#include <Eigen/SparseCholesky>
#include <memory>
#include <random>

#include "flowire/rod/banded.hpp"
#include "flowire/rod/simulator.hpp"

namespace {

using flowire::rod::BandedLDLT;
using flowire::rod::BandedMatrix;
using flowire::rod::LinearSolver;
using flowire::rod::RodSimulator;
using flowire::rod::WireSpec;

/// A realistic wire with `vertices` simulated vertices (1 mm segments), J tip, gravity.
WireSpec guidewire(int vertices) {
  WireSpec spec;
  spec.segment_length = 1e-3;
  spec.length = (vertices - 2) * 1e-3;
  spec.youngs_modulus = 67e9;
  spec.radius = 4.45e-4;
  spec.tip.length = std::min(0.03, 0.5 * spec.length);
  spec.tip.youngs_modulus = 10e9;
  spec.tip.shape = flowire::rod::TipShape::J;
  spec.tip.bend_radius = 0.003;
  spec.damping = 1e-3;
  return spec;
}

/// The cost of a step (Newton iterations) changes as the wire moves: the same sequence of
/// kCycle steps is timed over and over (the simulator rebuilt between cycles, untimed), and
/// the step benchmarks run a whole number of cycles, so two builds measure the same work.
constexpr int kCycle = 200;

void run_steps(benchmark::State& state, LinearSolver solver) {
  const int n = static_cast<int>(state.range(0));
  const double dt = 1e-3;
  auto make = [&] {
    auto sim = std::make_unique<RodSimulator>(guidewire(n));
    sim->settings().linear_solver = solver;
    sim->set_gravity({0.0, 0.0, -9.81});
    sim->set_rotation_speed(2.0);
    for (int i = 0; i < 3; ++i) sim->step(dt);  // leave the initial transient
    return sim;
  };
  auto sim = make();
  int in_cycle = 0;
  long iterations = 0, fallbacks = 0;
  for (auto _ : state) {
    if (in_cycle == kCycle) {
      state.PauseTiming();
      sim = make();
      in_cycle = 0;
      state.ResumeTiming();
    }
    const auto r = sim->step(dt);
    ++in_cycle;
    iterations += r.newton_iterations;
    fallbacks += r.regularizations;
    benchmark::DoNotOptimize(sim->tip_position());
  }
  state.counters["vertices"] = sim->vertex_count();
  state.counters["newton_per_step"] =
      benchmark::Counter(static_cast<double>(iterations), benchmark::Counter::kAvgIterations);
  state.counters["psd_fallbacks_per_step"] =
      benchmark::Counter(static_cast<double>(fallbacks), benchmark::Counter::kAvgIterations);
  state.SetComplexityN(n);
}

void BM_RodStepBanded(benchmark::State& state) { run_steps(state, LinearSolver::Banded); }
void BM_RodStepSparse(benchmark::State& state) { run_steps(state, LinearSolver::SparseLDLT); }

BENCHMARK(BM_RodStepBanded)
    ->RangeMultiplier(10)
    ->Range(10, 10000)
    ->Arg(1700)
    ->Iterations(2 * kCycle)
    ->Unit(benchmark::kMicrosecond)
    ->Complexity(benchmark::oN);
BENCHMARK(BM_RodStepSparse)->Arg(100)->Arg(1700)->Arg(10000)->Iterations(kCycle)->Unit(benchmark::kMicrosecond);

/// A random SPD matrix with the rod's band (half-width 10), n unknowns.
BandedMatrix rod_like_matrix(int n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  BandedMatrix a(n, 10);
  for (int i = 0; i < n; ++i) {
    for (int j = std::max(0, i - 10); j < i; ++j) a.lower(i, j) = u(rng);
    a.lower(i, i) = 25.0 + u(rng);
  }
  return a;
}

void BM_FactorSolveBanded(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const BandedMatrix a = rod_like_matrix(n);
  BandedLDLT ldlt;
  ldlt.reserve(n, 10);
  Eigen::VectorXd x(n);
  for (auto _ : state) {
    ldlt.factorize(a);
    x.setOnes();
    ldlt.solve_in_place(x);
    benchmark::DoNotOptimize(x.data());
  }
}

void BM_FactorSolveSparse(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const BandedMatrix a = rod_like_matrix(n);
  Eigen::SparseMatrix<double> s;
  a.to_sparse_lower(s);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt;
  ldlt.analyzePattern(s);  // symbolic factorization kept, as in the simulator
  Eigen::VectorXd b = Eigen::VectorXd::Ones(n), x(n);
  for (auto _ : state) {
    ldlt.factorize(s);
    x = ldlt.solve(b);
    benchmark::DoNotOptimize(x.data());
  }
}

/// One bend/twist stencil: value, gradient and exact Hessian (the assembly's kernel).
/// Arg 0: gradient only (the line search), 1: with the Hessian (Newton matrix), 2: with the
/// Gauss–Newton Hessian. The edge geometry is computed outside the timed kernel, as the
/// simulator computes it once per edge.
template <auto Kernel>
void bend_twist_kernel(benchmark::State& state) {
  using namespace flowire::rod;
  const Vec3 x0(0, 0, 0), x1(1e-3, 1e-5, 0), x2(2e-3, 4e-5, 1e-5);
  EdgeFrame fe, ff;
  const Vec3 te = (x1 - x0).normalized(), tf = (x2 - x1).normalized();
  fe.d1 = te.cross(Vec3::UnitZ()).normalized();
  fe.d2 = te.cross(fe.d1);
  ff.d1 = parallel_transport(fe.d1, te, tf);
  ff.d2 = tf.cross(ff.d1);
  VertexParams p;
  p.voronoi_length = 1e-3;
  const bool hessian = state.range(0) != 0;
  const bool gauss_newton = state.range(0) == 2;
  // A few stencils cycled through, so the timing is not of one memoised input.
  constexpr int kStencils = 8;
  EdgeGeometry a[kStencils], b[kStencils];
  for (int i = 0; i < kStencils; ++i) {
    a[i] = edge_geometry(x0, x1, fe, 0.1 * i);
    b[i] = edge_geometry(x1, x2, ff, 0.3 + 0.05 * i);
  }
  Vec11 g;
  Mat11 H;
  int i = 0;
  for (auto _ : state) {
    const double e = Kernel(a[i], b[i], 0.1 * i, 0.3 + 0.05 * i, 0.0, p, &g, hessian ? &H : nullptr, gauss_newton);
    i = (i + 1) % kStencils;
    benchmark::DoNotOptimize(e);
    benchmark::DoNotOptimize(g.data());
    benchmark::DoNotOptimize(H.data());
    benchmark::ClobberMemory();
  }
}

using KernelFn = double (*)(const flowire::rod::EdgeGeometry&, const flowire::rod::EdgeGeometry&, double, double,
                            double, const flowire::rod::VertexParams&, flowire::rod::Vec11*, flowire::rod::Mat11*,
                            bool);
constexpr KernelFn kFast = &flowire::rod::bend_twist;
constexpr KernelFn kReference = &flowire::rod::detail::bend_twist_reference;

void BM_BendTwistKernel(benchmark::State& state) { bend_twist_kernel<kFast>(state); }
/// The straightforward evaluation the fast kernel replaced, for the ratio in one run.
void BM_BendTwistKernelReference(benchmark::State& state) { bend_twist_kernel<kReference>(state); }
BENCHMARK(BM_BendTwistKernel)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kNanosecond);
BENCHMARK(BM_BendTwistKernelReference)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kNanosecond);

// 4·1700 − 1 unknowns: the 1,700-vertex wire.
BENCHMARK(BM_FactorSolveBanded)->Arg(6799)->Arg(39999)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FactorSolveSparse)->Arg(6799)->Arg(39999)->Unit(benchmark::kMicrosecond);

}  // namespace
