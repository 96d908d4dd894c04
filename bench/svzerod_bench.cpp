// One generalized-α step of an svZeroDSolver model: binary trees of 2^depth − 1 RLC
// vessels (BloodVessel), sine inlet pressure table, resistance outlets, as the peer's
// generated trees. The whole-process comparison with the peer: scripts/bench_svzerod.sh.
#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include "flowire/flow/svzerod/integrator.hpp"
#include "flowire/flow/svzerod/model.hpp"

namespace {

namespace svz = flowire::flow::svzerod;

/// Write the tree model of the given depth; returns its path.
std::string write_tree(int depth) {
  const auto path = std::filesystem::temp_directory_path() / fmt::format("flowire_bench_svzerod_{}.json", depth);
  const int n = (1 << depth) - 1;
  std::string p, t;
  for (int k = 0; k <= 50; ++k) {
    const double tk = 0.8 * k / 50.0;
    p += fmt::format("{}{}", k ? "," : "", 13333.0 + 2667.0 * std::sin(2.0 * std::numbers::pi * tk / 0.8));
    t += fmt::format("{}{}", k ? "," : "", tk);
  }
  std::string vessels, junctions,
      bcs =
          fmt::format(R"({{"bc_name": "INFLOW", "bc_type": "PRESSURE", "bc_values": {{"P": [{}], "t": [{}]}}}})", p, t);
  for (int i = 0; i < n; ++i) {
    const int level = static_cast<int>(std::log2(i + 1));
    const double scale = std::pow(2.0, level / 3.0);  // Murray: r ∝ 2^{−level/3}
    std::string bc;
    if (i == 0) bc = R"(, "boundary_conditions": {"inlet": "INFLOW"})";
    if (2 * i + 1 >= n) {
      bc = fmt::format(R"(, "boundary_conditions": {{"outlet": "OUT{}"}})", i);
      bcs += fmt::format(R"(, {{"bc_name": "OUT{}", "bc_type": "RESISTANCE", "bc_values": {{"R": {}, "Pd": 0.0}}}})", i,
                         1e9 * scale);
    } else {
      junctions += fmt::format(R"({}{{"junction_name": "J{}", "junction_type": "NORMAL_JUNCTION",
        "inlet_vessels": [{}], "outlet_vessels": [{}, {}]}})",
                               junctions.empty() ? "" : ",", i, i, 2 * i + 1, 2 * i + 2);
    }
    vessels += fmt::format(R"({}{{"vessel_id": {}, "vessel_name": "v{}", "zero_d_element_type": "BloodVessel",
      "zero_d_element_values": {{"R_poiseuille": {}, "C": {}, "L": {}}}{}}})",
                           i ? "," : "", i, i, 2e5 * scale * scale * scale * scale, 1e-9 / (scale * scale),
                           7e5 * scale * scale, bc);
  }
  std::ofstream(path) << fmt::format(R"({{"simulation_parameters": {{"number_of_cardiac_cycles": 3,
    "number_of_time_pts_per_cardiac_cycle": 800, "output_mean_only": true}},
    "boundary_conditions": [{}], "vessels": [{}], "junctions": [{}]}})",
                                     bcs, vessels, junctions);
  return path.string();
}

void BM_SvZeroDStep(benchmark::State& state) {
  const int depth = static_cast<int>(state.range(0));
  const auto path = write_tree(depth);
  const svz::Model m = svz::read_model(path);
  std::filesystem::remove(path);
  svz::System sys(m.block_pointers(), m.unknowns, m.period, m.file);
  sys.set_phase(false, 0.0);
  const double dt = m.period / 799.0;
  svz::GeneralizedAlpha ga(sys, m.sim.rho, dt, m.sim.atol, m.sim.max_iter, m.file);
  svz::State s = m.initial;
  long k = 0;
  for (auto _ : state) {
    ga.step(s, dt * static_cast<double>(k++));
    benchmark::DoNotOptimize(s.y.data());
  }
  state.counters["vessels"] = static_cast<double>(m.vessels.size());
  state.counters["unknowns"] = m.unknowns;
  state.counters["factorizations"] = static_cast<double>(sys.factorizations());
}
BENCHMARK(BM_SvZeroDStep)->Arg(8)->Arg(11)->Arg(14)->Unit(benchmark::kMicrosecond);

}  // namespace
