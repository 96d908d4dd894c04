// Run with `mpirun -n N`: the Y bifurcation comparison (MUMPS and fieldsplit) with the
// unknowns distributed over the ranks. Writes the outlet flows and sampled pressures to
// argv[1]; if argv[2] is given (the same run on one rank), checks that every value
// agrees (MUMPS to 1e-9, fieldsplit to 1e-5; flows as fractions of the total, pressures
// of the drop). A third run has outlet resistances instead of outlet pressures (MUMPS), a
// fourth is Navier–Stokes at an inlet Reynolds number of about 300 (Newton, MUMPS).
// Exit status 0 on success.
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "fem_test_cases.hpp"
#include "flowire/flow/fem/boundary_values.hpp"
#include "flowire/flow/fem/compare.hpp"
#include "flowire/flow/solver.hpp"

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int failures = 0;
  try {
    using namespace flowire::flow::fem;
    if (argc < 2) throw std::runtime_error("usage: fem_mpi OUT [REFERENCE]");
    const auto net = test::y_small(0.3);
    BoundaryValues bv;
    bv.inlet_pressure = 12850.0;
    bv.outlet_pressure = 12800.0;
    // The same Y with the outlets behind resistances (the boundary pressures then come from
    // one unit solve per open boundary and a small dense system on every rank).
    BoundaryValues bv_r = bv;
    for (int e : net.ends())
      if (e != net.widest_end()) bv_r.outlets.push_back({e, OutletValue::Type::Resistance, bv.outlet_pressure, 2e7});
    // Navier–Stokes: a drop of 300 Pa drives the Y at an inlet Reynolds number of about 300.
    BoundaryValues bv_ns;
    bv_ns.inlet_pressure = 300.0;
    bv_ns.outlet_pressure = 0.0;
    std::vector<double> values;
    std::vector<int> iterative;  // 1 for the values of the fieldsplit run
    for (int run = 0; run < 4; ++run) {
      FemOptions opt;
      opt.size_factor = 0.5;
      opt.solver = run == 1 ? LinearSolver::Fieldsplit : LinearSolver::Mumps;
      if (run == 3) opt.equations = Equations::NavierStokes;
      const BoundaryValues& b = run == 2 ? bv_r : run == 3 ? bv_ns : bv;
      const CompareResult r = compare(net, b, opt, "");
      if (run == 3 && rank == 0) std::printf("Navier–Stokes run: inlet Reynolds number %.0f\n", r.reynolds);
      // Flows as fractions of the total, pressures as fractions of the drop.
      double total = 0.0;
      for (const auto& o : r.outlets) total += o.flow_fem;
      for (const auto& o : r.outlets) values.push_back(o.flow_fem / total);
      for (const auto& p : r.samples)
        values.push_back((p.pressure_fem - b.outlet_pressure) / (b.inlet_pressure - b.outlet_pressure));
      iterative.resize(values.size(), run == 1 ? 1 : 0);
    }
    if (rank == 0) {
      std::ofstream out(argv[1]);
      out.precision(17);
      for (double v : values) out << v << '\n';
    }
    if (argc > 2) {
      std::ifstream ref(argv[2]);
      std::vector<double> expected;
      for (double v; ref >> v;) expected.push_back(v);
      // MUMPS runs (direct, must agree to rounding; Navier–Stokes to its Newton
      // tolerance, 1e-9), fieldsplit (iterative to a relative residual of 1e-10, so to
      // about 1e-6 in the values).
      if (expected.size() != values.size()) throw std::runtime_error("reference has a different length");
      double worst_direct = 0.0, worst_iterative = 0.0;
      for (size_t i = 0; i < values.size(); ++i) {
        double& worst = iterative[i] ? worst_iterative : worst_direct;
        worst = std::max(worst, std::abs(values[i] - expected[i]));
      }
      std::printf(
          "rank %d of %d: largest difference to the one-rank run (fraction of the flow / of the drop): "
          "MUMPS %.3e, fieldsplit %.3e\n",
          rank, size, worst_direct, worst_iterative);
      if (!(worst_direct <= 1e-9) || !(worst_iterative <= 1e-5)) failures = 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rank %d: %s\n", rank, e.what());
    failures = 1;
  }
  int total = 0;
  MPI_Allreduce(&failures, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  flowire::flow::finalize_petsc();
  MPI_Finalize();
  return total == 0 ? 0 : 1;
}
