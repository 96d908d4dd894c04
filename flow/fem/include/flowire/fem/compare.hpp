#pragma once
/// @file compare.hpp
/// @brief The network model against the 3D finite-element solution on the same lumen.
///
/// Both are driven by the same boundary values: a pressure at the inlet end and a
/// pressure at every outlet end. Compared are
/// - the pressure at `samples_per_branch` points along every branch centerline, equally
///   spaced in arc length from the first to the last node of the branch: the network's
///   value (linear along each segment, as in the Poiseuille model) against the FEM
///   cross-section mean (disk of 0.95 r normal to the centerline) and centre value;
/// - the flow through every outlet;
/// - the pressure drop along every branch.
///
/// Relative differences: `rel_diff` = (p_fem − p_net) / |p_net| as in the published
/// Table 1 (absolute pressures), and `rel_diff_drop` = (p_fem − p_net) / (p_in − min p_out),
/// the difference as a fraction of the pressure drop that drives the flow (independent
/// of the pressure level; this is the one the accuracy figures below use). A sample is
/// *near a junction* when it lies within two junction radii of a node where three or
/// more vessels meet.
///
/// Output files (`write_outputs`, rank 0 only): fem_compare.csv
/// (`branch,s,x,y,z,pressure_network,pressure_fem,rel_diff` then `pressure_fem_centre,
/// rel_diff_drop,path_distance,near_junction`), fem_outlets.csv
/// (`outlet,flow_network,flow_fem` then `rel_diff`), fem_compare.md (tables like the
/// paper's Table 1, flows, branch drops, timings), fem.vtu (quadratic tetrahedra, point
/// data `velocity` and `pressure`), fem_compare.png (network vs FEM pressure along the
/// path from the inlet, drawn by flow/fem/scripts/plot_fem_compare.py with matplotlib;
/// a warning, not an error, when python3/matplotlib is missing).
#include <string>
#include <utility>
#include <vector>

#include "flowire/fem/mesh.hpp"
#include "flowire/fem/stokes.hpp"

namespace flowire::fem {

struct FemOptions {
  double mesh_size = 0.0;      ///< m; <= 0: size_factor × local radius
  double size_factor = 0.3;
  Equations equations = Equations::Stokes;
  LinearSolver solver = LinearSolver::Mumps;
  std::string velocity_pc = "gamg";
  int samples_per_branch = 10;
  bool write_png = true;
  bool write_vtu = true;
};

struct BoundaryValues {
  int inlet_node = -1;           ///< -1: Network::widest_end()
  double inlet_pressure = 0.0;   ///< Pa
  double outlet_pressure = 0.0;  ///< Pa, every outlet not listed below
  std::vector<std::pair<int, double>> outlet_pressures;  ///< (end node, Pa)
  double viscosity = 3.5e-3;     ///< Pa·s
  double density = 1060.0;       ///< kg/m³
};

/// @brief Network solution the FEM is compared with (any network solver can supply it).
struct NetworkFlow {
  std::vector<double> node_pressure;  ///< (num_nodes) Pa
  std::vector<double> segment_flow;   ///< (num_segments) m³/s, node_from -> node_to
};

struct SamplePoint {
  int branch = -1;
  double s = 0.0;                  ///< arc length from the branch's first node (m)
  Vec3 x = Vec3::Zero();
  double path_distance = 0.0;      ///< along the network from the inlet (m)
  double pressure_network = 0.0;
  double pressure_fem = 0.0;       ///< cross-section mean
  double pressure_fem_centre = 0.0;
  double rel_diff = 0.0;           ///< (fem − network) / |network|
  double rel_diff_drop = 0.0;      ///< (fem − network) / driving pressure drop
  bool near_junction = false;
  bool found = false;              ///< false if the point is outside the mesh
};

struct OutletFlow {
  int node = -1;
  double flow_network = 0.0, flow_fem = 0.0;  ///< m³/s out of the network
};

struct BranchDrop {
  int branch = -1;
  double drop_network = 0.0, drop_fem = 0.0;  ///< p(first node) − p(last node), Pa
};

struct CompareResult {
  std::vector<SamplePoint> samples;
  std::vector<OutletFlow> outlets;
  std::vector<BranchDrop> branches;
  double max_rel_diff_drop_away = 0.0;      ///< max |rel_diff_drop| away from junctions
  double max_rel_diff_drop_junction = 0.0;  ///< max |rel_diff_drop| near junctions
  double max_flow_split_error = 0.0;        ///< max |Q_fem/ΣQ_fem − Q_net/ΣQ_net| over outlets
  double max_flow_error = 0.0;              ///< max |Q_fem/Q_net − 1| over outlets
  int tets = 0, unknowns = 0;
  double mesh_seconds = 0.0, assemble_seconds = 0.0, solve_seconds = 0.0, total_seconds = 0.0;
};

/// @brief Network pressures and flows for the boundary values (flowire::flow, sparse solver).
NetworkFlow network_flow(const Network& net, const BoundaryValues& bv);

/// @brief Pressure of each mesh group (wall: 0) for the boundary values.
std::vector<double> group_pressures(const TetMesh& mesh, const BoundaryValues& bv);

/// @brief Compare a FEM solution with a network solution (see the file comment).
CompareResult compare_fields(const Network& net, const TetMesh& mesh, const StokesSolution& sol,
                             const NetworkFlow& flow, int inlet_node, int samples_per_branch);

/// @brief Write the output files into `out_dir` (created if needed). Only rank 0 writes.
void write_outputs(const std::string& out_dir, const Network& net, const TetMesh& mesh, const StokesSolution& sol,
                   const CompareResult& result, const FemOptions& opt);

/// @brief The whole comparison: mesh, FEM solve, network solve, compare, and write the
/// files when `out_dir` is not empty. Collective under MPI.
/// @throws flowire::Error as build_mesh, solve_stokes and the flow solver do.
CompareResult compare(const Network& net, const BoundaryValues& bv, const FemOptions& opt, const std::string& out_dir);

}  // namespace flowire::fem
