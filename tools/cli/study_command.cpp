// `flowire study`: every run of a study file is a `flowire run` child process whose collected
// values are written, once it has finished, to runs/<id>/result.json (atomically: a study
// killed at any moment never keeps half a result); a rerun of the same command runs only the
// runs without one. The tables are assembled from the result.json files, in the runs' order,
// whatever ran them where: study.csv (values), timings.csv (what depends on the machine),
// pairs.csv (RMS between paired runs' tip traces), plots/*.png, study.json.
#include "study_command.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <sstream>
#include <thread>

#include "dispatch.hpp"
#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"
#include "flowire/common/output.hpp"
#include "flowire/coupling/trace_compare.hpp"
#include "study_file.hpp"
#include "terminal_line.hpp"

namespace flowire::cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

std::string now_text() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  ::gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string host_name() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

const char* kind_name(QuantityKind k) {
  switch (k) {
    case QuantityKind::Summary:
      return "summary";
    case QuantityKind::TipFinal:
      return "final_position";
    case QuantityKind::TipTimeToLength:
      return "time_to_length";
    case QuantityKind::ClampForceMax:
      return "clamp_force_max";
    case QuantityKind::ClampForceFinal:
      return "clamp_force_final";
  }
  return "";
}

QuantityKind kind_of(const std::string& s) {
  for (const auto k : {QuantityKind::Summary, QuantityKind::TipFinal, QuantityKind::TipTimeToLength,
                       QuantityKind::ClampForceMax, QuantityKind::ClampForceFinal})
    if (s == kind_name(k)) return k;
  throw_usage_error(fmt::format("study: unknown quantity kind '{}'", s));
}

// ---------------------------------------------------------------- one run (on any rank)

/// The value at a summary.json path ("wire.tip[2]"), or null.
const json* at_path(const json& root, const std::string& path) {
  const json* j = &root;
  size_t i = 0;
  while (i < path.size()) {
    const size_t end = path.find_first_of(".[", i);
    const std::string name = path.substr(i, end == std::string::npos ? std::string::npos : end - i);
    if (!j->is_object() || !j->contains(name)) return nullptr;
    j = &(*j)[name];
    i = end == std::string::npos ? path.size() : end;
    while (i < path.size() && path[i] == '[') {
      const size_t close = path.find(']', i);
      const size_t k = std::stoul(path.substr(i + 1, close - i - 1));
      if (!j->is_array() || k >= j->size()) return nullptr;
      j = &(*j)[k];
      i = close + 1;
    }
    if (i < path.size() && path[i] == '.') ++i;
  }
  return j;
}

/// The magnitudes of the clamp force, row by row, of a base_force.csv.
std::vector<double> clamp_forces(const fs::path& file) {
  std::istringstream in(read_input(file.string(), input_limit::kTable, "a base_force.csv"));
  std::string line;
  std::getline(in, line);
  std::vector<double> out;
  for (int n = 2; std::getline(in, line); ++n) {
    double t = 0, fx = 0, fy = 0, fz = 0;
    if (std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf", &t, &fx, &fy, &fz) != 4)
      throw_input_error(fmt::format("{}:{}", file.string(), n), "expected time,fx,fy,fz,...");
    out.push_back(std::sqrt(fx * fx + fy * fy + fz * fz));
  }
  return out;
}

/// The last `flowire: error:` line of a run's log.
std::string last_error(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line))
    if (line.rfind("flowire: error: ", 0) == 0) last = line.substr(16);
  return last;
}

/// Wait until no process holds the run folder's lock (a run of a study that was killed a
/// moment ago may still be ending), then empty the folder.
void fresh_folder(const fs::path& dir) {
  std::error_code ec;
  const fs::path lock = dir / ".flowire-run.lock";
  if (fs::exists(lock, ec)) {
    const int fd = ::open(lock.c_str(), O_RDWR | O_CLOEXEC);
    if (fd >= 0) {
      const auto t0 = Clock::now();
      while (::flock(fd, LOCK_EX | LOCK_NB) != 0 && Clock::now() - t0 < std::chrono::seconds(120))
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      ::close(fd);
    }
  }
  fs::remove_all(dir, ec);
  fs::create_directories(dir, ec);
  if (ec) throw_input_error(dir.string(), fmt::format("cannot create the run's folder: {}", ec.message()));
}

/// The outputs a study does not keep (`keep`: all, none, failed): everything of a finished run's
/// folder but its result.json.
void drop_outputs(const fs::path& dir, const std::string& keep, bool ok) {
  if (keep == "all" || (keep == "failed" && !ok)) return;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.path().filename() != "result.json") fs::remove_all(e.path(), ec);
}

const char* keep_name(KeepRuns k) { return k == KeepRuns::All ? "all" : k == KeepRuns::None ? "none" : "failed"; }

/// Run one run of a study and collect its values into runs/<id>/result.json. Returns a short
/// account for rank 0: {"finished": bool, "status": ..., "exit_status": n}.
std::string run_one(const std::string& payload, int rank) {
  const json task = json::parse(payload);
  const fs::path dir = task.at("dir").get<std::string>();
  fresh_folder(dir);
  std::vector<std::string> args{"flowire", "run", task.at("scene").get<std::string>(), "--out", dir.string()};
  for (const auto& s : task.at("sets")) args.insert(args.end(), {"--set", s.get<std::string>()});
  const std::string started = now_text();
  const auto t0 = Clock::now();
  const int exit_status = run_child(args, dir / "run.log");
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  // Exit status 0, 2 (the scene refused a value only when it ran) and 3 (a numerical failure)
  // are the run's own end; a signal (the study stopped, a node lost) leaves it to be run again.
  if (exit_status != 0 && exit_status != 2 && exit_status != 3)
    return json{{"finished", false}, {"exit_status", exit_status}}.dump();

  json result;
  result["run"] = task.at("id");
  result["case"] = task.at("case");
  result["parameters"] = task.at("parameters");
  result["exit_status"] = exit_status;
  json summary;
  if (fs::exists(dir / "summary.json")) {
    try {
      summary = json::parse(read_input((dir / "summary.json").string(), input_limit::kTable, "a summary.json"));
    } catch (const std::exception&) {
      summary = json();
    }
  }
  result["status"] = summary.is_object() && summary.contains("status") && summary["status"].is_string()
                         ? summary["status"].get<std::string>()
                         : std::string("failed");
  if (exit_status != 0) result["error"] = last_error(dir / "run.log");
  json values = json::object(), timings = json::object(), missing = json::array();
  std::vector<coupling::TracePoint> trace;
  bool trace_read = false;
  auto read_trace = [&]() -> const std::vector<coupling::TracePoint>& {
    if (!trace_read && fs::exists(dir / "tip_trace.csv"))
      trace = coupling::read_tip_trace((dir / "tip_trace.csv").string());
    trace_read = true;
    return trace;
  };
  try {
    for (const auto& q : task.at("collect")) {
      const std::string name = q.at("name");
      const QuantityKind kind = kind_of(q.at("kind"));
      if (kind == QuantityKind::Summary) {
        const json* v = at_path(summary, q.at("path").get<std::string>());
        json& target = q.at("timing").get<bool>() ? timings : values;
        if (v && (v->is_number() || v->is_boolean() || v->is_string())) {
          target[name] = *v;
        } else {
          target[name] = nullptr;
          missing.push_back(name);
        }
      } else if (kind == QuantityKind::TipFinal || kind == QuantityKind::TipTimeToLength) {
        const auto& tr = read_trace();
        if (kind == QuantityKind::TipFinal) {
          for (int c = 0; c < 3; ++c) values[name + "_" + "xyz"[c]] = tr.empty() ? json() : json(tr.back().x[c]);
        } else {
          const double target = q.at("length").get<double>();
          json t;
          for (size_t i = 0; i < tr.size(); ++i) {
            if (tr[i].inserted_length < target) continue;
            if (i == 0) {
              t = tr[0].time;
            } else {
              const auto& a = tr[i - 1];
              const auto& b = tr[i];
              const double f = (target - a.inserted_length) / (b.inserted_length - a.inserted_length);
              t = a.time + f * (b.time - a.time);
            }
            break;
          }
          values[name] = t;
        }
        if (tr.empty()) missing.push_back(name);
      } else {
        json v;
        if (fs::exists(dir / "base_force.csv")) {
          const auto f = clamp_forces(dir / "base_force.csv");
          if (!f.empty()) v = kind == QuantityKind::ClampForceMax ? *std::max_element(f.begin(), f.end()) : f.back();
        }
        if (v.is_null()) missing.push_back(name);
        values[name] = v;
      }
    }
    if (task.at("trace").get<bool>()) {
      json rows = json::array();
      for (const auto& p : read_trace()) rows.push_back({p.time, p.inserted_length, p.x[0], p.x[1], p.x[2]});
      result["trace"] = rows;
    }
  } catch (const Error& e) {
    // A run whose files cannot be read has failed, as a run; its result says why.
    result["status"] = "failed";
    result["error"] = e.what();
  }
  result["values"] = values;
  timings["seconds"] = seconds;
  result["timings"] = timings;
  result["missing"] = missing;
  result["rank"] = rank;
  result["host"] = host_name();
  result["session"] = task.at("session");
  result["started"] = started;
  result["finished"] = now_text();
  write_text_atomically(dir / "result.json", result.dump(1) + "\n");

  drop_outputs(dir, task.at("keep").get<std::string>(), exit_status == 0 && result["status"] == "ok");
  return json{{"finished", true}, {"status", result["status"]}, {"exit_status", exit_status}}.dump();
}

// ---------------------------------------------------------------- rank 0

/// Runs done out of the total, on the terminal line.
class StudyProgress {
 public:
  StudyProgress(size_t total, size_t done) : total_(total), done_(done) {
    if (done_ != total_)
      line_.draw(fmt::format("flowire: study: {} of {} runs done, {} to run", done_, total_, total_ - done_));
  }

  void finished(bool failed) {
    ++done_, ++now_;
    if (failed) ++failed_;
    if (!line_.enabled()) return;
    const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    const size_t left = total_ - done_;
    const double eta = elapsed / static_cast<double>(now_) * static_cast<double>(left);
    line_.draw(fmt::format("flowire: study: {} of {} runs done{}  elapsed {:.0f} s  ETA {:.0f} s", done_, total_,
                           failed_ ? fmt::format(" ({} failed)", failed_) : std::string(), elapsed, eta));
  }
  void clear() { line_.clear(); }

 private:
  TerminalLine line_;
  size_t total_, done_, now_ = 0, failed_ = 0;
  Clock::time_point start_ = Clock::now();
};

std::string csv_cell(const json& v) {
  if (v.is_null()) return "";
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_integer()) return fmt::format("{}", v.get<long long>());
  if (v.is_number_unsigned()) return fmt::format("{}", v.get<unsigned long long>());
  if (v.is_number()) return fmt::format("{}", v.get<double>());
  std::string s = v.is_string() ? v.get<std::string>() : v.dump();
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (const char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string csv_text(const std::string& s) { return csv_cell(json(s)); }

/// Append a cell to a CSV row.
void add_cell(std::string& row, const std::string& cell) {
  row += ',';
  row += cell;
}

std::vector<coupling::TracePoint> trace_of(const json& result) {
  std::vector<coupling::TracePoint> out;
  if (!result.contains("trace")) return out;
  for (const auto& r : result["trace"]) {
    coupling::TracePoint p;
    p.time = r[0].get<double>();
    p.inserted_length = r[1].get<double>();
    p.x = Eigen::Vector3d(r[2].get<double>(), r[3].get<double>(), r[4].get<double>());
    out.push_back(p);
  }
  return out;
}

/// The plotting script: next to an installed flowire, or in the source tree of a build.
fs::path plot_script() {
  if (const char* env = std::getenv("FLOWIRE_DATA_DIR")) return fs::path(env) / "plot_study.py";
  const fs::path installed = fs::path(FLOWIRE_INSTALL_DATADIR) / "plot_study.py";
  if (fs::exists(installed)) return installed;
  return fs::path(FLOWIRE_SOURCE_DATADIR) / "plot_study.py";
}

/// One PNG per quantity (and pairing) against each parameter, in OUT/plots. A missing
/// python3 or matplotlib is a warning: the tables are the study's results.
void draw_plots(const Study& s, const fs::path& out, bool pairs) {
  const fs::path script = plot_script();
  if (!fs::exists(script)) {
    warn(fmt::format("plots skipped: the plotting script {} is missing", script.string()));
    return;
  }
  if (!fs::exists("/usr/bin/python3")) {
    warn("plots skipped: /usr/bin/python3 is missing (Debian: python3-matplotlib)");
    return;
  }
  const fs::path tmp = out / fmt::format(".plots.{}", static_cast<long>(::getpid()));
  std::error_code ec;
  fs::remove_all(tmp, ec);
  fs::create_directories(tmp);
  std::string cmd =
      fmt::format("/usr/bin/python3 '{}' '{}' '{}'", script.string(), tmp.string(), (out / "study.csv").string());
  if (s.cases.size() > 1) cmd += " --parameter case";
  for (const auto& p : s.parameters) cmd += fmt::format(" --parameter '{}'", p.key);
  std::vector<std::string> names;
  for (const auto& q : s.quantities) {
    if (q.timing) continue;
    cmd += fmt::format(" --quantity '{}={}'", q.name, fmt::join(q.columns(), ","));
    names.push_back(q.name);
  }
  if (pairs) {
    cmd += fmt::format(" --pairs '{}'", (out / "pairs.csv").string());
    for (const auto& p : s.pairs) names.push_back(p.name);
  }
  const fs::path log = tmp / "plot.log";
  const int raw = std::system((cmd + fmt::format(" >'{}' 2>&1", log.string())).c_str());
  const int status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  if (status == 4) {
    warn("plots skipped: python3-matplotlib is missing (Debian: apt-get install python3-matplotlib)");
  } else if (status != 0) {
    std::ifstream in(log);
    std::string line, last;
    while (std::getline(in, line))
      if (!line.empty()) last = line;
    warn(fmt::format("plots failed (exit status {}): {}", status, last));
  } else {
    fs::create_directories(out / "plots");
    for (const auto& n : names) {
      const fs::path png = tmp / (n + ".png");
      if (fs::exists(png))
        write_atomically(out / "plots" / (n + ".png"), [&](const fs::path& t) { fs::rename(png, t); });
    }
  }
  fs::remove_all(tmp, ec);
}

json describe(const Study& s) {
  json j;
  j["study"] = s.file;
  j["hash"] = s.hash;
  j["cases"] = json::array();
  for (const auto& c : s.cases) j["cases"].push_back({{"name", c.name}, {"scene", c.scene}, {"set", c.sets}});
  j["parameters"] = json::array();
  for (const auto& p : s.parameters) j["parameters"].push_back({{"key", p.key}, {"values", p.texts}, {"axis", p.axis}});
  j["collect"] = json::array();
  for (const auto& q : s.quantities) {
    json e{{"name", q.name}, {"kind", kind_name(q.kind)}, {"columns", q.columns()}};
    if (q.kind == QuantityKind::Summary) e["path"] = q.path;
    if (q.kind == QuantityKind::TipTimeToLength) e["length"] = q.length;
    if (q.timing) e["table"] = "timings.csv";
    j["collect"].push_back(e);
  }
  j["pairs"] = json::array();
  for (const auto& p : s.pairs)
    j["pairs"].push_back({{"name", p.name},
                          {"parameter", s.parameters[p.parameter].key},
                          {"reference", s.parameters[p.parameter].texts[p.reference]},
                          {"spacing", p.spacing}});
  j["keep_runs"] = s.keep == KeepRuns::All ? "true" : s.keep == KeepRuns::None ? "false" : "failed";
  j["runs"] = json::array();
  for (const auto& r : s.runs) {
    json v = json::object();
    for (size_t i = 0; i < s.parameters.size(); ++i) v[s.parameters[i].key] = r.columns[i];
    j["runs"].push_back({{"id", r.id}, {"case", s.cases[r.case_index].name}, {"values", v}, {"set", r.sets}});
  }
  return j;
}

/// Whether DIR may receive this study: absent, empty (hidden files aside), or this study's.
/// Returns the sessions recorded there before.
json check_output_folder(const fs::path& out, const Study& s) {
  std::error_code ec;
  if (!fs::exists(out, ec)) return json::array();
  if (!fs::is_directory(out, ec)) throw_input_error(out.string(), "--out exists and is not a folder");
  const fs::path sj = out / "study.json";
  if (!fs::exists(sj, ec)) {
    for (const auto& e : fs::directory_iterator(out, ec))
      if (e.path().filename().string()[0] != '.')
        throw_input_error(out.string(),
                          "the folder is not empty and holds no study.json: choose an empty or new --out");
    return json::array();
  }
  json old;
  try {
    old = json::parse(read_input(sj.string(), input_limit::kTable, "a study.json"));
  } catch (const json::exception&) {
    throw_input_error(sj.string(), "not a study.json: choose an empty or new --out");
  }
  const std::string hash = old.value("hash", std::string());
  if (hash != s.hash)
    throw_input_error(out.string(), fmt::format("the folder holds the results of another study ({}, hash {}; this "
                                                "one: {}, hash {}): choose another --out, or remove it",
                                                old.value("study", std::string("?")), hash, s.file, s.hash));
  return old.value("sessions", json::array());
}

/// The run paired with @p run: the same case and values but @p pair's reference value.
size_t partner(const Study& s, const Run& run, const Pair& pair, const std::vector<size_t>& stride, size_t product) {
  const size_t axis = s.parameters[pair.parameter].axis;
  std::vector<size_t> at(stride.size(), 0);
  for (size_t i = 0; i < s.parameters.size(); ++i) at[s.parameters[i].axis] = run.value[i];
  at[axis] = pair.reference;
  size_t index = run.case_index * product;
  for (size_t a = 0; a < at.size(); ++a) index += at[a] * stride[a];
  return index;
}

int study_root(const StudyOptions& o, Dispatcher& d) {
  if (o.out.empty() && !o.list) throw_input_error("--out", "an output folder is required");
  const Study s = load_study(o.file);
  if (o.list) {
    std::printf("run,case");
    for (const auto& p : s.parameters) std::printf(",%s", p.key.c_str());
    std::printf("\n");
    for (const auto& r : s.runs) {
      std::printf("%s,%s", r.id.c_str(), csv_text(s.cases[r.case_index].name).c_str());
      for (const auto& c : r.columns) std::printf(",%s", csv_text(c).c_str());
      std::printf("\n");
    }
    return 0;
  }
  const fs::path out = fs::absolute(o.out).lexically_normal();
  json sessions = check_output_folder(out, s);

  // From here on the folder is this study's.
  OutputFolder folder(out);
  fs::create_directories(out / "runs");
  std::vector<size_t> pending;
  for (const auto& r : s.runs)
    if (!fs::exists(out / "runs" / r.id / "result.json")) pending.push_back(r.index);
  // The longest runs first: the last runs handed out are short, and the slots end together.
  std::stable_sort(pending.begin(), pending.end(), [&](size_t a, size_t b) { return s.runs[a].cost > s.runs[b].cost; });

  json session{{"started", now_text()},
               {"ranks", d.ranks()},
               {"jobs", d.jobs()},
               {"runs_pending", pending.size()},
               {"runs_finished", 0}};
  sessions.push_back(session);
  json study = describe(s);
  study["status"] = "running";
  study["sessions"] = sessions;
  write_text_atomically(out / "study.json", study.dump(1) + "\n");

  const bool trace = !s.pairs.empty();
  std::vector<std::string> payloads;
  for (const size_t i : pending) {
    const Run& r = s.runs[i];
    json collect = json::array();
    for (const auto& q : s.quantities)
      collect.push_back({{"name", q.name},
                         {"kind", kind_name(q.kind)},
                         {"path", q.path},
                         {"length", q.length},
                         {"timing", q.timing}});
    json params = json::object();
    for (size_t k = 0; k < s.parameters.size(); ++k) params[s.parameters[k].key] = r.columns[k];
    payloads.push_back(json{
        {"id", r.id},
        {"dir", (out / "runs" / r.id).string()},
        {"scene", s.cases[r.case_index].scene},
        {"sets", r.sets},
        {"case", s.cases[r.case_index].name},
        {"parameters", params},
        {"collect", collect},
        {"trace", trace},
        {"keep", keep_name(s.keep)},
        {"session",
         sessions.size()}}.dump());
  }

  const auto t0 = Clock::now();
  long finished_now = 0;
  std::string first_unfinished;
  {
    StudyProgress progress(s.runs.size(), s.runs.size() - pending.size());
    InterruptibleSection section;
    try {
      d.run(payloads, [&](size_t k, const Dispatcher::Outcome& oc) {
        bool finished = false, failed = true;
        if (oc.ok) {
          const json a = json::parse(oc.text, nullptr, false);
          finished = a.is_object() && a.value("finished", false);
          failed = !finished || a.value("exit_status", 0) != 0 || a.value("status", std::string()) != "ok";
          if (!finished && first_unfinished.empty())
            first_unfinished = fmt::format("run {} ended with status {}", s.runs[pending[k]].id,
                                           a.is_object() ? a.value("exit_status", -1) : -1);
        } else if (first_unfinished.empty()) {
          first_unfinished = fmt::format("run {}: {}", s.runs[pending[k]].id, oc.text);
        }
        if (finished) ++finished_now;
        progress.finished(failed);
      });
    } catch (const Error& e) {
      if (e.kind() == ErrorKind::Interrupted) {
        progress.clear();
        sessions.back()["runs_finished"] = finished_now;
        sessions.back()["ended"] = now_text();
        study["status"] = "interrupted";
        study["sessions"] = sessions;
        write_text_atomically(out / "study.json", study.dump(1) + "\n");
      }
      throw;
    }
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();

  // The tables, from the result.json files, in the runs' order.
  std::vector<json> results(s.runs.size());
  for (const auto& r : s.runs) {
    const fs::path f = out / "runs" / r.id / "result.json";
    if (!fs::exists(f)) continue;
    results[r.index] = json::parse(read_input(f.string(), input_limit::kTable, "a result.json"));
    // A study killed between a run's result and the dropping of its outputs left them.
    drop_outputs(f.parent_path(), keep_name(s.keep),
                 results[r.index].value("exit_status", -1) == 0 && results[r.index].value("status", "") == "ok");
  }
  std::vector<std::string> value_columns, timing_columns;
  for (const auto& q : s.quantities)
    for (const auto& c : q.columns()) (q.timing ? timing_columns : value_columns).push_back(c);
  std::string table = "run,case";
  for (const auto& p : s.parameters) add_cell(table, csv_text(p.key));
  table += ",status,exit_status";
  for (const auto& c : value_columns) add_cell(table, c);
  table += "\n";
  std::string timings = "run,rank,host,session,seconds";
  for (const auto& c : timing_columns) add_cell(timings, c);
  timings += "\n";
  size_t ok = 0, failed = 0, missing = 0;
  std::map<std::string, std::vector<std::string>> lacking;  // quantity -> runs without it
  std::string first_failure;
  int first_failure_status = 0;
  for (const auto& r : s.runs) {
    const json& res = results[r.index];
    table += r.id + "," + csv_text(s.cases[r.case_index].name);
    for (const auto& c : r.columns) add_cell(table, csv_text(c));
    if (res.is_null()) {
      ++missing;
      table += ",missing,";
      for (size_t k = 0; k < value_columns.size(); ++k) table += ",";
      table += "\n";
      continue;
    }
    const std::string status = res.value("status", std::string("failed"));
    const int exit_status = res.value("exit_status", -1);
    if (status == "ok" && exit_status == 0) {
      ++ok;
    } else {
      ++failed;
      if (first_failure.empty()) {
        first_failure = fmt::format("run {}: {}", r.id, res.value("error", status));
        first_failure_status = exit_status;
      }
    }
    add_cell(table, csv_text(status));
    add_cell(table, std::to_string(exit_status));
    const json& vals = res["values"];
    for (const auto& c : value_columns) add_cell(table, csv_cell(vals.contains(c) ? vals[c] : json()));
    table += "\n";
    const json& tim = res["timings"];
    timings += fmt::format("{},{},{},{},{}", r.id, res.value("rank", 0), csv_text(res.value("host", std::string())),
                           res.value("session", 0), csv_cell(tim.value("seconds", json())));
    for (const auto& c : timing_columns) add_cell(timings, csv_cell(tim.contains(c) ? tim[c] : json()));
    timings += "\n";
    if (status == "ok")
      for (const auto& m : res.value("missing", json::array())) lacking[m.get<std::string>()].push_back(r.id);
  }
  // A quantity missing in runs that ended ok: its path is not in their summary.json.
  for (const auto& [name, runs] : lacking)
    warn(fmt::format("collect.{}: {} run(s) that ended ok have no value (first: run {})", name, runs.size(),
                     runs.front()));
  write_text_atomically(out / "study.csv", table);
  write_text_atomically(out / "timings.csv", timings);

  if (!s.pairs.empty()) {
    // Product strides: the last axis varies fastest.
    size_t axes = 0;
    for (const auto& p : s.parameters) axes = std::max(axes, p.axis + 1);
    std::vector<size_t> length(axes, 1), stride(axes, 1);
    for (const auto& p : s.parameters) length[p.axis] = p.texts.size();
    for (size_t a = axes; a-- > 1;) stride[a - 1] = stride[a] * length[a];
    const size_t product = axes ? stride[0] * length[0] : 1;
    std::string pcsv = "pair,run,reference_run,case";
    for (const auto& p : s.parameters) add_cell(pcsv, csv_text(p.key));
    pcsv += ",rms,rms_mean,samples\n";
    for (const auto& pair : s.pairs) {
      for (const auto& r : s.runs) {
        if (r.value[pair.parameter] == pair.reference) continue;
        const Run& ref = s.runs[partner(s, r, pair, stride, product)];
        pcsv += fmt::format("{},{},{},{}", pair.name, r.id, ref.id, csv_text(s.cases[r.case_index].name));
        for (const auto& c : r.columns) add_cell(pcsv, csv_text(c));
        const auto a = results[r.index].is_null() ? std::vector<coupling::TracePoint>{} : trace_of(results[r.index]);
        const auto b =
            results[ref.index].is_null() ? std::vector<coupling::TracePoint>{} : trace_of(results[ref.index]);
        coupling::CompareResult c;
        if (a.size() >= 2 && b.size() >= 2) c = coupling::compare_traces(a, b, pair.spacing);
        if (c.samples > 0)
          pcsv += fmt::format(",{},{},{}\n", c.rms_published_total, c.rms_total, c.samples);
        else
          pcsv += ",,,0\n";
      }
    }
    write_text_atomically(out / "pairs.csv", pcsv);
  }
  if (s.plot) draw_plots(s, out, !s.pairs.empty());

  sessions.back()["runs_finished"] = finished_now;
  sessions.back()["ended"] = now_text();
  sessions.back()["seconds"] = seconds;
  const auto& st = d.stats();
  sessions.back()["dispatch"] = {
      {"runs", st.tasks},
      {"handed_to_other_ranks", st.handed_out},
      {"cpu_seconds", st.cpu_seconds},
      {"handling_seconds", st.handling_seconds},
      {"wall_seconds", st.wall_seconds},
      {"wakeups", st.wakeups},
      {"cpu_seconds_per_run", st.tasks ? st.cpu_seconds / static_cast<double>(st.tasks) : 0.0},
      {"handling_seconds_per_run", st.tasks ? st.handling_seconds / static_cast<double>(st.tasks) : 0.0}};
  study["sessions"] = sessions;
  study["status"] = missing ? "incomplete" : "done";
  study["counts"] = {{"runs", s.runs.size()}, {"ok", ok}, {"failed", failed}, {"missing", missing}};
  write_text_atomically(out / "study.json", study.dump(1) + "\n");

  for (const auto& w : take_warnings()) std::fprintf(stderr, "flowire: warning: %s\n", w.c_str());
  std::printf(
      "flowire: study: %zu runs: %zu ok, %zu failed%s; %ld run now on %d rank%s x %d job%s in %.1f s; "
      "outputs in %s\n",
      s.runs.size(), ok, failed, missing ? fmt::format(", {} without a result", missing).c_str() : "", finished_now,
      d.ranks(), d.ranks() == 1 ? "" : "s", d.jobs(), d.jobs() == 1 ? "" : "s", seconds, o.out.c_str());
  if (missing)
    throw_numerical_error(
        fmt::format("study: {} of {} runs have no result ({}); run the same command again to run "
                    "them",
                    missing, s.runs.size(), first_unfinished.empty() ? "see their run.log" : first_unfinished));
  if (ok == 0 && failed > 0) {
    const std::string msg = fmt::format("study: every run failed; the first, {}", first_failure);
    throw Error(first_failure_status == 2 ? ErrorKind::Input : ErrorKind::Numerical, msg);
  }
  return 0;
}

}  // namespace

int run_study(const StudyOptions& o) {
  int rank = 0;
  Dispatcher d(o.jobs, [&rank](const std::string& payload) { return run_one(payload, rank); });
  rank = d.rank();
  if (!d.root()) return d.serve();
  try {
    const int status = study_root(o, d);
    d.stop(status);
    return status;
  } catch (const Error& e) {
    d.stop(exit_status(e));
    throw;
  } catch (...) {
    d.stop(3);
    throw;
  }
}

}  // namespace flowire::cli
