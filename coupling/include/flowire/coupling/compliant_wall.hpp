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
  /// @brief The step's candidate contacts: their points on the rest lumen (the wall's closest
  /// points) and the lumen's outward normals there. Computes their compliance along the normals.
  virtual void anchor(std::span<const Vec3> points, std::span<const Vec3> normals) = 0;
  /// @brief C (m × m) of the anchored points [m/N]: symmetric positive definite.
  [[nodiscard]] virtual const Eigen::MatrixXd& compliance() const = 0;
  /// @brief (m, or empty: none) the anchored points' displacement along their normals before any
  /// contact force, under the wall's other loads (the blood pressure) [m].
  [[nodiscard]] virtual const Eigen::VectorXd& offsets() const = 0;
  /// @brief The blood pressure on the lumen from the network's node pressures (the flow's; the
  /// pressure along a segment interpolated between its nodes), less @p reference (the pressure
  /// at which the rest geometry was taken) [Pa]. A wall that does not take it ignores it.
  virtual void set_blood_pressure(std::span<const double> node_pressures, double reference) = 0;
  /// @brief The wall under forces @p forces at lumen points @p points (the opposites of the
  /// wire's contact forces) at the end of a step (its displacement field is solved when asked).
  virtual void load(std::span<const Vec3> points, std::span<const Vec3> forces) = 0;
  /// @brief What a run reports of the wall (summary.json's `wall`).
  [[nodiscard]] virtual nlohmann::json summary() const = 0;
  /// @brief The wall's state now (its displacement field), for an output frame.
  [[nodiscard]] virtual Eigen::VectorXd state() const = 0;
  /// @brief Write the wall in state @p state (from state()) as a VTK unstructured grid.
  virtual void write_vtu(const std::filesystem::path& path, const Eigen::VectorXd& state) const = 0;
};

}  // namespace flowire::coupling
