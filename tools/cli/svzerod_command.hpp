#pragma once
// `flowire run` on model files (svZeroDSolver JSON, openBF YAML): shared by the full command
// line and its lean front.
#include <string>
#include <vector>

namespace flowire::cli {

/// @brief Simulate an svZeroDSolver model into `out` (default "out"): svzerod_result.csv and
/// summary.json. @throws flowire::Error as the command line maps it to exit statuses.
int run_svzerod(const std::string& model, const std::string& out, const std::vector<std::string>& sets);

/// @brief Run an openBF model (flow/openbf.hpp) into `out`: vessels.csv and summary.json.
int run_openbf(const std::string& model, const std::string& out, const std::vector<std::string>& sets);

}  // namespace flowire::cli
