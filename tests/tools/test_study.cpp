// `flowire study` end to end (docs/study.md): bad study files refused before anything runs,
// the same table whatever ran the runs (--jobs, 1, 2 and 4 MPI ranks), a study killed by
// SIGKILL and resumed, children of MPI ranks starting as MPI singletons of their own, and
// `flowire fit` under mpirun.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>
#include <vector>

#include "cli_run.hpp"
#include "fit_probe_scene.hpp"
#include "flowire_test.hpp"

extern char** environ;

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using Result = flowire::testing::CliResult;

std::string flowire_exe() { return std::string(FLOWIRE_BINARY_DIR) + "/tools/flowire"; }

/// A shell command line's exit status, stdout and stderr (captured in @p dir).
Result shell(const std::string& cmd, const fs::path& dir) { return flowire::testing::run_shell(cmd, dir); }

Result cli(const std::string& args, const fs::path& dir) { return shell(flowire_exe() + " " + args, dir); }

#ifdef FLOWIRE_MPIEXEC
/// `mpiexec -n RANKS flowire ARGS`; as root and with more ranks than cores where need be (Open
/// MPI reads these variables; other launchers ignore them). A job that hangs (a child that
/// joined the launcher's job) fails after two minutes.
Result mpi_flowire(int ranks, const std::string& args, const fs::path& dir) {
  return shell(
      "timeout 120 env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 " +
          std::string(FLOWIRE_MPIEXEC) + " -n " + std::to_string(ranks) + " " + flowire_exe() + " " + args,
      dir);
}
#endif

std::string slurp(const fs::path& p) {
  std::stringstream s;
  s << std::ifstream(p, std::ios::binary).rdbuf();
  return s.str();
}

std::vector<std::map<std::string, std::string>> read_csv(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  auto split = [](const std::string& l) {
    std::vector<std::string> cells;
    std::stringstream ss(l);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    if (!l.empty() && l.back() == ',') cells.emplace_back();
    return cells;
  };
  const auto header = split(line);
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    const auto cells = split(line);
    std::map<std::string, std::string> row;
    for (size_t i = 0; i < header.size(); ++i) row[header[i]] = i < cells.size() ? cells[i] : "";
    rows.push_back(row);
  }
  return rows;
}

std::string arch_scene() { return std::string(FLOWIRE_SOURCE_DIR) + "/examples/aortic_arch/scene.yaml"; }

/// Eight runs of the aortic arch of 0.3 s each (30 steps): two insertion speeds × flow on and
/// off × two base rotations, with every kind of quantity and two pairings.
std::string small_study(bool plot) {
  return "scene: " + arch_scene() + R"(
set: {solve.duration: 0.3 s, output.vtk: false}
parameters:
  insertion.speed: [1 cm/s, 2 cm/s]
  coupling.drag: [cylinder, none]
  insertion.rotation_angle: [0 deg, 90 deg]
collect:
  inserted: {summary: wire.inserted_length}
  state: {summary: status}
  unconverged: {summary: wire.unconverged_steps}
  total: {summary: timings.total}
  tip: {tip: final_position}
  reach: {tip: time_to_length, length: 2.4 cm}
  clamp: {clamp_force: max}
pairs:
  flow: {parameter: coupling.drag, reference: none}
  turn: {parameter: insertion.rotation_angle, reference: 0 deg}
plot: )" +
         std::string(plot ? "true" : "false") + "\n";
}

bool have_matplotlib() { return std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") == 0; }

}  // namespace

TEST(Study, BadStudiesExitTwoNamingFileLineAndKeyAndWriteNothing) {
  const auto dir = flowire::testing::scratch_dir("study-bad");
  const std::string head = "scene: " + arch_scene() + "\n";
  auto expect_bad = [&](const std::string& body, const std::string& fragment) {
    const fs::path study = dir / "study.yaml";
    std::ofstream(study) << body;
    const auto out = dir / "out";
    const auto r = cli("study " + study.string() + " --out " + out.string(), dir);
    EXPECT_EQ(r.status, 2) << body << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("flowire: error: " + study.string() + ":", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(fragment), std::string::npos) << "expected '" << fragment << "' in: " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(out)) << body;
  };
  // The place: file and line, then the key.
  expect_bad(head + "colect: {a: {summary: status}}\n", "study.yaml:2: unknown key 'colect'");
  expect_bad(head + "parameters: [insertion.speed]\n", "study.yaml:2: parameters: expected a map");
  expect_bad(head + "plot: sometimes\n", "study.yaml:2: plot: 'sometimes' must be true or false");
  expect_bad(head + "keep_runs: maybe\n", "study.yaml:2: keep_runs");
  // Empty products.
  expect_bad(head + "parameters:\n  insertion.speed: []\n", "study.yaml:3: parameters.insertion.speed: an empty list");
  expect_bad(head + "parameters:\n  insertion.speed: {from: 1 cm/s, to: 2 cm/s, count: 0}\n",
             "study.yaml:3: parameters.insertion.speed.count: 0 must be at least 2");
  expect_bad(head + "parameters:\n  insertion.speed: {from: 1 cm/s, to: 2 cm/s, count: two}\n",
             "parameters.insertion.speed.count: 'two' must be a whole number");
  expect_bad(head + "parameters:\n  insertion.speed: {from: 1 cm/s, count: 3}\n", "'to' is missing");
  // Keys that are no scene keys, and values the scene refuses (each run's scene is loaded).
  expect_bad(head + "parameters:\n  insertion.sped: [1 cm/s]\n",
             "study.yaml:3: parameters.insertion.sped: not a scene key");
  expect_bad(head + "set: {wire.lenght: 1}\n", "study.yaml:2: set.wire.lenght: not a scene key");
  expect_bad(head + "parameters:\n  insertion.speed: [1 cm/s,\n    1 kg]\n",
             "study.yaml:4: parameters.insertion.speed: the scene refuses run 0001");
  expect_bad(head + "parameters:\n  wire.length: [0.5, -1]\n", "wire.length = -1 m: must be positive");
  expect_bad(head + "parameters:\n  coupling.drag: [cylinder, stokes]\n", "'stokes' is not one of");
  expect_bad(head + "parameters:\n  coupling.drag: {from: 0, to: 1, count: 2}\n", "a range needs a number key");
  expect_bad(head + "parameters:\n  insertion.speed: [1 cm/s, 0.01]\n", "'0.01' is the same value as '1 cm/s'");
  expect_bad(head + "set: {insertion.speed: 1 cm/s}\nparameters:\n  insertion.speed: [2 cm/s]\n", "also fixed by set");
  // Zip groups.
  expect_bad(head +
                 "parameters:\n  insertion.speed: [1 cm/s, 2 cm/s]\n  solve.duration: [1 s]\nzip:\n  - "
                 "[insertion.speed, solve.duration]\n",
             "zipped lists have equal lengths");
  expect_bad(head + "parameters:\n  insertion.speed: [1 cm/s, 2 cm/s]\nzip:\n  - [insertion.speed, wire.length]\n",
             "study.yaml:5: zip: 'wire.length' is not one of the parameters");
  // Quantities that no run produces.
  expect_bad(head + "set: {coupling.drag: none}\ncollect:\n  drag: {summary: drag.total}\n",
             "study.yaml:4: collect.drag: no run writes summary.json's 'drag'");
  expect_bad(head + "collect:\n  x: {summary: bogus.value}\n", "collect.x.summary: summary.json has no 'bogus'");
  expect_bad(head + "set: {output.csv: false}\ncollect:\n  tip: {tip: final_position}\n",
             "collect.tip: no run writes tip_trace.csv");
  expect_bad(head + "collect:\n  t: {tip: time_to_length}\n", "needs length:");
  expect_bad(head + "collect:\n  t: {tip: final_position, clamp_force: max}\n", "give exactly one of");
  // Pairs.
  expect_bad(head +
                 "parameters:\n  insertion.speed: [1 cm/s, 2 cm/s]\npairs:\n  p: {parameter: insertion.speed, "
                 "reference: 3 cm/s}\n",
             "pairs.p.reference: '3 cm/s' is not one of the values");
  expect_bad(head + "pairs:\n  p: {parameter: coupling.drag, reference: none}\n", "is not one of the parameters");
  // Files.
  expect_bad("scene: missing.yaml\n", "study.yaml:1: scene:");
  expect_bad(head + "cases:\n  a: {scene: nowhere.yaml}\n", "study.yaml:3: cases.a.scene:");
  expect_bad(head + "parameters: {insertion.speed: [1 cm/s, 2 cm/s]\n", "YAML syntax error");
}

TEST(Study, AFolderOfAnotherStudyIsRefusedAndLeftAsItWas) {
  const auto dir = flowire::testing::scratch_dir("study-other");
  const std::string base =
      "scene: " + arch_scene() + "\nset: {solve.duration: 0.05 s, output.vtk: false}\nplot: false\n";
  std::ofstream(dir / "a.yaml") << base;
  std::ofstream(dir / "b.yaml") << base + "collect:\n  inserted: {summary: wire.inserted_length}\n";
  const auto out = dir / "out";
  auto r = cli("study " + (dir / "a.yaml").string() + " --out " + out.string(), dir);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string table = slurp(out / "study.csv");
  const std::string study = slurp(out / "study.json");
  r = cli("study " + (dir / "b.yaml").string() + " --out " + out.string(), dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("holds the results of another study"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(out / "study.csv"), table);
  EXPECT_EQ(slurp(out / "study.json"), study);
  // A folder holding anything else is not taken either.
  fs::create_directories(dir / "other");
  std::ofstream(dir / "other" / "notes.txt") << "mine\n";
  r = cli("study " + (dir / "a.yaml").string() + " --out " + (dir / "other").string(), dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "other"), fs::directory_iterator()), 1);
}

TEST(Study, SameTablesWithJobsAndOnOneTwoAndFourRanks) {
  const auto dir = flowire::testing::scratch_dir("study-ranks");
  std::ofstream(dir / "plots.yaml") << small_study(true);
  std::ofstream(dir / "study.yaml") << small_study(false);
  auto r = cli("study " + (dir / "plots.yaml").string() + " --out " + (dir / "jobs1").string() + " --jobs 1", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  const fs::path ref = dir / "jobs1";

  // What the runs must give, from the scene itself: the feed is prescribed, so the inserted
  // length is the initial 2 cm plus speed × 0.3 s, and 2.4 cm is reached at 0.2 s at 2 cm/s
  // and never at 1 cm/s.
  const auto rows = read_csv(ref / "study.csv");
  ASSERT_EQ(rows.size(), 8u);
  std::set<std::string> seen;
  for (const auto& row : rows) {
    EXPECT_EQ(row.at("status"), "ok");
    EXPECT_EQ(row.at("state"), "ok");
    EXPECT_EQ(row.at("exit_status"), "0");
    const double speed = std::stod(row.at("insertion.speed"));
    EXPECT_NEAR(std::stod(row.at("inserted")), 0.02 + 0.3 * speed, 1e-9) << row.at("run");
    if (speed > 0.015) {
      EXPECT_NEAR(std::stod(row.at("reach")), 0.2, 1e-6) << row.at("run");
    } else {
      EXPECT_EQ(row.at("reach"), "") << row.at("run");
    }
    EXPECT_GT(std::stod(row.at("clamp")), 0.0);
    EXPECT_TRUE(std::isfinite(std::stod(row.at("tip_z"))));
    EXPECT_EQ(row.count("total"), 0u) << "timings go to timings.csv";
    seen.insert(row.at("insertion.speed") + row.at("coupling.drag") + row.at("insertion.rotation_angle"));
  }
  EXPECT_EQ(seen.size(), 8u) << "every combination once";
  EXPECT_EQ(std::stod(rows[1].at("insertion.rotation_angle")), M_PI / 2) << "SI values, exact";
  const auto timings = read_csv(ref / "timings.csv");
  ASSERT_EQ(timings.size(), 8u);
  for (const auto& t : timings) EXPECT_GT(std::stod(t.at("total")), 0.0);

  // Pairs: the flow pairing compares each run with its flow-off twin, the turn pairing each
  // turned run with its unturned twin; each RMS is what `flowire compare` says of the two traces.
  const auto pairs = read_csv(ref / "pairs.csv");
  ASSERT_EQ(pairs.size(), 8u);
  for (const auto& p : pairs) {
    const auto& run = rows[std::stoul(p.at("run"))];
    const auto& twin = rows[std::stoul(p.at("reference_run"))];
    EXPECT_EQ(run.at("insertion.speed"), twin.at("insertion.speed"));
    if (p.at("pair") == "flow") {
      EXPECT_EQ(run.at("coupling.drag"), "cylinder");
      EXPECT_EQ(twin.at("coupling.drag"), "none");
      EXPECT_EQ(run.at("insertion.rotation_angle"), twin.at("insertion.rotation_angle"));
    } else {
      EXPECT_EQ(run.at("coupling.drag"), twin.at("coupling.drag"));
      EXPECT_EQ(twin.at("insertion.rotation_angle"), "0");
      // Compared again on the kept runs: flowire compare prints the total in mm to 3 decimals.
      const auto c = cli("compare " + (ref / "runs" / p.at("run") / "tip_trace.csv").string() + " " +
                             (ref / "runs" / p.at("reference_run") / "tip_trace.csv").string(),
                         dir);
      ASSERT_EQ(c.status, 0) << c.err;
      int samples = -1;
      double rms_mm = -1;
      std::istringstream lines(c.out);
      for (std::string line; std::getline(lines, line);) std::sscanf(line.c_str(), " all %d %lf", &samples, &rms_mm);
      ASSERT_GE(samples, 0) << c.out;
      EXPECT_EQ(std::stoi(p.at("samples")), samples);
      EXPECT_NEAR(std::stod(p.at("rms")) * 1e3, rms_mm, 0.0006);
      EXPECT_GT(rms_mm, 1.0) << "a quarter turn of the J tip moves it by millimetres";
    }
  }
  if (have_matplotlib()) {
    for (const auto* name : {"inserted", "state", "unconverged", "tip", "reach", "clamp", "flow", "turn"})
      EXPECT_TRUE(fs::exists(ref / "plots" / (std::string(name) + ".png"))) << name;
    EXPECT_FALSE(fs::exists(ref / "plots" / "total.png"));
  }

  // The same tables however the runs were shared out.
  auto expect_same = [&](const fs::path& out, const std::string& how) {
    EXPECT_EQ(slurp(out / "study.csv"), slurp(ref / "study.csv")) << how;
    EXPECT_EQ(slurp(out / "pairs.csv"), slurp(ref / "pairs.csv")) << how;
  };
  r = cli("study " + (dir / "study.yaml").string() + " --out " + (dir / "jobs2").string() + " --jobs 2", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  expect_same(dir / "jobs2", "--jobs 2");
#ifdef FLOWIRE_MPIEXEC
  for (const int ranks : {1, 2, 4}) {
    const auto out = dir / ("ranks" + std::to_string(ranks));
    r = mpi_flowire(ranks, "study " + (dir / "study.yaml").string() + " --out " + out.string(), dir);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << "rank 0 alone reports:\n" << r.out;
    expect_same(out, std::to_string(ranks) + " ranks");
    std::set<std::string> ranks_used;
    for (const auto& t : read_csv(out / "timings.csv")) ranks_used.insert(t.at("rank"));
    EXPECT_EQ(ranks_used.size(), static_cast<size_t>(ranks)) << "every rank ran some of the 8 runs";
    const auto j = json::parse(std::ifstream(out / "study.json"));
    EXPECT_EQ(j["sessions"][0]["ranks"].get<int>(), ranks);
    EXPECT_EQ(j["sessions"][0]["dispatch"]["runs"].get<int>(), 8);
  }
#else
  GTEST_SKIP() << "built without MPI: the runs on 1, 2 and 4 ranks are not checked";
#endif
}

TEST(Study, KilledStudyResumesRunningOnlyTheRunsWithoutAResult) {
  const auto dir = flowire::testing::scratch_dir("study-resume");
  // Twelve runs of about half a second; the outputs of finished runs are dropped.
  std::ofstream(dir / "study.yaml") << "scene: " + arch_scene() + R"(
set: {solve.duration: 1 s, output.vtk: false}
parameters:
  insertion.speed: {from: 1 cm/s, to: 2 cm/s, count: 3}
  coupling.drag: [cylinder, none]
  contact.friction: [0.1, 0.2]
collect:
  inserted: {summary: wire.inserted_length}
  tip: {tip: final_position}
pairs:
  flow: {parameter: coupling.drag, reference: none}
keep_runs: false
plot: false
)";
  const std::string study = (dir / "study.yaml").string();
  auto r = cli("study " + study + " --out " + (dir / "whole").string() + " --jobs 2", dir);
  ASSERT_EQ(r.status, 0) << r.err;

  // The same study, killed (SIGKILL) once a few runs have their result.
  const fs::path out = dir / "killed";
  const std::vector<std::string> args{flowire_exe(), "study", study, "--out", out.string(), "--jobs", "2"};
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&fa);
  auto results = [&] {
    std::map<std::string, std::pair<std::string, fs::file_time_type>> found;
    if (!fs::exists(out / "runs")) return found;
    for (const auto& e : fs::directory_iterator(out / "runs"))
      if (fs::exists(e.path() / "result.json"))
        found[e.path().filename().string()] = {slurp(e.path() / "result.json"),
                                               fs::last_write_time(e.path() / "result.json")};
    return found;
  };
  const auto t0 = std::chrono::steady_clock::now();
  while (results().size() < 3 && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_EQ(::kill(pid, SIGKILL), 0);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the study ended before it was killed";
  const auto before = results();
  ASSERT_GE(before.size(), 3u);
  ASSERT_LT(before.size(), 12u) << "killed too late to leave runs to do";

  r = cli("study " + study + " --out " + out.string() + " --jobs 2", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(slurp(out / "study.csv"), slurp(dir / "whole" / "study.csv"));
  EXPECT_EQ(slurp(out / "pairs.csv"), slurp(dir / "whole" / "pairs.csv"));
  // Only the runs without a result ran again: the others' results are untouched, and the
  // second session counts the rest.
  const auto after = results();
  EXPECT_EQ(after.size(), 12u);
  for (const auto& [id, res] : before) {
    EXPECT_EQ(after.at(id).first, res.first) << id;
    EXPECT_EQ(after.at(id).second, res.second) << id;
    EXPECT_EQ(json::parse(res.first)["session"].get<int>(), 1) << id;
  }
  for (const auto& [id, res] : after) {
    if (!before.count(id)) {
      EXPECT_EQ(json::parse(res.first)["session"].get<int>(), 2) << id;
    }
  }
  const auto j = json::parse(std::ifstream(out / "study.json"));
  ASSERT_EQ(j["sessions"].size(), 2u);
  EXPECT_EQ(j["sessions"][1]["runs_pending"].get<size_t>(), 12 - before.size());
  EXPECT_EQ(j["sessions"][1]["runs_finished"].get<size_t>(), 12 - before.size());
  EXPECT_EQ(j["status"], "done");
  // Nothing half-written anywhere; the dropped runs keep only their result.
  for (const auto& e : fs::recursive_directory_iterator(out)) {
    EXPECT_EQ(e.path().filename().string().find(".partial"), std::string::npos) << e.path();
    if (e.path().parent_path().parent_path() == out / "runs") {
      EXPECT_EQ(e.path().filename(), "result.json");
    }
  }
}

#ifdef FLOWIRE_MPIEXEC
TEST(StudyMpi, ChildrenOfRanksStartAsMpiSingletonsOfTheirOwn) {
  // A run that uses PETSc (flow.solver: petsc) calls MPI_Init: started from a rank with the
  // launcher's variables it would try to join the launcher's job; stripped of them it starts
  // alone.
  const auto dir = flowire::testing::scratch_dir("study-petsc");
  std::ofstream(dir / "study.yaml") << "scene: " + arch_scene() + R"(
set: {solve.duration: 0.05 s, output.vtk: false, flow.solver: petsc}
parameters:
  insertion.speed: [1 cm/s, 2 cm/s]
collect:
  solver: {summary: flow.solver}
plot: false
)";
  const auto r = mpi_flowire(2, "study " + (dir / "study.yaml").string() + " --out " + (dir / "out").string(), dir);
  ASSERT_EQ(r.status, 0) << r.err;
  for (const auto& row : read_csv(dir / "out" / "study.csv")) {
    EXPECT_EQ(row.at("status"), "ok") << slurp(dir / "out" / "runs" / row.at("run") / "run.log");
    EXPECT_EQ(row.at("solver"), "petsc");
  }
}

TEST(StudyMpi, FitOnTwoRanksRecoversAHiddenRotation) {
  // The fit test's probe (tests/tools/test_fit.cpp): a J tip in a wide tube whose tip trace
  // fixes the base rotation. The "measured" trace is the scene's own at 0.5 rad; the fit runs
  // CMA-ES on rank 0 and each generation's runs on both ranks.
  const auto dir = flowire::testing::scratch_dir("study-fit");
  std::ofstream(dir / "scene.yaml") << flowire::testing::kFitProbeScene;
  const double hidden = 0.5;
  auto r = cli("run " + (dir / "scene.yaml").string() + " --out " + (dir / "truth").string() +
                   " --set insertion.rotation_angle=" + std::to_string(hidden),
               dir);
  ASSERT_EQ(r.status, 0) << r.err;
  r = mpi_flowire(2,
                  "fit " + (dir / "scene.yaml").string() + " --trace " + (dir / "truth" / "tip_trace.csv").string() +
                      " --param 'insertion.rotation_angle=0 deg..120 deg' --out " + (dir / "fit").string() +
                      " --max-evaluations 60 --seed 3",
                  dir);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = json::parse(std::ifstream(dir / "fit" / "fit.json"));
  // Without noise the fit is limited by the search: 0.5 % of the 2.09 rad range.
  EXPECT_NEAR(j["params"]["insertion.rotation_angle"].get<double>(), hidden, 0.01);
  EXPECT_EQ(j["evaluations"].get<long>(), 60);
  EXPECT_EQ(read_csv(dir / "fit" / "fit_history.csv").size(), 60u);
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 3) << "rank 0 alone reports:\n" << r.out;
}
#endif

TEST(Study, ExampleStudiesAreValid) {
  // The examples check and expand (--list: nothing runs): the flow on/off table is 3 speeds,
  // each zipped with its push duration, times flow on and off.
  const auto dir = flowire::testing::scratch_dir("study-examples");
  const std::string studies = std::string(FLOWIRE_SOURCE_DIR) + "/examples/studies/";
  auto r = cli("study " + studies + "flow_on_off.yaml --list", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out,
            "run,case,insertion.speed,solve.duration,coupling.drag\n"
            "0000,,0.01,48,cylinder\n0001,,0.01,48,none\n0002,,0.015,32,cylinder\n0003,,0.015,32,none\n"
            "0004,,0.02,24,cylinder\n0005,,0.02,24,none\n");
  FLOWIRE_REQUIRE_SHARED("data/real/aneurisk-c0015-ica-vampy");
  r = cli("study " + studies + "friction_tip.yaml --list", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 10) << r.out;
}

TEST(Study, DocsListEveryStudyKey) {
  // docs/study.md carries the table `flowire help study` prints, generated from the one declaration.
  const auto dir = flowire::testing::scratch_dir("study-docs");
  const auto r = cli("help study", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto at = r.out.find("| key |");
  ASSERT_NE(at, std::string::npos) << r.out;
  const std::string table = r.out.substr(at);
  const std::string doc = slurp(std::string(FLOWIRE_SOURCE_DIR) + "/docs/study.md");
  EXPECT_NE(doc.find(table), std::string::npos)
      << "regenerate the key table of docs/study.md from `flowire help study`:\n"
      << table;
}
