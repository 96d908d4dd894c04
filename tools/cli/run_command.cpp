// `flowire run` (run_command.hpp): shared by flowire-full and the scene runner flowire-run.
#include "run_command.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"
#include "flowire/common/output.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/flow/openbf.hpp"
#include "flowire/flow/output.hpp"
#include "svzerod_command.hpp"
#include "terminal_line.hpp"

namespace flowire::cli {
namespace {

/// The run's progress on the terminal line, redrawn at most 5 times a second.
class ProgressLine {
 public:
  [[nodiscard]] bool enabled() const { return line_.enabled(); }
  void update(const flowire::coupling::Progress& p) {
    if (p.steps <= 0 || (p.wall_seconds - last_ < 0.2 && p.step < p.steps)) return;
    last_ = p.wall_seconds;
    const double done = static_cast<double>(p.step) / static_cast<double>(p.steps);
    const double eta = done > 0 ? p.wall_seconds * (1.0 - done) / done : 0.0;
    line_.draw(fmt::format("flowire: {:5.1f}%  t = {:.4g} of {:.4g} s  elapsed {:.0f} s  ETA {:.0f} s", 100.0 * done,
                           p.time, p.duration, p.wall_seconds, eta));
  }
  void clear() { line_.clear(); }

 private:
  TerminalLine line_;
  double last_ = -1.0;
};

}  // namespace

int error_exit(const std::string& message, int status) {
  std::fprintf(stderr, "flowire: error: %s\n", message.c_str());
  return status;
}

void print_warnings() {
  for (const auto& w : flowire::take_warnings()) std::fprintf(stderr, "flowire: warning: %s\n", w.c_str());
}

int launcher_rank() {
  for (const char* name : {"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK"})
    if (const char* v = std::getenv(name); v && *v) return std::atoi(v);
  return 0;
}

CLI::App* add_run_command(CLI::App& app, RunArgs& args) {
  auto* run = app.add_subcommand("run", "run a scene: YAML scene file or svZeroDSolver JSON model");
  run->add_option(
         "scene", args.scene,
         "scene file (.yaml), svZeroDSolver model (.json) or openBF model (.yaml with a network: of sn/tn vessels)")
      ->required();
  run->add_option("--out", args.out, "output folder (overrides output.dir)");
  run->add_option("--set", args.sets, "override a scene key: --set flow.solver=sparse (repeatable)")
      ->allow_extra_args(false);
  run->add_option("--network-out", args.network_out,
                  "openBF models: also write the model's network laid out in 3D (.vtp: radius, branch names)");
  return run;
}

int cmd_run(const RunArgs& args, const BeforeRun& before) {
  const std::string& scene = args.scene;
  const std::string& out = args.out;
  const std::vector<std::string>& sets = args.sets;
  const std::string& network_out = args.network_out;
  namespace fs = std::filesystem;
  // Under mpirun every rank runs the scene and rank 0 alone writes it (and holds its folder),
  // from the start: PETSc, which also says so, may start only late in the run (the FEM).
  if (launcher_rank() != 0) flowire::set_writes_outputs(false);
  const bool model = fs::path(scene).extension() == ".json";
  flowire::check_input_file(scene, model ? flowire::input_limit::kTable : flowire::input_limit::kScene,
                            model ? "an svZeroDSolver model (JSON)" : "a scene (YAML)");
  const bool openbf_model = !model && flowire::flow::openbf::is_model(scene);
  if (!network_out.empty() && !openbf_model)
    flowire::throw_usage_error("--network-out writes the layout of an openBF model; " + scene + " is not one");
  if (model) return run_svzerod(scene, out, sets);
  if (openbf_model)
    return run_openbf(
        scene, out, sets, network_out,
        [](const std::vector<flowire::flow::WaveformSeries>& series, const std::string& title,
           const std::filesystem::path& png) { flowire::flow::render_waveforms_png(series, title, png); });
  const auto cfg = flowire::coupling::load_scene(scene, sets, out);
  if (before) before(cfg);
  flowire::coupling::RunOptions options;
  ProgressLine line;
  if (line.enabled()) options.progress = [&line](const flowire::coupling::Progress& p) { line.update(p); };
  const auto res = flowire::coupling::run_scene(cfg, options);
  line.clear();
  print_warnings();
  const auto& s = res.summary;
  if (!flowire::writes_outputs()) return 0;  // an MPI rank other than 0: rank 0 reports
  std::printf("flowire: %s: %s in %.3f s, %d steps; outputs in %s\n", scene.c_str(),
              s.value("status", std::string("ok")).c_str(), s["timings"].value("total", 0.0), s.value("steps", 0),
              res.out_dir.c_str());
  return 0;
}

}  // namespace flowire::cli
