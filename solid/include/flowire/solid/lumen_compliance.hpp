#pragma once
/// @file lumen_compliance.hpp
/// @brief The wall's compliance condensed onto points of its lumen: how far the lumen moves at
/// one point, along a direction, under a unit force at another.
///
/// About the wall's current state (ElasticSolid::linearize), the displacement under small
/// extra loads is linear: u = K⁻¹ f. A force λ along n at a lumen point p is distributed to the
/// six nodes of the curved face it lies on by the face's shape functions, f = Σ_b N_b(ξ) n λ,
/// and the lumen's displacement at another point q is read the same way, u(q) = Σ_a N_a(ζ) u_a.
/// The compliance between points is then C_pq = Σ_a Σ_b N_a(ζ) N_b(ξ) m_qᵀ G_ab n_p with G_ab
/// the 3 × 3 block of K⁻¹ between nodes a and b. Columns of K⁻¹ are solved per lumen node
/// (three right-hand sides, one back-substitution with the kept factorization) the first time a
/// point near that node asks, and kept restricted to the lumen's nodes: a wire that slides
/// along the wall pays only for the nodes it reaches. By Maxwell–Betti C is symmetric, and it is
/// positive definite where the points are distinct.
#include <Eigen/Dense>

#include <array>
#include <span>
#include <unordered_map>
#include <vector>

#include "flowire/solid/elastic_solid.hpp"

namespace flowire::solid {

/// @brief A point on the lumen: its face, its barycentric coordinates there, the point itself.
struct LumenPoint {
  int face = -1;                 ///< index into the mesh's faces
  std::array<double, 3> bary{};  ///< on the face's vertices (the flat triangle's projection)
  Vec3 point = Vec3::Zero();     ///< the projected point [m]
  Vec3 normal = Vec3::UnitX();   ///< the flat face's outward normal (out of the solid: into the lumen)
};

class LumenCompliance {
 public:
  /// @param solid linearized (its tangent factorized); outlives this object
  /// @param lumen the boundary group the points lie on
  LumenCompliance(const ElasticSolid& solid, int lumen);

  /// @brief The lumen point nearest to @p x.
  [[nodiscard]] LumenPoint locate(const Vec3& x) const;
  /// @brief C (m × m): the displacement along @p directions[i] at @p points[i] under a unit
  /// force along @p directions[j] at @p points[j] [m/N].
  Eigen::MatrixXd compliance(std::span<const LumenPoint> points, std::span<const Vec3> directions);
  /// @brief The displacement at @p at under forces @p forces at @p points (the kept columns;
  /// those the points' faces still lack solved first).
  Vec3 displacement(const LumenPoint& at, std::span<const LumenPoint> points, std::span<const Vec3> forces);
  /// @brief A nodal field (3 a node of the solid, e.g. a displacement) at a lumen point, by the
  /// face's shape functions.
  [[nodiscard]] Vec3 interpolate(const LumenPoint& at, const Eigen::VectorXd& field) const;
  /// @brief Nodal forces (3 a node of the solid) of forces @p forces at @p points.
  [[nodiscard]] Eigen::VectorXd nodal_forces(std::span<const LumenPoint> points, std::span<const Vec3> forces) const;
  /// @brief Solve the columns the faces of @p points still lack, many at a time.
  void prefetch(std::span<const LumenPoint> points);
  /// @brief Lumen nodes whose columns have been solved so far.
  [[nodiscard]] int solved_nodes() const { return static_cast<int>(columns_.size()); }
  /// @brief Forget the kept columns (after the solid was linearized again).
  void clear() { columns_.clear(); }

 private:
  /// Shape function weights of the face's six nodes at a point.
  [[nodiscard]] std::array<double, 6> weights(const LumenPoint& p) const;
  /// The kept column block of lumen node `node` (solved by prefetch): (3 × lumen nodes) × 3.
  [[nodiscard]] const Eigen::MatrixXd& column(int node) const;

  const ElasticSolid& solid_;
  std::vector<int> faces_;        ///< the lumen's faces
  std::vector<int> lumen_index_;  ///< (nodes) index among the lumen's nodes, −1 elsewhere
  std::vector<int> lumen_nodes_;  ///< the lumen's nodes
  std::unordered_map<int, Eigen::MatrixXd> columns_;
  // A uniform grid of the lumen faces' bounding boxes for `locate`.
  Vec3 grid_origin_ = Vec3::Zero();
  double cell_ = 1.0;
  std::array<int, 3> dims_{1, 1, 1};
  std::vector<std::vector<int>> cells_;
};

}  // namespace flowire::solid
