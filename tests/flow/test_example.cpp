// The aorta_flow example through the library API: aortic arch, 120/80 mmHg at 72 bpm,
// Murray-split peripheral resistance, one cycle written as a VTK series (and a PNG when a
// display is available).
#include <gtest/gtest.h>

#include <cstdlib>

#include "flowire/common/units.hpp"
#include "flowire/flow/output.hpp"
#include "flowire/flow/rlc.hpp"
#include "flowire/vessels/generators.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

TEST(FlowExample, AorticArchOverOneCycle) {
  const Network net = Network::build(vessels::aortic_arch());
  const double period = 60.0 / 72.0;
  FlowSpec spec = default_spec(net, Waveform::sine(120 * units::mmHg, 80 * units::mmHg, period));
  double sum_r3 = 0.0;
  for (const auto& o : spec.outlets) sum_r3 += std::pow(net.segment(*net.node_segments(o.node).first).radius, 3);
  const double total = 1.2 * units::mmHg * 1e6;  // 1.2 mmHg·s/mL in Pa·s/m³
  for (auto& o : spec.outlets) {
    o.type = OutletBC::Type::Resistance;
    o.resistance = total * sum_r3 / std::pow(net.segment(*net.node_segments(o.node).first).radius, 3);
  }
  auto s = make_solver(net, spec);
  const auto frames = sample_frames(*s, 0.0, period, 20, false);
  // Mean inflow over the cycle: 100 mmHg over about 1.2 mmHg·s/mL → about 80 mL/s (≈ 5 L/min).
  const int inlet = spec.inlets[0].node;
  const int first = *net.node_segments(inlet).first;
  const double sign = net.segment(first).node_from == inlet ? 1.0 : -1.0;
  double mean_q = 0.0;
  for (const auto& f : frames) mean_q += sign * f.flow[static_cast<size_t>(first)] / frames.size();
  EXPECT_GT(mean_q, 60e-6);
  EXPECT_LT(mean_q, 90e-6);
  const auto dir = flowire::testing::scratch_dir("flow_example_aorta");
  write_network_series(*s, frames, dir);
  write_nodes_csv(net, frames, dir / "nodes.csv");
  write_segments_csv(*s, frames, dir / "segments.csv");
  EXPECT_TRUE(std::filesystem::exists(dir / "network_000019.vtp"));
#ifdef FLOWIRE_TEST_HAVE_VTK
  const bool can_render = std::getenv("DISPLAY") != nullptr;
#else
  const bool can_render = false;
#endif
  if (can_render) {
    RenderOptions opt;
    opt.title = "aortic arch, t = T/4 (systolic peak)";
    opt.view_direction = Vec3(0.0, 1.0, 0.0);
    render_network_png(net, frames[5].pressure, dir / "pressure.png", opt);
    EXPECT_TRUE(std::filesystem::exists(dir / "pressure.png"));
  }
}

TEST(FlowExample, AorticArchRlcWithWindkesselsIsPeriodic) {
  const Network net = Network::build(vessels::aortic_arch());
  const double period = 60.0 / 72.0;
  FlowSpec spec = default_spec(net, Waveform::sine(120 * units::mmHg, 80 * units::mmHg, period));
  spec.model = Model::Rlc;
  spec.inertance = Inertance::Womersley;
  spec.dt = period / 500;
  double sum_r3 = 0.0;
  for (const auto& o : spec.outlets) sum_r3 += std::pow(net.segment(*net.node_segments(o.node).first).radius, 3);
  for (auto& o : spec.outlets) {
    const double f = sum_r3 / std::pow(net.segment(*net.node_segments(o.node).first).radius, 3);
    o.type = OutletBC::Type::Rcr;
    o.rp = 0.1 * units::mmHg * 1e6 * f;  // total 0.1 + 1.1 mmHg·s/mL, 1.5 mL/mmHg
    o.rd = 1.1 * units::mmHg * 1e6 * f;
    o.c = 1.5e-6 / units::mmHg / f;
  }
  auto s = make_solver(net, spec);
  const auto info = periodic_info(*s);
  EXPECT_TRUE(info.converged) << info.cycles << " cycles, change " << info.last_change;
  // Mean inflow over a periodic cycle: 100 mmHg over the 1.2 mmHg·s/mL of the windkessels.
  const int inlet = spec.inlets[0].node;
  const int first = *net.node_segments(inlet).first;
  const double sign = net.segment(first).node_from == inlet ? 1.0 : -1.0;
  double qmin = 1e9, qmax = -1e9, mean = 0.0;
  for (int k = 0; k < 100; ++k) {
    s->advance(period * k / 100);
    const double q = sign * s->segment_flow(first);
    qmin = std::min(qmin, q);
    qmax = std::max(qmax, q);
    mean += q / 100;
  }
  EXPECT_GT(mean, 50e-6);
  EXPECT_LT(mean, 110e-6);
  EXPECT_GT(qmax - qmin, 0.0);
}

}  // namespace
}  // namespace flowire::flow
