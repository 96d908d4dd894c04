#pragma once
/// @file elastic_solid.hpp
/// @brief A hyperelastic solid on a quadratic tetrahedral mesh: the vessel wall.
///
/// Total Lagrangian: the unknowns are the displacements u of the mesh's nodes (3 a node), the
/// deformation gradient \f$ F = I + \sum_k u_k \otimes \nabla_X N_k \f$ of the 10-node
/// tetrahedra, integrated with the 4-point degree-2 rule. The total potential is
/// \f[ \Pi(u) = \int_\Omega W(F)\,dV + \tfrac12 \int_{\Gamma_s} k\,|u|^2 dA
///     - \int_{\Gamma_p} (-p\,N)\cdot u\,dA - f\cdot u, \f]
/// a neo-Hookean W, an elastic support k (surrounding tissue; Pa/m) on chosen boundary groups,
/// a pressure p on others acting on the reference faces (dead load; N the outward normal of the
/// solid, so a lumen's pressure pushes the wall outwards), and nodal forces f. Chosen
/// displacement components of chosen groups are held at zero. `solve` finds the equilibrium
/// \f$ \nabla\Pi = 0 \f$ by Newton with CHOLMOD's Cholesky factorization, the tangent's pattern
/// analysed once, and a backtracking search that never accepts an inverted element.
/// The solid knows nothing of wires or blood: every load reaches it as a pressure or a force.
#include <Eigen/Sparse>

#include <array>
#include <functional>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "flowire/mesh/tet_mesh.hpp"
#include "flowire/solid/neo_hookean.hpp"

namespace flowire::solid {

using vessels::Vec3;

/// @brief When `solve` stops.
struct SolveOptions {
  double tolerance = 1e-10;  ///< |∇Π| ≤ tolerance × max(|loads|, |∇Π at the start|)
  int max_iterations = 50;
  /// Keep the last iteration's factorized tangent for `tangent_solve` (as `linearize` would, at the
  /// iterate before the last: within the tolerance's square of the tangent at the solution).
  bool keep_tangent = false;
};

/// @brief What `solve` did.
struct SolveReport {
  int iterations = 0;
  double residual = 0.0;  ///< |∇Π| (N) over the free components at the end
  bool converged = false;
};

/// @brief Up to three sparse vectors sharing one pattern, in the numbering of the tangent's factor:
/// what `half_solve` returns.
struct HalfColumns {
  std::vector<int> index;     ///< rows of L, ascending
  std::vector<double> value;  ///< 3 a row: column c of row index[k] at 3k + c
  [[nodiscard]] size_t size() const { return index.size(); }
};

/// @brief Room for `half_solve`'s work: a thread that solves while another does needs its own.
struct HalfSolveWork {
  /// per supernode, the first column a solve reaches (INT_MAX: none); the supernodes reached; the
  /// loads' rows; the right-hand sides (row by row, room for 3 × kHalfSolveBatch a row, zero between
  /// calls); one supernode's rows gathered (one contiguous run a right-hand side)
  std::vector<int> entry, touched, starts;
  std::vector<double> x, gathered;
};

/// @brief The wall as an elastic solid.
class ElasticSolid {
 public:
  ElasticSolid(mesh::TetMesh mesh, NeoHookean law);
  ~ElasticSolid();
  ElasticSolid(ElasticSolid&&) noexcept;
  ElasticSolid& operator=(ElasticSolid&&) noexcept;

  [[nodiscard]] const mesh::TetMesh& mesh() const { return mesh_; }
  /// @brief The law every tetrahedron has unless set_laws gave it another.
  [[nodiscard]] const NeoHookean& law() const { return laws_.front(); }
  /// @brief Tetrahedron @p t's law.
  [[nodiscard]] const NeoHookean& law_of(int t) const {
    return laws_[tet_law_.empty() ? 0 : static_cast<size_t>(tet_law_[static_cast<size_t>(t)])];
  }
  /// @brief Laws per tetrahedron: tetrahedron t has @p laws[@p tet_law[t]] (a wall whose vessels
  /// differ in stiffness). The first law stays law(). Before linearize/solve.
  /// @throws flowire::Error (usage) for a law without μ > 0 and a positive bulk modulus, or
  /// indices that are not one per tetrahedron into @p laws.
  void set_laws(std::vector<NeoHookean> laws, std::vector<int> tet_law);
  [[nodiscard]] int num_dofs() const { return 3 * mesh_.num_nodes(); }

  /// @brief Hold the chosen displacement components of every node of boundary group `group` at 0.
  void hold(int group, std::array<bool, 3> components = {true, true, true});
  /// @brief An elastic support on `group`: traction −k u, k in Pa/m (added to any before).
  void support(int group, double stiffness_per_area);
  /// @brief A pressure p (Pa) on `group`'s reference faces, against their outward normal
  /// (replaces the group's previous pressure).
  void set_pressure(int group, double pressure);
  /// @brief A pressure field p(X) (Pa) over `group`'s reference faces (the blood pressure
  /// along a vessel, a band load), integrated with the 6-point rule on each curved face.
  void set_pressure(int group, std::function<double(const Vec3&)> pressure);
  /// @brief The nodal forces (N, 3 a node) of a pressure on `group`'s reference faces that is a
  /// linear combination of `fields` basis pressures, p(X) = Σ_k w_k(X) p_k: the matrix B
  /// (3 nodes × fields) with f = B p. @p weights(X, out) lists the (k, w_k(X)) at X. For a load
  /// that changes often (the blood pressure of a pulsatile flow): one pass over the faces, then a
  /// product per change.
  [[nodiscard]] Eigen::SparseMatrix<double> pressure_basis(
      int group, int fields,
      const std::function<void(const Vec3&, std::vector<std::pair<int, double>>&)>& weights) const;
  /// @brief Nodal forces (N), 3 a node, added to the pressure loads; zero until set.
  [[nodiscard]] Eigen::VectorXd& nodal_forces() { return nodal_forces_; }

  /// @brief The Cauchy stress σ = P Fᵀ / J at every node under displacement @p u (3 a node),
  /// the mean over the tetrahedra that share the node of each one's stress there [Pa].
  [[nodiscard]] std::vector<Mat3> nodal_stress(const Eigen::VectorXd& u) const;
  /// @brief Π(u); +∞ when an element is inverted at a quadrature point.
  [[nodiscard]] double energy(const Eigen::VectorXd& u) const;
  /// @brief ∇Π(u) (every component, held ones included).
  [[nodiscard]] Eigen::VectorXd gradient(const Eigen::VectorXd& u) const;
  /// @brief ∇²Π(u), symmetric, full pattern (held components included).
  [[nodiscard]] Eigen::SparseMatrix<double> hessian(const Eigen::VectorXd& u) const;
  /// @brief All loads: pressures and nodal forces (N), 3 a node.
  [[nodiscard]] Eigen::VectorXd loads() const { return pressure_forces_ + nodal_forces_; }
  /// @brief True for a held component.
  [[nodiscard]] bool held(int dof) const { return held_[static_cast<size_t>(dof)] != 0; }

  /// @brief Equilibrium from the current displacement under the current loads.
  /// @throws flowire::Error (numerical) when an element would have to be inverted or the
  /// tangent cannot be factorized.
  SolveReport solve(const SolveOptions& options = {});
  /// @brief Factorize the tangent ∇²Π at the current displacement (held rows and columns as
  /// the identity) for `tangent_solve`: the wall's linear response about its current state.
  /// @throws flowire::Error (numerical) when it is not positive definite.
  void linearize();
  /// @brief x ← (∇²Π)⁻¹ x, column by column, with the factorization of the last `linearize`
  /// (held components of x are zeroed first and stay zero).
  void tangent_solve(Eigen::MatrixXd& x) const;
  /// @brief Y = L⁻¹ P B for up to three sparse loads @p loads (the columns of B: dof, value; held
  /// components dropped), where P K Pᵀ = L Lᵀ is the Cholesky factorization of the last
  /// `linearize`: then bᵀ K⁻¹ c = (L⁻¹ P b)ᵀ (L⁻¹ P c) for any two loads. Only the columns of L
  /// the loads reach (the ancestors of their rows in the elimination tree) are touched, a few per
  /// cent of a full solve for a node of the lumen, on CHOLMOD's supernodal factor (the tail of
  /// each supernode on the loads' paths to the root, dense).
  void half_solve(std::span<const std::vector<std::pair<int, double>>> loads, HalfColumns& y) const;
  /// @brief The same for up to kHalfSolveBatch results at once, three loads each (loads 3k, 3k + 1,
  /// 3k + 2 give y[k]): the columns of L their reaches share are read once for all (the top
  /// separators, which every lumen node's reach ends in). Each y[k] holds the rows its own loads
  /// reach.
  void half_solve(std::span<const std::vector<std::pair<int, double>>> loads, std::span<HalfColumns> y) const;
  /// @brief The same in workspace @p work: calls with distinct workspaces may run at the same time
  /// (they only read the factor) once `prepare_half_solve` has run after the last factorization, and
  /// while nothing factorizes. Each right-hand side's values do not depend on the others it is
  /// solved with (its supernodes' columns are taken in the same blocks whatever the batch).
  void half_solve(std::span<const std::vector<std::pair<int, double>>> loads, std::span<HalfColumns> y,
                  HalfSolveWork& work) const;
  /// @brief Make the maps half_solve walks the factor by (once a factorization).
  void prepare_half_solve() const;
  static constexpr size_t kHalfSolveBatch = 8;
  /// @brief Whether `tangent_solve` has a tangent (a `linearize`, or a `solve` that kept its own).
  [[nodiscard]] bool linearized() const { return linearized_; }
  [[nodiscard]] const Eigen::VectorXd& displacement() const { return u_; }
  void set_displacement(const Eigen::VectorXd& u);
  [[nodiscard]] Vec3 displacement(int node) const { return u_.segment<3>(3 * node); }

 private:
  struct Factor;
  void assemble_hessian(const Eigen::VectorXd& u, Eigen::SparseMatrix<double>& h) const;
  /// Factorize the tangent at u with held rows and columns as the identity; false if not SPD.
  bool factorize_tangent(const Eigen::VectorXd& u);
  double elastic_energy(const Eigen::VectorXd& u) const;

  mesh::TetMesh mesh_;
  std::vector<NeoHookean> laws_;         ///< [0] the solid's law
  std::vector<int> tet_law_;             ///< (tets) index into laws_; empty: all the first
  std::vector<double> geometry_;         ///< per tet and quadrature point: ∇_X N (10×3) and weight·det J
  Eigen::SparseMatrix<double> pattern_;  ///< the tangent's pattern (values zero)
  std::vector<int> scatter_;             ///< per tet, node pair (k, l), column c: index of entry (3k, 3l+c)
  Eigen::SparseMatrix<double> support_;  ///< ∫ k N_k N_l dA ⊗ I
  std::vector<int> support_scatter_;     ///< index in pattern_ of each of support_'s entries
  std::vector<std::function<double(const Vec3&)>> group_pressure_;  ///< per boundary group (empty: none)
  Eigen::VectorXd pressure_forces_, nodal_forces_;
  std::vector<char> held_;
  Eigen::VectorXd u_;
  std::unique_ptr<Factor> factor_;
  bool linearized_ = false;  ///< factor_ holds the tangent of the last linearize()
};

}  // namespace flowire::solid
