#pragma once
// Running the flowire executable from a test: its exit status and what it printed.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "flowire_test.hpp"

namespace flowire::testing {

struct CliResult {
  int status = -1;
  std::string out, err;
};

/// A shell command line's exit status (128 + the signal if one ended it), stdout and stderr,
/// captured in files of @p dir.
inline CliResult run_shell(const std::string& cmd, const std::filesystem::path& dir) {
  const int raw = std::system((cmd + " >" + (dir / "o").string() + " 2>" + (dir / "e").string()).c_str());
  CliResult r;
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
  std::stringstream so, se;
  so << std::ifstream(dir / "o").rdbuf();
  se << std::ifstream(dir / "e").rdbuf();
  r.out = so.str();
  r.err = se.str();
  return r;
}

/// `flowire ARGS` (a shell command line), captured in @p dir.
inline CliResult run_cli_in(const std::string& args, const std::filesystem::path& dir) {
  return run_shell(std::string(FLOWIRE_BINARY_DIR) + "/tools/flowire " + args, dir);
}

/// `flowire ARGS` (a shell command line): its exit status, stdout and stderr.
inline CliResult run_cli(const std::string& args) {
  // One capture folder per test and call: CTest runs the tests of a file in parallel.
  static int calls = 0;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return run_cli_in(args, scratch_dir(std::string("cli-capture-") + info->name() + "-" + std::to_string(calls++)));
}

/// Write @p text to the file @p p.
inline void write_file(const std::filesystem::path& p, const std::string& text) { std::ofstream(p) << text; }

}  // namespace flowire::testing
