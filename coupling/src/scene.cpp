// Scenes (scene.hpp): loading a scene file with its overrides, and running it from set-up to
// the last output (run_scene), timing each phase; the co-simulation itself is cosimulation.cpp.
#include <fmt/format.h>
#include <unistd.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/coupling/cosimulation.hpp"
#include "flowire/coupling/lumen.hpp"
#include "flowire/coupling/occlusion.hpp"
#include "flowire/coupling/paraview_script.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/coupling/tip_forces.hpp"
#include "flowire/coupling/vessel_forces.hpp"
#include "flowire/coupling/vessel_path.hpp"
#include "flowire/coupling/wire_output.hpp"
#include "flowire/flow/output.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire/vessels/spatial.hpp"
#include "run_output.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

nlohmann::json resolved_scene(const config::Config& c) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [path, v] : c.values()) {
    switch (v.type) {
      case config::Type::Section:
      case config::Type::List:
        break;
      case config::Type::Number:
      case config::Type::Integer:
      case config::Type::NumberOrSection:
        j[path] = v.number;
        break;
      case config::Type::Bool:
        j[path] = v.boolean;
        break;
      case config::Type::Vector3:
      case config::Type::NumberList:
        j[path] = v.list;
        break;
      default:
        j[path] = v.text;
    }
  }
  return j;
}

}  // namespace

config::Config load_scene(const std::string& file, const std::vector<std::string>& overrides,
                          const std::string& out_dir) {
  auto sets = overrides;
  if (!out_dir.empty()) sets.push_back("output.dir=" + out_dir);
  return config::load_config(file, scene_schema(), sets);
}

RunResult run_scene(const config::Config& c, const RunOptions& options) {
  const auto t_start = Clock::now();
  (void)take_warnings();
  RunResult result;
  result.out_dir = c.string("output.dir");
  const std::filesystem::path out(result.out_dir);
  // What could only fail after the run (pictures without a display) fails before it.
  if (c.boolean("output.png")) flow::check_can_render(c.where("output.png"));
  nlohmann::json& s = result.summary;
  s["status"] = "running";
  s["steps"] = 0;
  s["scene"] = resolved_scene(c);
  if (c.has("name")) s["name"] = c.string("name");
  // The folder is taken once the scene has been set up (bad input found in the set-up leaves
  // it as it was) and is this run's until it ends; its summary says "running" from then on,
  // so a run that crashes or is killed never leaves an earlier run's "ok" beside its frames.
  std::optional<OutputFolder> folder;
  auto take_folder = [&] {
    if (folder) return;
    folder.emplace(out);
    nlohmann::json running = s;
    running["pid"] = static_cast<long>(::getpid());
    write_text_atomically(out / "summary.json", running.dump(2) + "\n");
  };
  nlohmann::json timings = {{"setup", 0.0},    {"flow", 0.0},   {"rod", 0.0},   {"contact", 0.0},
                            {"coupling", 0.0}, {"output", 0.0}, {"total", 0.0}, {"stepping", 0.0}};
  auto finish = [&](const std::string& status) {
    take_folder();
    s["status"] = status;
    timings["total"] = seconds_since(t_start);
    s["timings"] = timings;
    auto w = take_warnings();
    // Repeated numerical warnings (one per step) are summarised, not listed thousands of times.
    std::map<std::string, int> count;
    for (const auto& x : w) ++count[x];
    nlohmann::json list = nlohmann::json::array();
    for (const auto& [msg, k] : count) list.push_back(k > 1 ? fmt::format("{} (x{})", msg, k) : msg);
    s["warnings"] = list;
    write_text_atomically(out / "summary.json", s.dump(2) + "\n");
  };

  try {
    // ---------------- setup: only what the scene has
    auto t0 = Clock::now();
    CoSimulation cosim(c, &s);
    const vessels::Network* net = cosim.network();
    flow::FlowSolver* fsolver = cosim.flow();
    timings["setup"] = seconds_since(t0);
    take_folder();

    // ---------------- stepping
    const double dt = cosim.dt();
    const long steps = cosim.planned_steps();
    const long out_every = output_every_steps(c, dt);
    const bool series = out_every > 0;

    RunRecorder recorder(c, cosim, out);
    cosim.start();
    if (series || steps == 0) recorder.record(0.0);
    long done = 0;
    double stepping = 0.0;  // the steps alone: no setup, start or output
    {
      // SIGINT/SIGTERM end the stepping after the current step: the frames so far are
      // written below and the summary says "interrupted".
      const InterruptibleSection interruptible;
      for (; done < steps && interrupt_signal() == 0; ++done) {
        const double t1 = (static_cast<double>(done) + 1.0) * dt;
        const auto ts = Clock::now();
        cosim.step();
        stepping += seconds_since(ts);
        recorder.after_step();
        if (series && (done + 1) % out_every == 0) recorder.record(t1);
        if (options.progress)
          options.progress({done + 1, steps, t1, static_cast<double>(steps) * dt, seconds_since(t_start)});
      }
    }
    if (!series && done > 0) recorder.record(static_cast<double>(done) * dt);
    s["steps"] = done;
    recorder.finish(series);
    const double t_out = recorder.seconds();
    throw_if_interrupted(fmt::format("the run at t = {:.6g} s", static_cast<double>(done) * dt));

    // ---------------- finite-element comparison of the flow (fem:)
    if (c.has_section("fem") && !fem_on_network(c)) {
      const auto tf = Clock::now();
      s["fem"] = run_fem_geometry(c, out);
      timings["fem"] = seconds_since(tf);
    } else if (c.has_section("fem")) {
      if (!fsolver) throw_input_error(c.where("fem"), "fem: compares the flow, so the scene needs a flow: section");
      const auto tf = Clock::now();
      s["fem"] = run_fem(c, *net, *fsolver, out);
      timings["fem"] = seconds_since(tf);
    }

    // ---------------- summary
    const RunSeconds split = add_run_summary(c, cosim, s);
    timings["flow"] = cosim.flow_seconds();
    timings["rod"] = std::max(0.0, cosim.rod_seconds() - split.contact - split.coupling);
    timings["contact"] = split.contact;
    timings["coupling"] = split.coupling;
    timings["output"] = t_out;
    timings["stepping"] = stepping;
  } catch (const Error& e) {
    // Whatever ended the run, the summary says so; if even that cannot be written (a full
    // disk), the "running" one stays and the first error is the one reported.
    // Bad input found before the folder was taken leaves no summary (nothing was written).
    s["error"] = e.what();
    try {
      if (folder || e.kind() == ErrorKind::Numerical)
        finish(e.kind() == ErrorKind::Interrupted ? "interrupted" : "error");
    } catch (const Error&) {
    }
    throw;
  }
  // A wire that left the lumen by more than its radius is no result to trust: said with
  // where and when, status "outside", and a numerical failure unless the scene allows it.
  if (const auto& o = result.summary["contact"]; o.contains("outside")) {
    const std::string msg = o["outside"]["message"];
    warn(msg);
    finish("outside");
    if (!contact_settings(c).allow_outside)
      throw_numerical_error(msg + " (contact.allow_outside: true accepts such a run)");
    return result;
  }
  finish("ok");
  return result;
}

}  // namespace flowire::coupling
