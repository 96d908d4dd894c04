// The FEM comparison on a Y bifurcation of about 30k quadratic tetrahedra (parent 5 mm,
// daughters 3.97 mm, 40 mm branches): mesh, assembly and solve timed as counters, once
// per solver. Run on two cores with
//   mpirun --allow-run-as-root --oversubscribe -n 2 build/bench/bench_fem
// (every rank runs the collective benchmark and prints its own report). A second
// benchmark times a pulsatile series of quasi-steady frames.
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "flowire/flow/fem/boundary_values.hpp"
#include "flowire/flow/fem/compare.hpp"
#include "flowire/flow/fem/pulsatile.hpp"
#include "flowire/vessels/generators.hpp"

namespace {

void BM_FemYBifurcation(benchmark::State& state) {
  using namespace flowire;
  const auto net = vessels::Network::build(vessels::y_bifurcation({}));
  flow::fem::FemOptions opt;
  opt.mesh_size = 1.05e-3;
  opt.solver = state.range(0) == 0 ? flow::fem::LinearSolver::Mumps : flow::fem::LinearSolver::Fieldsplit;
  flow::fem::BoundaryValues bv;
  bv.inlet_pressure = 12850.0;
  bv.outlet_pressure = 12800.0;
  flow::fem::CompareResult r;
  for (auto _ : state) {
    r = flow::fem::compare(net, bv, opt, "");
    benchmark::DoNotOptimize(r);
  }
  state.counters["tets"] = r.tets;
  state.counters["unknowns"] = r.unknowns;
  state.counters["mesh_s"] = r.mesh_seconds;
  state.counters["assemble_s"] = r.assemble_seconds;
  state.counters["solve_s"] = r.solve_seconds;
  state.counters["total_s"] = r.total_seconds;
  state.SetLabel(state.range(0) == 0 ? "mumps" : "fieldsplit");
}
BENCHMARK(BM_FemYBifurcation)->Arg(0)->Arg(1)->Iterations(1)->Unit(benchmark::kSecond);

// The pulsatile quasi-steady series on the same Y with outlet resistances: one
// factorization and one unit solve per open boundary (basis_s), then range(0) frames of a
// sine inlet over a period, each a small dense solve, a linear combination of the unit
// fields, a network solve and the sampling (frame_ms per frame).
void BM_FemPulsatileFrames(benchmark::State& state) {
  using namespace flowire;
  const auto net = vessels::Network::build(vessels::y_bifurcation({}));
  flow::fem::FemOptions opt;
  opt.mesh_size = 1.05e-3;
  opt.write_png = false;
  flow::fem::BoundaryValues base;
  base.inlet_pressure = 12850.0;
  for (int e : net.ends())
    if (e != net.widest_end()) base.outlets.push_back({e, flow::fem::OutletValue::Type::Resistance, 12800.0, 2e6});
  const auto n = static_cast<int>(state.range(0));
  std::vector<double> times;
  std::vector<flow::fem::BoundaryValues> frames;
  for (int i = 0; i < n; ++i) {
    times.push_back(0.8 * i / n);
    flow::fem::BoundaryValues bv = base;
    bv.inlet_pressure = 12850.0 + 25.0 * std::sin(2.0 * 3.141592653589793 * i / n);  // always above P_d
    frames.push_back(bv);
  }
  flow::fem::PulsatileResult r;
  for (auto _ : state) {
    r = flow::fem::compare_pulsatile(net, times, frames, base, 0.0, opt, "");
    benchmark::DoNotOptimize(r);
  }
  state.counters["tets"] = r.steady.tets;
  state.counters["frames"] = n;
  state.counters["factorizations"] = r.factorizations;
  state.counters["basis_s"] = r.basis_seconds;
  state.counters["frame_ms"] = 1e3 * r.frames_seconds / (n + 1);
  state.counters["max_split_error"] = r.max_flow_split_error;
}
BENCHMARK(BM_FemPulsatileFrames)->Arg(20)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace

namespace {

// Navier–Stokes on the same Y at an inlet Reynolds number of 600 (inlet flow 15.6 mL/s,
// outlets at one pressure), mesh size range(0)/10 mm: Newton steps (each an LU
// factorization), density steps, and the time of the whole comparison.
void BM_FemNavierStokesY(benchmark::State& state) {
  using namespace flowire;
  const auto net = vessels::Network::build(vessels::y_bifurcation({}));
  flow::fem::FemOptions opt;
  opt.mesh_size = static_cast<double>(state.range(0)) * 1e-4;
  opt.equations = flow::fem::Equations::NavierStokes;
  flow::fem::BoundaryValues bv;
  bv.inlet_type = flow::fem::BoundaryValues::Inlet::Flow;
  const double r = 5e-3, eta = 3.5e-3, rho = 1060.0;
  bv.inlet_flow = 600.0 * eta / (rho * 2 * r) * std::numbers::pi * r * r;
  bv.outlet_pressure = 12800.0;
  flow::fem::CompareResult res;
  for (auto _ : state) {
    res = flow::fem::compare(net, bv, opt, "");
    benchmark::DoNotOptimize(res);
  }
  state.counters["tets"] = res.tets;
  state.counters["unknowns"] = res.unknowns;
  state.counters["reynolds"] = res.reynolds;
  state.counters["newton_steps"] = res.newton_iterations;
  state.counters["assemble_s"] = res.assemble_seconds;
  state.counters["solve_s"] = res.solve_seconds;
  state.counters["total_s"] = res.total_seconds;
}
BENCHMARK(BM_FemNavierStokesY)->Arg(20)->Arg(14)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
