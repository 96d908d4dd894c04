#pragma once
// `flowire run` on model files (svZeroDSolver JSON, openBF YAML): shared by the full command
// line and its lean front.
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "flowire/flow/output.hpp"

namespace flowire::cli {

/// @brief Simulate an svZeroDSolver model into `out` (default "out"): svzerod_result.csv and
/// summary.json. @throws flowire::Error as the command line maps it to exit statuses.
int run_svzerod(const std::string& model, const std::string& out, const std::vector<std::string>& sets);

/// @brief Run an openBF model (flow/openbf.hpp) into `out`: vessels.csv and summary.json.
/// Draws a model's waveforms to a PNG (flow::render_waveforms_png; VTK, so not in the lean front).
using DrawWaveforms = std::function<void(const std::vector<flowire::flow::WaveformSeries>&, const std::string& title,
                                         const std::filesystem::path& png)>;

/// @p network_out: also write the model's layout (openbf::network) there as .vtp (empty: not).
/// @p draw: draws waveforms.png where an X display is (empty: not drawn, said in the summary).
int run_openbf(const std::string& model, const std::string& out, const std::vector<std::string>& sets,
               const std::string& network_out = {}, const DrawWaveforms& draw = {});

}  // namespace flowire::cli
