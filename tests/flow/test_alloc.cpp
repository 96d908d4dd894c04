// The per-frame and per-query paths the wire coupling calls allocate nothing.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "flow_test_networks.hpp"
#include "flowire/flow/solver.hpp"

namespace {
std::atomic<long> g_allocations{0};
}

// Count every allocation of this test program (the count is only read by this test).
void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace flowire::flow {
namespace {

TEST(FlowAllocation, AdvanceAndVelocityQueriesDoNotAllocate) {
  const Network net = test::random_network(500, 10, 3);
  for (const auto profile : {Profile::Laminar, Profile::Womersley}) {
    FlowSpec spec = default_spec(net, Waveform::sine(16000.0, 10666.0, 0.8));
    spec.profile = profile;
    auto s = make_solver(net, spec);
    double sum = 0.0;
    // The first velocity query in a segment tabulates its Womersley shape (once per run).
    for (int seg = 0; seg < net.num_segments(); ++seg) sum += s->velocity_at(seg, net.node(net.segment(seg).node_from)).norm();
    const long before = g_allocations.load();
    for (int k = 0; k < 2000; ++k) {
      const double t = 1e-3 * k;
      s->advance(t);
      const int seg = k % net.num_segments();
      const auto& sg = net.segment(seg);
      const Vec3 p = 0.5 * (net.node(sg.node_from) + net.node(sg.node_to)) + Vec3(0.0, 0.3 * sg.radius, 0.0);
      sum += s->velocity_at(seg, p).norm() + s->axial_velocity_at(seg, p, t + 0.01) + s->segment_flow(seg) +
             s->segment_state(seg).wall_shear_stress;
    }
    EXPECT_EQ(g_allocations.load() - before, 0) << (profile == Profile::Laminar ? "laminar" : "womersley");
    EXPECT_TRUE(std::isfinite(sum));
  }
}

}  // namespace
}  // namespace flowire::flow
