// view.py (coupling/src/paraview_script.cpp): written only when there is something to show,
// and what it sets read back by Python's own parser (ast), so quotes, backslashes and line
// breaks in a title survive, and the wire's drawn radius is max(3 r, 1.2 mm).
#include "flowire/coupling/paraview_script.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "flowire_test.hpp"

using namespace flowire::coupling;
namespace fs = std::filesystem;

namespace {

/// The module-level constants of @p script as Python parses them (skips without python3).
nlohmann::json python_constants(const fs::path& script, const fs::path& out) {
  const std::string cmd =
      "python3 -c \"import ast, json, sys\n"
      "tree = ast.parse(open(sys.argv[1]).read())\n"
      "names = {}\n"
      "for node in tree.body:\n"
      "    if isinstance(node, ast.Assign) and isinstance(node.value, ast.Constant):\n"
      "        for t in node.targets:\n"
      "            names[t.id] = node.value.value\n"
      "json.dump(names, open(sys.argv[2], 'w'))\n\" '" +
      script.string() + "' '" + out.string() + "'";
  if (std::system(cmd.c_str()) != 0) return nullptr;
  std::ifstream in(out);
  return nlohmann::json::parse(in);
}

bool have_python() { return std::system("python3 -c 'import ast' >/dev/null 2>&1") == 0; }

TEST(ParaViewScript, NothingToShowWritesNoScript) {
  const auto dir = flowire::testing::scratch_dir("paraview_script_none");
  EXPECT_FALSE(write_paraview_script(dir, {}));
  EXPECT_FALSE(fs::exists(dir / "view.py"));
}

TEST(ParaViewScript, PythonReadsBackTheFilesRadiusAndAnAwkwardTitle) {
  if (!have_python()) GTEST_SKIP() << "python3 not found";
  const auto dir = flowire::testing::scratch_dir("paraview_script_title");
  ParaViewScene s;
  s.network = "network.pvd";
  s.wire = "wire.pvd";
  s.wire_radius = 0.45e-3;  // 3 r = 1.35 mm > 1.2 mm
  s.title = "arch \"flow on\"\\ at 2 cm/s\nsecond line";
  ASSERT_TRUE(write_paraview_script(dir, s));
  const auto c = python_constants(dir / "view.py", dir / "constants.json");
  ASSERT_FALSE(c.is_null()) << "python3 could not parse view.py";
  EXPECT_EQ(c["NETWORK"], "network.pvd");
  EXPECT_EQ(c["WIRE"], "wire.pvd");
  EXPECT_EQ(c["TITLE"], s.title);
  EXPECT_NEAR(c["WIRE_DRAW_RADIUS"].get<double>(), 1.35e-3, 1e-9);
  EXPECT_EQ(c["WALL"], "");  // no wall: the script's `if WALL:` skips it
}

TEST(ParaViewScript, AWallThatYieldsIsShownWarpedByItsDisplacement) {
  if (!have_python()) GTEST_SKIP() << "python3 not found";
  const auto dir = flowire::testing::scratch_dir("paraview_script_wall");
  ParaViewScene s;
  s.wire = "wire.pvd";
  s.wall = "wall.pvd";
  ASSERT_TRUE(write_paraview_script(dir, s));
  const auto c = python_constants(dir / "view.py", dir / "constants.json");
  ASSERT_FALSE(c.is_null());
  EXPECT_EQ(c["WALL"], "wall.pvd");
  std::ifstream in(dir / "view.py");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("WarpByVector"), std::string::npos);
  EXPECT_NE(text.find("\"displacement_magnitude\""), std::string::npos);
}

TEST(ParaViewScript, AThinWireIsDrawnAtLeastOnePointTwoMillimetres) {
  if (!have_python()) GTEST_SKIP() << "python3 not found";
  const auto dir = flowire::testing::scratch_dir("paraview_script_thin");
  ParaViewScene s;
  s.wire = "wire.pvd";
  s.wire_radius = 0.178e-3;  // a 0.014" wire: 3 r = 0.53 mm
  ASSERT_TRUE(write_paraview_script(dir, s));
  const auto c = python_constants(dir / "view.py", dir / "constants.json");
  ASSERT_FALSE(c.is_null());
  EXPECT_EQ(c["NETWORK"], "");  // the script's `if NETWORK:` skips the network
  EXPECT_EQ(c["TITLE"], "");
  EXPECT_NEAR(c["WIRE_DRAW_RADIUS"].get<double>(), 1.2e-3, 1e-12);
}

}  // namespace
