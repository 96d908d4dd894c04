#pragma once
// `flowire run`: its options and the run itself, shared by flowire-full (main.cpp) and the scene
// runner flowire-run (runner.cpp), and the command line's error and warning lines.
#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

#include "flowire/common/config.hpp"

namespace flowire::cli {

/// @brief "flowire: error: MESSAGE" on stderr; returns @p status.
int error_exit(const std::string& message, int status);
/// @brief The warnings collected so far, one "flowire: warning:" line each on stderr.
void print_warnings();
/// @brief The rank of this process in an MPI job started by mpirun (0 otherwise), from the
/// variables the launchers set (Open MPI, PMIx, MPICH's Hydra): known before MPI itself is started.
[[nodiscard]] int launcher_rank();

/// @brief What `flowire run` was given.
struct RunArgs {
  std::string scene;
  std::string out;
  std::vector<std::string> sets;
  std::string network_out;
};

/// @brief The `run` subcommand of @p app, parsed into @p args.
CLI::App* add_run_command(CLI::App& app, RunArgs& args);

/// @brief Called with a scene once it is loaded, before anything of it is built or written.
using BeforeRun = std::function<void(const config::Config& scene)>;

/// @brief Run a scene, an svZeroDSolver model or an openBF model; the exit status.
/// @throws flowire::Error
int cmd_run(const RunArgs& args, const BeforeRun& before = {});

}  // namespace flowire::cli
