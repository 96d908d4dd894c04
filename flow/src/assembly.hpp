#pragma once
// Internal: boundary conditions turned into linear sources, and the nodal conductance system.
//
// Every boundary value that varies in time is one source k with waveform f_k; all constant
// values are folded into source 0 (coefficient 1). A source is a list of (node, value):
// at a pressure (Dirichlet) node the value is the prescribed pressure, at any other node
// the flow injected into it (inlet flow, or Pd/R of a resistance outlet).
#include <Eigen/Sparse>
#include <utility>
#include <vector>

#include "flowire/flow/spec.hpp"

namespace flowire::flow::detail {

struct Source {
  const Waveform* waveform = nullptr;  ///< nullptr: constant (coefficient 1)
  std::vector<std::pair<int, double>> node_values;
};

struct Assembly {
  std::vector<double> conductance;         // (num_segments) 1/R
  std::vector<char> dirichlet;             // (num_nodes) pressure prescribed
  std::vector<double> outlet_conductance;  // (num_nodes) 1/R_outlet to a distal pressure, 0 if none
  std::vector<int> unknown_of_node;        // (num_nodes) -1 at Dirichlet nodes
  std::vector<int> node_of_unknown;        // (num_unknowns)
  std::vector<Source> sources;             // [0] constant
  [[nodiscard]] int num_unknowns() const { return static_cast<int>(node_of_unknown.size()); }
  [[nodiscard]] int num_sources() const { return static_cast<int>(sources.size()); }
  /// Coefficients f_k(t) of every source (allocation-free).
  void coefficients(double t, double* out) const {
    for (size_t k = 0; k < sources.size(); ++k) out[k] = sources[k].waveform ? (*sources[k].waveform)(t) : 1.0;
  }
};

/// Validate BCs, compute resistances, build the source list and check that every connected
/// piece has a pressure reference (else a numerical flowire::Error naming it).
/// `steady_rcr`: RCR outlets become resistances Rp + Rd (with a warning).
Assembly assemble(const Network& net, const FlowSpec& spec, std::vector<double>& resistance, bool steady_rcr = true);

/// The nodal conductance matrix G over unknown nodes (both triangles).
Eigen::SparseMatrix<double> nodal_matrix(const Network& net, const Assembly& a);

/// Right-hand side of G p_u = b for one source scaled by `scale`, added to `b`.
void add_nodal_rhs(const Network& net, const Assembly& a, const Source& s, double scale, Eigen::VectorXd& b);

/// Full node pressures from unknowns and a source's Dirichlet values (scaled).
void add_dirichlet(const Assembly& a, const Source& s, double scale, double* pressures);

}  // namespace flowire::flow::detail
