// An openBF model as a network in space (openbf.hpp, "A model as a network"): its vessels laid
// out in 3D with their own lengths and tapers, ADAN56's anatomically, and the flow data of the
// model (inlet table, outlets, walls, blood) as a scene's flow.
#include <fmt/format.h>

#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/openbf.hpp"

namespace flowire::flow::openbf {

namespace {

using vessels::Vec3;

/// The directions of ADAN56's arteries in the body (x: the patient's left, y: anterior, z: up),
/// by label without its side and its numeral (`subclavian_R_II` → `subclavian`, right side:
/// x mirrored); the arch's pieces by their whole label. Approximate anatomy, enough for a wire
/// to be pushed from a femoral artery to the aortic root along the vessels' own lengths.
std::optional<Vec3> anatomical_direction(const std::string& label) {
  static const std::map<std::string, Vec3> exact = {
      {"aortic_arch_I", {0.1, 0.2, 1.0}},          {"aortic_arch_II", {0.6, -0.3, 0.6}},
      {"aortic_arch_III", {0.6, -0.6, 0.0}},       {"aortic_arch_IV", {0.2, -0.4, -0.9}},
      {"brachiocephalic_trunk", {-0.5, 0.1, 1.0}},
  };
  static const std::vector<std::pair<std::string, Vec3>> by_base = {
      {"thoracic_aorta", {0.0, 0.0, -1.0}},
      {"abdominal_aorta", {0.0, 0.0, -1.0}},
      {"common_carotid", {0.15, 0.05, 1.0}},
      {"internal_carotid", {0.1, -0.3, 1.0}},
      {"external_carotid", {0.1, 0.4, 1.0}},
      {"vertebral", {0.2, -0.4, 1.0}},
      {"subclavian", {1.0, 0.0, 0.3}},
      {"axillary", {1.0, 0.0, -0.4}},
      {"brachial", {0.3, 0.1, -1.0}},
      {"radial", {0.25, 0.3, -1.0}},
      {"ulnar", {0.1, 0.2, -1.0}},
      {"common_interosseous", {0.2, -0.1, -1.0}},
      {"posterior_interosseous", {0.2, -0.3, -1.0}},
      {"posterior_intercostal", {1.0, -0.6, 0.0}},
      {"celiac_trunk", {0.0, 1.0, 0.0}},
      {"common_hepatic", {-1.0, 0.5, 0.0}},
      {"splenic", {1.0, 0.3, 0.1}},
      {"left_gastric", {0.3, 0.5, 1.0}},
      {"superior_mesenteric", {0.0, 1.0, -0.6}},
      {"inferior_mesenteric", {0.3, 1.0, -0.6}},
      {"renal", {1.0, 0.0, -0.1}},
      {"common_iliac", {0.4, 0.05, -1.0}},
      {"external_iliac", {0.2, 0.2, -1.0}},
      {"internal_iliac", {0.3, -0.5, -1.0}},
      {"femoral", {0.0, 0.05, -1.0}},
      {"profunda_femoris", {0.3, -0.2, -1.0}},
      {"popliteal", {0.0, -0.15, -1.0}},
      {"anterior_tibial", {0.1, 0.3, -1.0}},
      {"tibiofibular_trunk", {0.0, -0.1, -1.0}},
      {"posterior_tibial", {-0.05, -0.25, -1.0}},
  };
  if (const auto it = exact.find(label); it != exact.end()) return it->second.normalized();
  // Tokens: the side (R, L) mirrors x; numerals (I, II, ...) and levels (T6) are dropped.
  std::istringstream in(label);
  std::string tok, base;
  double side = 1.0;
  bool sided = false;
  static const std::set<std::string> numerals = {"I", "II", "III", "IV", "V", "VI", "VII", "VIII"};
  while (std::getline(in, tok, '_')) {
    if (tok == "R" || tok == "L") {
      side = tok == "R" ? -1.0 : 1.0;
      sided = true;
    } else if (!numerals.count(tok) && !(tok.size() >= 2 && tok[0] == 'T' && std::isdigit(tok[1]))) {
      base += (base.empty() ? "" : "_") + tok;
    }
  }
  for (const auto& [name, d] : by_base)
    if (base == name) {
      Vec3 v = d;
      if (sided) v.x() *= side;
      return v.normalized();
    }
  return std::nullopt;
}

/// A unit vector normal to @p d.
Vec3 normal_to(const Vec3& d) {
  const Vec3 a = std::abs(d.z()) < 0.9 ? Vec3::UnitZ() : Vec3::UnitX();
  return d.cross(a).normalized();
}

/// A polyline of length @p len from @p a to @p b (|b − a| < len): k equal chords of a circle's
/// arc, bowed towards @p side. k chords spanning the angle θ of a circle through a and b are
/// k·c·sin(θ/2k)/sin(θ/2) long (c = |b − a|), which grows from c to ∞ as θ goes to 2π.
std::vector<Vec3> arc_between(const Vec3& a, const Vec3& b, double len, const Vec3& side) {
  constexpr int k = 32;
  const double c = (b - a).norm();
  const double ratio = len / c;
  auto polyline = [&](double theta) { return k * std::sin(theta / (2.0 * k)) / std::sin(0.5 * theta); };
  double lo = 1e-9, hi = 2.0 * std::numbers::pi - 1e-9;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (polyline(mid) < ratio ? lo : hi) = mid;
  }
  const double theta = 0.5 * (lo + hi);
  const double radius = 0.5 * c / std::sin(0.5 * theta);
  const Vec3 u = (b - a) / c;
  Vec3 n = side - side.dot(u) * u;
  if (n.norm() < 1e-9) n = normal_to(u);
  n.normalize();
  const Vec3 centre = 0.5 * (a + b) - n * radius * std::cos(0.5 * theta);
  std::vector<Vec3> p;
  for (int i = 0; i <= k; ++i) {
    const double phi = -0.5 * theta + theta * i / k;
    p.push_back(centre + radius * (std::sin(phi) * u + std::cos(phi) * n));
  }
  p.front() = a, p.back() = b;
  return p;
}

double polyline_length(const std::vector<Vec3>& p) {
  double s = 0.0;
  for (size_t i = 1; i < p.size(); ++i) s += (p[i] - p[i - 1]).norm();
  return s;
}

}  // namespace

vessels::Centerlines layout(const Model& m) {
  vessels::Centerlines c;
  c.source = m.file;
  bool anatomical = false;
  for (const auto& v : m.vessels) anatomical = anatomical || anatomical_direction(v.label).has_value();
  // Vessels from node 1 outwards (breadth first), each starting where its source node lies.
  std::map<int, Vec3> at = {{1, Vec3::Zero()}};
  std::map<int, Vec3> heading = {{1, Vec3(0.0, 0.0, anatomical ? 1.0 : -1.0)}};
  std::map<int, int> depth = {{1, 0}};
  std::vector<bool> done(m.vessels.size(), false);
  std::vector<std::vector<Vec3>> points(m.vessels.size());
  for (size_t placed = 0; placed < m.vessels.size();) {
    size_t before = placed;
    for (size_t k = 0; k < m.vessels.size(); ++k) {
      const Vessel& v = m.vessels[k];
      if (done[k] || !at.count(v.sn)) continue;
      const Vec3 a = at[v.sn];
      const Vec3 d_parent = heading[v.sn];
      const auto where = fmt::format("{}:{}", m.file, v.line);
      if (at.count(v.tn)) {
        // The vessel closes a loop: a bowed arc of its own length between placed ends.
        const Vec3 b = at[v.tn];
        const double chord = (b - a).norm();
        if (chord > v.length * (1.0 + 1e-9))
          throw_input_error(where, fmt::format("vessel `{}` closes a loop whose ends lie {:.4g} m apart, longer than "
                                               "its {:.4g} m: the layout cannot place it at its own length",
                                               v.label, chord, v.length));
        points[k] = chord >= v.length * (1.0 - 1e-9) ? std::vector<Vec3>{a, b}
                                                     : arc_between(a, b, v.length, normal_to(d_parent));
      } else {
        // Siblings leaving one node spread around the parent's direction (generic layout), or
        // take their anatomical direction.
        Vec3 d;
        if (const auto dir = anatomical ? anatomical_direction(v.label) : std::nullopt) {
          d = *dir;
        } else {
          int index = 0, count = 0;
          for (size_t j = 0; j < m.vessels.size(); ++j)
            if (m.vessels[j].sn == v.sn) {
              if (j < k) ++index;
              ++count;
            }
          const double spread = count > 1 ? (index - 0.5 * (count - 1)) * 0.6 : 0.0;  // rad between siblings
          // The plane of the turn alternates with depth so the tree fills space.
          const int dep = depth[v.sn];
          Vec3 n = normal_to(d_parent);
          if (dep % 2) n = d_parent.cross(n).normalized();
          d = (std::cos(spread) * d_parent + std::sin(spread) * n).normalized();
        }
        const Vec3 b = a + v.length * d;
        points[k] = {a, b};
        at[v.tn] = b;
        heading[v.tn] = d;
        depth[v.tn] = depth[v.sn] + 1;
      }
      done[k] = true;
      ++placed;
    }
    if (placed == before) throw_input_error(m.file, "some vessels are not reachable from node 1");  // read() checks
  }
  for (size_t k = 0; k < m.vessels.size(); ++k) {
    const Vessel& v = m.vessels[k];
    vessels::Polyline p;
    p.name = v.label;
    p.points = points[k];
    const double total = polyline_length(p.points);
    double s = 0.0;
    for (size_t i = 0; i < p.points.size(); ++i) {
      if (i > 0) s += (p.points[i] - p.points[i - 1]).norm();
      p.radii.push_back(v.rp + (v.rd - v.rp) * s / total);
    }
    c.branches.push_back(std::move(p));
  }
  return c;
}

vessels::Network network(const Model& m, const vessels::BuildOptions& options) {
  return vessels::Network::build(layout(m), options);
}

namespace {
/// The network node at position @p x (an end of the network built from the layout).
int node_at(const Network& net, const Vec3& x) {
  int best = -1;
  double d = std::numeric_limits<double>::infinity();
  for (int i = 0; i < net.num_nodes(); ++i)
    if ((net.node(i) - x).norm() < d) d = (net.node(i) - x).norm(), best = i;
  return best;
}
}  // namespace

FlowSpec flow_spec(const Model& m, const Network& net) {
  FlowSpec s;
  s.model = flow::Model::Rlc;
  s.density = m.rho;
  s.viscosity = m.mu;
  const vessels::Centerlines lay = layout(m);
  std::map<std::string, int> branch_of;
  for (size_t b = 0; b < net.branches().size(); ++b) branch_of[net.branches()[b].name] = static_cast<int>(b);
  bool warned_gamma = false;
  for (size_t k = 0; k < m.vessels.size(); ++k) {
    const Vessel& v = m.vessels[k];
    const auto& pts = lay.branches[k].points;
    if (v.sn == 1) {
      InletBC in;
      in.node = node_at(net, pts.front());
      in.type = InletBC::Type::Flow;
      in.waveform = Waveform::table(m.inlet_time, m.inlet_flow);
      if (std::none_of(s.inlets.begin(), s.inlets.end(), [&](const InletBC& x) { return x.node == in.node; }))
        s.inlets.push_back(in);
    }
    if (std::none_of(m.vessels.begin(), m.vessels.end(), [&](const Vessel& w) { return w.sn == v.tn; })) {
      OutletBC o = outlet_condition(m, v);
      o.node = node_at(net, pts.back());
      s.outlets.push_back(o);
    }
    const auto b = branch_of.find(v.label);
    if (b == branch_of.end()) continue;
    BranchWall w;
    w.branch = b->second;
    w.youngs_modulus = v.youngs_modulus;
    w.thickness = wall_thickness(v, 0.5 * (v.rp + v.rd));  // Avolio's law at the mean radius
    s.branch_walls.push_back(w);
    if (v.gamma != 2.0 && !warned_gamma) {
      warn(fmt::format("{}: vessel `{}` has gamma_profile {}; the network's friction is Poiseuille's (gamma 2)", m.file,
                       v.label, v.gamma));
      warned_gamma = true;
    }
  }
  return s;
}

}  // namespace flowire::flow::openbf
