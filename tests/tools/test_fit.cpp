// `flowire fit` end to end: hidden scene values recovered from a noisy synthetic tip trace,
// and bad arguments rejected before anything is written (contract: flowire-cli.md, v2).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <vector>

#include "cli_run.hpp"
#include "fit_probe_scene.hpp"
#include "flowire_test.hpp"

namespace fs = std::filesystem;

namespace {

using Result = flowire::testing::CliResult;

Result run(const std::string& args, const fs::path& dir) { return flowire::testing::run_cli_in(args, dir); }

const char* const kScene = flowire::testing::kFitProbeScene;

#ifdef FLOWIRE_FIT_SLOW
struct Row {
  double t, L, x, y, z;
};

std::vector<Row> read_trace(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    Row r{};
    if (std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf", &r.t, &r.L, &r.x, &r.y, &r.z) == 5) rows.push_back(r);
  }
  return rows;
}

// 48 runs of about a second each (process start-up dominates): labelled slow (test_fit_slow).
TEST(Fit, RecoversAHiddenRotationFromANoisyTrace) {
  const auto dir = flowire::testing::scratch_dir("fit-recover");
  std::ofstream(dir / "scene.yaml") << kScene;
  // The "measured" trace: the scene run at the hidden rotation, plus Gaussian noise.
  const double hidden = 0.5;  // rad
  const double noise = 1e-4;  // m, per coordinate
  auto r = run("run " + (dir / "scene.yaml").string() + " --out " + (dir / "truth").string() +
                   " --set insertion.rotation_angle=" + std::to_string(hidden),
               dir);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto truth = read_trace(dir / "truth" / "tip_trace.csv");
  ASSERT_GT(truth.size(), 10u);
  std::mt19937_64 rng(42);
  std::normal_distribution<double> gauss(0.0, noise);
  double offset = 0;  // mean distance of the tip from the tube axis: the lever of the rotation
  {
    std::ofstream m(dir / "measured.csv");
    m << "time,inserted_length,x,y,z\n";
    m.precision(12);
    for (const auto& p : truth) {
      offset += std::hypot(p.y, p.z) / static_cast<double>(truth.size());
      m << p.t << "," << p.L << "," << p.x + gauss(rng) << "," << p.y + gauss(rng) << "," << p.z + gauss(rng) << "\n";
    }
  }
  ASSERT_GT(offset, 1e-3) << "the J tip must stand off the axis for the rotation to show";

  // Range 0..120 deg: centred at 60 deg (1.047 rad), not on the hidden 0.5 rad.
  const double lo = 0.0, hi = 120.0 * M_PI / 180.0;
  r = run("fit " + (dir / "scene.yaml").string() + " --trace " + (dir / "measured.csv").string() +
              " --param 'insertion.rotation_angle=0 deg..120 deg' --out " + (dir / "fit").string() +
              " --jobs 2 --max-evaluations 48 --seed 3",
          dir);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(std::ifstream(dir / "fit" / "fit.json"));
  const double fitted = j["params"]["insertion.rotation_angle"].get<double>();
  const int samples = j["samples"].get<int>();
  ASSERT_GT(samples, 3);
  // Least squares on `samples` points whose tangential position moves by offset·δθ, each with
  // noise σ per coordinate: δθ has standard deviation σ / (offset·√samples). Allow 4 of those
  // plus the search's stopping resolution (tol_x = 1e-3 of the range, twice).
  const double tol = 4.0 * noise / (offset * std::sqrt(samples)) + 2e-3 * (hi - lo);
  EXPECT_NEAR(fitted, hidden, tol) << "tolerance " << tol;
  EXPECT_LE(j["evaluations"].get<long>(), 48);
  // The reported rms is that of the best run's outputs, and near the noise floor:
  // eq. 11 over `samples` points of 3 coordinates each of variance σ² gives (3·samples·σ²/2)^½.
  const double floor = std::sqrt(1.5 * samples) * noise;
  EXPECT_LT(j["rms"].get<double>(), 2.0 * floor);
  EXPECT_TRUE(fs::exists(dir / "fit" / "tip_trace.csv"));
  EXPECT_TRUE(fs::exists(dir / "fit" / "summary.json"));
  std::ifstream h(dir / "fit" / "fit_history.csv");
  std::string header;
  std::getline(h, header);
  EXPECT_EQ(header, "evaluation,generation,insertion.rotation_angle,rms,rms_mean,status");
  long lines = 0;
  for (std::string l; std::getline(h, l);) ++lines;
  EXPECT_EQ(lines, j["evaluations"].get<long>());
  // No work folder left behind.
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".fit-work"), std::string::npos);
}

#else
TEST(Fit, BadArgumentsExitTwoNamingThemAndWriteNothing) {
  const auto dir = flowire::testing::scratch_dir("fit-bad");
  std::ofstream(dir / "scene.yaml") << kScene;
  std::ofstream(dir / "good.csv") << "time,inserted_length,x,y,z\n0,0.01,0,0,0\n1,0.03,0.02,0,0\n";
  std::ofstream(dir / "bad.csv") << "time,inserted_length,x,y,z\n0,0.01,0,0,0\n1,0.03,oops,0,0\n";
  const std::string scene = (dir / "scene.yaml").string();
  auto expect_bad = [&](const std::string& args, const std::string& fragment) {
    const auto out = dir / "out";
    const auto r = run("fit " + scene + " --out " + out.string() + " " + args, dir);
    EXPECT_EQ(r.status, 2) << args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("flowire: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(fragment), std::string::npos) << "expected '" << fragment << "' in: " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(out)) << args;
  };
  const std::string good = " --trace " + (dir / "good.csv").string();
  expect_bad(good + " --param wire.stiffnesss=1..2", "wire.stiffnesss");
  expect_bad(good + " --param insertion.speed=3cm/s..1cm/s", "must be less than");
  expect_bad(good + " --param insertion.speed=2cm/s..2cm/s", "must be less than");
  expect_bad(good + " --param insertion.speed=1cm/s-3cm/s", "malformed range");
  expect_bad(good + " --param insertion.speed=1..2..3", "malformed range");
  expect_bad(good + " --param insertion.speed=1kg..2kg", "insertion.speed");
  expect_bad(good + " --param wire.tip.shape=1..2", "not a number");
  expect_bad(" --trace " + (dir / "missing.csv").string() + " --param insertion.speed=1cm/s..3cm/s", "missing.csv");
  expect_bad(" --trace " + (dir / "bad.csv").string() + " --param insertion.speed=1cm/s..3cm/s", "bad.csv:3");
  expect_bad(good + " --param insertion.speed=1cm/s..3cm/s --param insertion.speed=1cm/s..2cm/s", "given twice");
  // A bound outside the key's declared range is refused naming the key and the range.
  expect_bad(good + " --param wire.length=-1..0.5", "wire.length = -1 m: must be positive (> 0)");
  expect_bad(good + " --param contact.friction=0..2 --param wire.tip.angle=0..7", "wire.tip.angle = 7 rad");
  // A value the scene rejects only when it runs (an initial length longer than the 0.1 m
  // wire): the first generation fails, the fit stops with the run's message and writes nothing.
  expect_bad(good + " --param insertion.initial_length=0.2..0.3 --jobs 2", "every run of the first generation failed");
}
#endif

}  // namespace
