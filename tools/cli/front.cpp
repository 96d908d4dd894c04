// The flowire command line's front. `flowire run MODEL.json [--out DIR]` (an svZeroDSolver
// model) and `flowire run MODEL.yaml [--out DIR]` for an openBF model run here, in a program that loads no rendering,
// PETSc or gmsh library: loading those takes longer than simulating a model of thousands of vessels. Every other
// command line is handed unchanged to flowire-run (a scene's run, programs.hpp) or to flowire-full (beside this
// program, or where it is installed). Exit status as
// flowire-full: 0 success; 2 bad usage or bad input; 3 numerical failure.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <new>
#include <string>
#include <string_view>
#include <vector>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/flow/openbf.hpp"
#include "programs.hpp"
#include "svzerod_command.hpp"

namespace {

namespace fs = std::filesystem;

enum class ModelKind { None, Svzerod, Openbf };

/// The model and output folder when the command line is `run MODEL.json [--out DIR]` or
/// `run MODEL.yaml [--out DIR]` with an openBF model.
ModelKind model_run(int argc, char** argv, std::string& model, std::string& out) {
  if (argc < 3 || std::string_view(argv[1]) != "run") return ModelKind::None;
  model = argv[2];
  std::error_code ec;
  if (!fs::is_regular_file(model, ec)) return ModelKind::None;
  const std::string ext = fs::path(model).extension().string();
  ModelKind kind = ModelKind::None;
  if (ext == ".json") kind = ModelKind::Svzerod;
  // An openBF model is run here where no display is; with one, flowire-full draws its waveforms too.
  const char* display = std::getenv("DISPLAY");
  if ((ext == ".yaml" || ext == ".yml") && flowire::flow::openbf::is_model(model) && !(display && *display))
    kind = ModelKind::Openbf;
  if (kind == ModelKind::None) return kind;
  for (int i = 3; i < argc;) {
    const std::string_view a = argv[i];
    if (a == "--out" && i + 1 < argc) {
      out = argv[i + 1];
      i += 2;
    } else if (a.substr(0, 6) == "--out=") {
      out = std::string(a.substr(6));
      ++i;
    } else {
      return ModelKind::None;
    }
  }
  return kind;
}

int error_exit(const std::string& message, int status) {
  for (const auto& w : flowire::take_warnings()) std::fprintf(stderr, "flowire: warning: %s\n", w.c_str());
  std::fprintf(stderr, "flowire: error: %s\n", message.c_str());
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  std::string model, out;
  if (const ModelKind kind = model_run(argc, argv, model, out); kind != ModelKind::None) {
    flowire::install_interrupt_handlers();
    try {
      if (kind == ModelKind::Openbf) {
        const int status = flowire::cli::run_openbf(model, out, {});
        for (const auto& w : flowire::take_warnings()) std::fprintf(stderr, "flowire: warning: %s\n", w.c_str());
        return status;
      }
      return flowire::cli::run_svzerod(model, out, {});
    } catch (const flowire::Error& e) {
      return error_exit(e.what(), flowire::exit_status(e));
    } catch (const std::bad_alloc&) {
      return error_exit("out of memory", 3);
    } catch (const std::exception& e) {
      return error_exit(std::string("unexpected failure: ") + e.what(), 3);
    }
  }
  // A run starts in the scene runner (flowire-run: no gmsh, no PETSc), which hands what it cannot
  // run to flowire-full; every other command goes to flowire-full.
  const bool run = argc > 1 && std::string_view(argv[1]) == "run";
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  std::vector<fs::path> dirs;
  if (!ec) {
    dirs.push_back(self.parent_path());                                    // build tree
    dirs.push_back(self.parent_path().parent_path() / "libexec/flowire");  // installed, moved
  }
  dirs.emplace_back(FLOWIRE_LIBEXECDIR);
  for (const char* name :
       run ? std::vector<const char*>{"flowire-run", "flowire-full"} : std::vector<const char*>{"flowire-full"})
    for (const auto& d : dirs)
      if (access((d / name).c_str(), X_OK) == 0) return flowire::cli::exec_program(d / name, argv);
  std::fprintf(stderr, "flowire: error: flowire-full is neither beside this program nor in %s\n", FLOWIRE_LIBEXECDIR);
  return 3;
}
