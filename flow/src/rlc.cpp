#include "flowire/common/error.hpp"
#include "solvers.hpp"

namespace flowire::flow::detail {

std::unique_ptr<FlowSolver> make_rlc_solver(const Network&, FlowSpec) {
  throw_input_error("flow.model: rlc", "the rlc model is not available yet");
}

}  // namespace flowire::flow::detail
