#include "assembly.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <numeric>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/union_find.hpp"
#include "flowire/flow/solver.hpp"

namespace flowire::flow::detail {
namespace {

void check_node(const Network& net, int node, const char* what) {
  if (node < 0 || node >= net.num_nodes())
    throw_usage_error(fmt::format("flow: {} node {} is not in the network (0..{})", what, node, net.num_nodes() - 1));
}

}  // namespace

Assembly assemble(const Network& net, const FlowSpec& spec, std::vector<double>& resistance, bool steady_rcr) {
  const auto nn = static_cast<size_t>(net.num_nodes());
  const auto ne = static_cast<size_t>(net.num_segments());
  if (!(spec.viscosity > 0.0) || !std::isfinite(spec.viscosity))
    throw_usage_error(fmt::format("flow: viscosity {} must be positive", spec.viscosity));
  if (!spec.segment_laws.empty() && spec.segment_laws.size() != ne)
    throw_usage_error(fmt::format("flow: {} segment laws for a network of {} segments", spec.segment_laws.size(), ne));
  for (size_t s = 0; s < spec.segment_laws.size(); ++s) {
    const auto& law = spec.segment_laws[s];
    if (!(law.resistance_factor > 0.0) || !std::isfinite(law.resistance_factor) || !(law.quadratic >= 0.0) ||
        !std::isfinite(law.quadratic) || !(law.dean >= 0.0) || !std::isfinite(law.dean))
      throw_usage_error(
          fmt::format("flow: segment {}: resistance factor {} must be > 0, quadratic {} and Dean coefficient {} >= 0",
                      s, law.resistance_factor, law.quadratic, law.dean));
    auto ordered = [](const std::array<double, 2>& c) { return c[0] >= 0.0 && c[1] >= c[0] && std::isfinite(c[1]); };
    if (!(law.entry >= 0.0) || !std::isfinite(law.entry) || !ordered(law.entry_forward) || !ordered(law.entry_backward))
      throw_usage_error(fmt::format(
          "flow: segment {}: entrance coefficient {} must be >= 0 and its distances [{}, {}], [{}, {}] ordered", s,
          law.entry, law.entry_forward[0], law.entry_forward[1], law.entry_backward[0], law.entry_backward[1]));
  }
  Assembly a;
  resistance.resize(ne);
  a.conductance.resize(ne);
  for (size_t s = 0; s < ne; ++s) {
    const auto& seg = net.segment(static_cast<int>(s));
    resistance[s] = segment_resistance(spec.viscosity, seg) *
                    (spec.segment_laws.empty() ? 1.0 : spec.segment_laws[s].resistance_factor);
    if (!(resistance[s] > 0.0) || !std::isfinite(resistance[s]))
      throw_input_error(net.source(),
                        fmt::format("segment {}: resistance {} is not positive and finite (r = {} to {}, l = {})", s,
                                    resistance[s], seg.radius_from, seg.radius_to, seg.length));
    a.conductance[s] = 1.0 / resistance[s];
  }
  a.dirichlet.assign(nn, 0);
  a.outlet_conductance.assign(nn, 0.0);
  std::vector<int> bc_count(nn, 0);
  a.sources.emplace_back();  // constant source

  auto add_value = [&](int node, const Waveform& w, double scale) {
    if (w.is_constant()) {
      a.sources[0].node_values.emplace_back(node, scale * w.value);
    } else {
      Source src;
      src.waveform = &w;
      src.node_values.emplace_back(node, scale);
      a.sources.push_back(std::move(src));
    }
  };

  for (const auto& in : spec.inlets) {
    check_node(net, in.node, "inlet");
    ++bc_count[static_cast<size_t>(in.node)];
    if (in.type == InletBC::Type::Pressure) a.dirichlet[static_cast<size_t>(in.node)] = 1;
    add_value(in.node, in.waveform, 1.0);
  }
  bool warned_dynamic = false;
  std::vector<char> dynamic_ground(nn, 0);  // outlets with state of the dynamic model (RCR, coronary)
  for (const auto& o : spec.outlets) {
    check_node(net, o.node, "outlet");
    ++bc_count[static_cast<size_t>(o.node)];
    const auto n = static_cast<size_t>(o.node);
    switch (o.type) {
      case OutletBC::Type::Pressure:
        a.dirichlet[n] = 1;
        add_value(o.node, o.pressure, 1.0);
        break;
      case OutletBC::Type::Flow:  // a flow leaving the network: injected with the opposite sign
        add_value(o.node, o.flow, -1.0);
        break;
      case OutletBC::Type::Rcr:
      case OutletBC::Type::Coronary:
      case OutletBC::Type::Resistance: {
        if (o.type != OutletBC::Type::Resistance) {
          if (!steady_rcr) {  // the dynamic model simulates the outlet's own block
            dynamic_ground[n] = 1;
            break;
          }
          if (!warned_dynamic) {
            warn(fmt::format(
                "flow: the quasi-steady Poiseuille model uses each {} outlet's steady resistance (Rp + Rd, or Ra + "
                "Ram + Rv) to its distal pressure (its compliance needs flow.model: rlc)",
                o.kind()));
            warned_dynamic = true;
          }
        }
        const double r = o.steady_resistance();
        if (!(r > 0.0) || !std::isfinite(r))
          throw_usage_error(fmt::format("flow: outlet at node {}: resistance {} must be positive", o.node, r));
        a.outlet_conductance[n] += 1.0 / r;
        a.sources[0].node_values.emplace_back(o.node, o.steady_pressure() / r);
        break;
      }
    }
  }
  for (size_t i = 0; i < nn; ++i)
    if (bc_count[i] > 1)
      throw_usage_error(fmt::format("flow: node {} has {} boundary conditions; give it one", i, bc_count[i]));

  a.unknown_of_node.assign(nn, -1);
  for (size_t i = 0; i < nn; ++i)
    if (!a.dirichlet[i]) {
      a.unknown_of_node[i] = static_cast<int>(a.node_of_unknown.size());
      a.node_of_unknown.push_back(static_cast<int>(i));
    }

  // Every piece of unknown nodes must see a pressure reference: a Dirichlet neighbour or
  // a resistance to a distal pressure. Otherwise G is singular.
  UnionFind uf(nn);
  std::vector<char> grounded(nn, 0);
  for (size_t s = 0; s < ne; ++s) {
    const auto& seg = net.segment(static_cast<int>(s));
    const bool df = a.dirichlet[static_cast<size_t>(seg.node_from)], dt = a.dirichlet[static_cast<size_t>(seg.node_to)];
    if (!df && !dt) uf.unite(seg.node_from, seg.node_to);
    if (df && !dt) grounded[static_cast<size_t>(seg.node_to)] = 1;
    if (dt && !df) grounded[static_cast<size_t>(seg.node_from)] = 1;
  }
  for (size_t i = 0; i < nn; ++i)
    if (a.outlet_conductance[i] > 0.0 || dynamic_ground[i]) grounded[i] = 1;
  std::vector<char> root_grounded(nn, 0);
  for (size_t i = 0; i < nn; ++i)
    if (!a.dirichlet[i] && grounded[i]) root_grounded[static_cast<size_t>(uf.find(static_cast<int>(i)))] = 1;
  for (size_t i = 0; i < nn; ++i) {
    if (a.dirichlet[i]) continue;
    const auto root = static_cast<size_t>(uf.find(static_cast<int>(i)));
    if (root_grounded[root]) continue;
    std::vector<int> members;
    for (size_t j = 0; j < nn; ++j)
      if (!a.dirichlet[j] && static_cast<size_t>(uf.find(static_cast<int>(j))) == root)
        members.push_back(static_cast<int>(j));
    std::string list;
    for (size_t m = 0; m < members.size() && m < 8; ++m) list += (m ? ", " : "") + std::to_string(members[m]);
    if (members.size() > 8) list += ", ...";
    throw_numerical_error(fmt::format(
        "flow: singular network: a connected piece of {} node(s) (nodes {}) has no pressure reference "
        "(no pressure inlet or outlet and no outlet resistance reaches it); give it a pressure or resistance "
        "outlet, or keep only the inlet's piece (Network::keep_component)",
        members.size(), list));
  }
  return a;
}

Eigen::SparseMatrix<double> nodal_matrix(const Network& net, const Assembly& a) {
  const int nu = a.num_unknowns();
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(static_cast<size_t>(nu) + 4 * static_cast<size_t>(net.num_segments()));
  for (int u = 0; u < nu; ++u) {
    const int i = a.node_of_unknown[static_cast<size_t>(u)];
    double diag = a.outlet_conductance[static_cast<size_t>(i)];
    const auto [b, e] = net.node_segments(i);
    for (const int* p = b; p != e; ++p) diag += a.conductance[static_cast<size_t>(*p)];
    trip.emplace_back(u, u, diag);
  }
  for (int s = 0; s < net.num_segments(); ++s) {
    const auto& seg = net.segment(s);
    const int uf = a.unknown_of_node[static_cast<size_t>(seg.node_from)];
    const int ut = a.unknown_of_node[static_cast<size_t>(seg.node_to)];
    if (uf < 0 || ut < 0) continue;
    const double g = a.conductance[static_cast<size_t>(s)];
    trip.emplace_back(uf, ut, -g);
    trip.emplace_back(ut, uf, -g);
  }
  Eigen::SparseMatrix<double> g(nu, nu);
  g.setFromTriplets(trip.begin(), trip.end());
  g.makeCompressed();
  return g;
}

void add_nodal_rhs(const Network& net, const Assembly& a, const Source& s, double scale, Eigen::VectorXd& b) {
  for (const auto& [node, value] : s.node_values) {
    const auto n = static_cast<size_t>(node);
    if (!a.dirichlet[n]) {
      b[a.unknown_of_node[n]] += scale * value;
      continue;
    }
    const auto [sb, se] = net.node_segments(node);
    for (const int* p = sb; p != se; ++p) {
      const auto& seg = net.segment(*p);
      const int other = seg.node_from == node ? seg.node_to : seg.node_from;
      const int u = a.unknown_of_node[static_cast<size_t>(other)];
      if (u >= 0) b[u] += scale * value * a.conductance[static_cast<size_t>(*p)];
    }
  }
}

void add_dirichlet(const Assembly& a, const Source& s, double scale, double* pressures) {
  for (const auto& [node, value] : s.node_values)
    if (a.dirichlet[static_cast<size_t>(node)]) pressures[node] += scale * value;
}

}  // namespace flowire::flow::detail
