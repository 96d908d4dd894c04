#pragma once
/// @file vessel_path.hpp
/// @brief The centerline path a wire follows from an end of the network (at each junction
/// the widest continuing segment, as a wire pushed from the femoral artery follows the
/// aorta), and the curve an initially inserted wire is laid on: the path, turned back at
/// its far end when the wire is longer than it.
#include <vector>

#include "flowire/vessels/network.hpp"

namespace flowire::coupling {

class VesselPath {
 public:
  /// @brief From end node @p entry, through the widest continuing segment at each node,
  /// until an end (or a node already visited, in a loop).
  VesselPath(const vessels::Network& net, int entry);

  [[nodiscard]] double length() const { return s_.back(); }
  /// @brief Point at arc length @p s from the entry, clamped to [0, length].
  [[nodiscard]] vessels::Vec3 at(double s) const;
  /// @brief Unit tangent at arc length @p s (pointing away from the entry).
  [[nodiscard]] vessels::Vec3 tangent(double s) const;
  /// @brief Vessel radius at arc length @p s.
  [[nodiscard]] double radius(double s) const;

  /// @brief Where a wire of inserted length L has its point at arc length s: on the path
  /// up to a turn of radius 0.3·r near the far end, then back down the path beside its own
  /// shaft, offset by 0.6·r, as far as the vessel stays 0.8·r wide. Throws
  /// std::invalid_argument for s beyond max_wire_length().
  [[nodiscard]] vessels::Vec3 wire_point(double s) const;
  /// @brief Longest wire wire_point() can lay.
  [[nodiscard]] double max_wire_length() const;

 private:
  [[nodiscard]] int piece(double s) const;
  std::vector<vessels::Vec3> points_;
  std::vector<double> s_, radius_;  ///< (points) arc length; (pieces) radius of each piece
  double turn_at_ = 0.0, turn_radius_ = 0.0, return_until_ = 0.0;
  vessels::Vec3 turn_normal_ = vessels::Vec3::UnitX();
};

}  // namespace flowire::coupling
