// svOneDSolver input decks (.in), CGS units (cm, cm^2) unless the caller says otherwise.
// The cards read: NODE id x y z; SEGMENT name id length elements inNode outNode inArea outArea
// ...; JOINT name node inletList outletList with its JOINTINLET / JOINTOUTLET lists. Every other
// card (MODEL, MATERIAL, DATATABLE ... ENDDATATABLE, SOLVEROPTIONS, ...) is skipped.
// - read_network: each deck segment keeps its own length (not the distance between its nodes)
//   and its linear taper between the radii sqrt(area / pi) at its ends; BuildOptions may cut
//   it into shorter pieces. read_centerlines: the radius at a node between two segments of a
//   branch is the mean of their end radii there.
// - At every JOINT the daughters start at the outlet node of its first inlet segment (in a
//   deck they may start at a node of their own, off the parent's end).
// - Branches are the runs of one vessel's segments (names `vessel_0`, `vessel_1`, ...) between
//   junctions; a vessel cut by junctions gives branches `vessel.1`, `vessel.2`, ...
// Every error names the file and the line of the card at fault.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "flowire/common/error.hpp"
#include "read_internal.hpp"

namespace flowire::vessels::detail {
namespace {

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
  const std::string text = read_network_text(path);
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

}  // namespace

Centerlines read_svonedsolver_centerlines(const std::string& path, const ReadOptions& opt) {
  const auto deck = parse_deck(path);
  return deck_centerlines(path, deck, length_factor(opt, std::string("cm"), path));
}

Network read_svonedsolver_network(const std::string& path, const ReadOptions& opt) {
  const auto deck = parse_deck(path);
  const double f = length_factor(opt, std::string("cm"), path);
  return finish(deck_network(path, deck, f, opt.build), opt, f, path);
}

}  // namespace flowire::vessels::detail
