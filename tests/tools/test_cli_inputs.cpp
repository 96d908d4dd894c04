// Inputs that are not what a scene should be, through the command line: special files,
// folders, numbers no type holds, positions far from any vessel, a wire too finely cut, keys
// that are not names, pictures without a display. Each is one line on stderr, exit status 2,
// and no output written.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>

#include <filesystem>
#include <string>

#include "cli_run.hpp"
#include "flowire_test.hpp"

namespace fs = std::filesystem;

namespace {

using flowire::testing::run_cli;
using flowire::testing::write_file;

/// A short wire scene on the built-in arch (a vessels: scene whose wire enters by itself).
const char* kArch =
    "vessels:\n  generator: {type: aortic_arch}\nwire:\n  length: 0.3\n  segment_length: 5 mm\n"
    "solve: {dt: 1 ms, duration: 3 ms}\n";

/// `flowire ARGS` must fail with status 2 and one line naming @p says; nothing written to @p out.
void expect_refused(const std::string& args, const std::string& says, const fs::path& out) {
  const auto r = run_cli(args + " --out " + out.string());
  EXPECT_EQ(r.status, 2) << args << "\n" << r.err;
  EXPECT_EQ(r.err.rfind("flowire: error: ", 0), 0U) << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "more than one line:\n" << r.err;
  EXPECT_NE(r.err.find(says), std::string::npos) << args << "\n" << r.err;
  EXPECT_FALSE(fs::exists(out)) << args << ": wrote " << out;
}

TEST(CliInputs, SpecialFilesAndFoldersAreNoScenes) {
  const auto dir = flowire::testing::scratch_dir("cli_inputs_special");
  fs::create_directories(dir / "folder.yaml");
  fs::create_directories(dir / "model.json");
  ASSERT_EQ(::mkfifo((dir / "pipe.yaml").c_str(), 0600), 0);
  expect_refused("run " + (dir / "folder.yaml").string(), "is a folder", dir / "o1");
  expect_refused("run " + (dir / "model.json").string(), "is a folder", dir / "o2");
  expect_refused("run /dev/zero", "not a regular file", dir / "o3");                        // read for ever before
  expect_refused("run " + (dir / "pipe.yaml").string(), "not a regular file", dir / "o4");  // blocked for ever
  expect_refused("run " + (dir / "none.yaml").string(), "no such file", dir / "o5");
}

TEST(CliInputs, NumbersNoTypeHoldsAreInputErrors) {
  const auto dir = flowire::testing::scratch_dir("cli_inputs_numbers");
  write_file(dir / "huge.json", R"({"simulation_parameters": {"number_of_cardiac_cycles": 1e400}})");
  expect_refused("run " + (dir / "huge.json").string(), "huge.json: not valid JSON", dir / "o1");
  write_file(dir / "arch.yaml", kArch);
  const std::string arch = "run " + (dir / "arch.yaml").string();
  // A wire of 1e300 m or segments of 1e-12 m: more segments than any memory holds.
  expect_refused(arch + " --set wire.length=1e300", "at most", dir / "o2");
  expect_refused(arch + " --set wire.segment_length=1e-12", "wire.segment_length", dir / "o3");
}

TEST(CliInputs, AKeyMustBeANameNotAListOrAMap) {
  const auto dir = flowire::testing::scratch_dir("cli_inputs_keys");
  write_file(dir / "list_key.yaml", "wire:\n  ? [length, radius]\n  : 1\n");
  expect_refused("run " + (dir / "list_key.yaml").string(), "list_key.yaml:2", dir / "o1");
  write_file(dir / "map_key.yaml", "? {wire: 1}\n: 1\n");
  expect_refused("run " + (dir / "map_key.yaml").string(), "a key must be a name", dir / "o2");
}

TEST(CliInputs, AWireBaseFarFromEveryVesselIsRefusedBeforeTheRun) {
  // At 1e155 m the lookups once overflowed (a crash); at 1e15 m the run "succeeded" with the
  // wire nowhere near the anatomy. Both are a wrong unit or a typo.
  const auto dir = flowire::testing::scratch_dir("cli_inputs_far");
  write_file(dir / "arch.yaml", kArch);
  for (const std::string x : {"1e155", "1e15", "-40"}) {
    expect_refused("run " + (dir / "arch.yaml").string() + " --set wire.base.position=[" + x + ",0,0]",
                   "wire.base.position", dir / ("o" + x));
  }
  // Near the network (an introducer a few centimetres out) is a scene, and runs.
  const auto r = run_cli("run " + (dir / "arch.yaml").string() + " --out " + (dir / "near").string());
  EXPECT_EQ(r.status, 0) << r.err;
}

TEST(CliInputs, PicturesWithoutADisplayFailBeforeTheRun) {
  const auto dir = flowire::testing::scratch_dir("cli_inputs_png");
  write_file(dir / "arch.yaml", kArch);
  // Without DISPLAY: refused at once, naming the key, nothing written (it failed after the
  // whole run before, leaving no summary).
  const std::string args = "run " + (dir / "arch.yaml").string() + " --set output.png=true";
  ::setenv("FLOWIRE_TEST_SAVED_DISPLAY", std::getenv("DISPLAY") ? std::getenv("DISPLAY") : "", 1);
  ::unsetenv("DISPLAY");
  expect_refused(args, "output.png", dir / "o3");
  const std::string saved = std::getenv("FLOWIRE_TEST_SAVED_DISPLAY");
  if (!saved.empty()) ::setenv("DISPLAY", saved.c_str(), 1);
}

TEST(CliInputs, AReadOnlyOutputFolderIsOneLine) {
  if (::geteuid() == 0) GTEST_SKIP() << "running as root: a read-only folder is writable to root";
  const auto dir = flowire::testing::scratch_dir("cli_inputs_readonly");
  write_file(dir / "arch.yaml", kArch);
  fs::create_directories(dir / "ro");
  fs::permissions(dir / "ro", fs::perms::owner_read | fs::perms::owner_exec);
  const auto r = run_cli("run " + (dir / "arch.yaml").string() + " --out " + (dir / "ro").string());
  fs::permissions(dir / "ro", fs::perms::owner_all);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "more than one line:\n" << r.err;
  EXPECT_NE(r.err.find("ro: cannot write to the output folder"), std::string::npos) << r.err;
}

}  // namespace
