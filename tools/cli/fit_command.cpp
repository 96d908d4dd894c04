// `flowire fit`: minimise the trace distance of the blood-flow paper's eq. 11 between a
// measured tip trace and a scene's simulated one over chosen scene values, with CMA-ES
// (common/cmaes: each value's range mapped onto [0, 1], box handled by repair and penalty),
// as the Cosserat guidewire paper fits push force and turn angle to tracked phantom data.
// Every evaluation is a separate `flowire run` process (an isolated scene run: nothing of one
// run can leak into the next), up to --jobs at a time; under mpirun a generation's runs are
// shared out over the ranks (dispatch.hpp) while rank 0 runs CMA-ES.
#include "fit_command.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "dispatch.hpp"
#include "flowire/common/cmaes.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/common/units.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/coupling/trace_compare.hpp"

namespace flowire::cli {
namespace {

namespace fs = std::filesystem;
using coupling::TracePoint;

struct Param {
  std::string key;
  double lo = 0, hi = 0;  // SI
};

std::string trim(std::string s) {
  const auto a = s.find_first_not_of(" \t");
  const auto b = s.find_last_not_of(" \t");
  return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

std::string si_text(double v) { return fmt::format("{:.17g}", v); }

/// "KEY=LO..HI" with LO and HI as the scene accepts them ("2 cm/s", "30 deg", 0.02).
Param parse_param(const std::string& text) {
  const std::string where = fmt::format("--param {}", text);
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0) throw_input_error(where, "must be KEY=LO..HI");
  Param p;
  p.key = trim(text.substr(0, eq));
  const std::string range = text.substr(eq + 1);
  const auto dots = range.find("..");
  if (dots == std::string::npos || range.find("..", dots + 2) != std::string::npos)
    throw_input_error(where, "malformed range: must be LO..HI (e.g. 1 cm/s..3 cm/s)");
  const auto* key = coupling::scene_schema().find(p.key);
  if (!key) throw_input_error(where, fmt::format("unknown scene key '{}' (flowire help scene lists them)", p.key));
  if (key->type != config::Type::Number)
    throw_input_error(where, fmt::format("scene key '{}' is not a number; only number keys can be fitted", p.key));
  const std::string lo = trim(range.substr(0, dots)), hi = trim(range.substr(dots + 2));
  if (lo.empty() || hi.empty()) throw_input_error(where, "malformed range: must be LO..HI (e.g. 1 cm/s..3 cm/s)");
  p.lo = units::parse_quantity(lo, key->dim, where);
  p.hi = units::parse_quantity(hi, key->dim, where);
  if (!(p.lo < p.hi)) throw_input_error(where, fmt::format("LO ({}) must be less than HI ({})", lo, hi));
  // Every value tried lies between the bounds: both must be in the key's declared range.
  config::check_range(*key, p.lo, "--param", p.key);
  config::check_range(*key, p.hi, "--param", p.key);
  return p;
}

/// The simulated trace padded to the measured trace's inserted lengths: a run whose tip trace
/// starts later or ends earlier (a stalled wire) holds its first or last tip position there, so
/// every run is compared on the same samples and falling short is not rewarded.
std::vector<TracePoint> padded(std::vector<TracePoint> sim, const std::vector<TracePoint>& measured) {
  double lo = measured.front().inserted_length, hi = lo;
  for (const auto& p : measured) lo = std::min(lo, p.inserted_length), hi = std::max(hi, p.inserted_length);
  double slo = sim.front().inserted_length, shi = slo;
  const TracePoint* first = &sim.front();
  const TracePoint* last = &sim.front();
  for (const auto& p : sim) {
    if (p.inserted_length < slo) slo = p.inserted_length, first = &p;
    if (p.inserted_length > shi) shi = p.inserted_length, last = &p;
  }
  const TracePoint a{first->time, lo, first->x}, b{last->time, hi, last->x};
  if (lo < slo) sim.insert(sim.begin(), a);
  if (hi > shi) sim.push_back(b);
  return sim;
}

struct RunOutcome {
  double rms = std::numeric_limits<double>::infinity();       // eq. 11, m
  double rms_mean = std::numeric_limits<double>::infinity();  // (1/n Σ)^½, m
  int status = 0;                                             // the run's exit status
};

/// One evaluation, on whichever rank the dispatcher gives it to: the run of the payload's
/// command line in its folder, and its trace distance to the measured trace. The result is
/// {"status": exit status, "rms": m, "rms_mean": m} (distances absent when not comparable).
std::string evaluate_run(const std::string& payload, const std::string& trace) {
  const auto task = nlohmann::json::parse(payload);
  const fs::path dir = task.at("dir").get<std::string>();
  fs::create_directories(dir);
  RunOutcome r;
  r.status = run_child(task.at("args").get<std::vector<std::string>>(), dir / "run.log");
  if (r.status == 0 && fs::exists(dir / "tip_trace.csv")) {
    try {
      const auto measured = coupling::read_tip_trace(trace);
      const auto c = coupling::compare_traces(
          measured, padded(coupling::read_tip_trace((dir / "tip_trace.csv").string()), measured));
      if (c.samples > 0) r.rms = c.rms_published_total, r.rms_mean = c.rms_total;
    } catch (const Error&) {
      r.status = -1;
    }
  }
  nlohmann::json j{{"status", r.status}};
  if (std::isfinite(r.rms)) j["rms"] = r.rms, j["rms_mean"] = r.rms_mean;
  return j.dump();
}

int fit_root(const FitOptions& o, Dispatcher& dispatcher) {
  // Everything is checked before anything is written.
  if (o.out.empty()) throw_input_error("--out", "an output folder is required");
  if (!fs::exists(o.scene)) throw_input_error(o.scene, "no such file");
  if (o.params.empty()) throw_input_error("--param", "give at least one --param KEY=LO..HI");
  std::vector<Param> params;
  std::set<std::string> seen;
  for (const auto& t : o.params) {
    params.push_back(parse_param(t));
    if (!seen.insert(params.back().key).second)
      throw_input_error(fmt::format("--param {}", t), fmt::format("'{}' is given twice", params.back().key));
  }
  for (const auto& s : o.sets)
    if (seen.count(trim(s.substr(0, s.find('=')))))
      throw_input_error(fmt::format("--set {}", s), "this key is also a --param");
  // The scene must accept both ends of every range (its own checks: signs, limits).
  for (const auto& p : params)
    for (double v : {p.lo, p.hi}) {
      auto sets = o.sets;
      sets.push_back(p.key + "=" + si_text(v));
      try {
        (void)coupling::load_scene(o.scene, sets);
      } catch (const Error& e) {
        throw_input_error(fmt::format("--param {}", p.key),
                          fmt::format("the scene rejects {} = {}: {}", p.key, v, e.what()));
      }
    }
  const auto scene_cfg = coupling::load_scene(o.scene, o.sets);
  if (!scene_cfg.has_section("wire"))
    throw_input_error(o.scene, "the scene has no wire: nothing to compare with a tip trace");
  if (!scene_cfg.boolean("output.csv"))
    throw_input_error(o.scene, "output.csv is false: the runs would write no tip_trace.csv");
  if (!fs::exists(o.trace)) throw_input_error(o.trace, "no such file (--trace)");
  const auto measured = coupling::read_tip_trace(o.trace);
  if (fs::exists(o.out) && !fs::is_directory(o.out)) throw_input_error(o.out, "--out exists and is not a folder");

  const int n = static_cast<int>(params.size());
  const int jobs = dispatcher.slots();  // runs at a time over every rank
  cmaes::Options co;
  co.unit_box = true;
  co.sigma0 = 0.3;
  co.seed = o.seed;
  co.max_evaluations = o.max_evaluations > 0 ? o.max_evaluations : 100L * (n + 1);
  co.tol_x = 1e-3;    // 0.1 % of each range
  co.tol_fun = 1e-9;  // 1 nm of trace distance
  // λ at least the number of parallel runs when the machine has many cores.
  co.lambda =
      std::max(4 + static_cast<int>(std::floor(3.0 * std::log(static_cast<double>(n)))), std::min(jobs, 4 * (n + 2)));

  fs::path out = fs::path(o.out).lexically_normal();
  if (!out.has_filename()) out = out.parent_path();
  // The runs' folders: hidden next to --out, removed at the end.
  const fs::path work = out.parent_path() / fmt::format(".{}.fit-work", out.filename().string());
  fs::remove_all(work);
  fs::create_directories(work);
  const std::string exe_name = "flowire";
  const fs::path scene_abs = fs::absolute(o.scene);

  long counter = 0;
  long best_id = -1;
  double best_rms = std::numeric_limits<double>::infinity();
  std::vector<double> best_values;
  std::ostringstream history;
  history << "evaluation,generation";
  for (const auto& p : params) history << "," << p.key;
  history << ",rms,rms_mean,status\n";
  int generation = 0;

  auto to_values = [&](const Eigen::VectorXd& u) {
    std::vector<double> v(n);
    for (int i = 0; i < n; ++i) v[i] = params[i].lo + u[i] * (params[i].hi - params[i].lo);
    return v;
  };

  cmaes::BatchEvaluator evaluate = [&](const Eigen::MatrixXd& pts) {
    const int k = static_cast<int>(pts.cols());
    std::vector<RunOutcome> outcome(k);
    std::vector<long> ids(k);
    for (int j = 0; j < k; ++j) ids[j] = counter++;
    std::vector<std::string> payloads(k);
    for (int j = 0; j < k; ++j) {
      const auto values = to_values(pts.col(j));
      const fs::path dir = fs::absolute(work / fmt::format("eval-{:05d}", ids[j]));
      std::vector<std::string> args{exe_name, "run", scene_abs.string(), "--out", dir.string()};
      for (const auto& s : o.sets) args.insert(args.end(), {"--set", s});
      for (int i = 0; i < n; ++i) args.insert(args.end(), {"--set", params[i].key + "=" + si_text(values[i])});
      payloads[j] = nlohmann::json{{"dir", dir.string()}, {"args", args}}.dump();
    }
    const auto results = dispatcher.run(payloads);
    for (int j = 0; j < k; ++j) {
      auto& r = outcome[j];
      r.status = -1;
      if (!results[j].ok) continue;
      const auto a = nlohmann::json::parse(results[j].text);
      r.status = a.value("status", -1);
      if (a.contains("rms")) r.rms = a["rms"].get<double>(), r.rms_mean = a["rms_mean"].get<double>();
    }

    std::vector<double> f(k);
    // A first generation in which every run fails is the scene's fault (a value it rejects
    // only when it runs, a missing file): stop with the first run's own message.
    if (generation == 0 &&
        std::all_of(outcome.begin(), outcome.end(), [](const RunOutcome& r) { return r.status != 0; })) {
      std::ifstream log(work / fmt::format("eval-{:05d}", ids[0]) / "run.log");
      std::string first, line;
      while (std::getline(log, line))
        if (line.rfind("flowire: error: ", 0) == 0) first = line.substr(16);
      const std::string msg = fmt::format("fit: every run of the first generation failed; the first: {}",
                                          first.empty() ? fmt::format("exit status {}", outcome[0].status) : first);
      throw Error(outcome[0].status == 2 ? ErrorKind::Input : ErrorKind::Numerical, msg);
    }
    for (int j = 0; j < k; ++j) {
      const auto values = to_values(pts.col(j));
      f[j] = outcome[j].rms;
      history << ids[j] << "," << generation;
      for (double v : values) history << "," << si_text(v);
      history << "," << si_text(outcome[j].rms) << "," << si_text(outcome[j].rms_mean) << "," << outcome[j].status
              << "\n";
      const fs::path dir = work / fmt::format("eval-{:05d}", ids[j]);
      if (f[j] < best_rms) {
        if (best_id >= 0) fs::remove_all(work / fmt::format("eval-{:05d}", best_id));
        best_rms = f[j], best_id = ids[j], best_values = values;
      } else {
        fs::remove_all(dir);
      }
    }
    ++generation;
    std::fprintf(stderr, "flowire: fit: generation %d, %ld runs, best rms %.6g m\n", generation, counter, best_rms);
    return f;
  };

  cmaes::Result res;
  try {
    res = cmaes::minimize(evaluate, Eigen::VectorXd::Constant(n, 0.5), co);
  } catch (...) {
    fs::remove_all(work);
    throw;
  }
  if (best_id < 0) {
    fs::remove_all(work);
    throw_numerical_error(
        fmt::format("fit: none of the {} runs produced a comparable tip trace (first run's log: run the "
                    "scene with flowire run to see why)",
                    counter));
  }
  // The best run's outputs, then the history, then fit.json last: its presence means done.
  fs::create_directories(out);
  const fs::path best_dir = work / fmt::format("eval-{:05d}", best_id);
  for (const auto& e : fs::directory_iterator(best_dir)) {
    const auto target = out / e.path().filename();
    fs::remove_all(target);
    fs::rename(e.path(), target);
  }
  fs::remove_all(work);
  write_text_atomically(out / "fit_history.csv", history.str());
  nlohmann::json j;
  j["params"] = nlohmann::json::object();
  for (int i = 0; i < n; ++i) j["params"][params[i].key] = best_values[i];
  j["rms"] = best_rms;
  j["evaluations"] = counter;
  const auto c =
      coupling::compare_traces(measured, padded(coupling::read_tip_trace((out / "tip_trace.csv").string()), measured));
  j["rms_mean"] = c.rms_total;
  j["samples"] = c.samples;
  j["generations"] = res.generations;
  j["stop"] = cmaes::to_string(res.stop);
  j["seed"] = o.seed;
  j["ranges"] = nlohmann::json::object();
  for (const auto& p : params) j["ranges"][p.key] = {p.lo, p.hi};
  write_text_atomically(out / "fit.json", j.dump(2) + "\n");
  std::printf("flowire: fit: rms %.6g m after %ld runs (%s)\n", best_rms, counter, cmaes::to_string(res.stop).c_str());
  for (int i = 0; i < n; ++i) std::printf("  %s = %.9g\n", params[i].key.c_str(), best_values[i]);
  std::printf("outputs in %s\n", o.out.c_str());
  return 0;
}

}  // namespace

int run_fit(const FitOptions& o) {
  Dispatcher dispatcher(o.jobs, [trace = o.trace](const std::string& payload) { return evaluate_run(payload, trace); });
  if (!dispatcher.root()) return dispatcher.serve();
  try {
    const int status = fit_root(o, dispatcher);
    dispatcher.stop(status);
    return status;
  } catch (const Error& e) {
    dispatcher.stop(exit_status(e));
    throw;
  } catch (...) {
    dispatcher.stop(3);
    throw;
  }
}

}  // namespace flowire::cli
