// Built when FLOWIRE_WITH_PETSC is off: the petsc solver is refused with a clear message.
#include "flowire/common/error.hpp"
#include "solvers.hpp"

namespace flowire::flow::detail {

std::unique_ptr<FlowSolver> make_petsc_solver(const Network&, FlowSpec) {
  throw_input_error("flow.solver: petsc",
                    "this flowire was built without PETSc (FLOWIRE_WITH_PETSC=OFF); use superposition or sparse");
}

}  // namespace flowire::flow::detail

namespace flowire::flow {
void finalize_petsc() {}
}  // namespace flowire::flow
