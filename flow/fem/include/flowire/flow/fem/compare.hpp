#pragma once
/// @file compare.hpp
/// @brief The network model against the 3D finite-element solution on the same lumen, at
/// one instant (the steady comparison; a series over a period is pulsatile.hpp).
///
/// Both are driven by the same boundary conditions, the network's own (BoundaryValues,
/// boundary_values.hpp). Compared are
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
/// The files a comparison writes are those of compare_output.hpp.
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "flowire/flow/fem/boundary_values.hpp"
#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/stokes.hpp"
#include "flowire/flow/spec.hpp"

namespace flowire::flow::fem {

/// @brief Options of a comparison: the mesh, the equations and solver, the samples and the
/// files (compare_output.hpp).
struct FemOptions {
  double mesh_size = 0.0;  ///< m; <= 0: size_factor × local radius
  double size_factor = 0.3;
  Equations equations = Equations::Stokes;
  LinearSolver solver = LinearSolver::Mumps;
  std::string velocity_pc = "gamg";
  Stabilization stabilization = Stabilization::Supg;  ///< Navier–Stokes
  InletCondition inlet = InletCondition::Profile;     ///< Navier–Stokes
  bool flat_inlet = false;                            ///< Navier–Stokes profile inlet: uniform, not Poiseuille's
  double backflow = 1.0;                              ///< Navier–Stokes: outlet backflow β
  int samples_per_branch = 10;
  /// A lumen surface file (lumen.hpp): the FEM domain is this real lumen, tagged by the
  /// network's ends, instead of the network's cylinders. Empty: the network's own lumen.
  std::string surface;
  double surface_length_factor = 1.0;  ///< metres per unit of the surface file
  /// The network's segment laws (a calibration, flow::FlowSpec::segment_laws), one per segment of
  /// the input network, or empty: Poiseuille. The network side of the comparison obeys them.
  std::vector<flow::SegmentLaw> segment_laws;
  /// The network side has Mynard & Valen-Sendstad's junction losses (`flow.losses.junction`).
  bool junction_losses = false;
  /// The laws are a calibration in total pressure (NetworkFlow::kinetic_density).
  bool total_pressure = false;
  /// (input nodes, or empty) in total pressure, each outlet's α (flow::Calibration::end_alpha)
  std::vector<double> end_alpha;
  bool write_png = true;
  bool write_vtu = true;
};

struct SamplePoint {
  int branch = -1;
  double s = 0.0;  ///< arc length from the branch's first node (m)
  Vec3 x = Vec3::Zero();
  double path_distance = 0.0;  ///< along the network from the inlet (m)
  double pressure_network = 0.0;
  double pressure_fem = 0.0;  ///< cross-section mean
  double pressure_fem_centre = 0.0;
  double rel_diff = 0.0;       ///< (fem − network) / |network|
  double rel_diff_drop = 0.0;  ///< (fem − network) / driving pressure drop
  /// Flow along the branch direction: the network segment's, and the FEM flux through the
  /// lumen's cross-section (the plane normal to the centerline, out to where each ray from
  /// the centre first leaves the mesh, at most 2 radii; NaN when the centre is outside it).
  double flow_network = 0.0, flow_fem = 0.0;
  double rel_diff_flow = 0.0;   ///< (fem − network) / |network|
  double radius_network = 0.0;  ///< the segment's radius (m)
  double radius_fem = 0.0;      ///< sqrt(A/π) of that cross-section's area A (m); NaN as flow_fem
  bool near_junction = false;
  bool found = false;  ///< false if the point is outside the mesh
};

struct OutletFlow {
  int node = -1;
  double flow_network = 0.0, flow_fem = 0.0;          ///< m³/s out of the network
  double pressure_network = 0.0, pressure_fem = 0.0;  ///< Pa at the outlet (imposed, or from its resistance)
};

struct BranchDrop {
  int branch = -1;
  double drop_network = 0.0, drop_fem = 0.0;  ///< p(first) − p(last sample inside the mesh), Pa
};

struct CompareResult {
  double time = 0.0;  ///< s: the instant of the boundary values
  std::vector<SamplePoint> samples;
  std::vector<OutletFlow> outlets;
  /// Inlet: flow into the network and pressure, network and FEM (one of them imposed).
  double inlet_flow_network = 0.0, inlet_flow_fem = 0.0;
  double inlet_pressure_network = 0.0, inlet_pressure_fem = 0.0;
  std::vector<BranchDrop> branches;
  /// max |rel_diff_drop| away from junctions (samples on an open end, the cap, are not counted)
  double max_rel_diff_drop_away = 0.0;
  double max_rel_diff_drop_junction = 0.0;  ///< max |rel_diff_drop| near junctions
  double max_flow_split_error = 0.0;        ///< max |Q_fem/ΣQ_fem − Q_net/ΣQ_net| over outlets
  double max_flow_error = 0.0;              ///< max |Q_fem/Q_net − 1| over outlets
  /// The pressures compared are total pressures (a network in total pressure,
  /// NetworkFlow::kinetic_density): the FEM's the flux-weighted p + ½ρ|u|² of each section, the
  /// network's its node values (its outlets' static)
  bool total_pressure = false;
  int tets = 0, unknowns = 0;
  /// Force of the fluid on each no-slip group (boundary_forces; `compare` only), N.
  std::vector<std::pair<std::string, Vec3>> forces;
  double reynolds = 0.0;      ///< inlet Reynolds number of the FEM flow (ρ ū D / η)
  int newton_iterations = 0;  ///< Navier–Stokes: Newton steps (0 for Stokes)
  double mesh_seconds = 0.0, assemble_seconds = 0.0, solve_seconds = 0.0, total_seconds = 0.0;
  /// real lumen: per cap (network end order), the length of centerline cut beyond it (m; < 0:
  /// the network was lengthened to reach it; ComparisonDomain)
  std::vector<double> cut_length;
  int lumen_ends_recut = 0;  ///< real lumen: open ends cut again square to their vessel (LumenSurface::recut_ends)
};

/// @brief Compare a FEM solution with a network solution (see the file comment).
CompareResult compare_fields(const Network& net, const TetMesh& mesh, const StokesSolution& sol,
                             const NetworkFlow& flow, int inlet_node, int samples_per_branch);

/// @brief The whole comparison: mesh, FEM solve, network solve, compare, and write the
/// files when `out_dir` is not empty (write_outputs). Collective under MPI.
/// @throws flowire::Error as build_mesh, solve_stokes and the flow solver do.
CompareResult compare(const Network& net, const BoundaryValues& bv, const FemOptions& opt, const std::string& out_dir);

/// @brief What a comparison solves on: the mesh, and the network of the same domain with the
/// boundary values on its nodes.
struct ComparisonDomain {
  TetMesh mesh;  ///< its groups name the nodes of `network`
  /// The input network, or, on a real lumen, the network cut at the lumen's caps (cap_cut.hpp):
  /// both models then impose the boundary values at the same places.
  Network network;
  std::vector<int> node;           ///< (input nodes) the node of `network` each became, -1 cut away
  std::vector<int> segment;        ///< (input segments) the segment of `network` each became, -1 cut away
  std::vector<double> cut_length;  ///< real lumen: per cap (network end order), the length cut (m)
  int lumen_ends_recut = 0;        ///< real lumen: open ends cut again square (LumenSurface::recut_ends)
  BoundaryValues bv;               ///< the input boundary values on `network`
  [[nodiscard]] bool cut() const { return !cut_length.empty(); }
  /// @brief Segment laws of the input network (one per input segment, or empty) on `network`: a
  /// segment keeps its resistance factor, and its quadratic coefficient in proportion to its
  /// Poiseuille resistance where it was shortened.
  [[nodiscard]] std::vector<flow::SegmentLaw> laws(const Network& input, std::span<const flow::SegmentLaw> laws) const;
  /// @brief Per-node values of the input network (or empty) on `network` (`fill` where none).
  [[nodiscard]] std::vector<double> nodal(std::span<const double> values, double fill) const;
};

/// @brief The domain a comparison solves on: the network's own lumen, or the real lumen of
/// `opt.surface` tagged by the network's ends (lumen.hpp) and the network cut at its caps; the
/// inlet is `bv.inlet_node`. Collective under MPI (build_mesh).
ComparisonDomain comparison_domain(const Network& net, const FemOptions& opt, const BoundaryValues& bv);

/// @brief The solver options of a comparison: the blood of `bv`, the equations, solver and
/// stabilization of `opt`.
StokesOptions comparison_stokes_options(const FemOptions& opt, const BoundaryValues& bv);

/// @brief A branch as the comparison's messages and files name it: its name, or
/// `branch_<index>` when it has none.
std::string branch_label(const Network& net, int branch);

}  // namespace flowire::flow::fem
