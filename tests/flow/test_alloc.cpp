// The per-frame and per-query paths the wire coupling calls, and the svZeroDSolver time
// step, allocate nothing.
#include <SuiteSparse_config.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <new>

#include "flow_test_networks.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/flow/svzerod/integrator.hpp"
#include "flowire/flow/svzerod/model.hpp"
#include "flowire_test.hpp"

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
    for (int seg = 0; seg < net.num_segments(); ++seg)
      sum += s->velocity_at(seg, net.node(net.segment(seg).node_from)).norm();
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

// The svZeroDSolver network's time step allocates nothing, C++ or C (SuiteSparse), for a
// linear model and for one with stenoses (Newton with refactorizations of J).

namespace {
std::atomic<long> g_c_allocations{0};
void* counting_malloc(size_t n) {
  ++g_c_allocations;
  return std::malloc(n);
}
void* counting_calloc(size_t n, size_t size) {
  ++g_c_allocations;
  return std::calloc(n, size);
}
void* counting_realloc(void* p, size_t n) {
  ++g_c_allocations;
  return std::realloc(p, n);
}
}  // namespace

namespace flowire::flow {
namespace {

TEST(FlowAllocation, SvZeroDStepsDoNotAllocate) {
  SuiteSparse_config.malloc_func = counting_malloc;
  SuiteSparse_config.calloc_func = counting_calloc;
  SuiteSparse_config.realloc_func = counting_realloc;
  const auto dir = flowire::testing::scratch_dir("flow_alloc_svzerod");
  for (const double stenosis : {0.0, 40.0}) {
    const auto path = dir / "m.json";
    std::ofstream(path) << R"({"simulation_parameters": {"number_of_cardiac_cycles": 1,
      "number_of_time_pts_per_cardiac_cycle": 11},
      "boundary_conditions": [{"bc_name": "IN", "bc_type": "FLOW",
                               "bc_values": {"Q": [1.0, 3.0, 1.0], "t": [0.0, 0.5, 1.0]}},
                              {"bc_name": "OUT", "bc_type": "RCR", "bc_values": {"Rp": 10.0, "C": 0.01, "Rd": 100.0}}],
      "vessels": [{"vessel_id": 0, "vessel_name": "v", "zero_d_element_type": "BloodVessel",
                   "zero_d_element_values": {"R_poiseuille": 2.0, "C": 0.05, "L": 0.3, "stenosis_coefficient": )"
                        << stenosis << R"(},
                   "boundary_conditions": {"inlet": "IN", "outlet": "OUT"}}]})";
    const svzerod::Model m = svzerod::read_model(path.string());
    svzerod::System sys(m.block_pointers(), m.unknowns, m.period, m.file);
    sys.set_phase(false, 0.0);
    svzerod::GeneralizedAlpha ga(sys, 0.5, 0.01, 1e-10, 30, m.file);
    svzerod::State s = m.initial;
    ga.step(s, 0.0);  // the first factorization with pivoting allocates its factors
    const long before = g_allocations.load(), c_before = g_c_allocations.load();
    for (int k = 1; k < 300; ++k) ga.step(s, 0.01 * k);
    EXPECT_EQ(g_allocations.load() - before, 0) << "stenosis " << stenosis;
    EXPECT_EQ(g_c_allocations.load() - c_before, 0) << "stenosis " << stenosis;
    EXPECT_GE(sys.factorizations(), stenosis > 0.0 ? 300 : 1);  // Newton refactorizes J
    EXPECT_TRUE(s.y.allFinite());
  }
}

}  // namespace
}  // namespace flowire::flow
