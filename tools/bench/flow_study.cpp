// flow-frame-cost: per-frame cost of the three quasi-steady solvers over network sizes, the
// dense/superposition ratio measured in the same run; rlc vs Womersley amplitude error vs dt.
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "flowire/common/diagnostics.hpp"
#include "flowire/flow/profile.hpp"
#include "flowire/flow/rlc.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/vessels/generators.hpp"
#include "studies.hpp"

namespace flowire::bench {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct NamedNetwork {
  std::string name;
  vessels::Network net;
};

/// The aortic arch split into about `target` segments.
vessels::Network arch_with_segments(int target) {
  const auto c = vessels::aortic_arch({});
  vessels::BuildOptions b;
  b.max_segment_length = 5e-3;
  double total = vessels::Network::build(c, b).counts().total_length;
  b.max_segment_length = total / target;
  vessels::Network net = vessels::Network::build(c, b);
  // Splitting rounds up per branch: shrink/grow once toward the target.
  b.max_segment_length *= static_cast<double>(net.num_segments()) / target;
  return vessels::Network::build(c, b);
}

/// Mean seconds of a frame: advance(t) then read `k` segment flows (all when k < 0).
double frame_seconds(flow::FlowSolver& s, int frames, int k, std::vector<double>& buf) {
  const int ns = s.network().num_segments();
  double sink = 0.0;
  const auto t0 = Clock::now();
  for (int f = 0; f < frames; ++f) {
    const double t = 0.01 * f;
    if (k < 0) {
      s.solve_at(t, std::span<double>(buf.data(), static_cast<size_t>(s.network().num_nodes())),
                 std::span<double>(buf.data() + s.network().num_nodes(), static_cast<size_t>(ns)));
      sink += buf[0];
    } else {
      s.advance(t);
      for (int i = 0; i < k; ++i) sink += s.segment_flow((i * 7919) % ns);
    }
  }
  const double sec = since(t0) / frames;
  if (sink == 12345.678) std::fputs("", stderr);  // keep the reads
  return sec;
}

}  // namespace

int flow_frame_cost(const Options& o) {
  std::string csv =
      "network,segments,nodes,solver,setup_seconds,frame_all_seconds,frame_wire_seconds,ratio_dense_over_"
      "superposition\n";
  std::vector<NamedNetwork> nets;
  const std::vector<int> depths = o.reduced ? std::vector<int>{5, 7, 9} : std::vector<int>{5, 7, 9, 10, 11};
  for (int d : depths) nets.push_back({fmt::format("binary_tree_d{}", d), vessels::binary_tree({.depth = d})});
  nets.push_back({"aortic_arch_5mm", vessels::Network::build(vessels::aortic_arch({}), {})});
  nets.push_back({"aortic_arch_2500", arch_with_segments(2500)});
  const auto inlet = flow::Waveform::sine(120 * 133.322, 80 * 133.322, 0.833);
  for (const auto& [name, net] : nets) {
    std::vector<double> buf(static_cast<size_t>(net.num_nodes() + net.num_segments()));
    const int frames = net.num_segments() > 1500 ? 40 : 200;
    const int wire_segments = std::min(100, net.num_segments());  // a wire spans ~100 segments
    double dense_frame = 0.0, super_frame = 0.0;
    for (auto kind : {flow::SolverKind::DenseInverse, flow::SolverKind::Superposition, flow::SolverKind::Sparse}) {
      // The dense inverse is O((N+E)³) to set up: skip it above ~5,000 unknowns.
      if (kind == flow::SolverKind::DenseInverse && net.num_nodes() + net.num_segments() > 5200) continue;
      auto spec = flow::default_spec(net, inlet);
      spec.solver = kind;
      const auto t0 = Clock::now();
      auto s = flow::make_solver(net, spec);
      const double setup = since(t0);
      const double all = frame_seconds(*s, frames, -1, buf);
      const double wire = frame_seconds(*s, frames, wire_segments, buf);
      if (kind == flow::SolverKind::DenseInverse) dense_frame = all;
      if (kind == flow::SolverKind::Superposition) super_frame = all;
      csv += fmt::format("{},{},{},{},{:.6e},{:.6e},{:.6e},{}\n", name, net.num_segments(), net.num_nodes(),
                         flow::to_string(kind), setup, all, wire,
                         kind == flow::SolverKind::Superposition && dense_frame > 0
                             ? fmt::format("{:.4g}", dense_frame / super_frame)
                             : std::string());
    }
  }
  emit(o, "flow_frame_cost.csv", csv);

  // RLC (Womersley inertance 4ρl/(3πr²), rigid wall) vs the exact Womersley flow ratio in a
  // tube (r = 2 mm, l = 5 cm), amplitude and phase error vs steps per cycle.
  std::string rlc =
      "alpha,inertance,steps_per_cycle,dt,amplitude_error,phase_error_deg,quasi_steady_amplitude_error,seconds\n";
  constexpr double eta = 3.5e-3, rho = 1060.0, R = 2e-3, l = 0.05;
  vessels::BuildOptions bo;
  bo.max_segment_length = l;
  const auto tube = vessels::Network::build(vessels::straight_tube({.length = l, .radius = R}), bo);
  const int inlet_node = 0;
  const int outlet_node = tube.segment(0).node_from == 0 ? tube.segment(0).node_to : tube.segment(0).node_from;
  const std::vector<int> spc =
      o.reduced ? std::vector<int>{10, 40, 160} : std::vector<int>{5, 10, 20, 40, 80, 160, 320, 640};
  for (double alpha : {2.0, 3.0, 4.0})
    for (auto inert : {flow::Inertance::Womersley, flow::Inertance::Poiseuille})
      for (int k : spc) {
        const double omega = alpha * alpha * eta / (rho * R * R);
        const double period = 2.0 * std::numbers::pi / omega;
        const double amp = 100.0;
        flow::FlowSpec spec;
        spec.model = flow::Model::Rlc;
        spec.inertance = inert;
        spec.wall_youngs_modulus = 0.0;
        spec.dt = period / k;
        spec.rho_infinity = 1.0;
        spec.periodic_tolerance = 1e-10;
        spec.inlets.push_back({.node = inlet_node,
                               .type = flow::InletBC::Type::Pressure,
                               .waveform = flow::Waveform::sine(1000.0 + amp, 1000.0 - amp, period)});
        flow::OutletBC out;
        out.node = outlet_node;
        out.pressure = flow::Waveform::constant(1000.0);
        spec.outlets.push_back(out);
        const auto t0 = Clock::now();
        auto s = flow::make_solver(tube, spec);
        double a = 0.0, b = 0.0;
        for (int i = 0; i < k; ++i) {
          const double t = period * i / k;
          s->advance(t);
          a += 2.0 / k * s->segment_flow(0) * std::sin(omega * t);
          b += 2.0 / k * s->segment_flow(0) * std::cos(omega * t);
        }
        const double sec = since(t0);
        const double qp = amp / flow::poiseuille_resistance(eta, l, R);
        const auto ratio = std::complex<double>(b, -a) / std::complex<double>(0.0, -qp);
        const auto exact = flow::womersley_flow_ratio(alpha);
        const double amp_err = std::abs(std::abs(ratio) - std::abs(exact)) / std::abs(exact);
        const double ph_err = std::abs(std::arg(ratio) - std::arg(exact)) * 180.0 / std::numbers::pi;
        rlc += fmt::format("{:g},{},{},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e}\n", alpha,
                           inert == flow::Inertance::Womersley ? "womersley" : "poiseuille", k, spec.dt, amp_err,
                           ph_err, std::abs(1.0 - std::abs(exact)) / std::abs(exact), sec);
      }
  (void)take_warnings();
  emit(o, "rlc_womersley.csv", rlc);
  return 0;
}

}  // namespace flowire::bench
