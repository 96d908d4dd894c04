#pragma once
/// @file obstacle.hpp
/// @brief Flow past obstacles on ShapeDomain meshes, and the force on them: the DFG
/// benchmark 3D-1Z (Schäfer & Turek 1996) and a guidewire segment inside a vessel.
///
/// DFG 3D-1Z, in the benchmark's coordinates: channel [0, 2.5] × [0, 0.41] × [0, 0.41] m,
/// flow along x, a cylinder of diameter D = 0.1 with its axis along z through
/// (x, y) = (0.5, 0.2) spanning the height H = 0.41; inflow
/// \f$ U(0,y,z) = 16 U_m yz(H-y)(H-z)/H^4 \f$, U_m = 0.45 m/s; no-slip on the channel walls
/// and the cylinder; do-nothing outflow (pressure 0 in the solver's η∂u/∂n − pn form) at
/// x = 2.5; ν = 10⁻³ m²/s, ρ = 1 kg/m³; steady Navier–Stokes at Re = ŪD/ν = 20 with
/// Ū = 4U_m/9 = 0.2 m/s. Reported: \f$ c_D = 2F_x/(\rho\bar U^2 DH) \f$,
/// \f$ c_L = 2F_y/(\rho\bar U^2 DH) \f$ (F by the weak form, boundary_forces) and
/// Δp = p(0.45, 0.2, 0.205) − p(0.55, 0.2, 0.205). The benchmark's intervals:
/// c_D ∈ [6.05, 6.25], c_L ∈ [0.008, 0.010], Δp ∈ [0.165, 0.175].
#include <string>
#include <utility>
#include <vector>

#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/shape_domain.hpp"
#include "flowire/flow/fem/stokes.hpp"

namespace flowire::flow::fem {

/// @brief Mesh sizes of an obstacle domain.
struct ObstacleMesh {
  double mesh_size = 0.0;           ///< far field (m)
  double obstacle_mesh_size = 0.0;  ///< on the obstacle's surface (m)
  double growth = 0.3;              ///< size increase per unit distance from the obstacle
};

/// @brief The fluid domain of DFG 3D-1Z with groups wall, obstacle, inlet, outlet.
ShapeDomain dfg_3d_1z_domain(const ObstacleMesh& sizes);

struct ObstacleResult {
  std::vector<std::pair<std::string, Vec3>> forces;       ///< (no-slip group, force on it, N)
  double drag_coefficient = 0.0, lift_coefficient = 0.0;  ///< DFG only
  double pressure_difference = 0.0;                       ///< DFG only: Δp (Pa)
  int tets = 0, unknowns = 0, newton_iterations = 0;
  double mesh_seconds = 0.0, solve_seconds = 0.0;
};

/// @brief Solve DFG 3D-1Z (Navier–Stokes, the inflow amplitude exactly U_m on the mesh)
/// and, when `out_dir` is not empty, write fem_forces.csv (`boundary,fx,fy,fz`, one row
/// per no-slip group) and, with `write_vtu`, fem.vtu there (rank 0). Collective under MPI.
/// @throws flowire::Error as build_mesh and solve_stokes.
ObstacleResult dfg_3d_1z(const ObstacleMesh& sizes, Stabilization stabilization, const std::string& out_dir,
                         bool write_vtu = true);

/// @brief A guidewire segment in a straight vessel: a tube of radius `tube_radius` along
/// x from 0 to `length` and a wire (cylinder) of radius `wire_radius`, either along the
/// whole axis (`across` false; it reaches past both ends) or across the tube along y
/// through (`wire_x`, 0, 0), spanning the whole diameter. Groups: wall, obstacle (the
/// wire), inlet (x = 0), outlet (x = length).
ShapeDomain wire_in_tube_domain(double tube_radius, double length, double wire_radius, bool across, double wire_x,
                                const ObstacleMesh& sizes);

/// @brief A guidewire lying along a straight vessel: a tube of radius `tube_radius` along x
/// from 0 to `length` and a parallel wire of radius `wire_radius` whose axis is `offset`
/// from the tube's (along +y; 0: coaxial; below tube_radius − wire_radius), reaching past
/// both ends. The exact Stokes flow under a pressure drop is the annular Poiseuille flow
/// (flow/annulus.hpp): the geometry does not vary along x and the open ends carry a
/// uniform pressure. Groups: wall, obstacle, inlet (x = 0), outlet (x = length).
ShapeDomain wire_along_tube_domain(double tube_radius, double length, double wire_radius, double offset,
                                   const ObstacleMesh& sizes);

/// @brief Write fem_forces.csv (`boundary,fx,fy,fz`) into `dir` (rank 0 only).
void write_forces(const std::string& dir, const std::vector<std::pair<std::string, Vec3>>& forces);

/// @brief The no-slip groups' names and forces (boundary_forces) of a solution.
std::vector<std::pair<std::string, Vec3>> named_forces(const TetMesh& mesh, const StokesSolution& sol,
                                                       const StokesOptions& opt);

}  // namespace flowire::flow::fem
