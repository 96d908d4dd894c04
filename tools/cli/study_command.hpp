#pragma once
// `flowire study`: a study file's runs (cases × a product of scene values) over --jobs child
// processes and MPI ranks, resumable, collected into tables and plots (docs/study.md).
#include <string>

namespace flowire::cli {

struct StudyOptions {
  std::string file;   ///< the study file (YAML)
  std::string out;    ///< the output folder
  int jobs = 0;       ///< runs at a time on each rank; 0: the hardware threads, 1 per rank under MPI
  bool list = false;  ///< print the runs and stop: nothing is run or written
};

/// @brief Run a study (every rank of an MPI job calls it; rank 0 reports). Returns the exit
/// status: 0 when every run has its result (failed runs included), 3 when some have none.
/// @throws flowire::Error naming the study file, line and key (exit status 2) before anything
/// is run or written.
int run_study(const StudyOptions& options);

}  // namespace flowire::cli
