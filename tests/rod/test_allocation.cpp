// A time step allocates nothing: every buffer is sized at construction. Counts calls to
// the global operator new around step() and solve_static().
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <numbers>
#include <vector>

#include "flowire/rod/simulator.hpp"
#include "flowire_test.hpp"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t n) {
  if (g_counting.load()) ++g_allocations;
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace flowire::rod {
namespace {

TEST(RodAllocation, StepsAllocateNothing) {
  WireSpec spec;
  spec.length = 0.3;
  spec.inserted_length = 0.1;
  spec.segment_length = 1e-3;
  spec.tip.shape = TipShape::J;
  spec.tip.bend_radius = 0.003;
  spec.damping = 1e-3;
  RodSimulator sim(spec);
  sim.set_gravity({0.0, 0.0, -9.81});
  sim.set_insertion_speed(0.1);  // vertices are added during the steps
  sim.set_rotation_speed(2.0 * std::numbers::pi);
  sim.add_external(std::make_shared<ExternalForceFunction>([](const RodView& rod, ForceAccumulator& out) {
    for (int i = 0; i < rod.first_clamped_vertex; ++i) {
      out.add_force(i, -1e-3 * rod.velocity(i));
      out.add_velocity_jacobian(i, -1e-3 * Eigen::Matrix3d::Identity());
    }
  }));
  sim.step(1e-3);  // first call may size lazily-built buffers
  g_allocations = 0;
  g_counting = true;
  for (int i = 0; i < 50; ++i) sim.step(1e-3);
  sim.set_insertion_speed(-0.1);  // and removed
  for (int i = 0; i < 50; ++i) sim.step(1e-3);
  sim.set_integrator(Integrator::ImplicitMidpoint);
  for (int i = 0; i < 20; ++i) sim.step(1e-3);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  // The hook itself sees allocations.
  g_counting = true;
  auto* probe = new std::vector<double>(10);
  g_counting = false;
  delete probe;
  EXPECT_GE(g_allocations.load(), 1);
}

}  // namespace
}  // namespace flowire::rod
