// flowire-run, the scene runner: `flowire run SCENE` in a program built without gmsh and PETSc,
// whose libraries take longer to load than a short scene takes to run (0.3 s of symbol binding
// at every start of flowire-full). A command line that is not a run, or a scene with a part this
// program lacks (wall:, fem:, flow.solver: petsc: coupling::unbuilt_scene_parts), is handed
// unchanged to flowire-full beside it, before anything of the scene is built or written. Exit
// status as flowire-full: 0 success; 2 bad usage or bad input; 3 numerical failure.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <new>
#include <string>
#include <string_view>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/coupling/scene.hpp"
#include "programs.hpp"
#include "run_command.hpp"

namespace {

int hand_over(char** argv) {
  const auto full = flowire::cli::sibling_program("flowire-full");
  if (full.empty()) {
    std::fprintf(stderr, "flowire: error: flowire-full is not beside flowire-run\n");
    return 3;
  }
  return flowire::cli::exec_program(full, argv);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3 || std::string_view(argv[1]) != "run") return hand_over(argv);
  flowire::install_interrupt_handlers();
  flowire::cli::follow_parent();  // a run of a study or a fit ends with the study
  CLI::App app{"flowire: guidewire and blood-flow co-simulation in vessel networks", "flowire"};
  app.require_subcommand(1, 1);
  flowire::cli::RunArgs args;
  flowire::cli::add_run_command(app, args);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError&) {
    return hand_over(argv);  // its help and its error messages are flowire-full's
  }
  try {
    return flowire::cli::cmd_run(args, [argv](const flowire::config::Config& scene) {
      if (!flowire::coupling::unbuilt_scene_parts(scene).empty()) {
        (void)flowire::take_warnings();  // flowire-full reads the scene again and says them
        std::exit(hand_over(argv));
      }
    });
  } catch (const flowire::Error& e) {
    flowire::cli::print_warnings();
    return flowire::cli::error_exit(e.what(), flowire::exit_status(e));
  } catch (const std::bad_alloc&) {
    return flowire::cli::error_exit("out of memory", 3);
  } catch (const std::exception& e) {
    return flowire::cli::error_exit(std::string("unexpected failure: ") + e.what(), 3);
  }
}
