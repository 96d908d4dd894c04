// The FEM comparison on a Y bifurcation of about 30k quadratic tetrahedra (parent 5 mm,
// daughters 3.97 mm, 40 mm branches): mesh, assembly and solve timed as counters, once
// per solver. Run on two cores with
//   mpirun --allow-run-as-root --oversubscribe -n 2 build/bench/bench_fem
// (every rank runs the collective benchmark and prints its own report).
#include <benchmark/benchmark.h>

#include "flowire/fem/compare.hpp"
#include "flowire/vessels/generators.hpp"

namespace {

void BM_FemYBifurcation(benchmark::State& state) {
  using namespace flowire;
  const auto net = vessels::Network::build(vessels::y_bifurcation({}));
  fem::FemOptions opt;
  opt.mesh_size = 1.05e-3;
  opt.solver = state.range(0) == 0 ? fem::LinearSolver::Mumps : fem::LinearSolver::Fieldsplit;
  fem::BoundaryValues bv;
  bv.inlet_pressure = 12850.0;
  bv.outlet_pressure = 12800.0;
  fem::CompareResult r;
  for (auto _ : state) {
    r = fem::compare(net, bv, opt, "");
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

}  // namespace
