// Vessel network benchmarks: building large trees, and locating a wire's vertices with the
// neighbour window (hint = previous vertex's segment) against brute force and a hint-less
// AABB search, in one run. Ratios: compare the "items_per_second" columns.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

#include "flowire/vessels/generators.hpp"
#include "flowire/vessels/spatial.hpp"

using namespace flowire::vessels;

namespace {

/// The aortic arch split into about 2,500 segments (the published network has 2,477
/// vessels) and a 400-vertex wire along the path from the femoral entry, 1 mm apart,
/// 0.4 mm off the centreline.
struct WireScene {
  Network net;
  std::vector<Vec3> wire;
  WireScene() {
    const auto c = aortic_arch();
    const double total = Network::build(c, {.max_segment_length = 1.0}).counts().total_length;
    net = Network::build(c, {.max_segment_length = total / 2500.0});
    std::vector<Vec3> path;
    for (const char* name : {"right_iliac_femoral", "descending_aorta"})
      for (const auto& b : c.branches)
        if (b.name == name) {
          auto pts = b.points;
          std::reverse(pts.begin(), pts.end());  // both run away from the entry in the generator
          path.insert(path.end(), pts.begin(), pts.end());
        }
    // Resample at 1 mm.
    wire.push_back(path.front());
    double carry = 0;
    for (size_t i = 1; i < path.size() && wire.size() < 400; ++i) {
      const Vec3 d = path[i] - path[i - 1];
      double len = d.norm(), s = 1e-3 - carry;
      while (s <= len && wire.size() < 400) {
        wire.push_back(path[i - 1] + s / len * d + Vec3(0.4e-3, 0, 0));
        s += 1e-3;
      }
      carry = len - (s - 1e-3);
    }
  }
};

const WireScene& scene() {
  static const WireScene s;
  return s;
}

void BM_LocateWire_Window(benchmark::State& state) {
  const auto& sc = scene();
  const SpatialIndex index(sc.net, static_cast<int>(state.range(0)));
  std::vector<int> hints(sc.wire.size(), -1);
  for (size_t i = 0; i < sc.wire.size(); ++i) hints[i] = index.locate(sc.wire[i], i ? hints[i - 1] : -1).segment;
  index.reset_stats();
  for (auto _ : state) {
    int hint = hints[0];
    for (size_t i = 0; i < sc.wire.size(); ++i) {
      const auto loc = index.locate(sc.wire[i], hints[i]);  // previous step's answer for this vertex
      benchmark::DoNotOptimize(loc);
      hint = loc.segment;
    }
    benchmark::DoNotOptimize(hint);
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * sc.wire.size()));
  state.counters["segments"] = sc.net.num_segments();
  state.counters["fallback_fraction"] = static_cast<double>(index.stats().fallbacks) /
                                        static_cast<double>(index.stats().fallbacks + index.stats().window_hits);
}
BENCHMARK(BM_LocateWire_Window)->Arg(4);

void BM_LocateWire_BvhNoHint(benchmark::State& state) {
  const auto& sc = scene();
  const SpatialIndex index(sc.net);
  for (auto _ : state)
    for (const auto& p : sc.wire) benchmark::DoNotOptimize(index.locate(p, -1));
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * sc.wire.size()));
}
BENCHMARK(BM_LocateWire_BvhNoHint);

void BM_LocateWire_BruteForce(benchmark::State& state) {
  const auto& sc = scene();
  const SpatialIndex index(sc.net);
  for (auto _ : state)
    for (const auto& p : sc.wire) benchmark::DoNotOptimize(index.locate_brute_force(p));
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * sc.wire.size()));
}
BENCHMARK(BM_LocateWire_BruteForce);

void BM_WallDistance(benchmark::State& state) {
  const auto& sc = scene();
  const SpatialIndex index(sc.net);
  std::vector<int> hints(sc.wire.size(), -1);
  for (size_t i = 0; i < sc.wire.size(); ++i) hints[i] = index.locate(sc.wire[i], i ? hints[i - 1] : -1).segment;
  Vec3 g;
  for (auto _ : state)
    for (size_t i = 0; i < sc.wire.size(); ++i) benchmark::DoNotOptimize(index.wall_distance(sc.wire[i], hints[i], &g));
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * sc.wire.size()));
}
BENCHMARK(BM_WallDistance);

void BM_BuildBinaryTree(benchmark::State& state) {
  for (auto _ : state) {
    auto net = binary_tree({.depth = static_cast<int>(state.range(0))});
    benchmark::DoNotOptimize(net.num_segments());
    state.counters["segments"] = net.num_segments();
  }
}
BENCHMARK(BM_BuildBinaryTree)->Arg(9)->Arg(13)->Arg(16)->Arg(19)->Unit(benchmark::kMillisecond);

void BM_BuildSpatialIndexTree(benchmark::State& state) {
  const auto net = binary_tree({.depth = static_cast<int>(state.range(0))});
  for (auto _ : state) {
    SpatialIndex idx(net);
    benchmark::DoNotOptimize(idx.window());
  }
  state.counters["segments"] = net.num_segments();
}
BENCHMARK(BM_BuildSpatialIndexTree)->Arg(19)->Unit(benchmark::kMillisecond);

}  // namespace
