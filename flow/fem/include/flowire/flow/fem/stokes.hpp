#pragma once
/// @file stokes.hpp
/// @brief Steady incompressible Stokes / Navier–Stokes on a TetMesh with Taylor–Hood
/// P2/P1 elements (Taylor & Hood 1973, Computers & Fluids 1, 73–100; isoparametric: the
/// quadratic geometry of the mesh is used).
///
/// Governing equations (η viscosity, ρ density, f a body force):
/// \f[ -\eta\Delta u + \rho (u\cdot\nabla)u + \nabla p = f, \qquad \nabla\cdot u = 0 \f]
/// with u = 0 on the wall and the "do-nothing" condition with a prescribed pressure on
/// every inlet / outlet face Γ_k: \f$ \eta\,\partial_n u - p\,n = -p_k\, n + g \f$ (g: an
/// optional extra traction, zero unless given), i.e. the weak form
/// \f[ \eta(\nabla u,\nabla v) + \rho((u\cdot\nabla)u, v) - (p,\nabla\cdot v) - (q,\nabla\cdot u)
///     = (f, v) - \sum_k p_k \int_{\Gamma_k} n\cdot v + \int g\cdot v \f]
/// (Stokes: ρ = 0).
///
/// Navier–Stokes at arterial Reynolds numbers (see solve_stokes): Newton's method with
/// the exact Jacobian of the convection, continuation in the density from the Stokes
/// solution (Re ∝ ρ) with an adaptive step, and three consistent stabilization terms:
/// - SUPG (streamline-upwind Petrov–Galerkin, Brooks & Hughes 1982, Comput. Methods Appl.
///   Mech. Engrg. 32, 199–259): \f$ \sum_e (\tau_M\,\rho\,u\cdot\nabla v,\ \rho(u\cdot\nabla)u - \eta\Delta u + \nabla
///   p - f)_e \f$ with \f$ \tau_M = [(2\rho|u|/h)^2 + (12\eta/h^2)^2]^{-1/2} \f$, h half the element size (P2); the
///   second derivatives of the curved (isoparametric) element are exact;
/// - LSIC (grad-div): \f$ \sum_e (\tau_C \nabla\cdot u, \nabla\cdot v)_e \f$ with
///   \f$ \tau_C = \rho|u|h/2\cdot\min(1, Re_h/3) \f$, \f$ Re_h = \rho|u|h/(2\eta) \f$;
/// - backflow on outlets: \f$ -\tfrac{\beta\rho}{2}\int_{\Gamma_{out}} \min(u\cdot n, 0)\, u\cdot v \f$,
///   which removes the kinetic energy that flow entering through an outlet would bring
///   in (zero where the flow leaves). The exact solution satisfies all three terms'
///   residuals, so the discretization keeps its order (tests: manufactured solution).
/// The Jacobian is exact, including the derivatives of τ_M, τ_C and of the backflow
/// term (finite-difference tests).
/// The inlet of a Navier–Stokes solve carries by default a prescribed velocity profile
/// (Poiseuille over the inlet disk, or `inlet_velocity`) whose amplitude is one more
/// unknown of the boundary system: a flow condition fixes its flux, a pressure condition
/// the mean pressure over the inlet. The traction condition at an inflow boundary lets
/// the convective term bring in kinetic energy unchecked (½ρ∫(u·n)|u|² < 0 there), which
/// made Newton stall near Re ≈ 100 even for Poiseuille flow; with the profile it reaches
/// Re = 1000 in a tube from the Stokes start in one density step.
/// Navier–Stokes runs with MUMPS only: the fieldsplit preconditioner's Schur
/// approximation (pressure mass) ignores convection.
///
/// Boundary conditions other than a pressure (a prescribed flow, or a resistance
/// p_k = P_d + R_k Q_k) use that the problem is affine in the boundary pressures: with
/// the matrix factorized once, the field is x = x_0 + Σ_{k∈U} p_k x_k, where x_0 solves
/// with the known pressures and 0 on the groups U whose pressure is unknown, and x_k with
/// 1 on group k and 0 elsewhere. The outward flows are then Q = F_0 + Σ_k p_k F_k
/// (F: fluxes of those fields), and the |U| conditions form a small dense system for the
/// p_k. Navier–Stokes does the same in every Newton step (the linearized problem is
/// affine in the boundary pressures too). `StokesBasis` keeps one unit field per open
/// group for many boundary values (a pulsatile series of quasi-steady frames) after a
/// single factorization.
///
/// Element matrices (quadrature of degree 5 on every tetrahedron) are assembled by
/// flowire into a PETSc AIJ matrix with exact preallocation; the wall nodes are removed
/// from the unknowns. Under MPI every rank assembles its share of the elements and owns
/// a contiguous block of unknowns; every rank receives the whole solution.
/// Linear solvers: `Mumps` (LU), or `Fieldsplit`: FGMRES with an upper block-triangular
/// Schur complement preconditioner, AMG (GAMG or hypre) on the velocity block and the
/// pressure mass matrix scaled by 1/η for the Schur complement. PETSc options with the
/// prefix `-fem_` (e.g. `-fem_ksp_monitor`, `-fem_fieldsplit_u_pc_type hypre`) override
/// these choices.
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "flowire/flow/fem/mesh.hpp"

namespace flowire::flow::fem {

enum class Equations { Stokes, NavierStokes };
enum class LinearSolver { Mumps, Fieldsplit };
/// Navier–Stokes stabilization: SUPG + LSIC (see the file comment), or plain Galerkin.
enum class Stabilization { Supg, None };
/// Navier–Stokes inlet: a prescribed velocity profile whose amplitude the inlet condition
/// (pressure: the mean pressure over the inlet; flow) determines, or the traction
/// condition of the outlets.
enum class InletCondition { Profile, Traction };

struct StokesOptions {
  double viscosity = 3.5e-3;  ///< Pa·s
  double density = 1060.0;    ///< kg/m³ (Navier–Stokes only)
  Equations equations = Equations::Stokes;
  Stabilization stabilization = Stabilization::Supg;  ///< Navier–Stokes only
  double backflow = 1.0;                              ///< β of the outlet backflow term (Navier–Stokes; 0: none)
  InletCondition inlet = InletCondition::Profile;     ///< Navier–Stokes only
  /// Shape of the inlet velocity profile (Navier–Stokes, `Profile`); empty: Poiseuille,
  /// −n(1 − r²/R²) over the inlet disk.
  std::function<Vec3(const Vec3&)> inlet_velocity;
  /// Without `inlet_velocity`: a uniform profile −n over the inlet (zero on its wall nodes: a plug
  /// entering a tube, where a developing boundary layer starts) instead of Poiseuille's.
  bool flat_inlet = false;
  LinearSolver solver = LinearSolver::Mumps;
  std::string velocity_pc = "gamg";  ///< fieldsplit: "gamg" or "hypre" on the velocity block
  double rtol = 1e-10;               ///< fieldsplit: relative residual tolerance
  int max_iterations = 5000;         ///< fieldsplit: Krylov iterations at most
  int newton_max_iterations = 12;    ///< Navier–Stokes: per continuation step
  double newton_tolerance = 1e-9;    ///< Navier–Stokes: max |Δu| / max |u| of the last update
  int continuation_max_steps = 60;   ///< Navier–Stokes: density steps at most (accepted or not)
  /// Navier–Stokes: start Newton from this field (same mesh) at the full density instead
  /// of from the Stokes solution (e.g. the previous frame of a series); if that Newton
  /// solve fails, the Stokes start and the continuation follow as usual. nullptr: none.
  const struct StokesSolution* initial_guess = nullptr;
  /// Body force f(x) (N/m³); empty: none. Not for StokesBasis.
  std::function<Vec3(const Vec3&)> body_force;
  /// Extra traction g(x, n, group) on the open groups (Pa), added to −p_k n; empty: none.
  /// Not for StokesBasis.
  std::function<Vec3(const Vec3&, const Vec3&, int)> traction;
};

/// @brief Condition on one open boundary group (inlet or outlet).
struct GroupCondition {
  enum class Type { Pressure, Flow, Resistance };
  Type type = Type::Pressure;
  double pressure = 0.0;    ///< Pressure: the group pressure; Resistance: the distal pressure P_d (Pa)
  double flow = 0.0;        ///< Flow: outward flow through the group (m³/s; an inflow is negative)
  double resistance = 0.0;  ///< Resistance: p = P_d + R·Q with Q the outward flow (Pa·s/m³, >= 0)

  static GroupCondition at_pressure(double p) { return {Type::Pressure, p, 0.0, 0.0}; }
  static GroupCondition with_flow(double q_out) { return {Type::Flow, 0.0, q_out, 0.0}; }
  static GroupCondition with_resistance(double r, double distal) { return {Type::Resistance, distal, 0.0, r}; }
};

struct StokesSolution {
  std::vector<Vec3> velocity;          ///< (num_nodes) m/s, zero on the wall
  std::vector<double> pressure;        ///< (num_vertices) Pa, indexed by TetMesh::vertex_index
  std::vector<double> group_flow;      ///< (groups) m³/s out of the domain through each group
  std::vector<double> group_pressure;  ///< (groups) Pa: the pressure imposed on each open group (wall: 0)
  int unknowns = 0;                    ///< size of the linear system
  int krylov_iterations = 0;           ///< fieldsplit: total over all linear solves (0 for MUMPS)
  int factorizations = 0;              ///< matrix factorizations (Stokes: 1; Navier–Stokes: Newton steps)
  int newton_iterations = 0;           ///< Navier–Stokes: Newton steps over all continuation steps
  int continuation_steps = 0;          ///< Navier–Stokes: accepted density steps (1: no continuation needed)
  double reynolds = 0.0;               ///< inlet Reynolds number ρ·ū·D/η (ū = |Q|/A, D = 2√(A/π))
  double assemble_seconds = 0.0;       ///< preallocation and element assembly
  double solve_seconds = 0.0;          ///< factorization / Krylov solve
};

/// @brief Solve with a prescribed pressure on every non-wall group:
/// `group_pressure[g]` (Pa) for group g of `mesh.groups` (the wall entry is ignored).
/// Collective under MPI.
/// @throws flowire::Error: usage (sizes, options), numerical (PETSc failure, no
/// convergence, an inverted curved element).
StokesSolution solve_stokes(const TetMesh& mesh, std::span<const double> group_pressure, const StokesOptions& opt = {});

/// @brief Solve with a condition on every non-wall group (`conditions[g]` for group g;
/// the wall entry is ignored): one factorization (Navier–Stokes: one per Newton step),
/// one solve with the known pressures plus one per group whose pressure is unknown (see
/// the file comment). Navier–Stokes starts from the Stokes solution and tries the full
/// density at once; a Newton solve that fails (no convergence within
/// `newton_max_iterations`, growing updates, NaN) is retried from the last converged
/// density with a quarter of the step, and successful steps double it.
/// @throws flowire::Error: usage (sizes, a negative resistance, no group fixing the
/// pressure level), numerical as above, and when the continuation stalls (the message
/// gives the Reynolds number reached).
StokesSolution solve_stokes(const TetMesh& mesh, std::span<const GroupCondition> conditions,
                            const StokesOptions& opt = {});

/// @brief Pressures on the groups that satisfy `conditions`, given the fluxes of unit
/// fields: `unit_flux[k][g]` is the outward flow through group g of the field with
/// pressure 1 on group `open[k]` and 0 on the others, `base_flux[g]` that of the field
/// with the known pressures (Pressure groups) and 0 elsewhere. Returns one pressure per
/// group (wall: 0). Also used by StokesBasis; exposed for tests.
/// @throws flowire::Error (usage) when the conditions do not fix the pressures.
std::vector<double> boundary_pressures(const TetMesh& mesh, std::span<const GroupCondition> conditions,
                                       const std::vector<int>& open, const std::vector<double>& base_flux,
                                       const std::vector<std::vector<double>>& unit_flux);

/// @brief Steady Stokes (no convection) for many boundary values with one factorization:
/// one unit field per open group (pressure 1 there, 0 on the others); any boundary
/// values are then a linear combination of them. Collective under MPI (constructor only).
class StokesBasis {
 public:
  /// @throws flowire::Error as solve_stokes; usage when `opt.equations` is Navier–Stokes.
  StokesBasis(const TetMesh& mesh, const StokesOptions& opt = {});
  /// @brief Group pressures satisfying `conditions` (one per group, wall 0).
  [[nodiscard]] std::vector<double> pressures(std::span<const GroupCondition> conditions) const;
  /// @brief The solution for `conditions`: the combination of the unit fields.
  [[nodiscard]] StokesSolution solve(std::span<const GroupCondition> conditions) const;
  /// @brief Outward flow through group g for pressure 1 on open group `open_groups()[k]`: [k][g].
  [[nodiscard]] const std::vector<std::vector<double>>& unit_flux() const { return flux_; }
  [[nodiscard]] const std::vector<int>& open_groups() const { return open_; }
  [[nodiscard]] int unknowns() const { return unknowns_; }
  [[nodiscard]] double assemble_seconds() const { return assemble_seconds_; }
  [[nodiscard]] double solve_seconds() const { return solve_seconds_; }

 private:
  const TetMesh& mesh_;
  std::vector<int> open_;
  std::vector<StokesSolution> unit_;
  std::vector<std::vector<double>> flux_;
  int unknowns_ = 0;
  double assemble_seconds_ = 0.0, solve_seconds_ = 0.0;
};

/// @brief Time-dependent Stokes, \f$ \rho\,\partial_t u - \eta\Delta u + \nabla p = 0 \f$, by BDF2
/// with a fixed step Δt from rest (u = 0 at t = 0; the first step sees u^{−1} = 0 too,
/// which only matters for a start that is not at rest). One factorization of
/// K + (3ρ/2Δt)M and one unit solve per open group; a step is one solve of the history
/// right-hand side and the small boundary system of the conditions at the new time (any
/// mix of pressure, flow and resistance, e.g. an RCR outlet's resistance to its current
/// capacitor pressure). Collective under MPI (every call).
class UnsteadyStokes {
 public:
  /// @throws flowire::Error (usage) for Navier–Stokes, a body force or traction, Δt,
  /// ρ or η not positive; as solve_stokes otherwise.
  UnsteadyStokes(const TetMesh& mesh, const StokesOptions& opt, double dt);
  ~UnsteadyStokes();
  UnsteadyStokes(const UnsteadyStokes&) = delete;
  UnsteadyStokes& operator=(const UnsteadyStokes&) = delete;
  /// @brief Advance by Δt to the conditions `conditions` (one per group, wall ignored),
  /// given at the new time. Returns the new field (valid until the next step).
  const StokesSolution& step(std::span<const GroupCondition> conditions);
  [[nodiscard]] const StokesSolution& current() const;
  [[nodiscard]] double time() const;
  [[nodiscard]] double dt() const;
  /// @brief Outward flow through group g of the step's unit field for pressure 1 on
  /// `open_groups()[k]`: [k][g] (the instantaneous resistance of the domain).
  [[nodiscard]] const std::vector<std::vector<double>>& unit_flux() const;
  [[nodiscard]] const std::vector<int>& open_groups() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// @brief The force of the fluid on every no-slip group (N; open groups: zero), for a
/// steady solution `sol` of `solve_stokes` with the same options:
/// \f[ F_g = -\int_{\Gamma_g} \sigma n\, dS, \qquad \sigma = -pI + \eta(\nabla u + \nabla u^T) \f]
/// (n the outward normal of the fluid). Evaluated in the weak ("variational") form,
/// \f$ F_g\cdot e_i = -R(u, p; \phi_i) \f$ with R the discrete residual the solver
/// drives to zero (viscous, pressure, convection, stabilization, body force and the
/// open-boundary terms) and \f$ \phi_i \f$ the P2 field equal to \f$ e_i \f$ on the nodes
/// of group g and 0 on every other node: a volume integral over the elements touching
/// Γ_g, which converges at the rate of the energy error squared, faster than the surface
/// integral of the stress (`surface_forces`). On a no-slip wall of a divergence-free
/// flow η∂u/∂n − pn = σn, so the solver's η∇u:∇v form gives the same force. Nodes
/// shared with another group (a wire meeting the channel wall) count for g. A profile
/// inlet (Navier–Stokes) has unknown traction; its faces are left out.
std::vector<Vec3> boundary_forces(const TetMesh& mesh, const StokesSolution& sol, const StokesOptions& opt);

/// @brief The same force as boundary_forces by the surface integral of
/// \f$ -\sigma n \f$ with the stress of the element behind each boundary triangle (for
/// comparison; on the coaxial-wire test its error is some 90 times that of the weak form).
std::vector<Vec3> surface_forces(const TetMesh& mesh, const StokesSolution& sol, double viscosity);

/// @brief Outward flux \f$ \int_{\Gamma_g} u\cdot n \f$ of a velocity field through each group.
std::vector<double> group_fluxes(const TetMesh& mesh, const std::vector<Vec3>& velocity);

namespace detail {
/// @brief One tetrahedron's Navier–Stokes residual `res` (34: velocity rows 3i+c for its
/// 10 nodes, then its 4 vertex pressures) and Jacobian `jac` (34 × 34, row major) at the
/// state (`velocity` per node, `pressure` per vertex index), with the density, viscosity,
/// stabilization and body force of `opt`. For tests.
/// @return false when the element is inverted.
bool navier_stokes_element(const TetMesh& mesh, int tet, const StokesOptions& opt, const std::vector<Vec3>& velocity,
                           const std::vector<double>& pressure, double* res, double* jac);
/// @brief One open boundary triangle's residual (18: rows 3k+c of its 6 nodes) and
/// Jacobian (18 × 18): the group pressure, the traction and the outlet backflow term.
void navier_stokes_face(const TetMesh& mesh, int face, const StokesOptions& opt, const std::vector<Vec3>& velocity,
                        const std::vector<double>& group_pressure, double* res, double* jac);
}  // namespace detail

/// @brief Initialize PETSc (and MPI) unless already done; build_mesh then sees every rank.
/// PETSc is owned by flow (flow/petsc_runtime.hpp): flow::finalize_petsc() ends it.
void initialize();

}  // namespace flowire::flow::fem
