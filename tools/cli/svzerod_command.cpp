// `flowire run` on model files: an svZeroDSolver model (JSON), simulated as svZeroDSolver does,
// svzerod_result.csv written like it; an openBF model (YAML with a `network:` of sn/tn vessels).
#include "svzerod_command.hpp"

#include <fmt/format.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/flow/openbf.hpp"
#include "flowire/flow/svzerod/simulate.hpp"
#include "flowire/vessels/io.hpp"

namespace flowire::cli {

using flowire::ErrorKind;

namespace {
/// What a model run reports: its files are written by `write` into the held folder.
struct ModelRun {
  nlohmann::json section;  ///< summary.json's section for the model kind
  int steps = 0;
  double seconds = 0.0;  ///< simulation
  std::string result;    ///< the main output file, for the closing line
};

/// The skeleton of `flowire run` on a model file (svZeroDSolver JSON, openBF YAML): the model
/// is read and simulated by @p simulate before anything is written, so bad input leaves the
/// folder as it was; then, as a scene run, the folder is held and summary.json says
/// "running" until @p write has put the results in place.
int run_model(const std::string& model, const std::string& out, const std::vector<std::string>& sets, const char* kind,
              const std::function<ModelRun()>& simulate,
              const std::function<void(const std::filesystem::path&, ModelRun&)>& write) {
  if (!sets.empty())
    throw flowire::Error(ErrorKind::Usage, fmt::format("{}: --set applies to YAML scenes, not {} models", model, kind));
  const std::filesystem::path dir = out.empty() ? std::filesystem::path("out") : std::filesystem::path(out);
  const auto t0 = std::chrono::steady_clock::now();
  ModelRun run;
  std::optional<flowire::OutputFolder> folder;
  try {
    run = simulate();
    folder.emplace(dir);
    flowire::write_text_atomically(
        dir / "summary.json",
        nlohmann::json{{"status", "running"}, {"pid", static_cast<long>(::getpid())}, {"model", model}}.dump(2) + "\n");
    write(dir, run);
  } catch (const flowire::Error& e) {
    if (folder || e.kind() == ErrorKind::Numerical) {
      try {
        if (!folder) folder.emplace(dir);
        nlohmann::json j = {{"status", "error"}, {"error", e.what()}, {"model", model}};
        flowire::write_text_atomically(dir / "summary.json", j.dump(2) + "\n");
      } catch (const flowire::Error&) {  // a full disk, a held folder: the first error is the one reported
      }
    }
    throw;
  }
  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  nlohmann::json j = {{"status", "ok"},
                      {"model", model},
                      {"steps", run.steps},
                      {"timings",
                       {{"setup", 0.0},
                        {"flow", run.seconds},
                        {"rod", 0.0},
                        {"contact", 0.0},
                        {"coupling", 0.0},
                        {"output", std::max(0.0, total - run.seconds)},
                        {"total", total}}},
                      {"warnings", flowire::take_warnings()}};
  j.update(run.section);
  flowire::write_text_atomically(dir / "summary.json", j.dump(2) + "\n");
  std::printf("flowire: %s: ok in %.3f s, %d steps; %s\n", model.c_str(), total, run.steps, run.result.c_str());
  return 0;
}
}  // namespace

/// An svZeroDSolver model: simulated as svZeroDSolver does, svzerod_result.csv written like it.
int run_svzerod(const std::string& model, const std::string& out, const std::vector<std::string>& sets) {
  flowire::flow::svzerod::Result result;
  return run_model(
      model, out, sets, "svZeroDSolver",
      [&] {
        flowire::flow::svzerod::Summary s;
        result = flowire::flow::svzerod::simulate(model, &s);
        ModelRun r;
        r.steps = s.steps;
        r.seconds = s.seconds;
        r.section = {{"svzerod",
                      {{"vessels", s.vessels},
                       {"junctions", s.junctions},
                       {"boundary_conditions", s.boundary_conditions},
                       {"unknowns", s.unknowns},
                       {"cycles", s.cycles},
                       {"period", s.period},
                       {"dt", s.dt},
                       {"rows", s.rows},
                       {"newton_iterations_per_step", s.newton_iterations_per_step},
                       {"factorizations", s.factorizations}}}};
        return r;
      },
      [&](const std::filesystem::path& dir, ModelRun& r) {
        r.result = (dir / "svzerod_result.csv").string();
        flowire::flow::svzerod::write_result_csv(result, r.result);
      });
}

/// An openBF model: run as a compliant lumped network (openbf.hpp), vessels.csv per openBF label.
int run_openbf(const std::string& model, const std::string& out, const std::vector<std::string>& sets,
               const std::string& network_out, const DrawWaveforms& draw) {
  namespace openbf = flowire::flow::openbf;
  openbf::Waveforms w;
  if (!network_out.empty()) {
    // The layout first (bad input stops the run before any output), written atomically.
    if (std::filesystem::path(network_out).extension() != ".vtp")
      flowire::throw_input_error("--network-out", fmt::format("'{}' must end in .vtp", network_out));
    const openbf::Model m = openbf::read(model);
    flowire::vessels::write_network_vtp(openbf::network(m), network_out);
  }
  return run_model(
      model, out, sets, "openBF",
      [&] {
        const openbf::Model m = openbf::read(model);
        for (const auto& msg : m.warnings) flowire::warn(msg);
        const openbf::Options options;
        w = openbf::simulate(m, options);
        ModelRun r;
        r.steps = w.steps;
        r.seconds = w.seconds;
        r.section = {{"openbf",
                      {{"name", m.name},
                       {"vessels", m.vessels.size()},
                       {"segments", w.segments},
                       {"max_segment_length", options.max_segment_length},
                       {"unknowns", w.unknowns},
                       {"cycles", w.cycles},
                       {"steps_per_cycle", options.steps_per_cycle},
                       {"periodicity", w.periodicity}}}};
        return r;
      },
      [&](const std::filesystem::path& dir, ModelRun& r) {
        r.result = (dir / "vessels.csv").string();
        openbf::write_vessels_csv(w, r.result);
        // The waveforms along the longest path from the inlet to an outlet, as the 1D papers
        // draw them: where a display is (xvfb-run), waveforms.png; else said in the summary.
        if (const char* display = std::getenv("DISPLAY"); draw && display && *display) {
          const openbf::Model m = openbf::read(model);
          draw(openbf::path_waveforms(m, w, 6), m.name, dir / "waveforms.png");
          r.section["openbf"]["waveforms_png"] = "waveforms.png";
        } else {
          r.section["openbf"]["waveforms_png"] = "not drawn: no X display (run under xvfb-run -a)";
        }
      });
}

}  // namespace flowire::cli
