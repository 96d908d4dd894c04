// PETSc (CG + GAMG / hypre) against the serial sparse direct answer.
#include <gtest/gtest.h>

#include <type_traits>

#include "flow_test_networks.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

using flowire::testing::tol;
using namespace flowire::flow::test;

// PETSc is finalized by the free function flow::finalize_petsc (what an MPI program calls
// before MPI_Finalize, tests/flow/petsc_mpi_main.cpp); a solver has no member of that name.
template <class T>
concept HasFinalizeMember = requires {
  &T::finalize_petsc;
};
static_assert(!HasFinalizeMember<FlowSolver>, "FlowSolver::finalize_petsc would be declared without a definition");
static_assert(std::is_same_v<decltype(&finalize_petsc), void (*)()>);

void compare(const Network& net, FlowSpec spec, const std::string& pc) {
  spec.solver = SolverKind::Sparse;
  auto ref = make_solver(net, spec);
  spec.solver = SolverKind::Petsc;
  spec.petsc_pc = pc;
  auto pet = make_solver(net, spec);
  for (double t : {0.0, 0.21, 0.6}) {
    std::vector<double> p0(static_cast<size_t>(net.num_nodes())), p1 = p0;
    std::vector<double> q0(static_cast<size_t>(net.num_segments())), q1 = q0;
    ref->solve_at(t, p0, q0);
    pet->solve_at(t, p1, q1);
    double pmax = 0, qmax = 0;
    for (double v : p0) pmax = std::max(pmax, std::abs(v));
    for (double v : q0) qmax = std::max(qmax, std::abs(v));
    for (size_t i = 0; i < p0.size(); ++i) ASSERT_NEAR(p1[i], p0[i], tol(1e-10) * pmax) << pc << " node " << i;
    for (size_t i = 0; i < q0.size(); ++i) ASSERT_NEAR(q1[i], q0[i], tol(1e-10) * qmax) << pc << " segment " << i;
  }
}

TEST(FlowPetsc, EqualsSerialOnRandomNetworksWithLoops) {
#ifndef FLOWIRE_WITH_PETSC
  GTEST_SKIP() << "built without PETSc";
#endif
  for (unsigned seed : {5u, 6u}) {
    const Network net = random_network(2000, 10, seed);
    FlowSpec spec = default_spec(net, Waveform::sine(16000.0, 10600.0, 0.8));
    compare(net, spec, "gamg");
    compare(net, spec, "hypre");
  }
}

TEST(FlowPetsc, WheatstoneLoop) {
#ifndef FLOWIRE_WITH_PETSC
  GTEST_SKIP() << "built without PETSc";
#endif
  const Network net = wheatstone();
  FlowSpec spec = pressure_spec(net, kS, Waveform::sine(1.5, 0.5, 1.0), {{kT, 0.2}});
  spec.viscosity = kUnitViscosity;
  spec.solver = SolverKind::Petsc;
  auto s = make_solver(net, spec);
  s->advance(0.0);
  EXPECT_NEAR(s->node_pressure(kA), 0.2 + 0.8 * 4.0 / 7.0, 1e-12);
  EXPECT_NEAR(s->segment_flow(kAB), 0.8 / 7.0, 1e-12);
}

}  // namespace
}  // namespace flowire::flow
