#include <cstdio>

#include "flowire/flow/solver.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire/vessels/generators.hpp"

int main() {
  const auto net = flowire::vessels::binary_tree({.depth = 3});
  auto spec = flowire::flow::default_spec(net, flowire::flow::Waveform::constant(1000.0));
  auto solver = flowire::flow::make_solver(net, spec);
  solver->advance(0.0);
  flowire::rod::WireSpec w;
  w.length = 0.1;
  w.segments = 10;
  flowire::rod::RodSimulator rod(w);
  rod.step(1e-3);
  std::printf("inlet flow %.6g m^3/s, rod vertices %d\n", solver->segment_flow(0), rod.vertex_count());
  return solver->segment_flow(0) > 0.0 ? 0 : 1;
}
