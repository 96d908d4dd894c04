// The flowire executable end to end: exit statuses, messages and files, per the contract.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli_run.hpp"
#include "flowire_test.hpp"

namespace fs = std::filesystem;

namespace {

using Result = flowire::testing::CliResult;

Result run(const std::string& args) { return flowire::testing::run_cli(args); }

void write(const fs::path& p, const std::string& text) { flowire::testing::write_file(p, text); }

/// A vmtkcenterlines-style file: one polyline per inlet→outlet path, overlapping along the
/// shared trunk, radius in MaximumInscribedSphereRadius, coordinates in mm.
/// Paths: trunk along z to 100 mm; one outlet leaves at z = 50 towards (+30, 0, 80), one at
/// z = 75 towards (−30, 0, 95). Expected: 1 inlet + 3 outlets, 2 junctions, 5 branches.
std::string vmtk_three_outlet_aorta(const std::string& radius_override = "") {
  std::vector<std::array<double, 4>> pts;  // x, y, z, r
  std::vector<std::vector<int>> lines;
  auto path = [&](double z_split, std::array<double, 3> end, double r_branch) {
    std::vector<int> ids;
    const double z_end = z_split < 0 ? 100.0 : z_split;
    for (double z = 0; z <= z_end + 1e-9; z += 1.0) {
      ids.push_back(static_cast<int>(pts.size()));
      pts.push_back({0, 0, z, 4.0});
    }
    if (z_split >= 0) {
      const std::array<double, 3> a{0, 0, z_split};
      const double len = std::hypot(end[0] - a[0], end[2] - a[2]);
      const int n = static_cast<int>(std::round(len));
      for (int i = 1; i <= n; ++i) {
        const double w = static_cast<double>(i) / n;
        ids.push_back(static_cast<int>(pts.size()));
        pts.push_back({w * end[0], 0, a[2] + w * (end[2] - a[2]), r_branch});
      }
    }
    lines.push_back(ids);
  };
  path(-1, {}, 0);
  path(50, {30, 0, 80}, 2.0);
  path(75, {-30, 0, 95}, 2.0);
  std::ostringstream x;
  x << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n<PolyData>\n"
    << "<Piece NumberOfPoints=\"" << pts.size() << "\" NumberOfVerts=\"0\" NumberOfLines=\"" << lines.size()
    << "\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n<PointData Scalars=\"MaximumInscribedSphereRadius\">\n"
    << "<DataArray type=\"Float64\" Name=\"MaximumInscribedSphereRadius\" format=\"ascii\">\n";
  for (size_t i = 0; i < pts.size(); ++i)
    x << (i == 5 && !radius_override.empty() ? radius_override : std::to_string(pts[i][3])) << " ";
  x << "\n</DataArray>\n</PointData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" "
       "format=\"ascii\">\n";
  for (const auto& p : pts) x << p[0] << " " << p[1] << " " << p[2] << " ";
  x << "\n</DataArray>\n</Points>\n<Lines>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  size_t off = 0;
  std::string offsets;
  for (const auto& l : lines) {
    for (int id : l) x << id << " ";
    off += l.size();
    offsets += std::to_string(off) + " ";
  }
  x << "\n</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n"
    << offsets << "\n</DataArray>\n</Lines>\n</Piece>\n</PolyData>\n</VTKFile>\n";
  return x.str();
}

}  // namespace

TEST(Cli, VersionAndHelp) {
  const auto v = run("--version");
  EXPECT_EQ(v.status, 0);
  EXPECT_NE(v.out.find("flowire 0."), std::string::npos) << v.out;
  const auto h = run("help");
  EXPECT_EQ(h.status, 0);
  EXPECT_NE(h.out.find("network"), std::string::npos);
  const auto hs = run("help scene");
  EXPECT_EQ(hs.status, 0);
  EXPECT_NE(hs.out.find("`flow.solver`"), std::string::npos);
  EXPECT_NE(hs.out.find("`wire.tip.shape`"), std::string::npos);
  EXPECT_EQ(run("frobnicate").status, 2);
  EXPECT_EQ(run("help frobnicate").status, 2);
}

TEST(Cli, NetworkInfoOnAVmtkThreeOutletAorta) {
  const auto dir = flowire::testing::scratch_dir("cli-info");
  write(dir / "aorta.vtp", vmtk_three_outlet_aorta());
  const auto r = run("network info " + (dir / "aorta.vtp").string() + " --length-unit mm --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["ends"], 4);
  EXPECT_EQ(j["junctions"], 2);
  EXPECT_EQ(j["branches"], 5);
  EXPECT_EQ(j["loops"], 0);
  const double expected = 0.100 + std::hypot(0.030, 0.030) + std::hypot(0.030, 0.020);
  EXPECT_NEAR(j["total_length"].get<double>(), expected, 0.02 * expected);
  EXPECT_NEAR(j["radius_max"].get<double>(), 4e-3, 1e-9);
  EXPECT_NEAR(j["radius_min"].get<double>(), 2e-3, 0.2e-3);
  // The text form carries the same counts.
  const auto t = run("network info " + (dir / "aorta.vtp").string() + " --length-unit mm");
  EXPECT_EQ(t.status, 0);
  EXPECT_NE(t.out.find("junctions:     2"), std::string::npos) << t.out;
}

TEST(Cli, ConvertWritesAVtpThatReadsBackIdentically) {
  const auto dir = flowire::testing::scratch_dir("cli-convert");
  write(dir / "aorta.vtp", vmtk_three_outlet_aorta());
  ASSERT_EQ(
      run("network convert " + (dir / "aorta.vtp").string() + " " + (dir / "net.vtp").string() + " --length-unit mm")
          .status,
      0);
  const auto a =
      nlohmann::json::parse(run("network info " + (dir / "aorta.vtp").string() + " --length-unit mm --json").out);
  const auto b = nlohmann::json::parse(run("network info " + (dir / "net.vtp").string() + " --json").out);
  for (const char* k : {"branches", "nodes", "segments", "junctions", "ends", "loops"}) EXPECT_EQ(a[k], b[k]) << k;
  EXPECT_NEAR(a["total_length"].get<double>(), b["total_length"].get<double>(), 1e-12);
}

TEST(Cli, BadInputGivesOneLineAndStatusTwo) {
  const auto dir = flowire::testing::scratch_dir("cli-bad");
  auto expect_bad = [&](const std::string& args, const std::string& fragment) {
    const auto r = run(args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("flowire: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(fragment), std::string::npos) << "expected '" << fragment << "' in: " << r.err;
    EXPECT_LE(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  };
  expect_bad("network info " + (dir / "missing.vtp").string(), "missing.vtp");
  write(dir / "nan.vtp", vmtk_three_outlet_aorta("nan"));
  expect_bad("network info " + (dir / "nan.vtp").string(), "nan.vtp");
  write(dir / "zero.vtp", vmtk_three_outlet_aorta("0"));
  expect_bad("network info " + (dir / "zero.vtp").string(), "zero.vtp");
  const auto full = vmtk_three_outlet_aorta();
  write(dir / "truncated.vtp", full.substr(0, full.size() / 2));
  expect_bad("network info " + (dir / "truncated.vtp").string(), "truncated.vtp");
  write(dir / "empty.vtp", "");
  expect_bad("network info " + (dir / "empty.vtp").string(), "empty.vtp");
  write(dir / "scene.yaml", "vessels:\n  generator: {type: straight_tube}\nflow:\n  solvr: sparse\n");
  expect_bad("run " + (dir / "scene.yaml").string() + " --out " + (dir / "o").string(), "scene.yaml:4");
  EXPECT_FALSE(fs::exists(dir / "o" / "summary.json"));
  write(dir / "scene2.yaml", "vessels:\n  generator: {type: straight_tube, radius: 2 mmHg}\n");
  expect_bad("run " + (dir / "scene2.yaml").string(), "scene2.yaml:2: vessels.generator.radius");
  write(dir / "scene3.yaml", "vessels:\n  generator: {type: straight_tube}\n");
  expect_bad("run " + (dir / "scene3.yaml").string() + " --set vessels.nothing=1", "vessels.nothing");
  expect_bad("run " + (dir / "scene3.yaml").string() + " --set vessels.generator.radius=0", "radius");
  expect_bad("network info", "file");
  // Adaptivity and the feed's force limit: out-of-range values name the file and line.
  write(dir / "wire.yaml",
        "wire:\n  length: 0.1\n  segment_length: 2 mm\n  adapt: {split_angle: 2 rad}\n"
        "insertion: {speed: 1 cm/s, max_force: -1 N}\nsolve: {dt: 1 ms, duration: 2 ms}\n");
  expect_bad("run " + (dir / "wire.yaml").string() + " --out " + (dir / "w").string(), "wire.yaml:4");
  EXPECT_FALSE(fs::exists(dir / "w" / "summary.json"));
  expect_bad("run " + (dir / "wire.yaml").string() + " --set wire.adapt.split_angle=0.1 --out " + (dir / "w").string(),
             "wire.yaml:5");
  // Force-driven feeding: with a speed too, or not positive, names the file and line.
  write(dir / "force.yaml",
        "wire:\n  length: 0.1\n  segment_length: 2 mm\ninsertion: {force: 0.05 N, speed: 1 cm/s}\n"
        "solve: {dt: 1 ms, duration: 2 ms}\n");
  expect_bad("run " + (dir / "force.yaml").string() + " --out " + (dir / "f").string(), "force.yaml:4");
  expect_bad("run " + (dir / "force.yaml").string() + " --out " + (dir / "f").string(), "insertion.force");
  EXPECT_FALSE(fs::exists(dir / "f" / "summary.json"));
  write(dir / "force2.yaml",
        "wire:\n  length: 0.1\n  segment_length: 2 mm\ninsertion: {force: -1 N}\nsolve: {dt: 1 ms, duration: 2 ms}\n");
  expect_bad("run " + (dir / "force2.yaml").string() + " --out " + (dir / "f").string(), "force2.yaml:4");
  EXPECT_FALSE(fs::exists(dir / "f" / "summary.json"));
}

TEST(Cli, AnOutputFolderThatCannotBeMadeExitsTwoNamingIt) {
  // --out below a regular file: no folder can be made there. Bad input (exit 2, one line
  // naming the place), not an unexpected failure (exit 3).
  const auto dir = flowire::testing::scratch_dir("cli-unwritable");
  write(dir / "plain", "a file, not a folder\n");
  write(dir / "scene.yaml", "vessels:\n  generator: {type: y_bifurcation}\n");
  write(dir / "aorta.vtp", vmtk_three_outlet_aorta());
  for (const std::string& args : {"run " + (dir / "scene.yaml").string() + " --out " + (dir / "plain" / "out").string(),
                                  "network convert " + (dir / "aorta.vtp").string() + " " +
                                      (dir / "plain" / "net.vtp").string() + " --length-unit mm"}) {
    const auto r = run(args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("flowire: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find((dir / "plain").string()), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("unexpected failure"), std::string::npos) << r.err;
  }
}

TEST(Cli, VesselsOnlySceneWritesSummaryAndSegments) {
  const auto dir = flowire::testing::scratch_dir("cli-run");
  write(dir / "scene.yaml", "vessels:\n  generator: {type: y_bifurcation}\n  max_segment_length: 10 mm\n");
  const auto r = run("run " + (dir / "scene.yaml").string() + " --out " + (dir / "out").string());
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream in(dir / "out" / "summary.json");
  const auto s = nlohmann::json::parse(in);
  EXPECT_EQ(s["status"], "ok");
  EXPECT_EQ(s["network"]["segments"], 12);
  EXPECT_EQ(s["scene"]["vessels.generator.type"], "y_bifurcation");
  for (const char* k : {"setup", "flow", "rod", "contact", "coupling", "output", "total"})
    EXPECT_TRUE(s["timings"].contains(k)) << k;
  EXPECT_TRUE(fs::exists(dir / "out" / "segments.csv"));
  for (const auto& e : fs::directory_iterator(dir / "out"))
    EXPECT_EQ(e.path().extension(), e.path().extension() == ".partial" ? ".none" : e.path().extension());
}

TEST(Cli, RunsAnSvZeroDSolverModel) {
  FLOWIRE_REQUIRE_SHARED("peers/svzerodsolver/cases/pulsatileFlow_R_RCR.json");
  const auto dir = flowire::testing::scratch_dir("cli-svzerod");
  const auto model = (flowire::testing::shared_dir() / "peers/svzerodsolver/cases/pulsatileFlow_R_RCR.json").string();
  const auto r = run("run " + model + " --out " + (dir / "o").string());
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream csv(dir / "o" / "svzerod_result.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "name,time,flow_in,flow_out,pressure_in,pressure_out");
  std::ifstream in(dir / "o" / "summary.json");
  EXPECT_EQ(nlohmann::json::parse(in)["status"], "ok");
  // A model that is not JSON is one clear error.
  std::ofstream(dir / "bad.json") << "{\"vessels\": [";
  const auto b = run("run " + (dir / "bad.json").string() + " --out " + (dir / "b").string());
  EXPECT_EQ(b.status, 2) << b.err;
  EXPECT_NE(b.err.find("bad.json"), std::string::npos) << b.err;
  EXPECT_FALSE(fs::exists(dir / "b" / "svzerod_result.csv"));
}

namespace {
/// ADAN56 with the brachiocephalic trunk's Rp set to 0, as dir/adan56.yaml beside its inlet table.
void write_adan56_with_a_zero_radius(const std::string& model, const fs::path& dir) {
  std::ifstream src(model);
  std::stringstream text;
  text << src.rdbuf();
  std::string bad = text.str();
  const auto at = bad.find("Rp: 0.00672809");
  ASSERT_NE(at, std::string::npos);
  bad.replace(at, std::string("Rp: 0.00672809").size(), "Rp: 0.0");
  fs::copy_file(fs::path(model).parent_path() / "adan56_inlet.dat", dir / "adan56_inlet.dat",
                fs::copy_options::overwrite_existing);
  std::ofstream(dir / "adan56.yaml") << bad;
}
}  // namespace

TEST(Cli, RunsAnOpenbfModel) {
  // `flowire run MODEL.yaml` on openBF's ADAN56: vessels.csv per openBF label, one period of
  // 101 samples, and the summary; a broken model is one line, status 2, and no folder.
  FLOWIRE_REQUIRE_SHARED("peers/openbf-models/boileau2015/adan56/adan56.yaml");
  const auto dir = flowire::testing::scratch_dir("cli-openbf");
  const auto model = (flowire::testing::shared_dir() / "peers/openbf-models/boileau2015/adan56/adan56.yaml").string();
  const auto r = run("run " + model + " --out " + (dir / "o").string());
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream csv(dir / "o" / "vessels.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "name,time,flow_in,flow_out,pressure_in,pressure_out");
  std::map<std::string, int> rows;
  while (std::getline(csv, line)) ++rows[line.substr(0, line.find(','))];
  EXPECT_EQ(rows.size(), 77u);
  EXPECT_EQ(rows["aortic_arch_I"], 101);
  std::ifstream in(dir / "o" / "summary.json");
  const auto s = nlohmann::json::parse(in);
  EXPECT_EQ(s["status"], "ok");
  EXPECT_EQ(s["openbf"]["vessels"].get<int>(), 77);
  EXPECT_EQ(s["openbf"]["cycles"].get<int>(), 10);
  EXPECT_LT(s["openbf"]["periodicity"].get<double>(), 0.01);
  // The waveforms along the aorta to the periphery, drawn where a display is.
  if (const char* display = std::getenv("DISPLAY"); display && *display) {
    EXPECT_EQ(s["openbf"]["waveforms_png"], "waveforms.png");
    ASSERT_TRUE(fs::exists(dir / "o" / "waveforms.png"));
    EXPECT_GT(fs::file_size(dir / "o" / "waveforms.png"), 10000u);
  } else {
    EXPECT_NE(s["openbf"]["waveforms_png"].get<std::string>().find("no X display"), std::string::npos);
  }
  // The same model with a vessel of zero radius.
  write_adan56_with_a_zero_radius(model, dir);
  const auto b = run("run " + (dir / "adan56.yaml").string() + " --out " + (dir / "b").string());
  EXPECT_EQ(b.status, 2) << b.err;
  EXPECT_NE(b.err.find("adan56.yaml:"), std::string::npos) << b.err;
  EXPECT_NE(b.err.find("vessel `brachiocephalic_trunk`: Rp = 0 must be > 0"), std::string::npos) << b.err;
  EXPECT_EQ(std::count(b.err.begin(), b.err.end(), '\n'), 1) << b.err;
  EXPECT_FALSE(fs::exists(dir / "b"));
}

TEST(Cli, AnOpenbfModelIsLaidOutInSpaceAndPushedThroughAsAScenesVessels) {
  // --network-out writes the model's layout (a network ParaView opens and flowire reads back,
  // one branch per vessel); the model as vessels.file of a scene runs a wire through it with the
  // model's own flow; a zero radius there, an outlet the model has not, or --network-out for a
  // scene: one line, status 2, nothing written.
  FLOWIRE_REQUIRE_SHARED("peers/openbf-models/boileau2015/adan56/adan56.yaml");
  const auto dir = flowire::testing::scratch_dir("cli-openbf-network");
  const auto model = (flowire::testing::shared_dir() / "peers/openbf-models/boileau2015/adan56/adan56.yaml").string();
  const auto r =
      run("run " + model + " --out " + (dir / "o").string() + " --network-out " + (dir / "adan56.vtp").string());
  ASSERT_EQ(r.status, 0) << r.err;
  const auto info = run("network info " + (dir / "adan56.vtp").string());
  ASSERT_EQ(info.status, 0) << info.err;
  EXPECT_NE(info.out.find("branches:      77"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("loops:         0"), std::string::npos) << info.out;
  int scenes = 0;
  auto scene = [&](const std::string& vessels_file, const std::string& flow) {
    const auto path = dir / ("scene" + std::to_string(++scenes) + ".yaml");
    std::ofstream(path) << "vessels: {file: " << vessels_file << ", max_segment_length: 1 cm}\n"
                        << "flow: " << flow << "\n"
                        << "wire: {length: 0.5, segment_length: 2 mm, entry: profunda_femoris_R, tip: {length: 2 cm, "
                           "shape: angled, angle: 30 deg, bend_radius: 5 mm}}\n"
                        << "insertion: {speed: 5 cm/s, initial_length: 2 cm}\n"
                        << "solve: {dt: 10 ms, duration: 1 s}\noutput: {vtk: false, png: false}\n";
    return path.string();
  };
  const auto ok = run("run " + scene(model, "{}") + " --out " + (dir / "w").string());
  ASSERT_EQ(ok.status, 0) << ok.err;
  std::ifstream in(dir / "w" / "summary.json");
  const auto s = nlohmann::json::parse(in);
  EXPECT_EQ(s["status"], "ok");
  EXPECT_EQ(s["flow"]["model"], "rlc");
  EXPECT_EQ(s["network"]["branches"].get<int>(), 77);
  EXPECT_EQ(s["wire"]["unconverged_steps"].get<int>(), 0);
  EXPECT_NEAR(s["wire"]["inserted_length"].get<double>(), 0.07, 1e-6);
  // Bad input.
  write_adan56_with_a_zero_radius(model, dir);
  for (const auto& [scene_file, message] : std::vector<std::pair<std::string, std::string>>{
           {scene((dir / "adan56.yaml").string(), "{}"), "vessel `brachiocephalic_trunk`: Rp = 0 must be > 0"},
           {scene(model, "{outlets: {nowhere: {resistance: 1e9}}}"), "flow.outlets.nowhere"}}) {
    const auto b = run("run " + scene_file + " --out " + (dir / "b").string());
    EXPECT_EQ(b.status, 2) << b.err;
    EXPECT_NE(b.err.find(message), std::string::npos) << b.err;
    EXPECT_EQ(std::count(b.err.begin(), b.err.end(), '\n'), 1) << b.err;
    EXPECT_FALSE(fs::exists(dir / "b"));
  }
  const auto n = run("run " + scene(model, "{}") + " --out " + (dir / "n").string() + " --network-out " +
                     (dir / "n.vtp").string());
  EXPECT_EQ(n.status, 2) << n.err;
  EXPECT_NE(n.err.find("--network-out writes the layout of an openBF model"), std::string::npos) << n.err;
  EXPECT_FALSE(fs::exists(dir / "n"));
  EXPECT_FALSE(fs::exists(dir / "n.vtp"));
}

TEST(Cli, AFlowSineWithoutAmplitudesIsRefusedNamingTheKey) {
  // A flow waveform has no default amplitude (the 120/80 mmHg of a pressure sine are not
  // m³/s): the key that is missing is named with the file and line of its section.
  const auto dir = flowire::testing::scratch_dir("cli-flow-sine");
  write(dir / "scene.yaml",
        "vessels:\n  generator: {type: straight_tube}\nflow:\n  inlet:\n    flow: {waveform: sine}\n"
        "solve: {dt: 10 ms, duration: 20 ms}\n");
  const auto r = run("run " + (dir / "scene.yaml").string() + " --out " + (dir / "o").string());
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(r.err.rfind("flowire: error: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("scene.yaml:5"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("flow.inlet.flow.systolic"), std::string::npos) << r.err;
  EXPECT_LE(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(dir / "o" / "summary.json"));
  // Given both amplitudes it runs; a pressure sine keeps its declared 120/80 mmHg defaults.
  write(dir / "flow.yaml",
        "vessels:\n  generator: {type: straight_tube}\nflow:\n  inlet:\n"
        "    flow: {waveform: sine, systolic: 2e-6, diastolic: 1e-6}\nsolve: {dt: 10 ms, duration: 20 ms}\n");
  const auto ok = run("run " + (dir / "flow.yaml").string() + " --out " + (dir / "f").string());
  EXPECT_EQ(ok.status, 0) << ok.err;
  write(dir / "pressure.yaml",
        "vessels:\n  generator: {type: straight_tube}\nflow:\n  inlet:\n    pressure: {waveform: sine}\n"
        "solve: {dt: 10 ms, duration: 20 ms}\n");
  const auto p = run("run " + (dir / "pressure.yaml").string() + " --out " + (dir / "p").string());
  EXPECT_EQ(p.status, 0) << p.err;
}

TEST(Cli, SceneKeyDefaultsAgreeWithTheirUnits) {
  // No key of flow rate (m³/s) shows a pressure in its default or its description.
  const auto r = run("help scene");
  ASSERT_EQ(r.status, 0);
  std::istringstream rows(r.out);
  int flow_rate_keys = 0;
  for (std::string row; std::getline(rows, row);) {
    if (row.find("| m^3/s |") == std::string::npos && row.find("| m³/s |") == std::string::npos) continue;
    ++flow_rate_keys;
    EXPECT_EQ(row.find("mmHg"), std::string::npos) << row;
    EXPECT_EQ(row.find(" Pa"), std::string::npos) << row;
  }
  EXPECT_GE(flow_rate_keys, 4);
}

TEST(Cli, AnSvZeroDSolverModelIsNotAVesselsFile) {
  // A 0D model has no geometry: `flowire run model.json` solves it, `vessels.file` refuses it.
  FLOWIRE_REQUIRE_SHARED("peers/svzerodsolver/cases/steadyFlow_bifurcationR_R1.json");
  const auto dir = flowire::testing::scratch_dir("cli-svzerod-vessels");
  const auto model =
      (flowire::testing::shared_dir() / "peers/svzerodsolver/cases/steadyFlow_bifurcationR_R1.json").string();
  write(dir / "scene.yaml", "vessels:\n  file: " + model + "\n");
  const auto r = run("run " + (dir / "scene.yaml").string() + " --out " + (dir / "o").string());
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(r.err.rfind("flowire: error: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("steadyFlow_bifurcationR_R1.json"), std::string::npos) << r.err;
  EXPECT_LE(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST(Cli, SceneKeyReferenceIsUpToDate) {
  // docs/scene-keys.md is generated from the one declaration: `flowire help scene > docs/scene-keys.md`.
  std::ifstream in(std::string(FLOWIRE_SOURCE_DIR) + "/docs/scene-keys.md");
  ASSERT_TRUE(in) << "docs/scene-keys.md is missing";
  std::stringstream doc;
  doc << in.rdbuf();
  const auto r = run("help scene");
  ASSERT_EQ(r.status, 0);
  EXPECT_EQ(doc.str(), r.out) << "regenerate it: flowire help scene > docs/scene-keys.md";
}

TEST(Cli, CompareTipTracesPrintsTheTableAndPlots) {
  const auto dir = flowire::testing::scratch_dir("cli-compare");
  std::ofstream a(dir / "a.csv"), b(dir / "b.csv");
  a << "time,inserted_length,x,y,z\n";
  b << "time,inserted_length,x,y,z\n";
  for (int i = 0; i <= 100; ++i) {
    const double L = 0.002 * i;
    a << i << "," << L << "," << L << ",0,0\n";
    b << i << "," << L << "," << L << ",0.003,0\n";  // 3 mm apart everywhere
  }
  a.close();
  b.close();
  const auto r = run("compare " + (dir / "a.csv").string() + " " + (dir / "b.csv").string() + " --out " +
                     (dir / "t.csv").string() + " --plot " + (dir / "t.png").string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("3.000"), std::string::npos) << r.out;  // RMS mean of a constant 3 mm offset
  EXPECT_TRUE(fs::exists(dir / "t.csv"));
  EXPECT_GT(fs::file_size(dir / "t.png"), 1000u);
  std::ofstream(dir / "bad.csv") << "time,inserted_length,x,y,z\n0,0,0,0\n";
  const auto bad = run("compare " + (dir / "a.csv").string() + " " + (dir / "bad.csv").string());
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("bad.csv:2"), std::string::npos) << bad.err;
}

TEST(Cli, ProgressLineOnATerminalOnly) {
  const auto dir = flowire::testing::scratch_dir("cli-progress");
  const std::string scene = std::string(FLOWIRE_SOURCE_DIR) + "/examples/aorta_flow/scene.yaml";
  // Into a file (as in a pipe or a log): no progress at all.
  const auto piped =
      run("run " + scene + " --out " + (dir / "piped").string() + " --set output.vtk=false --set output.png=false");
  ASSERT_EQ(piped.status, 0) << piped.err;
  EXPECT_EQ(piped.err.find("ETA"), std::string::npos) << piped.err;
  EXPECT_EQ(piped.err.find('\r'), std::string::npos);
  // On a terminal (a pseudo-terminal made by util-linux `script`): the line is drawn.
  if (std::system("command -v script >/dev/null 2>&1") != 0) GTEST_SKIP() << "util-linux `script` is not installed";
  const std::string cmd = "script -qec '" + std::string(FLOWIRE_BINARY_DIR) + "/tools/flowire run " + scene +
                          " --out " + (dir / "tty").string() +
                          " --set output.vtk=false --set output.png=false' /dev/null > " + (dir / "tty.txt").string() +
                          " 2>&1 </dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream in(dir / "tty.txt");
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("100.0%"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("ETA"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("ok in"), std::string::npos) << text.str();
}

TEST(Cli, BaseForceEveryStepBalancesTheTipLoadAtRest) {
  // base_force.csv: the clamp's force on the wire every step. A free wire (no vessels, no
  // gravity) pulled at its tip by F and damped to rest is held by −F at the clamp
  // (Newton's third law on the whole wire), and the clamp's torque balances F's moment.
  const auto dir = flowire::testing::scratch_dir("cli-base-force");
  write(dir / "scene.yaml", R"(name: pulled
wire: {length: 0.05, radius: 0.2 mm, youngs_modulus: 60 GPa, segment_length: 5 mm, damping: 5,
       base: {position: [0, 0, 0], direction: [1, 0, 0]}}
insertion: {speed: 0, initial_length: 5 cm}
loads: [{type: tip_force, value: [0, 0.002, 0]}]
solve: {dt: 10 ms, duration: 3 s}
output: {vtk: false}
)");
  const auto r = run("run " + (dir / "scene.yaml").string() + " --out " + (dir / "out").string());
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream in(dir / "out" / "base_force.csv");
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "time,fx,fy,fz,tx,ty,tz");
  int rows = 0;
  std::vector<double> last;
  while (std::getline(in, line)) {
    ++rows;
    last.clear();
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) last.push_back(std::stod(c));
  }
  EXPECT_EQ(rows, 300);
  ASSERT_EQ(last.size(), 7u);
  EXPECT_NEAR(last[0], 3.0, 1e-9);
  EXPECT_NEAR(last[1], 0.0, 2e-5);
  EXPECT_NEAR(last[2], -0.002, 2e-5);
  EXPECT_NEAR(last[3], 0.0, 2e-5);
  // Torque about the clamp: −(tip position × F), the tip near (x_tip, y_tip, 0).
  std::ifstream sj(dir / "out" / "summary.json");
  const auto j = nlohmann::json::parse(sj);
  const double x_tip = j["wire"]["tip"][0].get<double>();
  EXPECT_NEAR(last[6], -x_tip * 0.002, 0.02 * x_tip * 0.002);
  EXPECT_NEAR(last[2], j["wire"]["base_force"][1].get<double>(), 1e-9);
}

TEST(Cli, CatheterBadInputNamesTheKey) {
  // A lumen narrower than the wire, a wall with outer <= inner radius, non-positive values and
  // unknown keys: exit 2, the key named, no output.
  const auto dir = flowire::testing::scratch_dir("cli-catheter");
  write(dir / "scene.yaml", R"(name: catheter
wire: {length: 0.1, radius: 0.3 mm, youngs_modulus: 60 GPa, segment_length: 2 mm}
insertion: {speed: 1 cm/s, initial_length: 3 cm}
catheter: {length: 0.1, outer_radius: 0.8 mm, inner_radius: 0.4 mm, initial_length: 2 cm}
solve: {dt: 10 ms, duration: 0.05 s}
output: {vtk: false}
)");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"catheter.inner_radius=0.2mm", "catheter.inner_radius"},
      {"catheter.outer_radius=0.4mm", "catheter.outer_radius"},
      {"catheter.youngs_modulus=0", "catheter.youngs_modulus"},
      {"catheter.density=-5", "catheter.density"},
      {"catheter.initial_length=0.2", "catheter.initial_length"},
      {"catheter.stifness=5", "catheter.stifness"}};
  int k = 0;
  for (const auto& [set, key] : cases) {
    const auto out = dir / ("bad" + std::to_string(k++));
    const auto r = run("run " + (dir / "scene.yaml").string() + " --out " + out.string() + " --set " + set);
    EXPECT_EQ(r.status, 2) << set << ": " << r.err;
    EXPECT_NE(r.err.find(key), std::string::npos) << set << ": " << r.err;
    EXPECT_FALSE(std::filesystem::exists(out / "summary.json")) << set;
  }
  // The same scene as given runs, and writes the catheter as the wire.
  const auto ok = run("run " + (dir / "scene.yaml").string() + " --out " + (dir / "ok").string());
  ASSERT_EQ(ok.status, 0) << ok.err;
  std::ifstream head(dir / "ok" / "catheter.csv");
  std::string header;
  std::getline(head, header);
  std::ifstream wire_head(dir / "ok" / "wire.csv");
  std::string wire_header;
  std::getline(wire_head, wire_header);
  EXPECT_EQ(header, wire_header);
  std::ifstream sj(dir / "ok" / "summary.json");
  const auto j = nlohmann::json::parse(sj);
  EXPECT_EQ(j["catheter"]["unconverged_steps"], 0);
  EXPECT_NEAR(j["catheter"]["inserted_length"].get<double>(), 0.02, 1e-12);
}

TEST(Cli, OcclusionNeedsASolverThatCanRefactor) {
  // The published dense K⁻¹ cannot take the wire's resistance: asked for, that is bad input
  // (exit 2, the key named, no output); by default the run says the flow ignores the wire.
  const auto dir = flowire::testing::scratch_dir("cli-occlusion");
  write(dir / "scene.yaml", R"(name: occluded
vessels: {generator: {type: straight_tube, length: 0.05, radius: 1.5 mm}, max_segment_length: 5 mm}
flow: {solver: dense_inverse, inlet: {pressure: 100 Pa}, outlets: {pressure: 0 Pa}}
wire: {length: 0.1, radius: 0.178 mm, youngs_modulus: 60 GPa, segment_length: 2 mm}
insertion: {speed: 1 cm/s, initial_length: 2 cm}
solve: {dt: 10 ms, duration: 0.1 s}
output: {vtk: false}
)");
  const auto refused = run("run " + (dir / "scene.yaml").string() + " --out " + (dir / "a").string() +
                           " --set coupling.occlusion=annulus");
  EXPECT_EQ(refused.status, 2) << refused.err;
  EXPECT_NE(refused.err.find("coupling.occlusion"), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "a" / "summary.json"));
  const auto plain = run("run " + (dir / "scene.yaml").string() + " --out " + (dir / "b").string());
  EXPECT_EQ(plain.status, 0) << plain.err;
  std::ifstream sb(dir / "b" / "summary.json");
  EXPECT_EQ(nlohmann::json::parse(sb)["occlusion"]["model"], "none");
  // With the superposition solver the wire occludes the tube.
  const auto two_way = run("run " + (dir / "scene.yaml").string() + " --out " + (dir / "c").string() +
                           " --set flow.solver=superposition");
  EXPECT_EQ(two_way.status, 0) << two_way.err;
  std::ifstream sc(dir / "c" / "summary.json");
  const auto jc = nlohmann::json::parse(sc);
  EXPECT_EQ(jc["occlusion"]["model"], "annulus");
  EXPECT_GT(jc["occlusion"]["max_resistance_factor"].get<double>(), 1.0);
}

TEST(Cli, AWireOutsideTheLumenIsNoSuccess) {
  // Without wall contact the wire runs straight out of the iliac artery: the run must say so
  // (where and when), end with status "outside" and exit 3, unless the scene allows it.
  const auto dir = flowire::testing::scratch_dir("cli-outside");
  write(dir / "scene.yaml", R"(name: leaves_the_lumen
vessels: {generator: {type: aortic_arch}, max_segment_length: 5 mm}
flow:
  inlet: {pressure: {waveform: sine, systolic: 120 mmHg, diastolic: 80 mmHg, period: 0.833 s}}
  outlets: {resistance: 1 mmHg*s/mL, scaling: murray}
wire: {length: 0.6, radius: 0.445 mm, youngs_modulus: 60 GPa, segment_length: 5 mm}
insertion: {speed: 10 cm/s, initial_length: 2 cm}
contact: {enabled: false}
solve: {dt: 10 ms, duration: 2 s}
output: {vtk: false}
)");
  const auto refused = run("run " + (dir / "scene.yaml").string() + " --out " + (dir / "a").string());
  EXPECT_EQ(refused.status, 3) << refused.err;
  EXPECT_NE(refused.err.find("the wire left the lumen: at t = "), std::string::npos) << refused.err;
  std::ifstream sa(dir / "a" / "summary.json");
  const auto ja = nlohmann::json::parse(sa);
  EXPECT_EQ(ja["status"], "outside");
  EXPECT_GT(ja["contact"]["outside"]["wire_radii"].get<double>(), 1.0);
  const auto allowed = run("run " + (dir / "scene.yaml").string() + " --out " + (dir / "b").string() +
                           " --set contact.allow_outside=true");
  EXPECT_EQ(allowed.status, 0) << allowed.err;
  std::ifstream sb(dir / "b" / "summary.json");
  EXPECT_EQ(nlohmann::json::parse(sb)["status"], "outside");
  // Inside the lumen (contact on) the same push is ok.
  const auto inside =
      run("run " + (dir / "scene.yaml").string() + " --out " + (dir / "c").string() + " --set contact.enabled=true");
  EXPECT_EQ(inside.status, 0) << inside.err;
}

TEST(Cli, ABadLumenSurfaceExitsTwoNamingTheFile) {
  const auto dir = flowire::testing::scratch_dir("cli-bad-surface");
  write(dir / "lines.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\n");
  write(dir / "nan.stl",
        "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex nan 0 0\nvertex 0 1 0\n"
        "endloop\nendfacet\nendsolid s\n");
  for (const char* surface : {"missing.vtp", "lines.obj", "nan.stl"}) {
    write(dir / "scene.yaml", std::string(R"(vessels: {generator: {type: straight_tube}, surface: )") + surface + R"(}
wire: {length: 0.2, segment_length: 5 mm}
insertion: {initial_length: 1 cm}
solve: {duration: 0.01 s, dt: 10 ms}
output: {vtk: false, csv: false}
)");
    const auto r = run("run " + (dir / "scene.yaml").string() + " --out " + (dir / "out").string());
    EXPECT_EQ(r.status, 2) << surface << ": " << r.err;
    EXPECT_NE(r.err.find(surface), std::string::npos) << r.err;
  }
}

TEST(Cli, AnUnsortedScheduleExitsTwoNamingTheLineAndWritesNothing) {
  const auto dir = flowire::testing::scratch_dir("cli-bad-schedule");
  write(dir / "drive.csv", "time,speed,rotation_speed\n0,0.01,0\n0.2,0,0\n0.1,0,1\n");
  write(dir / "scene.yaml", R"(vessels: {generator: {type: straight_tube}}
wire: {length: 0.2, segment_length: 5 mm}
insertion: {initial_length: 1 cm, schedule: drive.csv}
solve: {duration: 0.05 s, dt: 10 ms}
)");
  const auto r = run("run " + (dir / "scene.yaml").string() + " --out " + (dir / "out").string());
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("drive.csv:4"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "tip_trace.csv"));
  // A good schedule runs.
  write(dir / "drive.csv", "time,speed,rotation_speed\n0,0.01,0\n0.02,-0.01,6.28\n");
  const auto ok = run("run " + (dir / "scene.yaml").string() + " --out " + (dir / "ok").string());
  EXPECT_EQ(ok.status, 0) << ok.err;
  std::ifstream in(dir / "ok" / "summary.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["wire"]["schedule"]["rows"], 2);
  EXPECT_NEAR(j["wire"]["schedule"]["driven_length"].get<double>(), 0.01 * 0.02 - 0.01 * 0.03, 1e-12);
}

namespace {
/// Rows of a CSV file with a header line, as numbers.
std::vector<std::vector<double>> read_csv_rows(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) row.push_back(std::stod(c));
    rows.push_back(row);
  }
  return rows;
}

/// The decay rate of a ringing tip: the least-squares slope of log|z − z_rest| over the
/// peaks of each half period (one extreme between two crossings of z_rest) [1/s].
double ringing_decay_rate(const std::vector<std::vector<double>>& trace, double z_rest, int* peaks) {
  std::vector<double> t, a;
  double best = 0.0, t_best = 0.0;
  int sign = 0;
  for (const auto& row : trace) {
    const double u = row[4] - z_rest;
    const int s = u > 0 ? 1 : -1;
    if (sign != 0 && s != sign && best > 0.0) t.push_back(t_best), a.push_back(std::log(best)), best = 0.0;
    sign = s;
    if (std::abs(u) > best) best = std::abs(u), t_best = row[0];
  }
  *peaks = static_cast<int>(t.size());
  const double n = static_cast<double>(t.size());
  double st = 0, sa = 0, stt = 0, sta = 0;
  for (size_t i = 0; i < t.size(); ++i) st += t[i], sa += a[i], stt += t[i] * t[i], sta += t[i] * a[i];
  return -(n * sta - st * sa) / (n * stt - st * st);
}
}  // namespace

TEST(Cli, WireDampingActsInItsDeclaredUnitOnARingingCantilever) {
  // wire.damping is mass-proportional, in 1/s: every vertex feels −ζ m v, so every mode of a
  // cantilever decays as e^(−ζt/2) whatever its frequency. A horizontal wire released
  // straight under gravity rings about its sagged rest; the implicit midpoint rule adds no
  // damping of its own, so the tip's peaks about the rest position fall at ζ/2 exactly. The
  // rest is the static solve of the same scene. (Multiplied by each cell's length, as it
  // once was, ζ = 2 on this 0.2 mm wire acted 2,500 times weaker.)
  const auto dir = flowire::testing::scratch_dir("cli-damping");
  const std::string base = R"(name: ringing
wire: {length: 0.1, radius: 0.2 mm, youngs_modulus: 60 GPa, segment_length: 5 mm,
       base: {position: [0, 0, 0], direction: [1, 0, 0]}}
insertion: {speed: 0, initial_length: 0.1}
loads: [{type: gravity, value: [0, 0, -9.81]}]
output: {vtk: false}
)";
  write(dir / "static.yaml", base + "solve: {mode: static}\n");
  auto r = run("run " + (dir / "static.yaml").string() + " --out " + (dir / "static").string());
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream summary(dir / "static" / "summary.json");
  const double z_rest = nlohmann::json::parse(summary)["wire"]["tip"][2].get<double>();
  ASSERT_LT(z_rest, -1e-4);  // it sags
  for (const double zeta : {0.0, 2.0, 6.0}) {
    write(dir / "ring.yaml", base + "solve: {dt: 1 ms, duration: 1.5 s, integrator: implicit_midpoint}\n");
    r = run("run " + (dir / "ring.yaml").string() + " --out " + (dir / "ring").string() +
            " --set wire.damping=" + std::to_string(zeta));
    ASSERT_EQ(r.status, 0) << r.err;
    int peaks = 0;
    const double rate = ringing_decay_rate(read_csv_rows(dir / "ring" / "tip_trace.csv"), z_rest, &peaks);
    EXPECT_GT(peaks, 20) << "zeta " << zeta;
    EXPECT_NEAR(rate, 0.5 * zeta, 0.03 * 0.5 * zeta + 0.02) << "zeta " << zeta;
  }
}

namespace {
nlohmann::json read_summary(const fs::path& out) {
  std::ifstream in(out / "summary.json");
  return nlohmann::json::parse(in);
}
}  // namespace

TEST(Cli, AScenePaysOnlyForThePhasesItUses) {
  // summary.json counts the calls of each phase. The arch with its walls, flow, drag and
  // occlusion makes all of them; the same wire in the same network without flow, contact,
  // drag or occlusion makes none but the rod's steps.
  const auto dir = flowire::testing::scratch_dir("cli-phase-calls");
  const std::string arch = std::string(FLOWIRE_SOURCE_DIR) + "/examples/aortic_arch/scene.yaml";
  auto r = run("run " + arch + " --out " + (dir / "full").string() +
               " --set solve.duration=0.1s --set output.vtk=false --set output.png=false");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto full = read_summary(dir / "full")["calls"];
  for (const char* phase : {"flow_frames", "occlusion_updates", "vertex_lookups", "wall_queries", "drag_evaluations"})
    EXPECT_GT(full[phase].get<long>(), 0) << phase;
  EXPECT_EQ(full["rod_steps"].get<long>(), 10);
  write(dir / "bare.yaml", R"(name: bare
vessels: {generator: {type: aortic_arch}}
wire: {length: 0.8, radius: 0.445 mm, youngs_modulus: 60 GPa, segment_length: 2 mm}
insertion: {speed: 1 cm/s, initial_length: 2 cm}
contact: {enabled: false}
coupling: {drag: none, occlusion: none}
solve: {dt: 10 ms, duration: 0.1 s}
output: {vtk: false}
)");
  r = run("run " + (dir / "bare.yaml").string() + " --out " + (dir / "bare").string());
  ASSERT_EQ(r.status, 0) << r.err;
  const auto bare = read_summary(dir / "bare")["calls"];
  for (const char* phase :
       {"flow_frames", "occlusion_updates", "vertex_lookups", "wall_queries", "drag_evaluations", "catheter_steps"})
    EXPECT_EQ(bare[phase].get<long>(), 0) << phase;
  EXPECT_EQ(bare["rod_steps"].get<long>(), 10);
}

TEST(Cli, TheLongWireOnTheFinelySampledArchConvergesEveryStep) {
  // 78 cm of wire held in the arch sampled at 1 mm (the density of real centerlines), the
  // example's defaults otherwise: the settle against the walls and every step converge.
  // (This run once left 199 of 200 steps unconverged: Newton steps of tens of centimetres
  // from a nearly singular static matrix, and energy tests below the merit's round-off.)
  const auto dir = flowire::testing::scratch_dir("cli-arch-1mm");
  const std::string arch = std::string(FLOWIRE_SOURCE_DIR) + "/examples/aortic_arch/scene.yaml";
  const auto r = run("run " + arch + " --out " + (dir / "out").string() +
                     " --set insertion.initial_length=0.78 --set vessels.max_segment_length=1mm"
                     " --set solve.duration=2s --set output.vtk=false --set output.png=false");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto s = read_summary(dir / "out");
  EXPECT_TRUE(s["wire"]["settle"]["converged"].get<bool>());
  EXPECT_EQ(s["wire"]["unconverged_steps"].get<int>(), 0);
  EXPECT_EQ(s["wire"]["solver"]["steps"].get<long>(), 200);
  EXPECT_EQ(s["status"], "ok");
}

TEST(Cli, PushedPulledAndTurnedWiresConvergeEveryStep) {
  // The published scale: 1 mm segments, 40 cm inside the arch (about 400 vertices), flow,
  // drag, friction and occlusion on, through the CLI with the scene's defaults: held,
  // pushed and pulled at 2 cm/s, turned while pushed, fed by a force, and pushed at 76 cm.
  const auto dir = flowire::testing::scratch_dir("cli-pushed");
  const std::string arch = std::string(FLOWIRE_SOURCE_DIR) + "/examples/aortic_arch/scene.yaml";
  const std::string common =
      " --set wire.segment_length=1mm --set insertion.initial_length=0.4 --set solve.duration=0.5s"
      " --set output.vtk=false --set output.png=false";
  // Force-driven feeding takes insertion.force instead of the example's speed.
  std::ifstream in(arch);
  std::stringstream text;
  text << in.rdbuf();
  std::string forced = text.str();
  const auto at = forced.find("insertion: {speed: 1 cm/s,");
  ASSERT_NE(at, std::string::npos);
  forced.replace(at, std::string("insertion: {speed: 1 cm/s,").size(), "insertion: {force: 0.2 N,");
  write(dir / "forced.yaml", forced);
  const std::vector<std::pair<std::string, std::string>> variants = {
      {"held", arch + " --set insertion.speed=0"},
      {"pushed", arch + " --set insertion.speed=2cm/s"},
      {"pulled", arch + " --set insertion.speed=-2cm/s"},
      {"turned", arch + " --set insertion.speed=2cm/s --set insertion.rotation_speed=3.14"},
      {"forced", (dir / "forced.yaml").string()},
      {"pushed76", arch + " --set insertion.speed=2cm/s --set insertion.max_length=0.8 "
                          "--set insertion.initial_length=0.76"},
  };
  for (const auto& [name, args] : variants) {
    const auto r = run("run " + args + " --out " + (dir / name).string() + common);
    ASSERT_EQ(r.status, 0) << name << ": " << r.err;
    const auto s = read_summary(dir / name);
    EXPECT_EQ(s["wire"]["unconverged_steps"].get<int>(), 0) << name;
    EXPECT_EQ(s["status"], "ok") << name;
    // Each fed variant moved the wire (at 2 cm/s, 1 cm in the half second).
    const double initial = name == "pushed76" ? 0.76 : 0.4;
    if (name != "held") {
      EXPECT_GT(std::abs(s["wire"]["inserted_length"].get<double>() - initial), 2e-3) << name;
    }
  }
}
