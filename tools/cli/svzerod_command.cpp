// `flowire run model.json`: simulated as svZeroDSolver does, svzerod_result.csv written like it.
#include "svzerod_command.hpp"

#include <fmt/format.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/flow/svzerod.hpp"

namespace flowire::cli {

using flowire::ErrorKind;

/// An svZeroDSolver model: simulated as svZeroDSolver does, svzerod_result.csv written like it.
int run_svzerod(const std::string& model, const std::string& out, const std::vector<std::string>& sets) {
  if (!sets.empty())
    throw flowire::Error(ErrorKind::Usage,
                         fmt::format("{}: --set applies to YAML scenes, not svZeroDSolver models", model));
  const std::filesystem::path dir = out.empty() ? std::filesystem::path("out") : std::filesystem::path(out);
  const auto t0 = std::chrono::steady_clock::now();
  flowire::flow::svzerod::Summary s;
  flowire::flow::svzerod::Result result;
  std::optional<flowire::OutputFolder> folder;
  try {
    // The model is read and simulated before anything is written: bad input leaves the
    // folder as it was. Then, as a scene run, the folder is held and the summary says
    // "running" until the result is in place.
    result = flowire::flow::svzerod::simulate(model, &s);
    folder.emplace(dir);
    flowire::write_text_atomically(
        dir / "summary.json",
        nlohmann::json{{"status", "running"}, {"pid", static_cast<long>(::getpid())}, {"model", model}}.dump(2) + "\n");
    s.result_file = (dir / "svzerod_result.csv").string();
    flowire::flow::svzerod::write_result_csv(result, s.result_file);
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
                      {"steps", s.steps},
                      {"svzerod",
                       {{"vessels", s.vessels},
                        {"junctions", s.junctions},
                        {"boundary_conditions", s.boundary_conditions},
                        {"unknowns", s.unknowns},
                        {"cycles", s.cycles},
                        {"period", s.period},
                        {"dt", s.dt},
                        {"rows", s.rows},
                        {"newton_iterations_per_step", s.newton_iterations_per_step},
                        {"factorizations", s.factorizations}}},
                      {"timings",
                       {{"setup", 0.0},
                        {"flow", s.seconds},
                        {"rod", 0.0},
                        {"contact", 0.0},
                        {"coupling", 0.0},
                        {"output", std::max(0.0, total - s.seconds)},
                        {"total", total}}},
                      {"warnings", flowire::take_warnings()}};
  flowire::write_text_atomically(dir / "summary.json", j.dump(2) + "\n");
  std::printf("flowire: %s: ok in %.3f s, %d steps; %s\n", model.c_str(), total, s.steps, s.result_file.c_str());
  return 0;
}

}  // namespace flowire::cli
