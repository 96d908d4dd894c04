#pragma once
/// @file body.hpp
/// @brief The rod as a body: its model (constant), its state (what changes), and the constants
/// of the vertices simulated now (those change only when the vertex set does). The parts that
/// act on it each do one job: the `Feeder` (feeder.hpp) decides which vertices are simulated and
/// where the held ones are, the `TimeStepper` (stepper.hpp) moves the free ones, the `Loads`
/// (loads.hpp) and the `ExternalForce`s (external.hpp) push on them.
#include <Eigen/Core>
#include <vector>

#include "flowire/rod/energies.hpp"
#include "flowire/rod/model.hpp"

namespace flowire::rod {

/// @brief One sample of the tip trace.
struct TipSample {
  double time = 0.0;
  double inserted_length = 0.0;
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();
};

/// @brief Energies of the current state [J].
struct RodEnergy {
  double kinetic = 0.0;
  double stretching = 0.0;
  double bending_twisting = 0.0;
  [[nodiscard]] double total() const { return kinetic + stretching + bending_twisting; }
};

/// @brief The changing state (sizes in comments; vertex 0 = distal tip).
struct RodState {
  std::vector<Eigen::Vector3d> x;  ///< (n_vertices) positions [m]
  std::vector<Eigen::Vector3d> v;  ///< (n_vertices) velocities [m/s]
  std::vector<double> theta;       ///< (n_edges) material angle w.r.t. reference frame [rad]
  std::vector<double> omega;       ///< (n_edges) dθ/dt [rad/s]
  std::vector<EdgeFrame> frame;    ///< (n_edges) reference frames (time-parallel)
  std::vector<double> ref_twist;   ///< (n_vertices) reference twist (interior vertices)
  std::vector<double> u;           ///< (n_vertices) material coordinate from the tip [m]
  double time = 0.0;               ///< [s]
  double inserted_length = 0.0;    ///< [m] wire length in front of the entry point
  double base_angle = 0.0;         ///< [rad] rotation of the clamp
  [[nodiscard]] int vertex_count() const { return static_cast<int>(x.size()); }
  [[nodiscard]] int edge_count() const { return static_cast<int>(x.size()) - 1; }
  /// @brief Room for @p vertices vertices in every array.
  void reserve(int vertices);
};

/// @brief The model, the state and the simulated vertices' constants, held together by the
/// simulator and shared by reference with its parts.
struct RodBody {
  RodModel model;       ///< constant
  RodState state;       ///< positions, angles, frames, velocities, time, inserted length
  Discretization disc;  ///< constants of the simulated vertices (at state.u)
  /// @brief disc for the current vertex set (after it changed).
  void rediscretize() { model.discretize(state.u, disc); }
  /// @brief The most vertices the wire can have (adaptive refinement included): every buffer
  /// is sized for it once.
  [[nodiscard]] int max_vertices() const;
};

}  // namespace flowire::rod
