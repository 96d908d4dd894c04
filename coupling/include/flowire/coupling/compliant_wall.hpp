#pragma once
/// @file compliant_wall.hpp
/// @brief What the wall contact needs of a wall that yields: the compliance between the
/// points the wire may touch in a step, and the wire's forces at the end of it.
/// Implemented by DeformableWall (deformable_wall.hpp: an elastic solid, built with gmsh).
#include <Eigen/Dense>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>
#include <vector>

#include "flowire/coupling/interaction.hpp"

namespace flowire::coupling {

class CompliantWall {
 public:
  virtual ~CompliantWall() = default;
  /// @brief What one body's contact condenses of the wall for a step: the compliance between
  /// its anchored points, and their normal displacement before its own forces act [m].
  struct Anchored {
    Eigen::MatrixXd compliance;  ///< C (m × m) [m/N], symmetric positive definite
    /// (m) along each normal: the blood pressure's displacement plus that of the other bodies'
    /// last forces on the wall (a catheter's under the wire's, and the converse), held for the step.
    Eigen::VectorXd offsets;
  };
  /// @brief The step's candidate contacts of body @p body (a wire, a catheter: any stable
  /// identity): their points on the rest lumen (the wall's closest points), the lumen's outward
  /// normals there, and the radius of the body at each (its force presses on a disc of that
  /// radius, whose mean displacement the compliance gives; none or 0: a point).
  virtual Anchored anchor(const void* body, std::span<const Vec3> points, std::span<const Vec3> normals,
                          std::span<const double> radii = {}) = 0;
  /// @brief The forces @p forces at lumen points @p points that body @p body puts on the wall (the
  /// opposites of its contact forces), each over a disc of its @p radii as anchor's, at the end of
  /// a step: they replace that body's last ones, and the wall carries every body's (its
  /// displacement field is solved when asked).
  virtual void load(const void* body, std::span<const Vec3> points, std::span<const Vec3> forces,
                    std::span<const double> radii = {}) = 0;
  /// @brief The blood pressure on the lumen from the network's node pressures (the flow's; the
  /// pressure along a segment interpolated between its nodes), less @p reference (the pressure
  /// at which the rest geometry was taken) [Pa]. A wall that does not take it ignores it.
  virtual void set_blood_pressure(std::span<const double> node_pressures, double reference) = 0;
  /// @brief Each network segment's widening [m]: the mean radial displacement of the lumen about
  /// the segment's axis under the wall's load now (the blood pressure and every body's forces).
  /// Empty for a wall that does not know the network's segments.
  [[nodiscard]] virtual std::vector<double> segment_widening() { return {}; }
  /// @brief What a run reports of the wall (summary.json's `wall`).
  [[nodiscard]] virtual nlohmann::json summary() const = 0;
  /// @brief The wall's state now (its displacement field), for an output frame.
  [[nodiscard]] virtual Eigen::VectorXd state() const = 0;
  /// @brief Write the wall in state @p state (from state()) as a VTK unstructured grid.
  virtual void write_vtu(const std::filesystem::path& path, const Eigen::VectorXd& state) const = 0;
};

}  // namespace flowire::coupling
