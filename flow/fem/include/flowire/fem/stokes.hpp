#pragma once
/// @file stokes.hpp
/// @brief Steady incompressible Stokes / Navier–Stokes on a TetMesh with Taylor–Hood
/// P2/P1 elements (isoparametric: the quadratic geometry of the mesh is used).
///
/// Governing equations (η viscosity, ρ density):
/// \f[ -\eta\Delta u + \rho (u\cdot\nabla)u + \nabla p = 0, \qquad \nabla\cdot u = 0 \f]
/// with u = 0 on the wall and the "do-nothing" condition with a prescribed pressure on
/// every inlet / outlet face Γ_k: \f$ \eta\,\partial_n u - p\,n = -p_k\, n \f$, i.e. the weak form
/// \f[ \eta(\nabla u,\nabla v) + \rho((w\cdot\nabla)u, v) - (p,\nabla\cdot v) - (q,\nabla\cdot u)
///     = -\sum_k p_k \int_{\Gamma_k} n\cdot v \f]
/// (Stokes: no convection; Navier–Stokes: Picard iterations with w the previous
/// velocity, starting from the Stokes solution).
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
#include <span>
#include <string>
#include <vector>

#include "flowire/fem/mesh.hpp"

namespace flowire::fem {

enum class Equations { Stokes, NavierStokes };
enum class LinearSolver { Mumps, Fieldsplit };

struct StokesOptions {
  double viscosity = 3.5e-3;   ///< Pa·s
  double density = 1060.0;     ///< kg/m³ (Navier–Stokes only)
  Equations equations = Equations::Stokes;
  LinearSolver solver = LinearSolver::Mumps;
  std::string velocity_pc = "gamg";  ///< fieldsplit: "gamg" or "hypre" on the velocity block
  double rtol = 1e-10;               ///< fieldsplit: relative residual tolerance
  int max_iterations = 5000;         ///< fieldsplit: Krylov iterations at most
  int picard_max_iterations = 50;    ///< Navier–Stokes
  double picard_tolerance = 1e-8;    ///< Navier–Stokes: max |Δu| / max |u|
};

struct StokesSolution {
  std::vector<Vec3> velocity;     ///< (num_nodes) m/s, zero on the wall
  std::vector<double> pressure;   ///< (num_vertices) Pa, indexed by TetMesh::vertex_index
  std::vector<double> group_flow; ///< (groups) m³/s out of the domain through each group
  int unknowns = 0;               ///< size of the linear system
  int krylov_iterations = 0;      ///< fieldsplit: total over Picard steps (0 for MUMPS)
  int picard_iterations = 0;      ///< linear solves done
  double assemble_seconds = 0.0;  ///< preallocation and element assembly
  double solve_seconds = 0.0;     ///< factorization / Krylov solve
};

/// @brief Solve with a prescribed pressure on every non-wall group:
/// `group_pressure[g]` (Pa) for group g of `mesh.groups` (the wall entry is ignored).
/// Collective under MPI.
/// @throws flowire::Error: usage (sizes, options), numerical (PETSc failure, no
/// convergence, an inverted curved element).
StokesSolution solve_stokes(const TetMesh& mesh, std::span<const double> group_pressure, const StokesOptions& opt = {});

/// @brief Outward flux \f$ \int_{\Gamma_g} u\cdot n \f$ of a velocity field through each group.
std::vector<double> group_fluxes(const TetMesh& mesh, const std::vector<Vec3>& velocity);

/// @brief Initialize PETSc (and MPI) unless already done; build_mesh then sees every rank.
void initialize();

/// @brief Finalize PETSc if the fem solver initialized it (also done at exit).
void finalize_petsc();

}  // namespace flowire::fem
