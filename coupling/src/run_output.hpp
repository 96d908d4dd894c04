#pragma once
// What a scene run writes (run_output.cpp): the output recorder and the summary's entries.
#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <optional>
#include <vector>

#include "flowire/common/config.hpp"
#include "flowire/coupling/cosimulation.hpp"
#include "flowire/coupling/wire_output.hpp"
#include "flowire/flow/output.hpp"

namespace flowire::coupling {

/// @brief What a run writes while it steps and at its end. Frames (flow, wire, catheter) are
/// captured at output times and written at the end: nodes.csv, segments.csv and network.vtp
/// (or the network.pvd series), wire.* and catheter.* (CSV and VTK as output.csv/output.vtk
/// ask), tip.csv and base_force.csv every step, the pictures (output.png) and view.py.
class RunRecorder {
 public:
  RunRecorder(const config::Config& scene, const CoSimulation& cosim, std::filesystem::path out);
  /// Capture one output frame at time @p t.
  void record(double t);
  /// The per-step streams (tip position, clamp force and torque) after a step.
  void after_step();
  /// Write everything; @p series: the frames form a time series (output.every > 0).
  void finish(bool series);
  /// Seconds spent capturing and writing.
  [[nodiscard]] double seconds() const { return seconds_; }

 private:
  const config::Config& c_;
  const CoSimulation& cosim_;
  std::filesystem::path out_;
  bool csv_ = false, vtk_ = false;
  std::vector<flow::FlowFrame> flow_frames_;
  std::optional<WireOutput> wire_, catheter_;
  std::vector<std::pair<double, Eigen::VectorXd>> wall_frames_;  ///< (time, the wall's state) per frame
  double seconds_ = 0.0;
};

/// @brief The seconds of a run's vessel forces, split out of the rod's own time.
struct RunSeconds {
  double contact = 0.0;   ///< lookup, wall distance, penalty and friction
  double coupling = 0.0;  ///< blood drag
};

/// @brief Add the end-of-run entries of summary.json (flow, occlusion, wire, catheter,
/// tip_forces, lookup, contact, drag) for what the scene has.
RunSeconds add_run_summary(const config::Config& scene, const CoSimulation& cosim, nlohmann::json& s);

}  // namespace flowire::coupling
