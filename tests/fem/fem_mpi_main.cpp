// Run with `mpirun -n N`: the Y bifurcation comparison (MUMPS and fieldsplit) with the
// unknowns distributed over the ranks. Writes the outlet flows and sampled pressures to
// argv[1]; if argv[2] is given (the same run on one rank), checks that every value
// agrees (MUMPS to 1e-9, fieldsplit to 1e-5; flows as fractions of the total, pressures
// of the drop). A third run has outlet resistances instead of outlet pressures (MUMPS).
// Exit status 0 on success.
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "fem_test_cases.hpp"
#include "flowire/fem/compare.hpp"

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int failures = 0;
  try {
    using namespace flowire::fem;
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
    std::vector<double> values;
    for (int run = 0; run < 3; ++run) {
      FemOptions opt;
      opt.size_factor = 0.5;
      opt.solver = run == 1 ? LinearSolver::Fieldsplit : LinearSolver::Mumps;
      const CompareResult r = compare(net, run == 2 ? bv_r : bv, opt, "");
      // Flows as fractions of the total, pressures as fractions of the drop.
      double total = 0.0;
      for (const auto& o : r.outlets) total += o.flow_fem;
      for (const auto& o : r.outlets) values.push_back(o.flow_fem / total);
      for (const auto& p : r.samples)
        values.push_back((p.pressure_fem - bv.outlet_pressure) / (bv.inlet_pressure - bv.outlet_pressure));
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
      // Thirds: MUMPS (direct, must agree to rounding), fieldsplit (iterative to a
      // relative residual of 1e-10, so to about 1e-6 in the values), MUMPS with outlet
      // resistances (direct).
      if (expected.size() != values.size()) throw std::runtime_error("reference has a different length");
      const size_t third = values.size() / 3;
      double worst_direct = 0.0, worst_iterative = 0.0;
      for (size_t i = 0; i < values.size(); ++i) {
        double& worst = i >= third && i < 2 * third ? worst_iterative : worst_direct;
        worst = std::max(worst, std::abs(values[i] - expected[i]));
      }
      std::printf("rank %d of %d: largest difference to the one-rank run (fraction of the flow / of the drop): "
                  "MUMPS %.3e, fieldsplit %.3e\n", rank, size, worst_direct, worst_iterative);
      if (!(worst_direct <= 1e-9) || !(worst_iterative <= 1e-5)) failures = 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rank %d: %s\n", rank, e.what());
    failures = 1;
  }
  int total = 0;
  MPI_Allreduce(&failures, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  flowire::fem::finalize_petsc();
  MPI_Finalize();
  return total == 0 ? 0 : 1;
}
