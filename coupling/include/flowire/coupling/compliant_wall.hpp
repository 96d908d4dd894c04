#pragma once
/// @file compliant_wall.hpp
/// @brief What the wall contact needs of a wall that yields: the compliance between the
/// points the wire may touch in a step, and the wire's forces at the end of it.
/// Implemented by DeformableWall (deformable_wall.hpp: an elastic solid, built with gmsh).
#include <Eigen/Dense>

#include <span>

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
  /// @brief The wall under forces @p forces at lumen points @p points (the opposites of the
  /// wire's contact forces) at the end of a step.
  virtual void load(std::span<const Vec3> points, std::span<const Vec3> forces) = 0;
  /// @brief The largest displacement of the wall so far [m] (sizes the candidates' reach).
  [[nodiscard]] virtual double max_displacement_ever() const = 0;
};

}  // namespace flowire::coupling
