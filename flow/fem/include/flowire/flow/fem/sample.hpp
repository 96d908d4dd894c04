#pragma once
/// @file sample.hpp
/// @brief Evaluate a Taylor–Hood solution at arbitrary points of the curved mesh.
///
/// A uniform grid of buckets holds the tetrahedra by bounding box; a point is located by
/// the straight (vertex) barycentric coordinates, then refined by Newton iterations on
/// the quadratic map of the element, so points near the curved wall are found too.
#include <optional>
#include <tuple>
#include <vector>

#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/stokes.hpp"

namespace flowire::flow::fem {

struct PointValue {
  Vec3 velocity = Vec3::Zero();  ///< m/s (P2 interpolation)
  double pressure = 0.0;         ///< Pa (P1 interpolation)
  int tet = -1;
};

class FieldSampler {
 public:
  /// Both must outlive the sampler.
  FieldSampler(const TetMesh& mesh, const StokesSolution& solution);
  /// @brief Value at x, or nothing when x is outside the mesh (farther than
  /// `tolerance` times the element size).
  [[nodiscard]] std::optional<PointValue> at(const Vec3& x, double tolerance = 1e-8) const;
  /// @brief Tetrahedron containing x and the reference coordinates, or -1.
  [[nodiscard]] int locate(const Vec3& x, double tolerance, std::array<double, 3>& xi) const;

 private:
  const TetMesh& mesh_;
  const StokesSolution& sol_;
  Vec3 lo_, cell_;
  std::array<int, 3> dims_{};
  std::vector<int> offset_, items_;  // CSR: bucket -> tetrahedra
};

/// @brief The pressure of a cross-section: the mean over a disk of 0.95 r normal to `axis` at `c`
/// (4 equal-area rings × 12 angles, the points inside the mesh), and the value at `c`; found is
/// false when no point of the disk lies in the mesh. Returns (mean, centre, found).
std::tuple<double, double, bool> section_pressure(const FieldSampler& fs, const Vec3& c, const Vec3& axis, double r);

/// @brief The mechanical energy a section carries per unit of flow: the flux-weighted total
/// pressure ∫(p + ½ρ|u|²) u·t dA / ∫ u·t dA over a disk of radius `r` normal to `axis` at `c`
/// (8 equal-area rings × 24 angles, the points inside the mesh): the total pressure of the 1D
/// energy balance, the kinetic energy correction of the velocity profile included. Nothing where
/// no flow crosses the points found.
std::optional<double> section_total_pressure(const FieldSampler& fs, const Vec3& c, const Vec3& axis, double r,
                                             double density);

}  // namespace flowire::flow::fem
