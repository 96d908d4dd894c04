// flow-fem-work-precision: the network model and the 3D finite elements on one Y bifurcation,
// each against the finest FEM solution: outlet-flow error against run time, the network over
// segment refinement (the Poiseuille model is exact on every cylinder, so its error is the
// model's: the junction), the FEM over mesh size (its discretization error).
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <vector>

#include "flowire/common/diagnostics.hpp"
#include "flowire/flow/fem/boundary_values.hpp"
#include "flowire/flow/fem/compare.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/flow/spec.hpp"
#include "flowire/vessels/generators.hpp"
#include "studies.hpp"

namespace flowire::bench {

namespace {

using Clock = std::chrono::steady_clock;

vessels::Network y_network(double max_segment_length) {
  vessels::YBifurcationParams p;
  p.parent_radius = 1e-3;
  p.parent_length = 10e-3;
  p.child_length = 10e-3;
  p.asymmetry = 0.4;
  return vessels::Network::build(vessels::y_bifurcation(p), {.max_segment_length = max_segment_length});
}

constexpr double kInletPressure = 200.0, kOutletPressure = 10.0;  // Pa

/// Outlet flows (m³/s) ordered like the outlets' positions in @p ends_at.
std::vector<double> network_flows(const vessels::Network& net, const std::vector<vessels::Vec3>& ends_at,
                                  double& seconds) {
  flow::FlowSpec spec;
  flow::InletBC in;
  in.type = flow::InletBC::Type::Pressure;
  in.waveform = flow::Waveform::constant(kInletPressure);
  spec.inlets.push_back(in);
  flow::OutletBC o;
  o.type = flow::OutletBC::Type::Pressure;
  o.pressure = flow::Waveform::constant(kOutletPressure);
  spec.outlets.push_back(o);
  flow::resolve_nodes(spec, net);
  // Setup and one frame, repeated so that the clock resolves it.
  const int repeats = 200;
  std::unique_ptr<flow::FlowSolver> solver;
  const auto t0 = Clock::now();
  for (int i = 0; i < repeats; ++i) {
    solver = flow::make_solver(net, spec);
    solver->advance(0.0);
  }
  seconds = std::chrono::duration<double>(Clock::now() - t0).count() / repeats;
  std::vector<double> q;
  for (const auto& x : ends_at) {
    int best = -1;
    for (int e : net.ends())
      if (best < 0 || (net.node(e) - x).norm() < (net.node(best) - x).norm()) best = e;
    const auto [b, e] = net.node_segments(best);
    q.push_back(std::abs(solver->segment_state(*b).flow_rate));
  }
  return q;
}

double flow_error(const std::vector<double>& q, const std::vector<double>& ref) {
  double total = 0.0, err = 0.0;
  for (double r : ref) total += r;
  for (size_t k = 0; k < q.size(); ++k) err = std::max(err, std::abs(q[k] - ref[k]));
  return err / total;
}

}  // namespace

int flow_fem_work_precision(const Options& o) {
  const vessels::Network net = y_network(5e-3);
  flow::fem::BoundaryValues bv;
  bv.inlet_pressure = kInletPressure;
  bv.outlet_pressure = kOutletPressure;
  flow::fem::FemOptions opt;
  opt.write_png = false;
  opt.write_vtu = false;
  const double ref_factor = o.reduced ? 0.4 : 0.2;
  const std::vector<double> factors =
      o.reduced ? std::vector<double>{0.9, 0.6} : std::vector<double>{0.9, 0.6, 0.45, 0.3};
  opt.size_factor = ref_factor;
  const flow::fem::CompareResult ref = flow::fem::compare(net, bv, opt, "");
  std::vector<vessels::Vec3> ends_at;
  std::vector<double> q_ref;
  for (const auto& out : ref.outlets) {
    ends_at.push_back(net.node(out.node));
    q_ref.push_back(out.flow_fem);
  }
  std::string csv = "model,parameter,size,error,seconds\n";
  csv += fmt::format("fem_reference,{:g},{},0,{:.6e}\n", ref_factor, ref.tets, ref.total_seconds);
  for (double f : factors) {
    opt.size_factor = f;
    const flow::fem::CompareResult r = flow::fem::compare(net, bv, opt, "");
    std::vector<double> q;
    for (const auto& out : r.outlets) q.push_back(out.flow_fem);
    csv += fmt::format("fem,{:g},{},{:.6e},{:.6e}\n", f, r.tets, flow_error(q, q_ref), r.total_seconds);
  }
  for (double h : {10e-3, 5e-3, 2.5e-3, 1.25e-3, 0.625e-3}) {
    const vessels::Network n = y_network(h);
    double seconds = 0.0;
    const auto q = network_flows(n, ends_at, seconds);
    csv += fmt::format("network,{:g},{},{:.6e},{:.6e}\n", h, n.num_segments(), flow_error(q, q_ref), seconds);
  }
  (void)take_warnings();
  emit(o, "flow_fem_work_precision.csv", csv);
  return 0;
}

}  // namespace flowire::bench
