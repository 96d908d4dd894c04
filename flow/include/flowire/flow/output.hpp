#pragma once
/// @file output.hpp
/// @brief Flow output files of the user contract: nodes.csv, segments.csv, network.vtp and
/// a network.pvd time series, and a PNG of the pressure-coloured network (VTK offscreen).
/// Every file is written atomically (flowire::write_atomically).
#include <array>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "flowire/flow/solver.hpp"

namespace flowire::flow {

/// @brief The full state at one time, for output.
struct FlowFrame {
  double time = 0.0;
  std::vector<double> pressure;  ///< (num_nodes) Pa
  std::vector<double> flow;      ///< (num_segments) m³/s
  /// (num_segments) or empty (no wire: 0 and 1): occluded length fraction and resistance
  /// factor of each segment (SegmentOcclusion)
  std::vector<double> occupied_fraction, resistance_factor;
  [[nodiscard]] double occupied(size_t s) const { return occupied_fraction.empty() ? 0.0 : occupied_fraction[s]; }
  [[nodiscard]] double factor(size_t s) const { return resistance_factor.empty() ? 1.0 : resistance_factor[s]; }
};

/// @brief Copy the solver's current state (its time, all pressures and flows).
FlowFrame capture_frame(const FlowSolver& solver);

/// @brief Advance the solver over [t0, t0 + duration] and capture `count` frames equally
/// spaced (count ≥ 1; the last frame at t0 + duration when count > 1). For one cardiac
/// cycle pass duration = spec.cycle() and the frames exclude the repeated end point.
std::vector<FlowFrame> sample_frames(FlowSolver& solver, double t0, double duration, int count,
                                     bool include_end = true);

/// @brief `time,node,x,y,z,pressure`, one block of rows per frame.
void write_nodes_csv(const Network& net, std::span<const FlowFrame> frames, const std::filesystem::path& path);

/// @brief `time,segment,node_from,node_to,length,radius,resistance,flow_rate,mean_velocity,
/// wall_shear_stress,reynolds,occupied_fraction,resistance_factor`, one block of rows per
/// frame (solver gives R, η, ρ). `resistance` is the empty segment's; with a wire in it the
/// segment's resistance is resistance × resistance_factor. Mean velocity, wall shear stress
/// and Reynolds number are those of the flow in the empty tube.
void write_segments_csv(const FlowSolver& solver, std::span<const FlowFrame> frames, const std::filesystem::path& path);

/// @brief One frame as VTK poly data: point data `pressure`; cell data `flow_rate`,
/// `mean_velocity`, `wall_shear_stress`, `reynolds`, `occupied_fraction`, `resistance_factor`
/// (plus the network writer's `radius`, ...).
void write_network_vtp(const FlowSolver& solver, const FlowFrame& frame, const std::filesystem::path& path);

/// @brief A time series in `dir`: `<stem>_NNNNNN.vtp` per frame, `<stem>.pvd` listing them
/// with their times (opens in ParaView as one animated dataset), and `<stem>.vtp` holding the
/// last frame.
void write_network_series(const FlowSolver& solver, std::span<const FlowFrame> frames, const std::filesystem::path& dir,
                          const std::string& stem = "network");

/// @brief A polyline drawn over the network (e.g. the guidewire), as a tube.
struct RenderOverlay {
  std::vector<Vec3> points;
  double radius = 0.4e-3;                         ///< m
  std::array<double, 3> color = {0.1, 0.1, 0.1};  ///< RGB in [0, 1]
};

/// @brief How `render_network_png` draws.
struct RenderOptions {
  int width = 1024, height = 768;
  std::string title;  ///< text at the top-left
  std::string scalar_name = "pressure (mmHg)";
  double scalar_scale = 1.0 / 133.322387415;   ///< multiplies node values for display (Pa → mmHg)
  double range_min = 0.0, range_max = 0.0;     ///< colour range (display units); equal: data range
  std::vector<RenderOverlay> overlays;         ///< drawn over the vessels
  Vec3 view_direction = Vec3(0.0, -1.0, 0.0);  ///< camera looks along this direction
  Vec3 view_up = Vec3(0.0, 0.0, 1.0);
};

/// @brief Render the network as tubes of their radius coloured by a node scalar (blue low,
/// red high) with a colour bar, offscreen, to a PNG. Needs VTK and an X display (run under
/// `xvfb-run -a -s "-screen 0 1024x768x24"`).
/// @throws flowire::Error (input) without VTK or without a display.
/// @brief Check, before a run, that PNGs can be drawn here (VTK built in, an X display that
/// answers); @p where names the key that asks for them. @throws flowire::Error (input).
void check_can_render(const std::string& where);

void render_network_png(const Network& net, std::span<const double> node_values, const std::filesystem::path& path,
                        const RenderOptions& options = {});

/// @brief One vessel's pressure (Pa) and flow (m³/s) over a cycle, for render_waveforms_png.
struct WaveformSeries {
  std::string name;
  std::vector<double> time, pressure, flow;
};

/// @brief Draw @p series as two charts in one PNG (offscreen, needs an X display as
/// render_network_png): pressure in mmHg above, flow in mL/s below, over time, one coloured line
/// and legend entry per series. Written atomically.
/// @throws flowire::Error (input) without VTK or a display, or if the file cannot be written;
/// (usage) for an empty list or a series whose samples do not match.
void render_waveforms_png(const std::vector<WaveformSeries>& series, const std::string& title,
                          const std::filesystem::path& path, int width = 1000, int height = 800);

}  // namespace flowire::flow
