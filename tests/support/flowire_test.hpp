#pragma once
// Shared test helpers: warning capture, tolerances scalable from the environment, and
// the location of the shared reference data (tests that need it skip, saying so, if absent).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace flowire::testing {

/// Captures library warnings for its lifetime instead of failing the test.
class ExpectWarnings {
 public:
  ExpectWarnings();
  ~ExpectWarnings();
  ExpectWarnings(const ExpectWarnings&) = delete;
  ExpectWarnings& operator=(const ExpectWarnings&) = delete;
  [[nodiscard]] const std::vector<std::string>& warnings() const { return captured_; }
  [[nodiscard]] bool contains(std::string_view fragment) const;

 private:
  std::vector<std::string> captured_;
  std::vector<std::string>* previous_;
};

/// Tolerance scaled by FLOWIRE_TOL_SCALE (default 1).
inline double tol(double base) {
  static const double scale = [] {
    const char* s = std::getenv("FLOWIRE_TOL_SCALE");
    return s ? std::atof(s) : 1.0;
  }();
  return base * scale;
}

/// The shared reference folder (real anatomies, peer cases, papers), or empty if absent.
inline std::filesystem::path shared_dir() {
  if (const char* env = std::getenv("FLOWIRE_SHARED_DIR")) return env;
  return FLOWIRE_SHARED_DIR;
}

/// A scratch directory for a test, emptied first. It lives in the build tree, so two builds
/// (two clones, two worktrees) running their tests at once never share one, and under the
/// running test's own name, so two tests of one file that CTest runs at once (each test is its
/// own process) never empty each other's.
inline std::filesystem::path scratch_dir(std::string_view name) {
  auto p = std::filesystem::path(FLOWIRE_BINARY_DIR) / "test-scratch" / std::string(name);
  if (const auto* test = ::testing::UnitTest::GetInstance()->current_test_info())
    p /= std::string(test->test_suite_name()) + "." + test->name();
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

/// Least-squares slope of log(y) against log(x): a convergence order.
inline double loglog_slope(const std::vector<double>& x, const std::vector<double>& y) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = static_cast<double>(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

}  // namespace flowire::testing

/// Skip the current test, with a message, when the shared data folder (or a file in it) is absent.
#define FLOWIRE_REQUIRE_SHARED(relpath)                                            \
  do {                                                                             \
    const auto flowire_p_ = ::flowire::testing::shared_dir() / (relpath);          \
    if (!std::filesystem::exists(flowire_p_))                                      \
      GTEST_SKIP() << "shared reference data not found at " << flowire_p_.string() \
                   << " (set FLOWIRE_SHARED_DIR); this test needs it";             \
  } while (0)
