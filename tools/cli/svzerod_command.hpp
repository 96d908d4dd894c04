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
/// @p network_out: also write the model's layout (openbf::network) there as .vtp (empty: not).
int run_openbf(const std::string& model, const std::string& out, const std::vector<std::string>& sets,
               const std::string& network_out = {});

}  // namespace flowire::cli
