#pragma once
/// @file wire_output.hpp
/// @brief Wire outputs: wire.csv (time,vertex,s,x,y,z,drag_x,drag_y,drag_z,contact_x,
/// contact_y,contact_z), tip_trace.csv (time,inserted_length,x,y,z), base_force.csv
/// (time,fx,fy,fz,tx,ty,tz: the clamp's force and torque every step), and a ParaView series
/// wire.pvd + wire_NNNNN.vtp with point data s, force, drag, contact and flow_velocity. Rows are buffered in memory and
/// every file is written atomically, so a failed run leaves no half-written file.
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace flowire::coupling {

/// @brief One output frame of the wire, vertices ordered from the base (s = 0) to the tip.
struct WireFrame {
  double time = 0.0;
  std::vector<Eigen::Vector3d> x;
  std::vector<double> s;
  std::vector<Eigen::Vector3d> force;          ///< interaction force per vertex (N): drag + contact
  std::vector<Eigen::Vector3d> drag;           ///< blood drag per vertex (N)
  std::vector<Eigen::Vector3d> contact;        ///< wall force per vertex, normal and friction (N)
  std::vector<Eigen::Vector3d> flow_velocity;  ///< blood velocity at each vertex (m/s)
};

class WireOutput {
 public:
  /// @p name: "wire", or "catheter" for the catheter's catheter.csv and catheter.pvd +
  /// catheter_NNNNN.vtp (same columns; no tip trace or base force).
  WireOutput(std::filesystem::path dir, bool csv, bool vtk, std::string name = "wire");
  /// @brief Record a frame (the VTK file of the frame is written now).
  void add_frame(const WireFrame& frame);
  /// @brief Record a tip-trace sample (every step).
  void add_tip(double time, double inserted_length, const Eigen::Vector3d& tip);
  /// @brief Record the clamp's force and torque on the wire (every step): base_force.csv,
  /// `time,fx,fy,fz,tx,ty,tz` [s, N, N·m], what a haptic device reads.
  void add_base(double time, const Eigen::Vector3d& force, const Eigen::Vector3d& torque);
  /// @brief Write wire.csv, tip_trace.csv, base_force.csv and wire.pvd.
  void finish();
  [[nodiscard]] int frames() const { return frame_count_; }

 private:
  std::filesystem::path dir_;
  bool csv_, vtk_;
  std::string name_;
  std::string wire_csv_, tip_csv_, base_csv_;
  std::vector<std::pair<double, std::string>> vtk_files_;
  int frame_count_ = 0;
};

/// @brief Write a ParaView collection (.pvd) listing (time, file) pairs, atomically.
void write_pvd(const std::filesystem::path& path, const std::vector<std::pair<double, std::string>>& files);

}  // namespace flowire::coupling
