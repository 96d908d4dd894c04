// svZeroDSolver interop: every peer case that uses only the supported blocks, against the
// peer's stored result with its own rule |a − b| ≤ rtol·(1 + |b|), rtol = 1e-7
// (reference 4: ../shared/peers/svzerodsolver, svZeroDSolver tests/utils.py).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "flowire/common/error.hpp"
#include "flowire/flow/svzerod/simulate.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// Blocks of a case that flowire does not support (empty: supported).
std::set<std::string> unsupported_blocks(const json& cfg) {
  std::set<std::string> out;
  for (const auto& v : cfg.value("vessels", json::array()))
    if (v.value("zero_d_element_type", "BloodVessel") != "BloodVessel" &&
        v.value("zero_d_element_type", "BloodVessel") != "BloodVesselCRL")
      out.insert(v["zero_d_element_type"]);
  for (const auto& b : cfg.value("boundary_conditions", json::array())) {
    const std::string t = b["bc_type"];
    if (t != "FLOW" && t != "PRESSURE" && t != "RESISTANCE" && t != "RCR" && t != "CORONARY" && t != "CORONARY_VAR_RES")
      out.insert(t);
  }
  for (const auto& j : cfg.value("junctions", json::array()))
    if (j["junction_type"] != "NORMAL_JUNCTION" && j["junction_type"] != "BloodVesselJunction")
      out.insert(j["junction_type"]);
  for (const char* k : {"closed_loop_blocks", "valves", "chambers", "external_solver_coupling_blocks"})
    if (cfg.contains(k)) out.insert(k);
  if (!cfg.contains("simulation_parameters")) out.insert("(no simulation_parameters: calibration input)");
  return out;
}

double value_of(const json& x) {
  if (x.is_number()) return x.get<double>();
  if (x.is_string()) return std::stod(x.get<std::string>());
  return std::nan("");
}

/// Compare with the stored column-wise result; returns the number of values out of tolerance.
int compare(const svzerod::Result& r, const json& ref, const std::string& label) {
  const double rtol = 1e-7;
  const auto& names = ref.at("name");
  const size_t rows = names.size();
  EXPECT_EQ(r.names.size(), rows) << label;
  if (r.names.size() != rows) return 1;
  int bad = 0;
  int checked = 0;
  for (size_t c = 2; c < r.columns.size(); ++c) {
    const std::string& col = r.columns[c];
    if (!ref.contains(col)) continue;
    if (col.find("flow") == std::string::npos && col.find("pressure") == std::string::npos && col != "y") continue;
    for (size_t i = 0; i < rows; ++i) {
      const std::string key = std::to_string(i);
      EXPECT_EQ(r.names[i], ref.at("name").at(key).get<std::string>()) << label << " row " << i;
      const double expect = value_of(ref.at(col).at(key));
      const double got = r.data[i][c - 2];
      ++checked;
      if (!(std::abs(got - expect) <= rtol + rtol * std::abs(expect))) {
        if (bad < 5)
          ADD_FAILURE() << label << ": " << col << " of " << r.names[i] << " at row " << i << ": " << got
                        << " vs stored " << expect;
        ++bad;
      }
    }
  }
  EXPECT_GT(checked, 0) << label;
  return bad;
}

TEST(FlowSvZeroD, PeerCasesWithSupportedBlocksMatchStoredResults) {
  FLOWIRE_REQUIRE_SHARED("peers/svzerodsolver/cases");
  const fs::path dir = flowire::testing::shared_dir() / "peers/svzerodsolver/cases";
  std::vector<std::string> passed, failed, skipped;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".json") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    const std::string name = f.stem().string();
    json cfg;
    std::ifstream(f) >> cfg;
    const auto missing = unsupported_blocks(cfg);
    if (!missing.empty()) {
      std::string m;
      for (const auto& x : missing) m += (m.empty() ? "" : ", ") + x;
      skipped.push_back(name + " (" + m + ")");
      continue;
    }
    const fs::path res = dir / "results" / ("result_" + name + ".json");
    if (!fs::exists(res)) {
      // The peer refuses this input (no stored result): flowire must refuse it too.
      try {
        (void)svzerod::simulate(f.string());
        ADD_FAILURE() << name << ": the peer has no result for it (it refuses the input), flowire accepted it";
        failed.push_back(name);
      } catch (const Error& e) {
        passed.push_back(name + " (refused: " + e.what() + ")");
      }
      continue;
    }
    json ref;
    std::ifstream(res) >> ref;
    try {
      const auto r = svzerod::simulate(f.string());
      (compare(r, ref, name) == 0 ? passed : failed).push_back(name);
    } catch (const Error& e) {
      ADD_FAILURE() << name << ": " << e.what();
      failed.push_back(name);
    }
  }
  std::printf("svZeroDSolver peer cases: %zu pass, %zu fail, %zu skipped\n", passed.size(), failed.size(),
              skipped.size());
  for (const auto& s : passed) std::printf("  pass  %s\n", s.c_str());
  for (const auto& s : failed) std::printf("  FAIL  %s\n", s.c_str());
  for (const auto& s : skipped) std::printf("  skip  %s\n", s.c_str());
  EXPECT_GE(passed.size(), 29u);
}

TEST(FlowSvZeroD, RunWritesTheResultCsv) {
  FLOWIRE_REQUIRE_SHARED("peers/svzerodsolver/cases/steadyFlow_bifurcationR_R1.json");
  const auto out = flowire::testing::scratch_dir("flow_svzerod_run");
  const auto s = svzerod::run(
      (flowire::testing::shared_dir() / "peers/svzerodsolver/cases/steadyFlow_bifurcationR_R1.json").string(), out);
  EXPECT_EQ(s.vessels, 3);
  EXPECT_EQ(s.junctions, 1);
  std::ifstream in(out / "svzerod_result.csv");
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "name,time,flow_in,flow_out,pressure_in,pressure_out");
  int lines = 0;
  for (std::string l; std::getline(in, l);) ++lines;
  EXPECT_EQ(lines, s.rows);
}

TEST(FlowSvZeroD, UnsupportedBlockIsAClearInputError) {
  const auto dir = flowire::testing::scratch_dir("flow_svzerod_bad");
  std::ofstream(dir / "m.json") << R"({"simulation_parameters": {"number_of_cardiac_cycles": 1,
    "number_of_time_pts_per_cardiac_cycle": 5},
    "boundary_conditions": [{"bc_name": "IN", "bc_type": "FLOW", "bc_values": {"Q": 1.0}},
                            {"bc_name": "OUT", "bc_type": "ClosedLoopRCR", "bc_values": {}}],
    "vessels": [{"vessel_id": 0, "vessel_name": "v", "zero_d_element_type": "BloodVessel",
                 "zero_d_element_values": {"R_poiseuille": 1.0},
                 "boundary_conditions": {"inlet": "IN", "outlet": "OUT"}}]})";
  try {
    (void)svzerod::simulate((dir / "m.json").string());
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("ClosedLoopRCR"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace flowire::flow
