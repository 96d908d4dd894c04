#pragma once
/// @file lumen_compliance.hpp
/// @brief The wall's compliance condensed onto points of its lumen: how far the lumen moves at
/// one point, along a direction, under a unit force at another.
///
/// About the wall's current state (ElasticSolid::linearize), the displacement under small
/// extra loads is linear: u = K⁻¹ f. A force λ along n at a lumen point p is distributed to the
/// lumen's nodes by weights w_b: at a point, the six nodes of the curved face it lies on by the
/// face's shape functions, w_b = N_b(ξ); over a patch (a disc of radius ρ about p: the footprint
/// of a wire of that radius), the shape functions' mean over the disc, w_b = (1/πρ²)∫ N_b dA, so
/// f = Σ_b w_b n λ, and the lumen's displacement at q is read with q's weights, u(q) = Σ_a w_a u_a
/// (the patch's mean). The compliance is then C_pq = Σ_a Σ_b w^q_a w^p_b m_qᵀ G_ab n_p with G_ab
/// the 3 × 3 block of K⁻¹ between nodes a and b. At a point it grows without bound as the mesh is
/// refined (a point load's displacement is singular in 3D); over a patch it converges to the
/// solid's (tests/solid: the mesh study through PETSc).
///
/// K⁻¹ is never formed. With the tangent's Cholesky factorization P K Pᵀ = L Lᵀ, a block is
/// G_ab = Y_aᵀ Y_b where Y_a = L⁻¹ P E_a (E_a: node a's three unit loads) is sparse: a forward
/// solve from a single node fills only the rows of L on its path to the elimination tree's root
/// (ElasticSolid::half_solve; on the Feel++ arch's wall about 3% of the rows, against 39 ms for a full solve of
/// three right-hand sides). Each lumen node's Y_a is solved the first time a point near it
/// asks and kept: a wire that slides along the wall pays only for the nodes it reaches. Beyond a memory budget the
/// columns used longest ago are dropped (and solved again should the wire come back). The compliance is symmetric by
/// this construction; it is positive definite where the points are distinct. The blocks G_ab among
/// the nodes of a cache's last two calls are kept: a wire that slides along the wall reaches a few
/// new nodes a step, and only their blocks are formed.
///
/// A second thread can solve columns ahead (anticipate): the nodes around where the contacts are
/// now, which the next step's footprints, a little further along, will ask for. A column is the
/// same whichever thread solves it and whatever it is solved with (ElasticSolid::half_solve), so
/// what the compliance gives does not depend on the threads' timing; only how many columns were
/// solved, and by which thread, does.
#include <Eigen/Dense>

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <unordered_map>
#include <utility>
#include <vector>

#include "flowire/solid/elastic_solid.hpp"

namespace flowire::solid {

/// @brief A point on the lumen (its face, its barycentric coordinates there, the point itself),
/// and the weights by which a force there is shared among the lumen's nodes.
struct LumenPoint {
  int face = -1;                 ///< index into the mesh's faces
  std::array<double, 3> bary{};  ///< on the face's vertices (the flat triangle's projection)
  Vec3 point = Vec3::Zero();     ///< the projected point [m]
  Vec3 normal = Vec3::UnitX();   ///< the flat face's outward normal (out of the solid: into the lumen)
  /// (mesh node, weight) summing to 1: the face's six shape functions at the point, or their mean
  /// over a patch (LumenCompliance::locate_patch)
  std::vector<std::pair<int, double>> weights;
};

class LumenCompliance {
 public:
  /// @param solid linearized (its tangent factorized); outlives this object
  /// @param lumen the boundary group the points lie on
  /// @param budget bytes the kept columns may take (those used longest ago are dropped beyond it)
  LumenCompliance(const ElasticSolid& solid, int lumen, double budget = 1024.0 * 1024.0 * 1024.0);
  ~LumenCompliance();
  LumenCompliance(const LumenCompliance&) = delete;
  LumenCompliance& operator=(const LumenCompliance&) = delete;

  /// @brief The lumen point nearest to @p x.
  [[nodiscard]] LumenPoint locate(const Vec3& x) const;
  /// @brief The lumen point nearest to @p x with the weights of a uniform pressure over the disc
  /// of radius @p radius about it in its tangent plane (each sample of the disc projected onto the
  /// lumen; rings as fine as the faces there, at least three): what a wire of that radius presses
  /// on. A radius of 0 is the point (locate).
  [[nodiscard]] LumenPoint locate_patch(const Vec3& x, double radius) const;
  /// @brief C (m × m): the displacement along @p directions[i] at @p points[i] under a unit
  /// force along @p directions[j] at @p points[j] [m/N].
  /// The blocks of K⁻¹ between the points' nodes are kept in cache @p cache (one a body whose
  /// anchorings follow each other: its next call forms only the blocks of nodes new to it).
  Eigen::MatrixXd compliance(std::span<const LumenPoint> points, std::span<const Vec3> directions, int cache = 0);
  /// @brief The displacement at each of @p points under forces @p forces at all of them [m]: what
  /// `displacement` gives, from the kept node blocks instead of a response as long as the solid.
  std::vector<Vec3> displacements(std::span<const LumenPoint> points, std::span<const Vec3> forces, int cache = 0);
  /// @brief The response to forces @p forces at @p points, in the factor's numbering (L⁻¹ P f,
  /// as long as the solid's unknowns): what `displacement` reads. Sums of responses are the
  /// responses to the summed forces.
  Eigen::VectorXd response(std::span<const LumenPoint> points, std::span<const Vec3> forces);
  /// @brief The displacement at @p at under the forces whose `response` is @p response.
  Vec3 displacement(const LumenPoint& at, const Eigen::VectorXd& response);
  /// @brief The displacement at @p at under forces @p forces at @p points.
  Vec3 displacement(const LumenPoint& at, std::span<const LumenPoint> points, std::span<const Vec3> forces) {
    return displacement(at, response(points, forces));
  }
  /// @brief A nodal field (3 a node of the solid, e.g. a displacement) at a lumen point, by the
  /// face's shape functions.
  [[nodiscard]] Vec3 interpolate(const LumenPoint& at, const Eigen::VectorXd& field) const;
  /// @brief Nodal forces (3 a node of the solid) of forces @p forces at @p points.
  [[nodiscard]] Eigen::VectorXd nodal_forces(std::span<const LumenPoint> points, std::span<const Vec3> forces) const;
  /// @brief Solve the columns the faces of @p points still lack.
  void prefetch(std::span<const LumenPoint> points);
  /// @brief Have a second thread solve, while the caller goes on, the columns of the lumen nodes on
  /// the faces within @p reach of @p points that are not solved yet; the calls that then ask for
  /// them take them solved (or wait for the few being solved). A later call replaces the nodes not
  /// begun. Nothing is done where the process may run on one core only. The solid must not be factorized again
  /// before `clear` (which waits for the thread).
  void anticipate(std::span<const Vec3> points, double reach);
  /// @brief Wait until the second thread has solved what it was last asked for.
  void wait_anticipated();
  /// @brief The lumen nodes on the faces within @p reach of @p points, in the points' order.
  [[nodiscard]] std::vector<int> nodes_near(std::span<const Vec3> points, double reach) const;
  /// @brief Columns solved so far (a lumen node's, three forward solves, each time it was
  /// solved), and those dropped to keep within the budget.
  [[nodiscard]] int solved_nodes() const { return solved_ + anticipated_nodes(); }
  [[nodiscard]] int dropped_nodes() const { return dropped_; }
  /// @brief Of the columns solved, those the second thread solved (anticipate).
  [[nodiscard]] int anticipated_nodes() const;
  /// @brief The second thread's time solving them and forming their blocks [s].
  [[nodiscard]] double anticipated_seconds() const;
  /// @brief Bytes the kept columns take.
  [[nodiscard]] size_t kept_bytes() const { return kept_bytes_; }
  /// @brief Forget the kept columns, and stop the second thread's (before the solid is factorized
  /// again, and after).
  void clear();
  /// @brief How `compliance` is formed: from the kept node blocks, as C = Zᵀ Z, or (the default) the
  /// way the operation counts favour for each cache. Both are exact.
  enum class Way { automatic, blocks, columns };
  void set_way(Way way) { way_ = way; }
  /// @brief The 3 × 3 blocks G_ab = Y_aᵀ Y_b that `compliance` formed on the caller's thread (not
  /// kept from its last call, nor formed ahead).
  [[nodiscard]] std::uint64_t block_products() const { return block_products_; }

 private:
  /// Node @p node's Y (L⁻¹ P times its three unit loads), solved by prefetch.
  using NodeColumns = HalfColumns;
  [[nodiscard]] const NodeColumns& column(int node) const { return *columns_.at(node); }
  /// @p near ← the lumen faces (indices into faces_) whose closest point to @p x is within @p r.
  void faces_within(const Vec3& x, double r, std::vector<int>& near) const;
  /// @p best ← lumen face k (index into faces_) if its closest point to @p x is nearer than @p best_d2.
  void closer(const Vec3& x, int k, LumenPoint& best, double& best_d2) const;
  /// @p p's normal: its flat face's.
  void set_normal(LumenPoint& p) const;
  /// @p p's weights: its face's six shape functions at its barycentric coordinates.
  void shape_weights(LumenPoint& p) const;
  const ElasticSolid& solid_;
  std::vector<int> faces_;               ///< the lumen's faces
  std::vector<Vec3> face_lo_, face_hi_;  ///< (by faces_) the bounding box of each one's corners
  /// (shared: the second thread reads the kept columns it forms blocks with, whatever the caller drops)
  std::unordered_map<int, std::shared_ptr<const NodeColumns>> columns_;
  /// Blocks G_ab = Y_aᵀ Y_b the second thread formed (key a·2³² + b), taken with its columns.
  std::unordered_map<std::uint64_t, Mat3> pair_blocks_;
  /// G_ab from pair_blocks_ (or its transpose from G_ba's), else formed here.
  Mat3 block_between(int a, int b);
  std::unordered_map<int, std::uint64_t> last_use_;  ///< per kept column, the prefetch that last asked
  std::uint64_t tick_ = 0;
  double budget_ = 0.0;    ///< bytes
  size_t kept_bytes_ = 0;  ///< bytes the kept columns take
  int solved_ = 0, dropped_ = 0;
  /// Blocks G_ab = Y_aᵀ Y_b kept among the nodes of a cache's last two calls: their nodes (in g's
  /// order), each mesh node's place among them (−1: none), the nodes of the last call.
  struct Blocks {
    std::vector<int> nodes, slot, last_call;
    Eigen::MatrixXd g;
    int calls = 0;             ///< compliance calls made with this cache
    bool by_blocks = true;     ///< the way its compliance is formed (by_blocks)
    double mean_fresh = -1.0;  ///< nodes new to a call, averaged over its calls
  };
  /// Whether cache @p cache's compliance at @p points is formed from its blocks (else as C = Zᵀ Z),
  /// by the operation counts of both ways with the nodes new to a call averaged over its calls.
  bool by_blocks(std::span<const LumenPoint> points, int cache);
  /// The compliance as C = Zᵀ Z (the points' forces forward-solved, summed from their nodes' columns).
  Eigen::MatrixXd compliance_by_columns(std::span<const LumenPoint> points, std::span<const Vec3> directions);
  /// compliance_by_columns's workspace, kept across calls: each mesh node's place among a call's
  /// distinct nodes and each row's among its rows (−1 between calls), the (point, w d) uses grouped
  /// by node, Zᵀ, and the rows' places and weights of one node.
  struct Use {
    int node;
    Eigen::Index point;
    Vec3 weight;
  };
  std::vector<int> node_slot_, row_slot_;
  std::vector<Use> uses_;
  std::vector<double> zt_, node_weights_;
  std::vector<int> node_rows_;
  /// Cache @p cache (made on first use).
  Blocks& cache_at(int cache);
  /// Cache @p cache's blocks among @p points' nodes (their columns solved) and its last call's,
  /// formed where not kept.
  Blocks& form_blocks(std::span<const LumenPoint> points, int cache);
  std::vector<Blocks> blocks_;  ///< by cache
  Way way_ = Way::automatic;
  std::vector<char> mark_;  ///< per mesh node (0 between calls)
  std::uint64_t block_products_ = 0;
  /// The second thread of `anticipate` and what it hands over (made on first use).
  struct Ahead;
  std::unique_ptr<Ahead> ahead_;
  /// Solve the columns of nodes @p fresh on this thread.
  void solve_columns(const std::vector<int>& fresh);
  /// Keep column @p y as node @p node's.
  void keep(int node, std::shared_ptr<const HalfColumns> y);
  /// Take what the second thread has solved and formed (its lock held).
  void take_ready();
  // A uniform grid of the lumen faces' bounding boxes for `locate`.
  Vec3 grid_origin_ = Vec3::Zero();
  double cell_ = 1.0;
  std::array<int, 3> dims_{1, 1, 1};
  std::vector<std::vector<int>> cells_;
};

}  // namespace flowire::solid
