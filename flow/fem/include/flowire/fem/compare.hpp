#pragma once
/// @file compare.hpp
/// @brief The network model against the 3D finite-element solution on the same lumen.
///
/// Both are driven by the same boundary conditions, the network's own: a pressure or a
/// flow at the inlet end, and at every outlet end a pressure or a resistance to a distal
/// pressure (see BoundaryValues; the FEM enforces them through its affine structure, see
/// stokes.hpp). Compared are
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
/// rel_diff_drop,path_distance,near_junction,flow_network,flow_fem,rel_diff_flow,radius_network,
/// radius_fem`), fem_outlets.csv
/// (`outlet,flow_network,flow_fem` then `rel_diff,pressure_network,pressure_fem`), fem_compare.md (tables like the
/// paper's Table 1, flows, branch drops, timings), fem.vtu (quadratic tetrahedra, point
/// data `velocity` and `pressure`), fem_forces.csv (`boundary,fx,fy,fz`: the force of the
/// fluid on the wall, boundary_forces), fem_compare.png (network vs FEM pressure along the
/// path from the inlet, drawn by flow/fem/scripts/plot_fem_compare.py with matplotlib;
/// a warning, not an error, when python3/matplotlib is missing).
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "flowire/fem/mesh.hpp"
#include "flowire/fem/stokes.hpp"
#include "flowire/flow/spec.hpp"

namespace flowire::fem {

struct FemOptions {
  double mesh_size = 0.0;  ///< m; <= 0: size_factor × local radius
  double size_factor = 0.3;
  Equations equations = Equations::Stokes;
  LinearSolver solver = LinearSolver::Mumps;
  std::string velocity_pc = "gamg";
  Stabilization stabilization = Stabilization::Supg;  ///< Navier–Stokes
  InletCondition inlet = InletCondition::Profile;     ///< Navier–Stokes
  double backflow = 1.0;                              ///< Navier–Stokes: outlet backflow β
  int samples_per_branch = 10;
  /// A lumen surface file (lumen.hpp): the FEM domain is this real lumen, tagged by the
  /// network's ends, instead of the network's cylinders. Empty: the network's own lumen.
  std::string surface;
  double surface_length_factor = 1.0;  ///< metres per unit of the surface file
  bool write_png = true;
  bool write_vtu = true;
};

/// @brief Condition at one outlet end of the network.
struct OutletValue {
  enum class Type { Pressure, Resistance };
  int node = -1;  ///< network end node
  Type type = Type::Pressure;
  double pressure = 0.0;    ///< Pressure: Pa; Resistance: the distal pressure P_d (Pa)
  double resistance = 0.0;  ///< Resistance: p = P_d + R·Q, Q the flow out (Pa·s/m³)
};

/// @brief The network's boundary conditions at one instant, imposed on both models.
///
/// Inlet: a pressure or a flow (into the network). Outlets: listed in `outlets`, else in
/// `outlet_pressures`, else `outlet_pressure`. An RCR outlet is steady (quasi-steady
/// frames too) a resistance Rp + Rd to its distal pressure, as in the network's
/// Poiseuille model.
struct BoundaryValues {
  enum class Inlet { Pressure, Flow };
  int inlet_node = -1;  ///< -1: Network::widest_end()
  Inlet inlet_type = Inlet::Pressure;
  double inlet_pressure = 0.0;                           ///< Pa (Inlet::Pressure)
  double inlet_flow = 0.0;                               ///< m³/s into the network (Inlet::Flow)
  double outlet_pressure = 0.0;                          ///< Pa, every outlet not listed below
  std::vector<std::pair<int, double>> outlet_pressures;  ///< (end node, Pa)
  std::vector<OutletValue> outlets;                      ///< take precedence over the two above
  double viscosity = 3.5e-3;                             ///< Pa·s
  double density = 1060.0;                               ///< kg/m³
};

/// @brief Network solution the FEM is compared with (any network solver can supply it).
struct NetworkFlow {
  std::vector<double> node_pressure;  ///< (num_nodes) Pa
  std::vector<double> segment_flow;   ///< (num_segments) m³/s, node_from -> node_to
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
  double max_rel_diff_drop_away = 0.0;      ///< max |rel_diff_drop| away from junctions
  double max_rel_diff_drop_junction = 0.0;  ///< max |rel_diff_drop| near junctions
  double max_flow_split_error = 0.0;        ///< max |Q_fem/ΣQ_fem − Q_net/ΣQ_net| over outlets
  double max_flow_error = 0.0;              ///< max |Q_fem/Q_net − 1| over outlets
  int tets = 0, unknowns = 0;
  /// Force of the fluid on each no-slip group (boundary_forces; `compare` only), N.
  std::vector<std::pair<std::string, Vec3>> forces;
  double reynolds = 0.0;      ///< inlet Reynolds number of the FEM flow (ρ ū D / η)
  int newton_iterations = 0;  ///< Navier–Stokes: Newton steps (0 for Stokes)
  double mesh_seconds = 0.0, assemble_seconds = 0.0, solve_seconds = 0.0, total_seconds = 0.0;
};

/// @brief The boundary values of a flow spec at time t: its (single) inlet and its
/// outlets (RCR as Rp + Rd); ends of the network without an outlet condition are an error.
/// @throws flowire::Error (input) for several inlets or an end without a condition.
BoundaryValues boundary_values(const flow::FlowSpec& spec, const Network& net, double t);

/// @brief Network pressures and flows for the boundary values (flowire::flow quasi-steady
/// Poiseuille model, sparse solver).
NetworkFlow network_flow(const Network& net, const BoundaryValues& bv);

/// @brief Condition of each mesh group (wall: ignored) for the boundary values.
std::vector<GroupCondition> group_conditions(const TetMesh& mesh, const BoundaryValues& bv);

/// @brief Compare a FEM solution with a network solution (see the file comment).
CompareResult compare_fields(const Network& net, const TetMesh& mesh, const StokesSolution& sol,
                             const NetworkFlow& flow, int inlet_node, int samples_per_branch);

/// @brief Write a solution as quadratic tetrahedra (.vtu, point data `velocity` and
/// `pressure`; edge nodes take the mean pressure of their vertices).
void write_vtu(const std::string& path, const TetMesh& mesh, const StokesSolution& sol);
/// @brief Write the output files into `out_dir` (created if needed), fem_forces.csv
/// (`boundary,fx,fy,fz`: the `forces`) too. Only rank 0 writes.
void write_outputs(const std::string& out_dir, const Network& net, const TetMesh& mesh, const StokesSolution& sol,
                   const CompareResult& result, const FemOptions& opt);

/// @brief The whole comparison: mesh, FEM solve, network solve, compare, and write the
/// files when `out_dir` is not empty. Collective under MPI.
/// @throws flowire::Error as build_mesh, solve_stokes and the flow solver do.
CompareResult compare(const Network& net, const BoundaryValues& bv, const FemOptions& opt, const std::string& out_dir);

/// @brief Time integration of a pulsatile FEM series (see compare_pulsatile).
struct DynamicOptions {
  /// Boundary values at any time of the period (inlet waveform; the outlets listed in
  /// `windkessels` are replaced by their windkessels).
  std::function<BoundaryValues(double)> values_at;
  /// The network solution at a time of the period, in its periodic state (e.g. the rlc
  /// model run over enough periods); empty: the quasi-steady Poiseuille network of the
  /// frame's boundary values.
  std::function<NetworkFlow(double)> network_at;
  /// RCR outlets of the catalogue (flow::OutletBC::Type::Rcr, with C > 0) at their ends:
  /// C dP_c/dt = Q − (P_c − P_d)/R_d, outlet pressure P_c + R_p·Q (Q the flow out).
  std::vector<flow::OutletBC> windkessels;
  double period = 0.0;          ///< s, > 0; the frame times are k·period/N
  bool time_dependent = false;  ///< time-dependent Stokes (UnsteadyStokes) instead of quasi-steady frames
  int steps_per_period = 200;   ///< at least; rounded up to a multiple of the frames
  int max_periods = 40;
  double periodic_tolerance = 1e-5;  ///< max change of the frames' outlet flows over a period / max flow
};

/// @brief A pulsatile series of quasi-steady comparisons.
struct PulsatileResult {
  CompareResult steady;               ///< the comparison at `steady_time` (the fem_compare.* files)
  std::vector<CompareResult> frames;  ///< one per time
  double max_rel_diff_drop_away = 0.0, max_rel_diff_drop_junction = 0.0;  ///< over all frames
  double max_flow_split_error = 0.0, max_flow_error = 0.0;                ///< over all frames
  int factorizations = 0;                                                 ///< FEM matrix factorizations (1 for Stokes)
  double basis_seconds = 0.0;                                             ///< assembly, factorization and unit solves
  double frames_seconds = 0.0;                                            ///< combining the frames and comparing them
  int periods = 0;               ///< dynamic: periods integrated until periodic
  int steps_per_period = 0;      ///< dynamic: time steps per period
  double periodic_change = 0.0;  ///< dynamic: the last period's change (see DynamicOptions)
};

/// @brief Quasi-steady FEM frames at `times` with the boundary values `frames[i]`, and the
/// steady comparison `steady` (at time `steady_time`), all compared with the network.
/// Stokes: one factorization and one unit solve per open boundary (StokesBasis); every
/// frame is a linear combination. Navier–Stokes: every frame is solved on its own.
/// Every frame must have the same inlet node and the same kinds of conditions.
/// Writes, besides the steady files of `compare`: fem_pulsatile.csv (`time`, then the
/// columns of fem_compare.csv), fem_pulsatile_outlets.csv (`time`, then the columns of
/// fem_outlets.csv), and with `write_vtu` fem.pvd + fem_NNNN.vtu.
/// @throws flowire::Error (usage) for inconsistent frames, and as `compare`.
/// With `dyn` (Stokes only), the frames come from a time integration instead: BDF2 with
/// `steps_per_period` steps, each outlet in `dyn->windkessels` carrying its capacitor
/// (BDF2 too: at each step a resistance R_p + 1/(C·D) to a pressure set by the history,
/// D = 3/(2Δt) + 1/(R_d C)), quasi-steady 3D fields or, with `time_dependent`,
/// UnsteadyStokes; period after period until the frames' outlet flows change by less than
/// `periodic_tolerance` (else a numerical error). The frames are those of the last period.
PulsatileResult compare_pulsatile(const Network& net, std::span<const double> times,
                                  std::span<const BoundaryValues> frames, const BoundaryValues& steady,
                                  double steady_time, const FemOptions& opt, const std::string& out_dir,
                                  const DynamicOptions* dyn = nullptr);

}  // namespace flowire::fem
