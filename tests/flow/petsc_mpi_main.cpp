// Run under `mpirun -n 2`: every rank solves a looped random network with the petsc solver
// (rows distributed over the ranks) and compares with its own serial sparse solve.
// Exit status 0 when every rank agrees to 1e-10 relative to the largest value.
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <exception>

#include "flow_test_networks.hpp"
#include "flowire/flow/solver.hpp"

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int failures = 0;
  try {
    using namespace flowire::flow;
    const Network net = test::random_network(3000, 15, 42);
    FlowSpec spec = default_spec(net, Waveform::sine(16000.0, 10600.0, 0.8));
    spec.solver = SolverKind::Sparse;
    auto ref = make_solver(net, spec);
    spec.solver = SolverKind::Petsc;
    auto pet = make_solver(net, spec);
    double worst = 0.0;
    for (double t : {0.0, 0.3}) {
      std::vector<double> p0(static_cast<size_t>(net.num_nodes())), p1 = p0;
      std::vector<double> q0(static_cast<size_t>(net.num_segments())), q1 = q0;
      ref->solve_at(t, p0, q0);
      pet->solve_at(t, p1, q1);
      double pmax = 0, qmax = 0;
      for (double v : p0) pmax = std::max(pmax, std::abs(v));
      for (double v : q0) qmax = std::max(qmax, std::abs(v));
      for (size_t i = 0; i < p0.size(); ++i) worst = std::max(worst, std::abs(p1[i] - p0[i]) / pmax);
      for (size_t i = 0; i < q0.size(); ++i) worst = std::max(worst, std::abs(q1[i] - q0[i]) / qmax);
    }
    std::printf("rank %d of %d: largest relative difference petsc vs serial %.3e\n", rank, size, worst);
    if (!(worst <= 1e-10)) failures = 1;
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
