#pragma once
/// @file trace_compare.hpp
/// @brief Distance between two tip traces by inserted length (the published Table 2).
///
/// Both traces (`time,inserted_length,x,y,z`) are resampled at equal inserted lengths
/// (spacing `spacing`, 5 mm in the published experiment) by linear interpolation. For each
/// table row at inserted length L the window (L − row_spacing, L] is summarised by
/// RMS = (½·Σ|X_i − Y_i|²)^½ (the published eq. 11) and by the conventional root mean
/// square (1/n·Σ|X_i − Y_i|²)^½.
#include <string>
#include <vector>

#include <Eigen/Core>

namespace flowire::coupling {

struct TracePoint {
  double time = 0, inserted_length = 0;
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
};

/// @brief Read a tip_trace.csv. @throws flowire::Error naming file and line.
std::vector<TracePoint> read_tip_trace(const std::string& path);

struct CompareRow {
  double inserted_length = 0;  ///< end of the window (m)
  int samples = 0;
  double rms_published = 0;  ///< (½·Σ|X−Y|²)^½ over the window (m)
  double rms = 0;            ///< (1/n·Σ|X−Y|²)^½ over the window (m)
  double max_distance = 0;   ///< m
};

struct CompareResult {
  std::vector<CompareRow> rows;
  double rms_published_total = 0;
  double rms_total = 0;
  int samples = 0;
};

/// @brief Compare two traces; only the inserted lengths both cover are compared.
CompareResult compare_traces(const std::vector<TracePoint>& a, const std::vector<TracePoint>& b, double spacing = 5e-3,
                             double row_spacing = 50e-3);

/// @brief The result as a CSV table (lengths and distances in m).
std::string compare_csv(const CompareResult& r);

}  // namespace flowire::coupling
