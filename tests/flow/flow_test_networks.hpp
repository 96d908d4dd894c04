#pragma once
// Small networks for the flow tests, built as graphs (Network::from_graph).
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include "flowire/common/config.hpp"
#include "flowire/flow/spec.hpp"
#include "flowire/vessels/network.hpp"

namespace flowire::flow::test {

/// The flow keys as the scene declares them (declare_scene_keys).
inline config::Schema flow_schema() {
  config::Schema s;
  declare_scene_keys(s);
  return s;
}

/// η = π/8 with r = 1 makes R = 8ηl/(πr⁴) = l: dimensionless resistances are lengths.
inline constexpr double kUnitViscosity = 3.14159265358979323846 / 8.0;

/// A straight tube along +x split into n segments.
inline Network tube(double length, double radius, int n) {
  std::vector<Vec3> nodes;
  std::vector<vessels::Segment> segs;
  for (int i = 0; i <= n; ++i) nodes.emplace_back(length * i / n, 0.0, 0.0);
  for (int i = 0; i < n; ++i) segs.push_back({i, i + 1, radius, 0.0, -1});
  return Network::from_graph(nodes, segs);
}

/// Binary Murray tree of the reference README: generations 0..depth, r_k = 2 mm·2^(−k/3),
/// L_k = 20 mm·2^(−k/3); node 0 is the root, segment s (breadth first) ends at node s + 1.
inline Network murray_tree(int depth) {
  std::vector<Vec3> nodes = {Vec3::Zero()};
  std::vector<vessels::Segment> segs;
  const int count = (1 << (depth + 1)) - 1;
  for (int s = 0; s < count; ++s) {
    const int gen = static_cast<int>(std::floor(std::log2(s + 1)));
    const double f = std::pow(2.0, -gen / 3.0);
    const int parent_node = s == 0 ? 0 : (s - 1) / 2 + 1;  // end node of the parent segment
    const Vec3 dir = Vec3(1.0, (s % 2 ? 0.3 : -0.3) * (s > 0), 0.01 * s).normalized();
    nodes.push_back(nodes[static_cast<size_t>(parent_node)] + 20e-3 * f * dir);
    segs.push_back({parent_node, s + 1, 2e-3 * f, 20e-3 * f, -1});
  }
  return Network::from_graph(nodes, segs);
}

/// Wheatstone loop of reference 3: S–A 1, S–B 2, A–T 2, B–T 1, A–B 1 (use kUnitViscosity).
inline constexpr int kS = 0, kA = 1, kB = 2, kT = 3, kAB = 4;
inline Network wheatstone() {
  std::vector<Vec3> nodes = {Vec3(0, 0, 0), Vec3(1, 1, 0),  Vec3(1, -1, 0),
                             Vec3(2, 0, 0), Vec3(-1, 0, 0), Vec3(3, 0, 0)};
  std::vector<vessels::Segment> segs = {{kS, kA, 1.0, 1.0, -1},
                                        {kS, kB, 1.0, 2.0, -1},
                                        {kA, kT, 1.0, 2.0, -1},
                                        {kB, kT, 1.0, 1.0, -1},
                                        {kA, kB, 1.0, 1.0, -1}};
  // Only the four nodes; the spare points are not referenced.
  nodes.resize(4);
  return Network::from_graph(nodes, segs);
}

/// A random connected tree of n segments with `extra` additional segments closing loops.
inline Network random_network(int n, int extra, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> nodes = {Vec3::Zero()};
  std::vector<vessels::Segment> segs;
  std::vector<int> degree = {0};
  // Root segment is the widest.
  nodes.emplace_back(0.01, 0.0, 0.0);
  degree.push_back(0);
  segs.push_back({0, 1, 4e-3, 0.0, -1});
  degree[0] = degree[1] = 1;
  for (int i = 1; i < n; ++i) {
    int parent = 0;
    do parent = 1 + static_cast<int>(u(rng) * static_cast<double>(nodes.size() - 1));
    while (parent >= static_cast<int>(nodes.size()) || degree[static_cast<size_t>(parent)] >= 3);
    const Vec3 p = nodes[static_cast<size_t>(parent)] + 0.01 * Vec3(u(rng) - 0.2, u(rng) - 0.5, u(rng) - 0.5);
    nodes.push_back(p);
    degree.push_back(1);
    ++degree[static_cast<size_t>(parent)];
    segs.push_back({parent, static_cast<int>(nodes.size()) - 1, 0.5e-3 + 2e-3 * u(rng), 0.0, -1});
  }
  for (int k = 0; k < extra; ++k) {
    int a = 0, b = 0;
    do {
      a = 1 + static_cast<int>(u(rng) * static_cast<double>(nodes.size() - 2));
      b = 1 + static_cast<int>(u(rng) * static_cast<double>(nodes.size() - 2));
    } while (a == b || degree[static_cast<size_t>(a)] < 2 || degree[static_cast<size_t>(b)] < 2);
    segs.push_back({a, b, 0.5e-3 + 1e-3 * u(rng), 0.0, -1});
    ++degree[static_cast<size_t>(a)];
    ++degree[static_cast<size_t>(b)];
  }
  return Network::from_graph(nodes, segs);
}

/// Pressure inlet at `inlet` and pressure outlets {(node, pressure)}.
inline FlowSpec pressure_spec(const Network& net, int inlet, const Waveform& w,
                              const std::vector<std::pair<int, double>>& outlets) {
  (void)net;
  FlowSpec s;
  InletBC in;
  in.node = inlet;
  in.waveform = w;
  s.inlets.push_back(in);
  for (const auto& [node, p] : outlets) {
    OutletBC o;
    o.node = node;
    o.pressure = Waveform::constant(p);
    s.outlets.push_back(o);
  }
  return s;
}

}  // namespace flowire::flow::test
