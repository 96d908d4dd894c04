#pragma once
/// @file studies.hpp
/// @brief The studies of `flowire_bench`; each writes one CSV (and echoes it to stdout).
#include <string>
#include <vector>

namespace flowire::bench {

struct Options {
  std::string out_dir = ".";      ///< where the CSV goes
  std::string scene;              ///< the aortic-arch scene file
  bool reduced = false;           ///< CI / quick size
  std::string known_failures;     ///< stress: file listing the failures that are known and explained
  std::vector<std::string> only;  ///< stress: run only the points whose id contains all of these
};

int rod_work_precision(const Options& o);
int flow_frame_cost(const Options& o);
/// Built with FLOWIRE_WITH_FEM only (FLOWIRE_BENCH_FEM).
int flow_fem_work_precision(const Options& o);
int cosim_work_precision(const Options& o);
int feature_cost(const Options& o);
int stress(const Options& o);

/// @brief Write `text` to `out_dir/name` and to stdout.
void emit(const Options& o, const std::string& name, const std::string& text);

}  // namespace flowire::bench
