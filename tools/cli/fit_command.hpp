#pragma once
// `flowire fit`: scene values fitted to a measured tip trace with CMA-ES (docs/fit.md).
#include <string>
#include <vector>

namespace flowire::cli {

struct FitOptions {
  std::string scene, trace, out;
  std::vector<std::string> params;  ///< "KEY=LO..HI", values with units as the scene accepts them
  std::vector<std::string> sets;    ///< fixed --set overrides for every run
  int jobs = 0;                     ///< runs at a time; 0: hardware concurrency
  long max_evaluations = 0;         ///< 0: 100·(n + 1) for n parameters
  unsigned long long seed = 1;
};

/// @brief Run the fit; writes OUT/fit.json, OUT/fit_history.csv and the best run's outputs.
/// @throws flowire::Error naming the bad argument or file (exit status 2) before anything is written.
int run_fit(const FitOptions& options);

}  // namespace flowire::cli
