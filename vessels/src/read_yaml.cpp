// flowire's YAML network file (.yaml / .yml), as people write it and as write_network_yaml
// writes it:
//   length_unit: mm                      # optional: m, cm, mm or um; the file's unit wins
//   branches:                            # one centerline per branch
//     - name: trunk                      # optional
//       points: [[x, y, z, r], ...]      # at least 2, radius r > 0, no repeated point
//   nodes: [[x, y, z], ...]              # optional, with segments: the exact network
//   segments: [[from, to, radius, length, branch(, radius_from, radius_to(, shape))], ...]
// (with nodes/segments, each branch lists its `nodes` and `segments` by index; shape, ≥ 1, the
// sections' resistance over the circles' of the same area, Segment::shape). Coordinates,
// radii and lengths are in length_unit (else the caller's unit, else metres). Every error names
// the file, its line and the branch, point, node or segment at fault.
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/common/units.hpp"
#include "read_internal.hpp"

namespace flowire::vessels::detail {
namespace {

std::string at(const std::string& path, const YAML::Node& n) {
  const auto m = n.Mark();
  return m.line >= 0 ? fmt::format("{}:{}", path, m.line + 1) : path;
}

double number(const std::string& path, const YAML::Node& n, std::string_view what) {
  if (!n.IsScalar()) throw_input_error(at(path, n), fmt::format("{}: expected a number", what));
  try {
    return n.as<double>();
  } catch (const YAML::Exception&) {
    throw_input_error(at(path, n), fmt::format("{}: '{}' is not a number", what, n.Scalar()));
  }
}

long long integer(const std::string& path, const YAML::Node& n, std::string_view what) {
  const double v = number(path, n, what);
  if (!(std::abs(v) < 1e15) || std::floor(v) != v)
    throw_input_error(at(path, n), fmt::format("{}: expected a whole number, not {}", what, n.Scalar()));
  return static_cast<long long>(v);
}

struct YamlFile {
  YAML::Node root;
  std::optional<std::string> unit;
};

YamlFile load_yaml(const std::string& path) {
  const std::string text = read_network_text(path);
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) throw_input_error(path, "the file is empty");
  YamlFile f;
  try {
    f.root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw_input_error(fmt::format("{}:{}", path, e.mark.line + 1), fmt::format("YAML syntax error: {}", e.msg));
  } catch (const YAML::Exception& e) {
    throw_input_error(path, fmt::format("YAML error: {}", e.msg));
  }
  if (!f.root.IsMap()) throw_input_error(at(path, f.root), "expected a map with 'branches' (a flowire network file)");
  for (const auto& kv : f.root) {
    const auto key = kv.first.Scalar();
    if (key != "branches" && key != "length_unit" && key != "nodes" && key != "segments" && key != "format" &&
        key != "version" && key != "name")
      throw_input_error(
          at(path, kv.first),
          fmt::format("unknown key '{}' (a network file has branches, length_unit, nodes, segments)", key));
  }
  if (const auto u = f.root["length_unit"]) {
    if (!u.IsScalar()) throw_input_error(at(path, u), "length_unit: expected m, cm, mm or um");
    units::length_unit_factor(u.Scalar(), at(path, u) + ": length_unit");
    f.unit = u.Scalar();
  }
  return f;
}

std::string branch_label(size_t b, const std::string& name) {
  return name.empty() ? fmt::format("branch {}", b) : fmt::format("branch {} ('{}')", b, name);
}

Centerlines yaml_centerlines(const std::string& path, const YamlFile& f) {
  const auto branches = f.root["branches"];
  if (!branches) throw_input_error(path, "no 'branches' list: not a flowire network file");
  if (!branches.IsSequence() || branches.size() == 0)
    throw_input_error(at(path, branches), "branches: expected a non-empty list of {name, points}");
  Centerlines c;
  c.source = path;
  for (size_t b = 0; b < branches.size(); ++b) {
    const auto br = branches[b];
    if (!br.IsMap()) throw_input_error(at(path, br), fmt::format("branch {}: expected a map with name and points", b));
    Polyline p;
    for (const auto& kv : br) {
      const auto key = kv.first.Scalar();
      if (key != "name" && key != "points" && key != "nodes" && key != "segments")
        throw_input_error(at(path, kv.first),
                          fmt::format("branch {}: unknown key '{}' (expected name, points)", b, key));
    }
    if (const auto name = br["name"]) {
      if (!name.IsScalar()) throw_input_error(at(path, name), fmt::format("branch {}: name must be text", b));
      p.name = name.Scalar();
    }
    const auto label = branch_label(b, p.name);
    const auto points = br["points"];
    if (!points) throw_input_error(at(path, br), fmt::format("{}: no 'points'", label));
    if (!points.IsSequence() || points.size() < 2)
      throw_input_error(at(path, points), fmt::format("{}: points: expected a list of at least 2 [x, y, z, r]", label));
    for (size_t i = 0; i < points.size(); ++i) {
      const auto pt = points[i];
      const auto what = fmt::format("{}, point {}", label, i);
      if (!pt.IsSequence() || pt.size() != 4)
        throw_input_error(at(path, pt), fmt::format("{}: expected [x, y, z, r]", what));
      const Vec3 x(number(path, pt[0], what), number(path, pt[1], what), number(path, pt[2], what));
      const double r = number(path, pt[3], what);
      if (!x.allFinite()) throw_input_error(at(path, pt), fmt::format("{}: coordinate is not finite", what));
      if (!std::isfinite(r)) throw_input_error(at(path, pt), fmt::format("{}: radius is not finite", what));
      if (r <= 0.0) throw_input_error(at(path, pt), fmt::format("{}: radius {} is not positive", what, r));
      if (!p.points.empty() && p.points.back() == x)
        throw_input_error(at(path, pt), fmt::format("{}: same position as point {} (duplicate point)", what, i - 1));
      p.points.push_back(x);
      p.radii.push_back(r);
    }
    c.branches.push_back(std::move(p));
  }
  return c;
}

/// The exact form written by write_network_yaml: nodes, segments, and branch lists.
std::optional<Network> yaml_network(const std::string& path, const YamlFile& f, double factor) {
  const auto nodes_n = f.root["nodes"];
  const auto segs_n = f.root["segments"];
  if (!nodes_n && !segs_n) return std::nullopt;
  if (!nodes_n || !segs_n)
    throw_input_error(at(path, nodes_n ? nodes_n : segs_n), "'nodes' and 'segments' go together");
  if (!nodes_n.IsSequence() || !segs_n.IsSequence() || segs_n.size() == 0)
    throw_input_error(at(path, nodes_n), "nodes and segments: expected lists");
  std::vector<Vec3> nodes;
  for (size_t i = 0; i < nodes_n.size(); ++i) {
    const auto n = nodes_n[i];
    const auto what = fmt::format("node {}", i);
    if (!n.IsSequence() || n.size() != 3) throw_input_error(at(path, n), what + ": expected [x, y, z]");
    const Vec3 x(number(path, n[0], what), number(path, n[1], what), number(path, n[2], what));
    if (!x.allFinite()) throw_input_error(at(path, n), what + ": coordinate is not finite");
    nodes.push_back(x * factor);
  }
  const auto nn = static_cast<long long>(nodes.size());
  std::vector<Segment> segs;
  for (size_t s = 0; s < segs_n.size(); ++s) {
    const auto n = segs_n[s];
    const auto what = fmt::format("segment {}", s);
    if (!n.IsSequence() || (n.size() != 5 && n.size() != 7 && n.size() != 8))
      throw_input_error(
          at(path, n),
          what + ": expected [node_from, node_to, radius, length, branch(, radius_from, radius_to(, shape))]");
    Segment seg;
    const long long a = integer(path, n[0], what), b = integer(path, n[1], what);
    if (a < 0 || a >= nn || b < 0 || b >= nn)
      throw_input_error(at(path, n), fmt::format("{}: node index out of range (there are {} nodes)", what, nn));
    if (a == b) throw_input_error(at(path, n), fmt::format("{} joins node {} to itself (self-loop)", what, a));
    seg.node_from = static_cast<int>(a);
    seg.node_to = static_cast<int>(b);
    seg.radius = number(path, n[2], what) * factor;
    seg.length = number(path, n[3], what) * factor;
    if (!(seg.radius > 0.0) || !std::isfinite(seg.radius))
      throw_input_error(at(path, n), fmt::format("{}: radius is not positive and finite", what));
    if (n.size() == 8) {
      seg.shape = number(path, n[7], what);
      if (!(seg.shape >= 1.0) || !std::isfinite(seg.shape))
        throw_input_error(at(path, n[7]),
                          fmt::format("{}: shape {} is not finite and at least 1 (a circle's)", what, seg.shape));
    }
    if (n.size() >= 7) {
      seg.radius_from = number(path, n[5], what) * factor;
      seg.radius_to = number(path, n[6], what) * factor;
      if (!(seg.radius_from > 0.0 && seg.radius_to > 0.0) || !std::isfinite(seg.radius_from) ||
          !std::isfinite(seg.radius_to))
        throw_input_error(at(path, n), fmt::format("{}: end radius is not positive and finite", what));
    }
    if (!(seg.length > 0.0) || !std::isfinite(seg.length))
      throw_input_error(at(path, n), fmt::format("{}: length is not positive and finite", what));
    const long long br = integer(path, n[4], what);
    seg.branch = static_cast<int>(std::clamp<long long>(br, -1, std::numeric_limits<int>::max()));
    segs.push_back(seg);
  }
  std::vector<Branch> branches;
  if (const auto bl = f.root["branches"]) {
    if (!bl.IsSequence()) throw_input_error(at(path, bl), "branches: expected a list");
    for (size_t b = 0; b < bl.size(); ++b) {
      const auto bn = bl[b];
      Branch br;
      if (!bn.IsMap()) throw_input_error(at(path, bn), fmt::format("branch {}: expected a map", b));
      if (bn["name"]) br.name = bn["name"].Scalar();
      auto ids = [&](const char* key, long long limit) {
        std::vector<int> out;
        const auto l = bn[key];
        if (!l || !l.IsSequence())
          throw_input_error(at(path, bn),
                            fmt::format("{}: '{}' list needed with nodes/segments", branch_label(b, br.name), key));
        for (size_t k = 0; k < l.size(); ++k) {
          const long long v = integer(path, l[k], key);
          if (v < 0 || v >= limit)
            throw_input_error(at(path, l[k]),
                              fmt::format("{}: {} entry {} is out of range", branch_label(b, br.name), key, v));
          out.push_back(static_cast<int>(v));
        }
        return out;
      };
      br.nodes = ids("nodes", nn);
      br.segments = ids("segments", static_cast<long long>(segs.size()));
      branches.push_back(std::move(br));
    }
  }
  for (size_t s = 0; s < segs.size(); ++s)
    if (!branches.empty() && (segs[s].branch < 0 || static_cast<size_t>(segs[s].branch) >= branches.size()))
      throw_input_error(at(path, segs_n[s]), fmt::format("segment {}: branch {} is not listed", s, segs[s].branch));
  return Network::from_graph(std::move(nodes), std::move(segs), std::move(branches), path);
}

}  // namespace

Centerlines read_yaml_centerlines(const std::string& path, const ReadOptions& opt) {
  const auto file = load_yaml(path);
  const double f = length_factor(opt, file.unit, path);
  auto c = yaml_centerlines(path, file);
  scale(c, f);
  return c;
}

Network read_yaml_network(const std::string& path, const ReadOptions& opt) {
  const auto file = load_yaml(path);
  const double f = length_factor(opt, file.unit, path);
  if (auto net = yaml_network(path, file, f)) return finish(std::move(*net), opt, f, path);
  auto c = yaml_centerlines(path, file);
  scale(c, f);
  return finish(build_checked(c, opt.build), opt, f, path);
}

}  // namespace flowire::vessels::detail
