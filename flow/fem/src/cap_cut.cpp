// The network cut at a lumen's caps (cap_cut.hpp).
#include "flowire/flow/fem/cap_cut.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "flowire/common/error.hpp"

namespace flowire::flow::fem {
namespace {

using vessels::Branch;
using vessels::mm;
using vessels::Segment;

/// The end's branch as nodes and segments from the end inwards: chain.nodes[0] = end,
/// chain.segments[i] joins chain.nodes[i] and chain.nodes[i + 1].
struct Chain {
  std::vector<int> nodes, segments;
};

Chain chain_from(const Network& net, int end) {
  const int s0 = *net.node_segments(end).first;
  const Branch& br = net.branch(net.segment(s0).branch);
  Chain c{br.nodes, br.segments};
  if (c.nodes.front() != end) {
    std::reverse(c.nodes.begin(), c.nodes.end());
    std::reverse(c.segments.begin(), c.segments.end());
  }
  return c;
}

}  // namespace

CapCut cut_at_caps(const Network& net, std::span<const LumenCap> caps, const std::string& source) {
  std::vector<Vec3> nodes = net.nodes();
  std::vector<Segment> segments = net.segments();
  std::vector<Branch> branches = net.branches();
  std::vector<char> node_cut(nodes.size(), 0), segment_cut(segments.size(), 0);
  CapCut out;
  out.cut_length.assign(caps.size(), 0.0);
  for (size_t ci = 0; ci < caps.size(); ++ci) {
    const LumenCap& cap = caps[ci];
    const int end = cap.node;
    const Chain ch = chain_from(net, end);
    // Signed distance of each chain node from the cap's plane, > 0 beyond it (outside the lumen).
    auto beyond = [&](int n) { return cap.normal.dot(net.node(n) - cap.centroid); };
    size_t k = 0;  // first node from the end that is not beyond the plane
    while (k < ch.nodes.size() && beyond(ch.nodes[k]) > 0.0) ++k;
    if (k == ch.nodes.size())
      throw_input_error(source, fmt::format("the cap at {} lies inside the branch '{}' of the end at {}: the whole "
                                            "branch is beyond the lumen's open end",
                                            mm(cap.centroid), net.branch(net.segment(ch.segments[0]).branch).name,
                                            mm(net.node(end))));
    Segment& across = segments[static_cast<size_t>(ch.segments[k == 0 ? 0 : k - 1])];
    const bool end_is_from = across.node_from == ch.nodes[k == 0 ? 0 : k - 1];
    double& r_end = end_is_from ? across.radius_from : across.radius_to;
    const double r_in = end_is_from ? across.radius_to : across.radius_from;
    if (k == 0) {
      // The cap lies beyond the centerline's end: lengthen the last segment along its line.
      const Vec3 d = net.node(end) - net.node(ch.nodes[1]);
      const double slope = cap.normal.dot(d);
      if (!(slope > 0.0))
        throw_input_error(source, fmt::format("the cap at {} faces away from the end at {} of its branch",
                                              mm(cap.centroid), mm(net.node(end))));
      const double t = -beyond(end) / slope;  // ≥ 0: the part of d to add
      nodes[static_cast<size_t>(end)] = net.node(end) + t * d;
      out.cut_length[ci] = -t * across.length;
      across.length *= 1.0 + t;
      r_end = r_end + t * (r_end - r_in);  // the segment's taper continued
      if (!(r_end > 0.0)) r_end = across.radius;
    } else {
      // The branch crosses the plane between ch.nodes[k] (inside) and ch.nodes[k - 1]: the end
      // takes the crossing, the nodes and segments beyond it go.
      const double h_in = beyond(ch.nodes[k]), h_out = beyond(ch.nodes[k - 1]);
      const double mu = h_in / (h_in - h_out);  // in [0, 1): from the inside node to the crossing
      const Vec3 x = net.node(ch.nodes[k]) + mu * (net.node(ch.nodes[k - 1]) - net.node(ch.nodes[k]));
      double cut = (1.0 - mu) * across.length;
      for (size_t i = 0; i + 1 < k; ++i) {
        cut += segments[static_cast<size_t>(ch.segments[i])].length;
        segment_cut[static_cast<size_t>(ch.segments[i])] = 1;
        node_cut[static_cast<size_t>(ch.nodes[i + 1])] = 1;
      }
      out.cut_length[ci] = cut;
      nodes[static_cast<size_t>(end)] = x;
      // A crossing within a thousandth of the segment of its inside node keeps that length, so
      // that no segment has none (the resistance changes by that thousandth of one segment's).
      const double kept = std::max(mu, 1e-3);
      r_end = r_in + kept * (r_end - r_in);
      across.length *= kept;
      (end_is_from ? across.node_from : across.node_to) = end;
    }
    across.radius = 0.5 * (across.radius_from + across.radius_to);
  }
  // Renumber: the nodes and segments that stay, in their order.
  out.node.assign(nodes.size(), -1);
  std::vector<Vec3> kept_nodes;
  for (size_t i = 0; i < nodes.size(); ++i)
    if (!node_cut[i]) {
      out.node[i] = static_cast<int>(kept_nodes.size());
      kept_nodes.push_back(nodes[i]);
    }
  std::vector<int>& segment_index = out.segment;
  segment_index.assign(segments.size(), -1);
  std::vector<Segment> kept_segments;
  for (size_t s = 0; s < segments.size(); ++s)
    if (!segment_cut[s]) {
      Segment seg = segments[s];
      seg.node_from = out.node[static_cast<size_t>(seg.node_from)];
      seg.node_to = out.node[static_cast<size_t>(seg.node_to)];
      segment_index[s] = static_cast<int>(kept_segments.size());
      kept_segments.push_back(seg);
    }
  for (auto& br : branches) {
    // A branch's end node moved into the place of the first node cut (chain order kept).
    std::vector<int> bn, bs;
    for (int n : br.nodes)
      if (out.node[static_cast<size_t>(n)] >= 0) bn.push_back(out.node[static_cast<size_t>(n)]);
    for (int s : br.segments)
      if (segment_index[static_cast<size_t>(s)] >= 0) bs.push_back(segment_index[static_cast<size_t>(s)]);
    br.nodes = std::move(bn);
    br.segments = std::move(bs);
  }
  out.network = Network::from_graph(std::move(kept_nodes), std::move(kept_segments), std::move(branches),
                                    std::string(net.source()));
  return out;
}

}  // namespace flowire::flow::fem
