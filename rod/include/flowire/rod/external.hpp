#pragma once
/// @file external.hpp
/// @brief How other modules (contact, blood drag, haptics) push on the rod.
///
/// An `ExternalForce` is asked, at every Newton iterate of an implicit step, for per-vertex
/// forces f_i(x, v) and their Jacobians ∂f_i/∂x_i and ∂f_i/∂v_i (3×3 blocks on the vertex
/// diagonal). The rod adds −∂f/∂x − ∂f/∂v / Δt to its system matrix, so stiff contact
/// penalties and drag stay implicit. The blocks are symmetrized; forces whose Jacobian is
/// not negative semi-definite (not dissipative, not a convex penalty) may slow Newton.
/// Give the whole Jacobian: for a penalty −k(r − R)n on a curved wall that includes the
/// tangential term −k(r − R)/r (P − n nᵀ); with only −k n nᵀ Newton converges linearly
/// and stiff contacts then exhaust the iteration budget. Start from a consistent state
/// (no deep initial penetration): a large initial overlap is a large impulsive load.
///
/// Forces that derive from a potential (penalty contact) should be added with
/// `add_conservative_force` and their energy with `add_energy`: the Newton line search then
/// uses the exact incremental potential for them and the trapezoidal work along the search
/// ray only for the rest (friction, drag), which keeps stiff contacts from stalling it.
///
/// rod/ knows nothing about vessels or blood: implementations live in coupling/.
///
/// Example — a floor z ≥ 0 as a stiff penalty:
/// @code
/// class Floor : public flowire::rod::ExternalForce {
///   void evaluate(const RodView& rod, ForceAccumulator& out) override {
///     for (int i = 0; i < rod.vertex_count(); ++i) {
///       const double d = rod.position(i).z();
///       if (d < 0) {
///         out.add_conservative_force(i, {0, 0, -k * d});
///         out.add_energy(0.5 * k * d * d);
///         out.add_position_jacobian(i, -k * e_z e_zᵀ);
///       }
///     }
///   }
/// };
/// @endcode
#include <Eigen/Core>
#include <functional>
#include <span>
#include <vector>

namespace flowire::rod {

/// @brief Read-only view of the rod at the configuration being evaluated.
struct RodView {
  std::span<const Eigen::Vector3d> positions;   ///< (vertex_count) [m], vertex 0 = distal tip
  std::span<const Eigen::Vector3d> velocities;  ///< (vertex_count) [m/s] at this iterate
  std::span<const double> arc_length;           ///< (vertex_count) [m] from the entry, >0 inserted
  std::span<const double> radius;               ///< (vertex_count − 1) per edge [m]
  /// (vertex_count − 1) rest length of each edge [m]: the feeding grid's `segment_length`,
  /// shorter where adaptivity refined the wire (longer where it coarsened it)
  std::span<const double> rest_lengths;
  double segment_length = 0.0;  ///< [m] the feeding grid's edge length
  /// (vertex_count − 1) spin rate of each edge's material frame about its tangent [rad/s]
  std::span<const double> spin_rates;
  /// (vertex_count − 1) unit tangent of each edge, pointing from the tip toward the base
  std::span<const Eigen::Vector3d> tangents;
  int first_clamped_vertex = 0;  ///< vertices with index ≥ this are held by the clamp
  double time = 0.0;             ///< [s] end of the step (implicit evaluation time)
  double dt = 0.0;               ///< [s] step size (0 in a static solve)
  /// Serial number of the solve this evaluation belongs to: it changes whenever a step (or a
  /// stage of one) is started or taken again, so that a force can keep what it computed at
  /// a step's first evaluation for the rest of that step.
  long solve_serial = 0;
  [[nodiscard]] int vertex_count() const { return static_cast<int>(positions.size()); }
  [[nodiscard]] const Eigen::Vector3d& position(int i) const { return positions[i]; }
  [[nodiscard]] const Eigen::Vector3d& velocity(int i) const { return velocities[i]; }
  /// @brief The wire's radius at vertex @p i: the mean of its edges' radii (the one radius of
  /// the wire wherever it is uniform); @p fallback where the view carries no (positive) radii.
  [[nodiscard]] double vertex_radius(int i, double fallback) const {
    const int ne = static_cast<int>(radius.size());
    if (ne == 0) return fallback;
    const double r = i <= 0 ? radius[0] : i >= ne ? radius[ne - 1] : 0.5 * (radius[i - 1] + radius[i]);
    return r > 0.0 ? r : fallback;
  }
  /// @brief Mean rest length of the edges at vertex @p i over the grid's segment length: 1 on
  /// a uniform grid. Per-vertex penalties scaled by it stay per unit length under refinement.
  [[nodiscard]] double cell_weight(int i) const {
    if (rest_lengths.empty() || !(segment_length > 0.0)) return 1.0;
    const int ne = static_cast<int>(rest_lengths.size());
    double sum = 0.0;
    int count = 0;
    if (i > 0 && i - 1 < ne) sum += rest_lengths[i - 1], ++count;
    if (i < ne) sum += rest_lengths[i], ++count;
    return count ? sum / count / segment_length : 1.0;
  }
};

/// @brief Where forces and Jacobians are accumulated (sized by the rod; no allocation).
class ForceAccumulator {
 public:
  /// @brief Add a force that is not (or not declared as) the gradient of an energy
  /// (friction, drag, follower loads). The line search accounts for it by the trapezoidal
  /// work along the search ray.
  void add_force(int vertex, const Eigen::Vector3d& f) { force_[vertex] += f; }
  /// @brief Add a conservative force f = −∂E/∂x_i whose potential E is reported through
  /// `add_energy` (e.g. a penalty contact). The line search then measures it by E exactly
  /// instead of by the trapezoidal work, which is what keeps stiff penalties robust.
  /// Forces added here without their energy make the line-search merit wrong.
  void add_conservative_force(int vertex, const Eigen::Vector3d& f) {
    force_[vertex] += f;
    conservative_[vertex] += f;
  }
  /// @brief Add potential energy [J] of the conservative forces (see add_conservative_force).
  void add_energy(double e) { energy_ += e; }
  /// @brief Add ∂f_i/∂x_i (e.g. −k n nᵀ for a penalty contact of stiffness k).
  void add_position_jacobian(int vertex, const Eigen::Matrix3d& dfdx) { dfdx_[vertex] += dfdx; }
  /// @brief Add the full ∂(f_j, f_{j+1})/∂(x_j, x_{j+1}) of edge @p edge's two vertices (a
  /// force on a point of the edge split between its ends, e.g. a contact on the edge).
  void add_edge_jacobian(int edge, const Eigen::Matrix<double, 6, 6>& dfdx) {
    edge_dfdx_[edge] += dfdx;
    has_edge_dfdx_ = true;
  }
  /// @brief Add a stiffness −∂f/∂x = Σ_ij R_ij (d_i ⊗ e_{v_i})(d_j ⊗ e_{v_j})ᵀ that couples vertices
  /// far apart along the wire (the contacts of a deformable wall: a push at one contact moves
  /// the wall under another). Vertex @p vertices[i] with direction @p directions[i]; @p core
  /// is R (symmetric). Several calls add block-diagonally. Newton solves with it exactly
  /// (Sherman–Morrison–Woodbury on the band), so such forces converge quadratically.
  void add_coupled_stiffness(std::span<const int> vertices, std::span<const Eigen::Vector3d> directions,
                             const Eigen::MatrixXd& core) {
    const auto m0 = static_cast<Eigen::Index>(coupled_vertices_.size());
    const auto m = static_cast<Eigen::Index>(vertices.size());
    coupled_vertices_.insert(coupled_vertices_.end(), vertices.begin(), vertices.end());
    coupled_directions_.insert(coupled_directions_.end(), directions.begin(), directions.end());
    Eigen::MatrixXd merged = Eigen::MatrixXd::Zero(m0 + m, m0 + m);
    merged.topLeftCorner(m0, m0) = coupled_core_;
    merged.bottomRightCorner(m, m) = core;
    coupled_core_.swap(merged);
  }
  /// @brief Add ∂f_i/∂v_i (e.g. −c·I for viscous drag).
  void add_velocity_jacobian(int vertex, const Eigen::Matrix3d& dfdv) { dfdv_[vertex] += dfdv; }
  /// @brief Add a torque about edge @p edge's tangent [N m] (e.g. rotational friction or
  /// drag resisting the wire's spin), with optionally its derivative w.r.t. the edge's spin
  /// rate (e.g. −c for a drag torque −c·ω), kept implicit like the force Jacobians.
  void add_twist_torque(int edge, double torque, double dtorque_dspin = 0.0) {
    torque_[edge] += torque;
    dtorque_[edge] += dtorque_dspin;
  }

  // Used by the simulator.
  void reserve(int n) {
    force_.reserve(n);
    dfdx_.reserve(n);
    dfdv_.reserve(n);
    torque_.reserve(n);
    dtorque_.reserve(n);
    conservative_.reserve(n);
    edge_dfdx_.reserve(n);
  }
  void reset(int n) {
    force_.assign(n, Eigen::Vector3d::Zero());
    dfdx_.assign(n, Eigen::Matrix3d::Zero());
    dfdv_.assign(n, Eigen::Matrix3d::Zero());
    torque_.assign(n > 0 ? n - 1 : 0, 0.0);
    dtorque_.assign(n > 0 ? n - 1 : 0, 0.0);
    conservative_.assign(n, Eigen::Vector3d::Zero());
    if (has_edge_dfdx_ || static_cast<int>(edge_dfdx_.size()) != (n > 0 ? n - 1 : 0))
      edge_dfdx_.assign(n > 0 ? n - 1 : 0, Eigen::Matrix<double, 6, 6>::Zero());
    has_edge_dfdx_ = false;
    energy_ = 0.0;
    coupled_vertices_.clear();
    coupled_directions_.clear();
    coupled_core_.resize(0, 0);
  }
  /// @brief All forces per vertex (conservative ones included).
  [[nodiscard]] const std::vector<Eigen::Vector3d>& forces() const { return force_; }
  /// @brief The conservative part of forces() (added by add_conservative_force).
  [[nodiscard]] const std::vector<Eigen::Vector3d>& conservative_forces() const { return conservative_; }
  /// @brief Potential energy of the conservative forces [J].
  [[nodiscard]] double energy() const { return energy_; }
  [[nodiscard]] const std::vector<Eigen::Matrix3d>& position_jacobians() const { return dfdx_; }
  [[nodiscard]] const std::vector<Eigen::Matrix3d>& velocity_jacobians() const { return dfdv_; }
  /// @brief (n − 1) edge Jacobians (add_edge_jacobian); all zero unless has_edge_jacobians().
  [[nodiscard]] const std::vector<Eigen::Matrix<double, 6, 6>>& edge_jacobians() const { return edge_dfdx_; }
  [[nodiscard]] bool has_edge_jacobians() const { return has_edge_dfdx_; }
  [[nodiscard]] const std::vector<double>& twist_torques() const { return torque_; }
  /// @brief The coupled stiffness (add_coupled_stiffness): its vertices, directions and core.
  [[nodiscard]] const std::vector<int>& coupled_vertices() const { return coupled_vertices_; }
  [[nodiscard]] const std::vector<Eigen::Vector3d>& coupled_directions() const { return coupled_directions_; }
  [[nodiscard]] const Eigen::MatrixXd& coupled_core() const { return coupled_core_; }
  [[nodiscard]] const std::vector<double>& twist_torque_spin_derivatives() const { return dtorque_; }

 private:
  std::vector<Eigen::Vector3d> force_;
  std::vector<Eigen::Matrix3d> dfdx_;
  std::vector<Eigen::Matrix3d> dfdv_;
  std::vector<double> torque_;
  std::vector<double> dtorque_;
  std::vector<Eigen::Vector3d> conservative_;
  std::vector<int> coupled_vertices_;
  std::vector<Eigen::Vector3d> coupled_directions_;
  Eigen::MatrixXd coupled_core_;
  std::vector<Eigen::Matrix<double, 6, 6>> edge_dfdx_;
  bool has_edge_dfdx_ = false;
  double energy_ = 0.0;
};

/// @brief A source of external forces on the rod's vertices.
class ExternalForce {
 public:
  virtual ~ExternalForce() = default;
  /// @brief Add forces (and Jacobians) at the configuration in @p rod. Called several
  /// times per step (once per Newton iterate and line-search trial): must not keep state
  /// that assumes one call per step; use `end_step` for that.
  virtual void evaluate(const RodView& rod, ForceAccumulator& out) = 0;
  /// @brief Called once after each accepted step (e.g. to update friction anchors).
  virtual void end_step(const RodView& /*rod*/) {}
  /// Keep / bring back what end_step records (RodSimulator::save_checkpoint and
  /// restore_checkpoint: a step taken again from its start must see the force as it was there).
  virtual void save_checkpoint() {}
  virtual void restore_checkpoint() {}
  /// @brief The rod's state was set outside a dynamic step (the force was just added, or a
  /// static solve finished): record what end_step would record for it.
  virtual void start(const RodView& rod) { (void)rod; }
  /// @brief The rod resampled its vertices (adaptivity) before a step: vertex i of @p rod
  /// continues old vertex source[i], or is new (source[i] = −1). Per-vertex state kept
  /// between steps must be carried over here.
  virtual void remap(const RodView& /*rod*/, std::span<const int> /*source*/) {}
};

/// @brief Adapter for a plain function.
class ExternalForceFunction : public ExternalForce {
 public:
  using Fn = std::function<void(const RodView&, ForceAccumulator&)>;
  explicit ExternalForceFunction(Fn fn) : fn_(std::move(fn)) {}
  void evaluate(const RodView& rod, ForceAccumulator& out) override { fn_(rod, out); }

 private:
  Fn fn_;
};

}  // namespace flowire::rod
