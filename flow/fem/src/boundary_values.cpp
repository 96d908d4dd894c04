// The network's boundary conditions at one instant (BoundaryValues) from a flow spec, and
// what each model of the comparison makes of them: the network's quasi-steady Poiseuille
// solution (network_flow) and the condition of every open group of the FEM mesh
// (group_conditions).
#include "flowire/flow/fem/boundary_values.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "flowire/common/error.hpp"
#include "flowire/flow/junction.hpp"
#include "flowire/flow/solver.hpp"

namespace flowire::flow::fem {
namespace {

/// The condition of the outlet at end `node`: its entry in `outlets`, else its pressure in
/// `outlet_pressures`, else `outlet_pressure`.
OutletValue outlet_value_of(const BoundaryValues& bv, int node) {
  for (const auto& o : bv.outlets)
    if (o.node == node) return o;
  OutletValue o;
  o.node = node;
  o.pressure = bv.outlet_pressure;
  for (const auto& [n, p] : bv.outlet_pressures)
    if (n == node) o.pressure = p;
  return o;
}

}  // namespace

int inlet_of(const Network& net, const BoundaryValues& bv) {
  return bv.inlet_node >= 0 ? bv.inlet_node : net.widest_end();
}

BoundaryValues boundary_values(const flow::FlowSpec& spec, const Network& net, double t) {
  if (spec.inlets.size() != 1)
    throw_input_error("fem",
                      fmt::format("the comparison needs exactly one inlet; the flow has {}", spec.inlets.size()));
  BoundaryValues bv;
  const auto& in = spec.inlets.front();
  bv.inlet_node = in.node >= 0 ? in.node : net.widest_end();
  if (in.type == flow::InletBC::Type::Flow) {
    bv.inlet_type = BoundaryValues::Inlet::Flow;
    bv.inlet_flow = in.waveform(t);
  } else {
    bv.inlet_pressure = in.waveform(t);
  }
  for (const auto& o : spec.outlets) {
    OutletValue v;
    v.node = o.node;
    switch (o.type) {
      case flow::OutletBC::Type::Pressure:
        v.pressure = o.pressure(t);
        break;
      case flow::OutletBC::Type::Resistance:
      case flow::OutletBC::Type::Rcr:  // quasi-steady: the capacitors carry no flow
      case flow::OutletBC::Type::Coronary:
        v.type = OutletValue::Type::Resistance;
        v.pressure = o.steady_pressure();
        v.resistance = o.steady_resistance();
        break;
      case flow::OutletBC::Type::Flow:
        throw_input_error("fem", fmt::format("outlet node {}: a fixed outflow is not a condition the comparison "
                                             "takes (pressure, resistance, RCR or coronary)",
                                             o.node));
    }
    bv.outlets.push_back(v);
  }
  for (int e : net.ends()) {
    if (e == bv.inlet_node) continue;
    if (std::none_of(bv.outlets.begin(), bv.outlets.end(), [&](const OutletValue& o) { return o.node == e; }))
      throw_input_error("fem",
                        fmt::format("network end node {} has no outlet condition (the FEM mesh opens every end)", e));
  }
  bv.viscosity = spec.viscosity;
  bv.density = spec.density;
  return bv;
}

BoundaryValues renumbered(const BoundaryValues& bv, const Network& net, std::span<const int> node) {
  if (node.size() != static_cast<size_t>(net.num_nodes()))
    throw_usage_error(fmt::format("fem: a node map of {} entries for {} nodes", node.size(), net.num_nodes()));
  auto map = [&](int n) {
    const int m = n >= 0 && static_cast<size_t>(n) < node.size() ? node[static_cast<size_t>(n)] : -1;
    if (m < 0) throw_usage_error(fmt::format("fem: boundary node {} is not in the renumbered network", n));
    return m;
  };
  BoundaryValues out = bv;
  out.inlet_node = map(inlet_of(net, bv));
  for (auto& [n, p] : out.outlet_pressures) n = map(n);
  for (auto& o : out.outlets) o.node = map(o.node);
  return out;
}

NetworkFlow network_flow(const Network& net, const BoundaryValues& bv, std::span<const flow::SegmentLaw> laws,
                         bool junction_losses) {
  flow::FlowSpec spec;
  if (junction_losses) spec.junctions = flow::find_junctions(net);
  spec.solver = flow::SolverKind::Sparse;
  spec.segment_laws.assign(laws.begin(), laws.end());
  spec.viscosity = bv.viscosity;
  spec.density = bv.density;
  const int inlet = inlet_of(net, bv);
  flow::InletBC in;
  in.node = inlet;
  if (bv.inlet_type == BoundaryValues::Inlet::Flow) {
    in.type = flow::InletBC::Type::Flow;
    in.waveform = flow::Waveform::constant(bv.inlet_flow);
  } else {
    in.type = flow::InletBC::Type::Pressure;
    in.waveform = flow::Waveform::constant(bv.inlet_pressure);
  }
  spec.inlets.push_back(in);
  for (int e : net.ends()) {
    if (e == inlet) continue;
    const OutletValue v = outlet_value_of(bv, e);
    flow::OutletBC out = v.type == OutletValue::Type::Resistance
                             ? flow::OutletBC::with_resistance(v.resistance, v.pressure)
                             : flow::OutletBC::at_pressure(v.pressure);
    out.node = e;
    spec.outlets.push_back(out);
  }
  auto solver = flow::make_solver(net, spec);
  NetworkFlow nf;
  nf.node_pressure.resize(static_cast<size_t>(net.num_nodes()));
  nf.segment_flow.resize(static_cast<size_t>(net.num_segments()));
  solver->solve_at(0.0, nf.node_pressure, nf.segment_flow);
  if (!spec.junctions.empty())
    flow::segment_end_drops(net, spec.junctions, spec.density, nf.segment_flow.data(), nf.segment_end_drop);
  return nf;
}

std::vector<GroupCondition> group_conditions(const TetMesh& mesh, const BoundaryValues& bv) {
  std::vector<GroupCondition> c(mesh.groups.size());
  for (size_t g = 0; g < mesh.groups.size(); ++g) {
    const auto& grp = mesh.groups[g];
    if (grp.kind == BoundaryGroup::Kind::Inlet) {
      // The FEM flux is outward: an inflow into the network is a negative outward flow.
      c[g] = bv.inlet_type == BoundaryValues::Inlet::Flow ? GroupCondition::with_flow(-bv.inlet_flow)
                                                          : GroupCondition::at_pressure(bv.inlet_pressure);
    } else if (grp.kind == BoundaryGroup::Kind::Outlet) {
      const OutletValue v = outlet_value_of(bv, grp.node);
      if (v.type == OutletValue::Type::Resistance && !(v.resistance >= 0.0))
        throw_usage_error(fmt::format("fem: outlet {} has a negative resistance", grp.node));
      c[g] = v.type == OutletValue::Type::Resistance ? GroupCondition::with_resistance(v.resistance, v.pressure)
                                                     : GroupCondition::at_pressure(v.pressure);
    }
  }
  return c;
}

}  // namespace flowire::flow::fem
