// Declared ranges of the scene keys, and numbers of time steps, as the loader and the command
// line enforce them: every bounded key of the scene's declaration at its limit and just past
// it, then the out-of-range values of scenes and svZeroDSolver models from the outside (exit
// status 2, one line naming the file or --set, the key, the value and the limit).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_run.hpp"
#include "flowire/common/config.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/steps.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire_test.hpp"

namespace fs = std::filesystem;
using flowire::config::Key;
using flowire::config::Type;

namespace {

/// A one-line YAML scene that gives the declared key @p path the value @p value: its sections
/// nested as flow maps, a list item key ("loads[].s") as the one item of its list, a named
/// entry ("flow.outlets.*.pressure") under the name some_name.
std::string scene_with(const std::string& path, const std::string& value) {
  std::vector<std::string> parts;
  std::stringstream ss(path);
  for (std::string p; std::getline(ss, p, '.');) parts.push_back(p);
  std::string text = value;
  for (auto it = parts.rbegin(); it != parts.rend(); ++it) {
    const bool list = it->ends_with("[]");
    const std::string name = list ? it->substr(0, it->size() - 2) : *it == "*" ? "some_name" : *it;
    text = list ? fmt::format("{{{}: [{}]}}", name, text) : fmt::format("{{{}: {}}}", name, text);
  }
  return text + "\n";
}

/// The concrete path of a declared key in the scene scene_with() writes ("loads[].s" is "loads[0].s").
std::string concrete(std::string path) {
  for (size_t at; (at = path.find("[]")) != std::string::npos;) path.replace(at, 2, "[0]");
  for (size_t at; (at = path.find(".*")) != std::string::npos;) path.replace(at, 2, ".some_name");
  return path;
}

/// @p v as the YAML value of @p key: a number, or a vector or list of it.
std::string value_text(const Key& key, double v) {
  const std::string x = fmt::format("{:.17g}", v);
  if (key.type == Type::Vector3) return fmt::format("[{0}, {0}, {0}]", x);
  if (key.type == Type::NumberList) return fmt::format("[{}]", x);
  return x;
}

struct Probe {
  double value;
  bool accepted;
};

/// Values at each finite bound of @p key's range and just inside or past it: a closed bound
/// is accepted and the value a step beyond refused; an open bound is refused and the value a
/// step inside accepted. A step is 1 for integers, else 1e-9 of the bound (at least 1e-9).
std::vector<Probe> probes(const Key& key) {
  const auto& r = key.range;
  const auto step = [&](double bound) {
    return key.type == Type::Integer ? 1.0 : 1e-9 * std::max(std::abs(bound), 1.0);
  };
  std::vector<Probe> out;
  if (std::isfinite(r.lower)) {
    const double s = step(r.lower);
    if (r.lower_open)
      out.insert(out.end(), {{r.lower, false}, {r.lower + s, true}});
    else
      out.insert(out.end(), {{r.lower, true}, {r.lower - s, false}});
  }
  if (std::isfinite(r.upper)) {
    const double s = step(r.upper);
    if (r.upper_open)
      out.insert(out.end(), {{r.upper, false}, {r.upper - s, true}});
    else
      out.insert(out.end(), {{r.upper, true}, {r.upper + s, false}});
  }
  return out;
}

const flowire::config::Schema& schema() { return flowire::coupling::scene_schema(); }

}  // namespace

TEST(SceneRanges, EveryBoundedKeyAcceptsItsLimitAndRefusesJustPastItNamingTheLimit) {
  int bounded = 0, probed = 0;
  for (const Key& key : schema().keys()) {
    if (!flowire::config::is_numeric(key.type) || !key.range.bounded()) continue;
    ++bounded;
    for (const Probe& p : probes(key)) {
      ++probed;
      const std::string yaml = scene_with(key.path, value_text(key, p.value));
      SCOPED_TRACE(key.path + " = " + fmt::format("{:.17g}", p.value) + " in " + yaml);
      try {
        (void)flowire::config::load_config_text(yaml, "scene.yaml", schema());
        EXPECT_TRUE(p.accepted) << "a value outside " << key.range.text() << " was accepted";
      } catch (const flowire::Error& e) {
        const std::string what = e.what();
        EXPECT_FALSE(p.accepted) << "refused: " << what;
        if (p.accepted) continue;
        EXPECT_EQ(e.kind(), flowire::ErrorKind::Input) << what;
        EXPECT_EQ(what.rfind("scene.yaml:1: " + concrete(key.path), 0), 0u) << what;
        EXPECT_NE(what.find(key.range.text()), std::string::npos) << "the limit is not named: " << what;
        EXPECT_EQ(what.find('\n'), std::string::npos) << what;
      }
    }
  }
  // The scene declares ranges for most of its numbers; each bounded side is probed twice.
  EXPECT_GE(bounded, 60);
  EXPECT_GE(probed, 2 * bounded);
}

TEST(SceneRanges, EveryNumericKeyRefusesAValueThatIsNotFinite) {
  // 1e308 GPa is a finite number as written and infinite in Pa, the SI unit it is converted to.
  for (const Key& key : schema().keys()) {
    if (!flowire::config::is_numeric(key.type) || key.dim != flowire::units::Dimension::Pressure) continue;
    const std::string yaml = scene_with(key.path, key.type == Type::Vector3 ? "[0, 0, 1e308 GPa]" : "1e308 GPa");
    try {
      (void)flowire::config::load_config_text(yaml, "scene.yaml", schema());
      ADD_FAILURE() << key.path << ": an infinite value was accepted";
    } catch (const flowire::Error& e) {
      EXPECT_NE(std::string(e.what()).find("must be a finite number"), std::string::npos) << e.what();
    }
  }
}

TEST(SceneRanges, DeclaredDefaultsLieInTheirRanges) {
  // Every top-level section given empty takes its keys' defaults, each checked against its range.
  for (const Key* section : schema().children("")) {
    if (section->type != Type::Section) continue;
    EXPECT_NO_THROW((void)flowire::config::declared_defaults(schema(), section->path)) << section->path;
  }
  for (const Key& key : schema().keys()) {
    if (!flowire::config::is_numeric(key.type) || key.default_text.empty() || key.type == Type::NumberOrSection)
      continue;
    EXPECT_NO_THROW(
        (void)flowire::config::load_config_text(scene_with(key.path, key.default_text), "scene.yaml", schema()))
        << key.path;
  }
}

TEST(SceneRanges, PhysicalQuantitiesHaveTheSignTheyMustHave) {
  // Sizes, material constants and times of a step cannot be zero or negative; lengths and
  // frictions cannot be negative. A key added later without its range fails here.
  auto leaf = [](const std::string& path) { return path.substr(path.rfind('.') + 1); };
  int checked = 0;
  for (const Key& key : schema().keys()) {
    if (key.type != Type::Number && key.type != Type::Integer) continue;
    const std::string name = leaf(key.path);
    const auto has = [&](const char* part) { return name.find(part) != std::string::npos; };
    const auto& r = key.range;
    if (name.ends_with("radius") || name == "radius_ratio" || has("density") || has("viscosity") ||
        has("youngs_modulus") || has("mesh_size") || has("period") || name == "dt" ||
        (has("stiffness") && name != "support_stiffness")) {
      ++checked;
      EXPECT_TRUE(r.lower >= 0.0 && (r.lower > 0.0 || r.lower_open)) << key.path << " must be declared positive";
    } else if (has("length") || has("friction") || has("damping") || name == "support_stiffness" ||
               key.dim == flowire::units::Dimension::Time) {  // (a tissue support of 0: none)
      ++checked;
      EXPECT_GE(r.lower, 0.0) << key.path << " must be declared non-negative";
    }
  }
  EXPECT_GE(checked, 30);
}

TEST(SceneRanges, EveryExampleSceneLoads) {
  // The examples' values lie in the declared ranges (their runs are tests of their own).
  int scenes = 0;
  for (const auto& e : fs::recursive_directory_iterator(fs::path(FLOWIRE_SOURCE_DIR) / "examples")) {
    // examples/studies holds study files (flowire study), checked by Study.ExampleStudiesAreValid.
    if (e.path().extension() != ".yaml" || e.path().parent_path().filename() == "studies") continue;
    ++scenes;
    try {
      (void)flowire::coupling::load_scene(e.path().string(), {});
    } catch (const flowire::Error& err) {
      ADD_FAILURE() << err.what();
    }
  }
  EXPECT_GE(scenes, 10);
}

// ---------------------------------------------------------------- from the command line

namespace {

/// A short wire run in a straight tube (two steps), values changed by --set.
const char* kWireScene = R"(vessels:
  generator: {type: straight_tube, length: 50 mm, radius: 3 mm}
wire:
  length: 0.1
  segment_length: 5 mm
  tip: {length: 1 cm}
insertion: {speed: 1 cm/s, initial_length: 2 cm}
contact: {friction: 0.1}
solve: {dt: 10 ms, duration: 20 ms}
output: {every: 0, vtk: false, csv: false}
)";

/// An svZeroDSolver model: a flow into a vessel (R_poiseuille) and an RCR outlet.
nlohmann::json rcr_model(double r_poiseuille, double capacitance) {
  return {{"simulation_parameters", {{"number_of_cardiac_cycles", 2}, {"number_of_time_pts_per_cardiac_cycle", 11}}},
          {"boundary_conditions",
           {{{"bc_name", "INFLOW"}, {"bc_type", "FLOW"}, {"bc_values", {{"Q", {5.0, 5.0}}, {"t", {0.0, 1.0}}}}},
            {{"bc_name", "OUT"},
             {"bc_type", "RCR"},
             {"bc_values", {{"Rp", 100.0}, {"C", capacitance}, {"Rd", 1000.0}, {"Pd", 0.0}}}}}},
          {"vessels",
           {{{"vessel_id", 0},
             {"vessel_name", "branch0_seg0"},
             {"zero_d_element_type", "BloodVessel"},
             {"zero_d_element_values", {{"R_poiseuille", r_poiseuille}}},
             {"boundary_conditions", {{"inlet", "INFLOW"}, {"outlet", "OUT"}}}}}}};
}

/// The run of @p args exits 2 with one line on stderr holding every one of @p fragments, and
/// reports no success: a summary.json in @p out, if written, does not say "ok".
void expect_refused(const std::string& args, const std::vector<std::string>& fragments, const fs::path& out) {
  const auto r = flowire::testing::run_cli(args + " --out " + out.string());
  EXPECT_EQ(r.status, 2) << args << "\n" << r.err;
  EXPECT_EQ(r.err.rfind("flowire: error: ", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  for (const auto& f : fragments) EXPECT_NE(r.err.find(f), std::string::npos) << "expected '" << f << "' in: " << r.err;
  if (fs::exists(out / "summary.json")) {
    std::ifstream in(out / "summary.json");
    EXPECT_NE(nlohmann::json::parse(in).value("status", ""), "ok") << args;
  }
  EXPECT_FALSE(fs::exists(out / "svzerod_result.csv")) << args;
}

}  // namespace

TEST(CliRanges, OutOfRangeSceneValuesExitTwoNamingKeyValueAndLimit) {
  const auto dir = flowire::testing::scratch_dir("cli-ranges");
  flowire::testing::write_file(dir / "scene.yaml", kWireScene);
  const std::string scene = "run " + (dir / "scene.yaml").string();
  // The scene itself runs: what is refused below is the value changed.
  const auto ok = flowire::testing::run_cli(scene + " --out " + (dir / "ok").string());
  ASSERT_EQ(ok.status, 0) << ok.err;
  struct Case {
    std::string set;
    std::vector<std::string> fragments;
  };
  const std::vector<Case> cases = {
      {"wire.tip.youngs_modulus=0", {"--set: wire.tip.youngs_modulus = 0 Pa", "must be positive (> 0)"}},
      {"wire.tip.youngs_modulus=-5GPa", {"wire.tip.youngs_modulus = -5000000000 Pa", "(> 0)"}},
      {"contact.friction=-0.1", {"--set: contact.friction = -0.1", "must not be negative (>= 0)"}},
      {"contact.tip_friction=-1", {"contact.tip_friction = -1", "(>= 0)"}},
      {"insertion.initial_length=-1cm", {"insertion.initial_length = -0.01 m", "(> 0)"}},
      {"insertion.max_length=-1cm", {"insertion.max_length = -0.01 m", "(>= 0)"}},
      {"vessels.max_segment_length=0", {"vessels.max_segment_length = 0 m", "(> 0)"}},
      {"vessels.max_segment_length=-1mm", {"vessels.max_segment_length = -0.001 m", "(> 0)"}},
      {"output.every=-1", {"output.every = -1 s", "(>= 0)"}},
      {"solve.dt=0", {"solve.dt = 0 s", "(> 0)"}},
      {"wire.poisson_ratio=0.5", {"wire.poisson_ratio = 0.5", "(-1, 0.5)"}},
      {"coupling.flow_every=0", {"coupling.flow_every = 0", ">= 1"}},
  };
  for (const auto& c : cases)
    expect_refused(scene + " --set " + c.set, c.fragments, dir / ("o-" + c.set.substr(0, c.set.find('='))));
  // Written in the file, the value is named with its file and line; a list item by its index.
  flowire::testing::write_file(dir / "load.yaml", std::string(kWireScene) +
                                                      "loads:\n  - {type: point_force, value: [0, 0, 0], s: 1 cm}\n"
                                                      "  - {type: point_force, value: [0, 0, 0], s: -1 cm}\n");
  expect_refused("run " + (dir / "load.yaml").string(), {"load.yaml:13: loads[1].s = -0.01 m", "(>= 0)"},
                 dir / "o-load");
  // Beyond the wire's end, a point force would act nowhere.
  flowire::testing::write_file(
      dir / "beyond.yaml", std::string(kWireScene) + "loads:\n  - {type: point_force, value: [0, 0, 0], s: 20 cm}\n");
  expect_refused("run " + (dir / "beyond.yaml").string(), {"loads[0].s", "wire.length"}, dir / "o-beyond");
}

TEST(CliRanges, AbsurdNumbersOfStepsExitTwoNamingTheKeysAndTheLimit) {
  const auto dir = flowire::testing::scratch_dir("cli-steps");
  flowire::testing::write_file(dir / "scene.yaml", kWireScene);
  const std::string scene = "run " + (dir / "scene.yaml").string();
  const std::string limit = fmt::format("{:.0e}", flowire::kMaxSteps);
  expect_refused(scene + " --set solve.duration=1e20", {"solve.duration / solve.dt", limit}, dir / "o1");
  expect_refused(scene + " --set solve.dt=1e-300", {"solve.duration / solve.dt", limit}, dir / "o2");
  expect_refused(scene + " --set output.every=1e20", {"output.every / solve.dt", limit}, dir / "o3");
  // A flow-only scene, its duration written in the file: named with its line.
  flowire::testing::write_file(dir / "flow.yaml",
                               "vessels:\n  generator: {type: straight_tube}\nflow: {}\n"
                               "solve: {dt: 1 ms, duration: 2e6 s}\noutput: {every: 0, vtk: false, csv: false}\n");
  expect_refused("run " + (dir / "flow.yaml").string(),
                 {"flow.yaml:4: solve.duration", "solve.duration / solve.dt = 2e+09 steps", limit}, dir / "o4");
}

TEST(CliRanges, SvZeroDSolverModelsOutOfRangeExitTwoNamingFileAndBlockOrKey) {
  const auto dir = flowire::testing::scratch_dir("cli-svzerod-ranges");
  auto write_model = [&](const std::string& name, const nlohmann::json& m) {
    flowire::testing::write_file(dir / name, m.dump(2));
    return "run " + (dir / name).string();
  };
  // The model runs as written.
  const auto ok =
      flowire::testing::run_cli(write_model("ok.json", rcr_model(100.0, 1e-4)) + " --out " + (dir / "ok").string());
  ASSERT_EQ(ok.status, 0) << ok.err;
  expect_refused(write_model("neg_r.json", rcr_model(-100.0, 1e-4)),
                 {"neg_r.json", "block 'branch0_seg0'", "R_poiseuille", "-100", "(>= 0)"}, dir / "o1");
  expect_refused(write_model("neg_c.json", rcr_model(100.0, -1e-4)), {"neg_c.json", "block 'OUT'", "'C'", "(>= 0)"},
                 dir / "o2");
  auto huge = rcr_model(100.0, 1e-4);
  huge["simulation_parameters"]["number_of_time_pts_per_cardiac_cycle"] = 2000000000;
  expect_refused(write_model("huge.json", huge),
                 {"huge.json", "number_of_time_pts_per_cardiac_cycle", fmt::format("{:.0e}", flowire::kMaxSteps)},
                 dir / "o3");
  auto none = rcr_model(100.0, 1e-4);
  none["simulation_parameters"]["number_of_cardiac_cycles"] = 0;
  expect_refused(write_model("none.json", none), {"none.json", "number_of_cardiac_cycles = 0"}, dir / "o7");
  // Within each key's own range, but their product is more steps than a run may plan.
  auto many = rcr_model(100.0, 1e-4);
  many["simulation_parameters"]["number_of_time_pts_per_cardiac_cycle"] = 100001;
  many["simulation_parameters"]["number_of_cardiac_cycles"] = 20000;
  expect_refused(write_model("many.json", many),
                 {"many.json", "number_of_cardiac_cycles", "number_of_time_pts_per_cardiac_cycle",
                  fmt::format("{:.0e}", flowire::kMaxSteps)},
                 dir / "o4");
  auto tol = rcr_model(100.0, 1e-4);
  tol["simulation_parameters"]["absolute_tolerance"] = -1e-8;
  expect_refused(write_model("tol.json", tol), {"tol.json", "absolute_tolerance", "(> 0)"}, dir / "o5");
  auto rho = rcr_model(100.0, 1e-4);
  rho["simulation_parameters"]["rho_infty"] = 1.5;
  expect_refused(write_model("rho.json", rho), {"rho.json", "rho_infty", "[0, 1]"}, dir / "o6");
}
