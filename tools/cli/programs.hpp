#pragma once
// The command line's programs and how they find one another: `flowire` (front.cpp) starts
// flowire-run (runner.cpp) for a run and flowire-full for everything else; flowire-run hands a
// scene it was built without the parts for to flowire-full; a study's or a fit's runs start in
// flowire-run. All three lie side by side in the build tree and in libexec/flowire once installed.
#include <filesystem>

namespace flowire::cli {

/// @brief The program @p name beside this one, if it is there and executable (else empty).
[[nodiscard]] std::filesystem::path sibling_program(const char* name);

/// @brief Replace this process by @p program with @p argv (the same command line). Returns only
/// if it could not be started, with the exit status to end with (3) after saying why.
int exec_program(const std::filesystem::path& program, char** argv);

/// @brief In a child started by run_child (dispatch.hpp): end by SIGTERM when the parent ends (a
/// study killed by SIGKILL leaves no run behind). Does nothing in a process that run_child did
/// not start. Call from main after install_interrupt_handlers.
void follow_parent();

}  // namespace flowire::cli
