// flowire's own .vtp, as write_network_vtp writes it (field array flowire_network = 1): the
// exact network back, in metres. Points are the nodes; each line cell is one segment of exactly
// two points, with the cell arrays radius, branch_id and optionally length, radius_from and
// radius_to (absent in files written before tapered segments: cylinders) and shape (absent
// before the sections' shape factors: circles); the field arrays branch_segment_offsets /
// branch_segments and branch_node_offsets / branch_nodes list each
// branch's segments and nodes, and the string array branch_names names them. Read as
// centerlines, each branch gives its nodes with the radius the branch has at each.
#include <fmt/format.h>

#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "flowire/common/error.hpp"
#include "polydata_internal.hpp"

namespace flowire::vessels::detail {

std::optional<Network> polydata_to_network(const PolyData& pd) {
  const auto* marker = find_array(pd.field_data, "flowire_network");
  if (!marker) return std::nullopt;
  const std::string& src = pd.source;
  if (marker->values.empty() || marker->values[0] != 1.0)
    throw_input_error(src, "field array flowire_network: unknown version (this flowire reads version 1)");
  const size_t ns = pd.lines.size();
  const size_t nn = pd.points.size();
  if (ns == 0) throw_input_error(src, "a flowire network file without line cells");
  const auto* radius = find_array(pd.cell_data, "radius");
  const auto* length = find_array(pd.cell_data, "length");
  const auto* radius_from = find_array(pd.cell_data, "radius_from");  // absent before end radii: cylinders
  const auto* radius_to = find_array(pd.cell_data, "radius_to");
  if (radius_from) require_tuples(pd, *radius_from, ns, "cell");
  if (radius_to) require_tuples(pd, *radius_to, ns, "cell");
  const auto* shape = find_array(pd.cell_data, "shape");  // absent before shape factors: circles
  if (shape) require_tuples(pd, *shape, ns, "cell");
  const auto* branch = find_array(pd.cell_data, "branch_id");
  if (!radius) throw_input_error(src, "flowire network file without the cell array 'radius'");
  if (!branch) throw_input_error(src, "flowire network file without the cell array 'branch_id'");
  require_tuples(pd, *radius, ns, "cell");
  require_tuples(pd, *branch, ns, "cell");
  if (length) require_tuples(pd, *length, ns, "cell");

  std::vector<Segment> segs(ns);
  for (size_t s = 0; s < ns; ++s) {
    const auto& ids = pd.lines[s];
    if (ids.size() != 2)
      throw_input_error(src,
                        fmt::format("line cell {}: a flowire network has 2 points per cell, not {}", s, ids.size()));
    for (const long long id : ids)
      if (id < 0 || static_cast<size_t>(id) >= nn)
        throw_input_error(src,
                          fmt::format("line cell {}: point id {} is out of range (the file has {} points)", s, id, nn));
    segs[s].node_from = static_cast<int>(ids[0]);
    segs[s].node_to = static_cast<int>(ids[1]);
    segs[s].radius = radius->values[s * static_cast<size_t>(radius->components)];
    for (const auto& [arr, out] :
         {std::pair{radius_from, &segs[s].radius_from}, std::pair{radius_to, &segs[s].radius_to}}) {
      if (!arr) continue;
      *out = arr->values[s * static_cast<size_t>(arr->components)];
      if (!(*out > 0.0 && std::isfinite(*out)))
        throw_input_error(src, fmt::format("line cell {}: {} {} is not positive and finite", s, arr->name, *out));
    }
    if (shape) {
      segs[s].shape = shape->values[s * static_cast<size_t>(shape->components)];
      if (!(segs[s].shape >= 1.0 && std::isfinite(segs[s].shape)))
        throw_input_error(
            src, fmt::format("line cell {}: shape {} is not finite and at least 1 (a circle's)", s, segs[s].shape));
    }
    segs[s].length = length ? length->values[s * static_cast<size_t>(length->components)] : 0.0;
    if (length && !(segs[s].length > 0.0 && std::isfinite(segs[s].length)))
      throw_input_error(src, fmt::format("line cell {}: length {} is not positive and finite", s, segs[s].length));
    const long long b = int_at(*branch, s);
    if (b < 0 || b > static_cast<long long>(ns))
      throw_input_error(src, fmt::format("line cell {}: branch_id {} is out of range", s, b));
    segs[s].branch = static_cast<int>(b);
  }
  for (size_t i = 0; i < nn; ++i)
    if (!pd.points[i].allFinite()) throw_input_error(src, fmt::format("point {}: coordinate is not finite", i));

  // Branch lists: offsets + flat index arrays in field data.
  const auto* names = find_strings(pd.field_strings, "branch_names");
  auto list = [&](const char* offsets_name, const char* values_name, size_t limit) {
    const auto* off = find_array(pd.field_data, offsets_name);
    const auto* val = find_array(pd.field_data, values_name);
    if (!off || !val)
      throw_input_error(
          src, fmt::format("flowire network file without the field arrays {} and {}", offsets_name, values_name));
    std::vector<std::vector<int>> out;
    for (size_t b = 0; b + 1 < off->values.size(); ++b) {
      const long long lo = int_at(*off, b), hi = int_at(*off, b + 1);
      if (lo < 0 || hi < lo || static_cast<size_t>(hi) > val->values.size())
        throw_input_error(src, fmt::format("field array {}: entry {} is out of range", offsets_name, b));
      std::vector<int> ids;
      for (long long k = lo; k < hi; ++k) {
        const long long v = int_at(*val, static_cast<size_t>(k));
        if (v < 0 || static_cast<size_t>(v) >= limit)
          throw_input_error(src, fmt::format("field array {}: entry {} ({}) is out of range", values_name, k, v));
        ids.push_back(static_cast<int>(v));
      }
      out.push_back(std::move(ids));
    }
    return out;
  };
  const auto branch_segments = list("branch_segment_offsets", "branch_segments", ns);
  const auto branch_nodes = list("branch_node_offsets", "branch_nodes", nn);
  if (branch_segments.size() != branch_nodes.size())
    throw_input_error(src, "field arrays branch_segment_offsets and branch_node_offsets differ in length");
  std::vector<Branch> branches(branch_segments.size());
  for (size_t b = 0; b < branches.size(); ++b) {
    branches[b].name = names && b < names->values.size() ? names->values[b] : fmt::format("branch_{}", b);
    branches[b].segments = branch_segments[b];
    branches[b].nodes = branch_nodes[b];
  }
  for (size_t s = 0; s < ns; ++s)
    if (static_cast<size_t>(segs[s].branch) >= branches.size())
      throw_input_error(src, fmt::format("line cell {}: branch_id {} but the file lists {} branches", s, segs[s].branch,
                                         branches.size()));
  return Network::from_graph(pd.points, std::move(segs), std::move(branches), src);
}

std::vector<Polyline> flowire_network_branches(const Network& net) {
  std::vector<Polyline> out;
  for (const auto& br : net.branches()) {
    Polyline p;
    p.name = br.name;
    for (size_t k = 0; k < br.nodes.size(); ++k) {
      p.points.push_back(net.node(br.nodes[k]));
      // The radius this branch has at the node (the segment after it, the last one at the end).
      p.radii.push_back(k < br.segments.size() ? net.segment(br.segments[k]).radius_from
                                               : net.segment(br.segments[k - 1]).radius_to);
    }
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace flowire::vessels::detail
