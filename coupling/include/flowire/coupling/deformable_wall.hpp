#pragma once
/// @file deformable_wall.hpp
/// @brief The vessel wall as an elastic solid the wire pushes (the scene's `wall:` section).
///
/// The wall (solid/: neo-Hookean, 10-node tetrahedra, ends held, an elastic support on its
/// outer surface) is linearized about its rest state, and its compliance is condensed onto the
/// lumen points the wire may touch in a step (solid::LumenCompliance). The contact law
/// (wall_contact.hpp) then solves, at every Newton iterate, for the normal forces λ ≥ 0 of the
/// step's candidate contacts with the wall's displacement under all of them,
/// λ = k·max(0, δ − C λ), δ the penetration into the rest wall: the wire meets the wall where
/// the wall has moved to, implicitly, and the rod's Newton gets the coupled stiffness
/// (K⁻¹ + C)⁻¹ of the contacts exactly (a low-rank term off its band). At the end of a step
/// the wire's contact forces, normal and friction, load the wall with their opposites (Newton's
/// third law) and the wall's displacement field is solved for the outputs.
/// The wall is built around the lumen the wire's contact sees: a network's capsules
/// (solid::mesh_network_wall) or an image's lumen surface (solid::mesh_surface_wall), every end held; the contact sees
/// the wall's displacement along its normal (the wall's tangential motion is not seen).
#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "flowire/coupling/compliant_wall.hpp"
#include "flowire/coupling/interaction.hpp"
#include "flowire/mesh/tet_mesh.hpp"
#include "flowire/solid/wall_thickness.hpp"
#include "flowire/vessels/network.hpp"
#include "flowire/vessels/surface.hpp"

namespace flowire::solid {
class ElasticSolid;
class LumenCompliance;
struct LumenPoint;
}  // namespace flowire::solid

namespace flowire::coupling {

/// @brief The wall's material, size and support.
struct WallSpec {
  double thickness = 0.0;        ///< [m]; 0: thickness_ratio × the local radius
  double thickness_ratio = 0.0;  ///< used where thickness is 0
  double youngs_modulus = 0.0;   ///< [Pa]
  double poisson_ratio = 0.45;
  double support = 0.0;    ///< elastic support of the outer surface [Pa/m]
  double mesh_size = 0.0;  ///< target tetrahedron size [m]; around a surface, 0: twice the local thickness
  /// (branch index, Young's modulus [Pa]) of branches whose wall differs from youngs_modulus: each
  /// tetrahedron takes the modulus of the branch of the segment nearest its centroid
  std::vector<std::pair<int, double>> branch_youngs_modulus;
  /// branches whose wall is thicker or thinner than the rest's (their own thickness or ratio)
  std::vector<solid::BranchThickness> branch_thickness;
  /// The wall is solved (nonlinear) and linearized again about its loaded state once a loaded
  /// lumen point has moved this fraction of its local thickness from where the last
  /// linearization left it; 0: linear about rest throughout.
  double relinearize = 0.0;
  /// @brief The nominal thickness of branch @p branch's wall where its lumen radius is @p radius.
  [[nodiscard]] double thickness_at(int branch, double radius) const {
    return solid::wall_thickness_at(thickness, thickness_ratio, branch_thickness, branch, radius);
  }
};

class DeformableWall final : public CompliantWall {
 public:
  /// @brief The wall around the lumen of @p net (its capsules), or around @p surface (a scene's
  /// `vessels.surface`: solid::mesh_surface_wall, its ends named by @p net's), every end held.
  /// @throws flowire::Error (usage) for a non-positive size, thickness or modulus, a ratio
  /// ν ∉ (−1, 0.5); (input) for a network a tube cannot be built along, a surface no wall can
  /// be grown around (naming the file and the place).
  DeformableWall(const vessels::Network& net, const WallSpec& spec, const vessels::LumenSurface* surface = nullptr);
  /// @brief The wall of the straight vessel from @p p0 to @p p1 of lumen radius @p radius.
  DeformableWall(const Vec3& p0, const Vec3& p1, double radius, const WallSpec& spec);
  ~DeformableWall() override;
  DeformableWall(const DeformableWall&) = delete;
  DeformableWall& operator=(const DeformableWall&) = delete;

  /// @brief Body @p body's candidate contacts: their compliance along the normals, and the
  /// normal displacement there of the blood pressure and of the other bodies' last loads.
  Anchored anchor(const void* body, std::span<const Vec3> points, std::span<const Vec3> normals,
                  std::span<const double> radii = {}) override;
  /// @brief The blood pressure as a dead load on the lumen (linear about the wall's state: the
  /// lumen's response to each unit node pressure solved once a linearization, read at the
  /// contacts' nodes as the pressures change), which the contacts meet and the outputs add.
  void set_blood_pressure(std::span<const double> node_pressures, double reference) override;
  /// @brief The mean radial displacement of each segment's lumen vertices about its axis, by
  /// reciprocity: ū_s = w_sᵀ K⁻¹ f = (K⁻¹ w_s)ᵀ f with w_s the mean over the segment's lumen
  /// vertices of their radial directions, K⁻¹ W solved once (one back-substitution of as many
  /// columns as segments) and kept; a call is then a product with the load's nonzero entries and
  /// with the pressure's (K⁻¹W)ᵀB. A segment without lumen vertices of its own (shorter than the
  /// wall's elements) takes the mean of its neighbours'.
  [[nodiscard]] std::vector<double> segment_widening() override;
  /// @brief Body @p body's forces on the wall (its contact forces' opposites), replacing its last
  /// ones: with every other body's, the wall's load (displacement field, total load). Where a
  /// loaded point has moved more than WallSpec::relinearize of its local thickness since the last
  /// linearization, the wall is solved under its loads (neo-Hookean, Newton) and linearized there.
  void load(const void* body, std::span<const Vec3> points, std::span<const Vec3> forces,
            std::span<const double> radii = {}) override;
  /// @brief The solid's mesh in the scene's frame, and its displacement (3 a node) [m] under
  /// the last load (solved on first request after a load: one back-substitution).
  [[nodiscard]] const mesh::TetMesh& mesh() const;
  [[nodiscard]] const Eigen::VectorXd& displacement() const;
  [[nodiscard]] double max_displacement() const;
  /// @brief Sum of the forces on the wall at the last load [N].
  [[nodiscard]] const Vec3& load_total() const { return load_total_; }
  /// @brief Lumen nodes whose compliance columns were solved, and the seconds spent on the
  /// wall (mesh, factorization, columns, loads).
  [[nodiscard]] int compliance_columns() const;
  [[nodiscard]] double seconds() const { return seconds_; }
  [[nodiscard]] double mesh_seconds() const { return mesh_seconds_; }
  /// @brief The wall's least thickness [m] (around a surface, after thinning for room).
  [[nodiscard]] double thinnest() const { return thinnest_; }
  /// @brief Solve the wall under its current loads (the bodies' and the blood pressure, dead
  /// loads) from the linear estimate, and linearize it there: its displacement is then
  /// u = u_b + K_b⁻¹(f − f_b) about that state. @throws flowire::Error (numerical) when the
  /// solid cannot carry the loads (an element would invert, Newton fails).
  void relinearize();
  /// @brief How many times the wall was linearized again about a loaded state.
  [[nodiscard]] int relinearizations() const { return relinearizations_; }
  /// @brief Load increments the linearizations that could not reach their loads in one go took.
  [[nodiscard]] int relinearize_load_increments() const { return load_increments_; }
  /// @brief Largest displacement, ever and now (and whether it went beyond the wall's thickness,
  /// the linear wall's range: warned once), the load now, columns solved, seconds.
  [[nodiscard]] nlohmann::json summary() const override;
  [[nodiscard]] Eigen::VectorXd state() const override { return displacement(); }
  /// @brief The 10-node tetrahedra (VTK_QUADRATIC_TETRA) with point data `displacement` [m],
  /// `displacement_magnitude` [m], `stress` (the Cauchy stress, 9 components) [Pa] and
  /// `von_mises_stress` [Pa]; warp by the vector to see the deformed wall.
  void write_vtu(const std::filesystem::path& path, const Eigen::VectorXd& state) const override;

 private:
  /// How far beyond a footprint the columns a next step may ask for are solved ahead [m].
  static constexpr double kAnticipation = 1e-3;
  /// Solve ahead the columns about @p points (a body's anchored points or loads, of @p radii).
  void anticipate(std::span<const Vec3> points, std::span<const double> radii);
  std::unique_ptr<solid::ElasticSolid> solid_;
  std::unique_ptr<solid::LumenCompliance> lumen_;
  /// Each body's last forces on the wall: where (on the lumen) and how much.
  struct BodyLoad {
    std::vector<solid::LumenPoint> points;
    std::vector<Vec3> forces;
    Vec3 total = Vec3::Zero();
    Eigen::VectorXd
        response;  ///< the forces' response (LumenCompliance::response) about the current tangent; empty until asked
  };
  /// @p l's response, formed on first use (another body's anchoring reads it).
  const Eigen::VectorXd& response(BodyLoad& l);
  std::vector<std::pair<const void*, std::unique_ptr<BodyLoad>>> loads_;
  std::vector<const void*> cache_bodies_;  ///< body k's anchorings keep their blocks in cache k + 1
  Eigen::MatrixXd pressure_response_;      ///< (3 lumen nodes × network nodes) K⁻¹B on the lumen
  std::vector<int> lumen_nodes_;
  std::vector<double> node_pressures_;  ///< the last pressures set (to skip unchanged ones)
  double reference_pressure_ = 0.0;
  vessels::Network net_;                        ///< for the pressure along the lumen
  Eigen::SparseMatrix<double> pressure_basis_;  ///< nodal forces per unit network-node pressure
  std::vector<int> lumen_row_;                  ///< (nodes) a lumen node's place in pressure_response_, −1 elsewhere
  /// Solve the displacement field of the last load if not yet done.
  void solve_field() const;
  Eigen::VectorXd load_;        ///< nodal forces of the last load
  std::vector<int> load_dofs_;  ///< the components load_ may be nonzero at (the loaded points' nodes)
  mutable Eigen::VectorXd displacement_;
  mutable bool field_current_ = true;
  Vec3 load_total_ = Vec3::Zero();
  mutable double max_displacement_ = 0.0, max_ever_ = 0.0, seconds_ = 0.0;
  mutable double max_ratio_ever_ = 0.0;                  ///< the largest lumen displacement over the local thickness
  std::vector<std::pair<int, double>> local_thickness_;  ///< (lumen vertices) node, the wall's thickness there [m]
  /// Each lumen vertex's thickness: the distance to the outer surface's nearest vertex.
  void measure_thickness();
  /// The solid's laws per tetrahedron from spec.branch_youngs_modulus.
  void assign_branch_laws(const WallSpec& spec);
  double thinnest_ = 0.0;              ///< the wall's least thickness [m]
  mutable bool warned_range_ = false;  ///< a run beyond the linear range said so once
  double mesh_seconds_ = 0.0;
  nlohmann::json lumen_facts_;  ///< what the wall was grown around (summary)
  /// (dofs × segments) K⁻¹W, empty until first asked; by rows (a load's dof reads its row)
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> widening_;
  Eigen::MatrixXd widening_pressure_;  ///< (segments × network nodes) (K⁻¹W)ᵀB
  std::vector<char> segment_has_nodes_;
  Eigen::VectorXd last_pressure_;  ///< the network-node pressures less the reference of the last set
  /// (lumen nodes) each node's displacement under the last pressure, valid where its stamp is
  /// the generation (counted up at each new pressure and each new response)
  mutable std::vector<Vec3> pressure_node_u_;
  mutable std::vector<std::uint64_t> pressure_node_stamp_;
  std::uint64_t pressure_generation_ = 1;
  // The state the wall is linear about (rest until relinearize): u = base_ + K_b⁻¹ f with
  // base_ = u_b − K_b⁻¹ f_b (0 at rest), f the loads (bodies' and pressure's nodal forces).
  Eigen::VectorXd base_;                ///< (3 a node) u_b − K_b⁻¹ f_b
  Eigen::VectorXd base_u_;              ///< (3 a node) u_b
  Eigen::VectorXd base_load_;           ///< (3 a node) f_b
  Eigen::SparseMatrix<double> radial_;  ///< (dofs × segments) W, each segment's mean radial direction
  Eigen::VectorXd base_widening_;       ///< (segments) Wᵀ base_
  std::vector<double> node_thickness_;  ///< (nodes) the lumen's local thickness, 0 elsewhere
  double relinearize_ = 0.0;            ///< WallSpec::relinearize
  int relinearizations_ = 0;
  int load_increments_ = 0;  ///< increments of relinearizations that took more than one
  double relinearize_seconds_ = 0.0;
  mutable double max_increment_ratio_ = 0.0;  ///< largest |u − u_b| over the local thickness
  /// Whether a loaded point moved beyond the relinearize fraction of its thickness from u_b.
  bool moved_beyond_linearization();
  /// The lumen's response to the blood pressure (K_b⁻¹B on the lumen's nodes) and its field.
  void solve_pressure_response();
  /// The lumen's displacement at @p at under the last blood pressure (pressure_response_).
  [[nodiscard]] Vec3 pressure_displacement(const solid::LumenPoint& at) const;
  /// The largest displacement of a lumen node under the last blood pressure [m].
  [[nodiscard]] double max_pressure_displacement() const;
};

}  // namespace flowire::coupling
