#pragma once
/// @file boundary_values.hpp
/// @brief The network's boundary conditions at one instant, and what each model makes of
/// them: the network's own solution (network_flow) and the condition of every open group
/// of the FEM mesh (group_conditions).
///
/// Both models of the comparison (compare.hpp) are driven by the same values: a pressure or
/// a flow at the inlet end, and at every outlet end a pressure or a resistance to a distal
/// pressure. The FEM enforces them through its affine structure (stokes.hpp); the network
/// solves them with its quasi-steady Poiseuille model (flowire::flow, sparse solver).
#include <array>
#include <span>
#include <utility>
#include <vector>

#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/stokes.hpp"
#include "flowire/flow/spec.hpp"

namespace flowire::flow::fem {

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
  /// > 0: the network is in total pressure (a calibration, calibrate.hpp) with this density: its
  /// nodes hold the energy per unit flow, p + ½ρ|u|² weighted by the flux, but for the outlets,
  /// which hold their static values; the comparison is then one of total pressures
  double kinetic_density = 0.0;
  /// (nodes, or empty: 1) in total pressure, the kinetic energy factor α of each outlet: its total
  /// is its static value plus α½ρ(Q/A)²
  std::vector<double> end_alpha;
  /// (segments, or empty) with junction losses, each segment's static pressure below its node's
  /// at its start and at its end (flow/junction.hpp; 0 away from junctions)
  std::vector<std::array<double, 2>> segment_end_drop;
};

/// @brief The inlet end node of the boundary values: `bv.inlet_node`, or
/// Network::widest_end() when it is not set.
int inlet_of(const Network& net, const BoundaryValues& bv);

/// @brief The boundary values of a flow spec at time t: its (single) inlet and its
/// outlets (RCR as Rp + Rd); ends of the network without an outlet condition are an error.
/// @throws flowire::Error (input) for several inlets or an end without a condition.
BoundaryValues boundary_values(const flow::FlowSpec& spec, const Network& net, double t);

/// @brief `bv` on a renumbered network (cap_cut.hpp): the inlet (resolved on `net` when it was
/// not set, so that it stays the end the mesh opened as the inlet) and every outlet node taken
/// through `node` (one entry per node of `net`).
/// @throws flowire::Error (usage) for a node that `node` drops.
BoundaryValues renumbered(const BoundaryValues& bv, const Network& net, std::span<const int> node);

/// @brief Network pressures and flows for the boundary values (flowire::flow quasi-steady
/// Poiseuille model, sparse solver; Newton's method where `laws`, one per segment, have quadratic
/// terms; with @p junction_losses, Mynard & Valen-Sendstad's junction model at every junction,
/// flow/junction.hpp, and the drops it gives each branch's end in NetworkFlow::segment_end_drop).
NetworkFlow network_flow(const Network& net, const BoundaryValues& bv, std::span<const flow::SegmentLaw> laws = {},
                         bool junction_losses = false);

/// @brief Condition of each mesh group (wall: ignored) for the boundary values.
/// @throws flowire::Error (usage) for a negative outlet resistance.
std::vector<GroupCondition> group_conditions(const TetMesh& mesh, const BoundaryValues& bv);

}  // namespace flowire::flow::fem
