// Network readers: format dispatch, length units, the YAML network format, svOneDSolver
// decks, and the checks made on every network read (pieces, unit plausibility).
#include "flowire/vessels/io.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"
#include "flowire/common/units.hpp"
#include "polydata_internal.hpp"

namespace flowire::vessels {
namespace {

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string read_all(const std::string& path) { return read_input(path, input_limit::kGeometry, "a network file"); }

/// Factor from file units to metres. `declared`: the unit the file itself states, if any.
double length_factor(const ReadOptions& opt, const std::optional<std::string>& declared, const std::string& where) {
  std::optional<double> user;
  std::string user_name = opt.length_unit;
  if (opt.length_factor > 0.0) {
    if (!std::isfinite(opt.length_factor)) throw_usage_error("length factor must be finite");
    user = opt.length_factor;
    user_name = fmt::format("factor {}", opt.length_factor);
  } else if (!opt.length_unit.empty()) {
    user = units::length_unit_factor(opt.length_unit, "length unit");
  }
  if (declared) {
    const double f = units::length_unit_factor(*declared, where + ": length_unit");
    if (user && std::abs(*user - f) > 1e-12 * f)
      warn(fmt::format("{}: the file declares length_unit {}; the length unit given ({}) is ignored", where, *declared,
                       user_name));
    return f;
  }
  return user.value_or(1.0);
}

void scale(Centerlines& c, double f) {
  if (f == 1.0) return;
  for (auto& b : c.branches) {
    for (auto& p : b.points) p *= f;
    for (auto& r : b.radii) r *= f;
  }
}

/// Warn when the radii (already in metres) look like another unit.
void check_units(double r_max, double factor, const std::string& where) {
  if (!(r_max > 0.05 || (r_max > 0.0 && r_max < 1e-6))) return;
  const double raw = r_max / factor;  // in file units
  struct Cand {
    const char* name;
    double f;
  };
  std::vector<std::pair<double, const char*>> plausible;
  for (const Cand c : {Cand{"m", 1.0}, Cand{"cm", 1e-2}, Cand{"mm", 1e-3}, Cand{"um", 1e-6}}) {
    const double r = raw * c.f;
    if (r >= 1e-4 && r <= 0.05) plausible.emplace_back(std::abs(std::log10(r / 5e-3)), c.name);  // typical: 5 mm
  }
  std::sort(plausible.begin(), plausible.end());
  std::string hint = "check length_unit";
  if (!plausible.empty()) {
    hint = fmt::format("the file is probably in {}", plausible[0].second);
    if (plausible.size() > 1) hint += fmt::format(" (or {})", plausible[1].second);
    hint += fmt::format(": set length_unit: {0} (command line: --length-unit {0})", plausible[0].second);
  }
  warn(fmt::format("{}: the largest radius is {:.4g} m, not a blood vessel in the length unit used; {}", where, r_max,
                   hint));
}

/// Refuses centerlines that would build an absurd number of segments (wrong unit, corrupt
/// coordinates) before Network::build allocates them.
void check_build_size(const Centerlines& c, const BuildOptions& opt) {
  double total = 0.0;
  for (size_t b = 0; b < c.branches.size(); ++b) {
    const auto& p = c.branches[b];
    double len = 0.0;
    for (size_t i = 1; i < p.points.size(); ++i) len += (p.points[i] - p.points[i - 1]).norm();
    if (!std::isfinite(len))
      throw_input_error(c.source, fmt::format("branch {}: coordinates too large (its length is not finite)", b));
    total += static_cast<double>(p.points.size());
    if (opt.max_segment_length > 0.0) total += len / opt.max_segment_length;
  }
  if (total > 2e7)
    throw_input_error(c.source, fmt::format("cutting the branches into segments of at most {} m would make about "
                                            "{:.3g} segments; check length_unit and max_segment_length",
                                            opt.max_segment_length, total));
}

Network build_checked(const Centerlines& c, const BuildOptions& opt) {
  check_build_size(c, opt);
  return Network::build(c, opt);
}

// ---------------------------------------------------------------------------------------
// YAML network

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
  const std::string text = read_all(path);
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
    if (!n.IsSequence() || (n.size() != 5 && n.size() != 7))
      throw_input_error(at(path, n),
                        what + ": expected [node_from, node_to, radius, length, branch(, radius_from, radius_to)]");
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
    if (n.size() == 7) {
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

// ---------------------------------------------------------------------------------------
// svOneDSolver deck

struct OneDNode {
  Vec3 x;
  int line = 0;
};
struct OneDSegment {
  std::string name;
  long long id = 0;
  double length = 0.0;
  long long in = 0, out = 0;
  double area_in = 0.0, area_out = 0.0;
  int line = 0;
};
struct OneDDeck {
  std::map<long long, OneDNode> nodes;
  std::vector<OneDSegment> segments;  // in file order
};

std::vector<std::string> tokens(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream ss(line.substr(0, line.find('#')));
  for (std::string t; ss >> t;) out.push_back(t);
  return out;
}

double parse_number(const std::string& where, const std::string& tok, std::string_view what) {
  size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(tok, &used);
  } catch (...) {
    used = 0;
  }
  if (used != tok.size() || tok.empty()) throw_input_error(where, fmt::format("{}: '{}' is not a number", what, tok));
  return v;
}

long long parse_id(const std::string& where, const std::string& tok, std::string_view what) {
  const double v = parse_number(where, tok, what);
  if (!(std::abs(v) < 1e15) || std::floor(v) != v)
    throw_input_error(where, fmt::format("{}: '{}' is not a whole number", what, tok));
  return static_cast<long long>(v);
}

OneDDeck parse_deck(const std::string& path) {
  const std::string text = read_all(path);
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) throw_input_error(path, "the file is empty");
  OneDDeck deck;
  struct Joint {
    long long node;
    std::string inlet, outlet;
    int line;
  };
  std::vector<Joint> joints;
  std::map<std::string, std::pair<std::vector<long long>, int>> lists;
  std::istringstream in(text);
  std::string line;
  int lineno = 0;
  bool in_table = false;
  while (std::getline(in, line)) {
    ++lineno;
    const auto t = tokens(line);
    if (t.empty()) continue;
    const auto where = fmt::format("{}:{}", path, lineno);
    const std::string card = t[0];
    if (in_table) {
      if (card == "ENDDATATABLE") in_table = false;
      continue;
    }
    if (card == "DATATABLE") {
      in_table = true;
    } else if (card == "NODE") {
      if (t.size() < 5) throw_input_error(where, "NODE needs an id and x y z");
      const long long id = parse_id(where, t[1], "NODE id");
      const Vec3 x(parse_number(where, t[2], "NODE x"), parse_number(where, t[3], "NODE y"),
                   parse_number(where, t[4], "NODE z"));
      if (!x.allFinite()) throw_input_error(where, fmt::format("NODE {}: coordinate is not finite", id));
      if (!deck.nodes.emplace(id, OneDNode{x, lineno}).second)
        throw_input_error(where, fmt::format("NODE {} is defined twice (first on line {})", id, deck.nodes[id].line));
    } else if (card == "SEGMENT") {
      if (t.size() < 9)
        throw_input_error(where, "SEGMENT needs name id length elements inNode outNode inArea outArea ...");
      OneDSegment s;
      s.name = t[1];
      s.id = parse_id(where, t[2], "SEGMENT id");
      const auto label = fmt::format("SEGMENT {}", s.name);
      s.length = parse_number(where, t[3], label + " length");
      s.in = parse_id(where, t[5], label + " inlet node");
      s.out = parse_id(where, t[6], label + " outlet node");
      s.area_in = parse_number(where, t[7], label + " inlet area");
      s.area_out = parse_number(where, t[8], label + " outlet area");
      s.line = lineno;
      if (!(s.length > 0.0) || !std::isfinite(s.length))
        throw_input_error(where, fmt::format("{}: length {} is not positive", label, t[3]));
      for (const double a : {s.area_in, s.area_out})
        if (!(a > 0.0) || !std::isfinite(a))
          throw_input_error(where, fmt::format("{}: area {} is not positive (radius = sqrt(area/pi))", label, a));
      deck.segments.push_back(std::move(s));
    } else if (card == "JOINT") {
      if (t.size() < 5) throw_input_error(where, "JOINT needs name node inletList outletList");
      joints.push_back({parse_id(where, t[2], "JOINT node"), t[3], t[4], lineno});
    } else if (card == "JOINTINLET" || card == "JOINTOUTLET") {
      if (t.size() < 3) throw_input_error(where, card + " needs name count segments...");
      const long long n = parse_id(where, t[2], card + " count");
      if (n < 0 || static_cast<size_t>(n) != t.size() - 3)
        throw_input_error(where, fmt::format("{} {}: count {} but {} segments listed", card, t[1], n, t.size() - 3));
      std::vector<long long> ids;
      for (size_t k = 3; k < t.size(); ++k) ids.push_back(parse_id(where, t[k], card + " segment"));
      lists[card + ":" + t[1]] = {std::move(ids), lineno};
    }
  }
  if (deck.segments.empty()) throw_input_error(path, "no SEGMENT cards: not an svOneDSolver input deck");

  // Joints: the junction is the first inlet segment's outlet node; every other segment of the
  // joint is moved onto it (daughters in a deck may start off the parent's last node).
  std::map<long long, size_t> seg_index;
  for (size_t k = 0; k < deck.segments.size(); ++k) {
    const auto& s = deck.segments[k];
    if (!seg_index.emplace(s.id, k).second)
      throw_input_error(fmt::format("{}:{}", path, s.line), fmt::format("SEGMENT id {} is used twice", s.id));
    for (const long long n : {s.in, s.out})
      if (!deck.nodes.count(n))
        throw_input_error(fmt::format("{}:{}", path, s.line),
                          fmt::format("SEGMENT {}: node {} is not defined", s.name, n));
  }
  std::map<long long, long long> moved;  // node -> node it is merged into
  auto find = [&](long long n) {
    for (int guard = 0; moved.count(n) && guard < 1000000; ++guard) n = moved[n];
    return n;
  };
  for (const auto& j : joints) {
    const auto where = fmt::format("{}:{}", path, j.line);
    auto get = [&](const std::string& key, const std::string& name) -> const std::vector<long long>& {
      const auto it = lists.find(key + ":" + name);
      if (it == lists.end()) throw_input_error(where, fmt::format("JOINT: no {} named {}", key, name));
      for (const long long id : it->second.first)
        if (!seg_index.count(id))
          throw_input_error(fmt::format("{}:{}", path, it->second.second),
                            fmt::format("{} {}: segment {} is not defined", key, name, id));
      return it->second.first;
    };
    const auto& ins = get("JOINTINLET", j.inlet);
    const auto& outs = get("JOINTOUTLET", j.outlet);
    if (ins.empty()) throw_input_error(where, "JOINT without inlet segments");
    const long long hub = find(deck.segments[seg_index[ins.front()]].out);
    auto merge = [&](long long n) {
      n = find(n);
      if (n != hub) moved[n] = hub;
    };
    for (size_t k = 1; k < ins.size(); ++k) merge(deck.segments[seg_index[ins[k]]].out);
    for (const long long id : outs) merge(deck.segments[seg_index[id]].in);
  }
  for (auto& s : deck.segments) {
    s.in = find(s.in);
    s.out = find(s.out);
    if (s.in == s.out)
      throw_input_error(fmt::format("{}:{}", path, s.line),
                        fmt::format("SEGMENT {} starts and ends at node {} (self-loop)", s.name, s.in));
  }
  return deck;
}

std::string vessel_name(const std::string& seg) {
  const auto p = seg.find_last_of('_');
  if (p == std::string::npos || p + 1 == seg.size()) return seg;
  for (size_t k = p + 1; k < seg.size(); ++k)
    if (!std::isdigit(static_cast<unsigned char>(seg[k]))) return seg;
  return seg.substr(0, p);
}

/// Consecutive deck segments of one vessel, cut at junctions: the network's branches.
std::vector<std::pair<std::string, std::vector<size_t>>> deck_branches(const OneDDeck& deck) {
  std::map<long long, int> degree;
  for (const auto& s : deck.segments) ++degree[s.in], ++degree[s.out];
  std::vector<std::pair<std::string, std::vector<size_t>>> out;
  std::map<std::string, int> pieces;
  for (size_t k = 0; k < deck.segments.size(); ++k) {
    const auto& s = deck.segments[k];
    const auto vessel = vessel_name(s.name);
    bool cont = false;
    if (!out.empty()) {
      const auto& prev = deck.segments[out.back().second.back()];
      cont = vessel_name(prev.name) == vessel && prev.out == s.in && degree[s.in] == 2;
    }
    if (!cont) {
      out.push_back({vessel, {}});
      ++pieces[vessel];
    }
    out.back().second.push_back(k);
  }
  std::map<std::string, int> seen;
  for (auto& [name, segs] : out)
    if (pieces[name] > 1) name = fmt::format("{}.{}", name, ++seen[name]);
  return out;
}

double area_radius(double a) { return std::sqrt(a / std::numbers::pi); }

Centerlines deck_centerlines(const std::string& path, const OneDDeck& deck, double f) {
  Centerlines c;
  c.source = path;
  for (const auto& [name, segs] : deck_branches(deck)) {
    Polyline p;
    p.name = name;
    for (size_t k = 0; k < segs.size(); ++k) {
      const auto& s = deck.segments[segs[k]];
      if (k == 0) {
        p.points.push_back(deck.nodes.at(s.in).x * f);
        p.radii.push_back(area_radius(s.area_in) * f);
      } else {
        p.radii.back() = 0.5 * (p.radii.back() + area_radius(s.area_in) * f);
      }
      p.points.push_back(deck.nodes.at(s.out).x * f);
      p.radii.push_back(area_radius(s.area_out) * f);
    }
    c.branches.push_back(std::move(p));
  }
  return c;
}

Network deck_network(const std::string& path, const OneDDeck& deck, double f, const BuildOptions& opt) {
  std::map<long long, int> node_index;
  std::vector<Vec3> nodes;
  auto node = [&](long long id) {
    const auto [it, fresh] = node_index.emplace(id, static_cast<int>(nodes.size()));
    if (fresh) nodes.push_back(deck.nodes.at(id).x * f);
    return it->second;
  };
  std::vector<Segment> segs;
  std::vector<Branch> branches;
  double total_pieces = 0.0;
  for (const auto& [name, list] : deck_branches(deck)) {
    Branch br;
    br.name = name;
    for (const size_t k : list) {
      const auto& s = deck.segments[k];
      const int a = node(s.in), b = node(s.out);
      const double r0 = area_radius(s.area_in) * f, r1 = area_radius(s.area_out) * f;
      const double len = s.length * f;
      // Split into pieces no longer than max_segment_length, and finer where the taper is steep.
      double pieces = 1.0;
      if (opt.max_segment_length > 0.0) pieces = std::max(pieces, std::ceil(len / opt.max_segment_length - 1e-9));
      if (opt.radius_change > 0.0)
        pieces = std::max(pieces, std::ceil(std::abs(r1 - r0) / (opt.radius_change * std::min(r0, r1)) - 1e-9));
      if (!(pieces <= 1e5))
        throw_input_error(
            fmt::format("{}:{}", path, s.line),
            fmt::format("SEGMENT {} would be split into more than 1e5 pieces (length {} m)", s.name, len));
      total_pieces += pieces;
      if (total_pieces > 2e7)
        throw_input_error(fmt::format("{}:{}", path, s.line),
                          "the deck would make more than 2e7 segments; check max_segment_length");
      const int n = static_cast<int>(pieces);
      if (br.nodes.empty()) br.nodes.push_back(a);
      int prev = a;
      for (int i = 1; i <= n; ++i) {
        int next = b;
        if (i < n) {
          next = static_cast<int>(nodes.size());
          const double w = static_cast<double>(i) / n;
          nodes.push_back((1.0 - w) * nodes[static_cast<size_t>(a)] + w * nodes[static_cast<size_t>(b)]);
        }
        const double w0 = static_cast<double>(i - 1) / n, w1 = static_cast<double>(i) / n;
        Segment seg;
        seg.node_from = prev;
        seg.node_to = next;
        seg.radius_from = (1.0 - w0) * r0 + w0 * r1;  // the deck's linear taper, exactly
        seg.radius_to = (1.0 - w1) * r0 + w1 * r1;
        seg.radius = 0.5 * (seg.radius_from + seg.radius_to);
        seg.length = len / n;
        seg.branch = static_cast<int>(branches.size());
        br.segments.push_back(static_cast<int>(segs.size()));
        br.nodes.push_back(next);
        segs.push_back(seg);
        prev = next;
      }
    }
    branches.push_back(std::move(br));
  }
  return Network::from_graph(std::move(nodes), std::move(segs), std::move(branches), path);
}

// ---------------------------------------------------------------------------------------

Network finish(Network net, const ReadOptions& opt, double factor, const std::string& path) {
  int pieces = 0;
  const auto comp = net.components(&pieces);
  if (pieces > 1) {
    if (opt.keep_inlet_piece) {
      const int inlet = net.widest_end();
      const int keep = inlet >= 0 ? inlet : 0;
      const int kept = comp[static_cast<size_t>(keep)];
      int dropped_segments = 0;
      for (const auto& s : net.segments())
        if (comp[static_cast<size_t>(s.node_from)] != kept) ++dropped_segments;
      warn(
          fmt::format("{}: the network has {} disconnected pieces; kept the piece with the widest end (node {}) and "
                      "dropped {} segment(s) of the others",
                      path, pieces, keep, dropped_segments));
      net = net.keep_component(keep);
    } else {
      std::vector<std::vector<std::string>> names(static_cast<size_t>(pieces));
      std::vector<int> seg_count(static_cast<size_t>(pieces), 0);
      for (const auto& s : net.segments()) ++seg_count[static_cast<size_t>(comp[static_cast<size_t>(s.node_from)])];
      for (const auto& b : net.branches())
        if (!b.nodes.empty()) names[static_cast<size_t>(comp[static_cast<size_t>(b.nodes.front())])].push_back(b.name);
      std::string list;
      for (size_t k = 0; k < names.size(); ++k) {
        std::string bn;
        for (size_t i = 0; i < names[k].size() && i < 4; ++i) bn += (i ? ", " : "") + names[k][i];
        if (names[k].size() > 4) bn += fmt::format(", ... ({} branches)", names[k].size());
        list += fmt::format("{}piece {}: {} segment(s), branches {}", k ? "; " : "", k + 1, seg_count[k], bn);
      }
      throw_input_error(path, fmt::format("the network is in {} disconnected pieces ({}); join them in the file, or "
                                          "keep only the piece of the inlet (keep_inlet_piece)",
                                          pieces, list));
    }
  }
  if (opt.check_units) check_units(net.counts().radius_max, factor, path);
  return net;
}

Centerlines vtk_centerlines(const std::string& path, const ReadOptions& opt) {
  const auto pd = detail::read_vtk_polydata(path);
  const bool own = detail::find_array(pd.field_data, "flowire_network") != nullptr;
  const double f = length_factor(opt, own ? std::optional<std::string>("m") : std::nullopt, path);
  auto c = detail::polydata_to_centerlines(pd, opt.merge_tolerance);
  scale(c, f);
  return c;
}

Network vtk_network(const std::string& path, const ReadOptions& opt) {
  const auto pd = detail::read_vtk_polydata(path);
  if (detail::find_array(pd.field_data, "flowire_network")) {
    const double f = length_factor(opt, std::string("m"), path);
    return finish(*detail::polydata_to_network(pd), opt, f, path);
  }
  const double f = length_factor(opt, std::nullopt, path);
  auto c = detail::polydata_to_centerlines(pd, opt.merge_tolerance);
  scale(c, f);
  return finish(build_checked(c, opt.build), opt, f, path);
}

Centerlines yaml_file_centerlines(const std::string& path, const ReadOptions& opt) {
  const auto file = load_yaml(path);
  const double f = length_factor(opt, file.unit, path);
  auto c = yaml_centerlines(path, file);
  scale(c, f);
  return c;
}

Network yaml_file_network(const std::string& path, const ReadOptions& opt) {
  const auto file = load_yaml(path);
  const double f = length_factor(opt, file.unit, path);
  if (auto net = yaml_network(path, file, f)) return finish(std::move(*net), opt, f, path);
  auto c = yaml_centerlines(path, file);
  scale(c, f);
  return finish(build_checked(c, opt.build), opt, f, path);
}

Centerlines deck_file_centerlines(const std::string& path, const ReadOptions& opt) {
  const auto deck = parse_deck(path);
  return deck_centerlines(path, deck, length_factor(opt, std::string("cm"), path));
}

Network deck_file_network(const std::string& path, const ReadOptions& opt) {
  const auto deck = parse_deck(path);
  const double f = length_factor(opt, std::string("cm"), path);
  return finish(deck_network(path, deck, f, opt.build), opt, f, path);
}

bool vtk_head(std::string_view head) {
  return head.find("<VTKFile") != std::string_view::npos || head.starts_with("# vtk DataFile");
}
bool yaml_head(std::string_view head) {
  return head.find("branches:") != std::string_view::npos || head.find("segments:") != std::string_view::npos;
}
bool deck_head(std::string_view head) {
  return head.find("NODE ") != std::string_view::npos && head.find("SEGMENT ") != std::string_view::npos;
}

/// The reader for `path`: by extension, else by the first 4 KiB of its content.
const NetworkReader& reader_for(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw_input_error(path, "is a directory, not a network file");
  const auto ext = lower(std::filesystem::path(path).extension().string());
  for (const auto& r : network_readers())
    for (const auto e : r.extensions)
      if (ext == e) return r;
  std::ifstream in = open_input(path, input_limit::kGeometry, "a network file");
  std::string head(4096, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  for (const auto& r : network_readers())
    if (r.recognises(head)) return r;
  std::string known;
  for (const auto& r : network_readers())
    known += fmt::format("{}{} ({})", known.empty() ? "" : ", ", fmt::join(r.extensions, "/"), r.name);
  throw_input_error(path, "unknown network format: expected " + known);
}

}  // namespace

const std::vector<NetworkReader>& network_readers() {
  static const std::vector<NetworkReader> readers = {
      {"VMTK, SimVascular or flowire centerlines", {".vtp", ".vtk"}, vtk_head, vtk_centerlines, vtk_network},
      {"flowire network", {".yaml", ".yml"}, yaml_head, yaml_file_centerlines, yaml_file_network},
      {"svOneDSolver deck", {".in"}, deck_head, deck_file_centerlines, deck_file_network},
  };
  return readers;
}

std::string network_extensions() {
  std::vector<std::string_view> all;
  for (const auto& r : network_readers()) all.insert(all.end(), r.extensions.begin(), r.extensions.end());
  return fmt::format("{}", fmt::join(all, ", "));
}

Centerlines read_centerlines(const std::string& path, const ReadOptions& opt) {
  return reader_for(path).centerlines(path, opt);
}

Network read_network(const std::string& path, const ReadOptions& opt) { return reader_for(path).network(path, opt); }

}  // namespace flowire::vessels
