#include "flowire/flow/spec.hpp"

#include "flowire/flow/outlet_file.hpp"
#include "flowire/flow/rlc.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "flowire/common/config.hpp"
#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"
#include "flowire/flow/losses.hpp"

namespace flowire::flow {
namespace {
constexpr double kPi = 3.14159265358979323846;
}

Waveform Waveform::constant(double v) {
  Waveform w;
  w.kind = Kind::Constant;
  w.value = v;
  return w;
}

Waveform Waveform::sine(double systolic, double diastolic, double period) {
  if (!(period > 0.0) || !std::isfinite(period))
    throw_usage_error(fmt::format("sine waveform: period {} must be positive", period));
  Waveform w;
  w.kind = Kind::Sine;
  w.systolic = systolic;
  w.diastolic = diastolic;
  w.period = period;
  return w;
}

Waveform Waveform::table(std::vector<double> times, std::vector<double> values, bool periodic) {
  if (times.size() != values.size() || times.empty())
    throw_usage_error("table waveform: times and values must be non-empty and of equal length");
  for (size_t i = 1; i < times.size(); ++i)
    if (!(times[i] > times[i - 1])) throw_usage_error(fmt::format("table waveform: times must increase (row {})", i));
  Waveform w;
  w.kind = Kind::Table;
  w.times = std::move(times);
  w.values = std::move(values);
  w.periodic = periodic && w.times.size() > 1;
  return w;
}

double Waveform::operator()(double t) const {
  switch (kind) {
    case Kind::Constant:
      return value;
    case Kind::Sine:
      return 0.5 * (systolic - diastolic) * std::sin(2.0 * kPi * t / period) + 0.5 * (systolic + diastolic);
    case Kind::Table: {
      if (times.size() == 1) return values[0];
      const double t0 = times.front(), t1 = times.back();
      if (periodic) {
        t = t0 + std::fmod(t - t0, t1 - t0);
        if (t < t0) t += t1 - t0;
      } else {
        if (t <= t0) return values.front();
        if (t >= t1) return values.back();
      }
      const auto it = std::upper_bound(times.begin(), times.end(), t);
      size_t i = static_cast<size_t>(std::max<std::ptrdiff_t>(1, it - times.begin())) - 1;
      i = std::min(i, times.size() - 2);
      const double w = (t - times[i]) / (times[i + 1] - times[i]);
      return (1.0 - w) * values[i] + w * values[i + 1];
    }
  }
  return 0.0;
}

double Waveform::mean() const {
  switch (kind) {
    case Kind::Constant:
      return value;
    case Kind::Sine:
      return 0.5 * (systolic + diastolic);
    case Kind::Table: {
      if (times.size() == 1) return values[0];
      double s = 0.0;
      for (size_t i = 1; i < times.size(); ++i) s += 0.5 * (values[i] + values[i - 1]) * (times[i] - times[i - 1]);
      return s / (times.back() - times.front());
    }
  }
  return 0.0;
}

double Waveform::cycle() const {
  switch (kind) {
    case Kind::Constant:
      return 0.0;
    case Kind::Sine:
      return period;
    case Kind::Table:
      return periodic ? times.back() - times.front() : 0.0;
  }
  return 0.0;
}

Waveform read_waveform_csv(const std::string& path) {
  std::ifstream in = open_input(path, input_limit::kTable, "a waveform table (CSV)");
  std::string line;
  std::vector<double> t, v;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty() || line[0] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream ss(line);
    double a = 0, b = 0;
    if (!(ss >> a >> b)) {
      if (t.empty() && lineno == 1) continue;  // header
      throw_input_error(fmt::format("{}:{}", path, lineno), "expected two numbers: time,value");
    }
    if (!t.empty() && !(a > t.back())) throw_input_error(fmt::format("{}:{}", path, lineno), "times must increase");
    t.push_back(a);
    v.push_back(b);
  }
  if (t.empty()) throw_input_error(path, "the waveform table has no rows");
  return Waveform::table(std::move(t), std::move(v), true);
}

std::string_view to_string(Model m) { return m == Model::Rlc ? "rlc" : "poiseuille"; }

std::string_view to_string(SolverKind s) {
  switch (s) {
    case SolverKind::Superposition:
      return "superposition";
    case SolverKind::DenseInverse:
      return "dense_inverse";
    case SolverKind::Sparse:
      return "sparse";
    case SolverKind::Petsc:
      return "petsc";
  }
  return "?";
}

bool FlowSpec::has_nonlinear_losses() const {
  return !junctions.empty() ||
         std::any_of(segment_laws.begin(), segment_laws.end(), [](const SegmentLaw& l) { return l.nonlinear(); });
}

double FlowSpec::cycle() const {
  // The period after which every periodic inlet repeats together: the least common multiple of
  // their periods, sought among the first 64 multiples of the longest (to 1e-9), so that inlets
  // of periods T and T/2 give T whichever is listed first; the first inlet's period where there
  // is no such multiple.
  double longest = 0.0, first = 0.0;
  for (const auto& in : inlets) {
    const double c = in.waveform.cycle();
    longest = std::max(longest, c);
    if (first == 0.0 && c > 0.0) first = c;
  }
  if (!(longest > 0.0)) return 0.0;
  for (int m = 1; m <= 64; ++m) {
    const double t = m * longest;
    const bool common = std::all_of(inlets.begin(), inlets.end(), [t](const InletBC& in) {
      const double c = in.waveform.cycle();
      return !(c > 0.0) || std::abs(t / c - std::round(t / c)) <= 1e-9 * (t / c);
    });
    if (common) return t;
  }
  return first;
}

double FlowSpec::segment_compliance(const Network& net, int s) const {
  const auto& seg = net.segment(s);
  const double r1 = seg.radius_from, r2 = seg.radius_to, l = seg.length;
  for (const auto& w : branch_walls) {
    if (w.branch != seg.branch) continue;
    if (w.thickness > 0.0)  // 3π/(2Eh) ∫ r³ dx, r linear: l (r1 + r2)(r1² + r2²)/4
      return 3.0 * std::numbers::pi * l * (r1 + r2) * (r1 * r1 + r2 * r2) / (8.0 * w.youngs_modulus * w.thickness);
    return flow::segment_compliance(w.youngs_modulus, w.thickness_ratio, l, r1, r2);
  }
  return flow::segment_compliance(wall_youngs_modulus, wall_thickness_ratio, l, r1, r2);
}

FlowSpec default_spec(const Network& net, const Waveform& inlet_pressure) {
  FlowSpec s;
  InletBC in;
  in.node = net.widest_end();
  in.waveform = inlet_pressure;
  s.inlets.push_back(in);
  resolve_nodes(s, net);
  return s;
}

void resolve_nodes(FlowSpec& spec, const Network& net) {
  if (spec.inlets.empty()) throw_usage_error("flow: no inlet boundary condition");
  for (auto& in : spec.inlets)
    if (in.node < 0) in.node = net.widest_end();
  // An outlet with node -1 (at most one) is a template for every end that is neither an
  // inlet nor given an outlet of its own; no outlet at all: 0 Pa at every such end.
  OutletBC tmpl;
  const auto templates =
      std::count_if(spec.outlets.begin(), spec.outlets.end(), [](const OutletBC& o) { return o.node < 0; });
  const bool expand = spec.outlets.empty() || templates == 1;
  if (templates == 1) {
    const auto it =
        std::find_if(spec.outlets.begin(), spec.outlets.end(), [](const OutletBC& o) { return o.node < 0; });
    tmpl = *it;
    spec.outlets.erase(it);
  }
  if (expand) {
    for (int e : net.ends()) {
      const bool is_inlet =
          std::any_of(spec.inlets.begin(), spec.inlets.end(), [&](const InletBC& i) { return i.node == e; });
      const bool given =
          std::any_of(spec.outlets.begin(), spec.outlets.end(), [&](const OutletBC& o) { return o.node == e; });
      if (is_inlet || given) continue;
      OutletBC o = tmpl;
      o.node = e;
      o.defaulted = true;
      spec.outlets.push_back(o);
    }
  }
  for (const auto& o : spec.outlets)
    if (o.node < 0) throw_usage_error("flow: an outlet without node among several outlets");
}

namespace {

using config::Config;

bool is_section(const Config& cfg, const std::string& path) {
  const auto& vals = cfg.values();
  const auto it = vals.find(path);
  if (it != vals.end()) return it->second.type == config::Type::Section;
  return cfg.has_section(path);
}

Waveform waveform_from(const Config& cfg, const std::string& path) {
  if (!is_section(cfg, path)) return Waveform::constant(cfg.number(path));
  const std::string kind = cfg.string_or(path + ".waveform", cfg.has(path + ".file") ? "table" : "sine");
  if (kind == "constant") {
    if (!cfg.has(path + ".value")) throw_input_error(cfg.where(path), "waveform: constant needs 'value'");
    return Waveform::constant(cfg.number(path + ".value"));
  }
  if (kind == "sine") {
    // Every value comes from the scene or from the defaults its schema declares (a pressure
    // sine has them, a flow sine has none): nothing is assumed here.
    for (const char* key : {"systolic", "diastolic", "period"})
      if (!cfg.has(path + "." + key))
        throw_input_error(cfg.where(path),
                          fmt::format("a sine waveform needs '{}.{}'{}", path, key,
                                      path.ends_with(".flow") ? " (a flow has no default amplitude)" : ""));
    const double period = cfg.number(path + ".period");
    if (!(period > 0.0)) throw_input_error(cfg.where(path + ".period"), "period must be positive");
    return Waveform::sine(cfg.number(path + ".systolic"), cfg.number(path + ".diastolic"), period);
  }
  if (kind == "table") {
    if (!cfg.has(path + ".file")) throw_input_error(cfg.where(path), "waveform: table needs 'file' (CSV time,value)");
    return read_waveform_csv(cfg.resolve_path(cfg.string(path + ".file")));
  }
  throw_input_error(cfg.where(path + ".waveform"), fmt::format("unknown waveform '{}' (constant, sine, table)", kind));
}

int node_from(const Config& cfg, const std::string& path, const Network& net) {
  const std::string text = cfg.string(path);
  try {
    size_t used = 0;
    const int n = std::stoi(text, &used);
    if (used == text.size()) {
      if (n < 0 || n >= net.num_nodes())
        throw_input_error(cfg.where(path),
                          fmt::format("node {} is not in the network (0..{})", n, net.num_nodes() - 1));
      return n;
    }
  } catch (const std::logic_error&) {
  }
  for (const auto& b : net.branches()) {
    if (b.name != text) continue;
    const int first = b.nodes.front(), last = b.nodes.back();
    if (net.degree(first) == 1) return first;
    if (net.degree(last) == 1) return last;
    return first;
  }
  throw_input_error(cfg.where(path), fmt::format("'{}' is neither a node index nor a branch name", text));
}

/// The condition of the section at @p path (flow.outlets, or one named outlet under it).
OutletBC outlet_from(const Config& cfg, const std::string& path) {
  OutletBC o;
  const bool has_r = cfg.has(path + ".resistance");
  const bool has_rcr = cfg.has_section(path + ".rcr");
  const bool has_cor = cfg.has_section(path + ".coronary");
  const bool has_q = cfg.has(path + ".flow");
  const bool has_p = cfg.has(path + ".pressure");
  if (has_r + has_rcr + has_cor + has_q + (has_p && path != "flow.outlets") > 1)
    throw_input_error(cfg.where(path),
                      fmt::format("{}: give one of pressure, resistance, rcr, coronary or flow", path));
  const auto num = [&](const std::string& key, double fallback) { return cfg.number_or(path + key, fallback); };
  std::string where = cfg.where(path);
  if (has_rcr) {
    o = OutletBC::rcr(num(".rcr.Rp", 0.0), num(".rcr.C", 0.0), num(".rcr.Rd", 0.0), num(".rcr.Pd", 0.0));
    where = cfg.where(path + ".rcr");
  } else if (has_cor) {
    o.type = OutletBC::Type::Coronary;
    auto& k = o.coronary;
    k.ra = num(".coronary.Ra", 0.0);
    k.ca = num(".coronary.Ca", 0.0);
    k.ram = num(".coronary.Ram", 0.0);
    k.cim = num(".coronary.Cim", 0.0);
    k.pv = num(".coronary.Pv", 0.0);
    where = cfg.where(path + ".coronary");
    if (!cfg.has(path + ".coronary.Rv")) throw_input_error(where, "a coronary bed needs Rv");
    k.rv = cfg.number(path + ".coronary.Rv");
    if (cfg.has(path + ".coronary.Pim") && cfg.has(path + ".coronary.Pim_file"))
      throw_input_error(where, "give Pim or Pim_file, not both");
    k.pim = cfg.has(path + ".coronary.Pim_file")
                ? read_waveform_csv(cfg.resolve_path(cfg.string(path + ".coronary.Pim_file")))
                : Waveform::constant(num(".coronary.Pim", 0.0));
  } else if (has_r) {
    o = OutletBC::with_resistance(cfg.number(path + ".resistance"), num(".distal_pressure", 0.0));
    where = cfg.where(path + ".resistance");
  } else if (has_q) {
    o.type = OutletBC::Type::Flow;
    o.flow = Waveform::constant(cfg.number(path + ".flow"));
  } else {
    o = OutletBC::at_pressure(num(".pressure", 0.0));
  }
  o.check(where);
  return o;
}

/// The network end a named outlet stands for: a node id that is an end, or the end of the
/// branch of that name that is not the inlet.
int outlet_node(const Config& cfg, const std::string& path, const std::string& name, const Network& net,
                const std::vector<InletBC>& inlets) {
  const auto is_inlet = [&](int e) {
    return std::any_of(inlets.begin(), inlets.end(), [e](const InletBC& in) { return in.node == e; });
  };
  int node = -1;
  size_t used = 0;
  try {
    const int n = std::stoi(name, &used);
    if (used == name.size()) {
      if (n < 0 || n >= net.num_nodes())
        throw_input_error(cfg.where(path),
                          fmt::format("outlet node {} is not in the network (0..{})", n, net.num_nodes() - 1));
      node = n;
    }
  } catch (const std::logic_error&) {
  }
  if (node < 0) {
    for (const auto& b : net.branches()) {
      if (b.name != name) continue;
      for (int e : {b.nodes.back(), b.nodes.front()})
        if (node < 0 && net.degree(e) == 1 && !is_inlet(e)) node = e;
      if (node < 0)
        throw_input_error(cfg.where(path),
                          fmt::format("branch '{}' has no outlet: neither of its ends ({} and {}) is a network end "
                                      "other than the inlet",
                                      name, b.nodes.front(), b.nodes.back()));
    }
  }
  if (node < 0) {
    std::string names;
    for (const auto& b : net.branches())
      if (!b.name.empty() && (net.degree(b.nodes.front()) == 1 || net.degree(b.nodes.back()) == 1))
        names += (names.empty() ? "" : ", ") + b.name;
    throw_input_error(cfg.where(path), fmt::format("no branch named '{}' and no such node (branches with an end: {})",
                                                   name, names.empty() ? "none named" : names));
  }
  if (net.degree(node) != 1 || is_inlet(node))
    throw_input_error(cfg.where(path), fmt::format("node {} ('{}') is not an outlet: {}", node, name,
                                                   is_inlet(node) ? "it is an inlet" : "not a network end"));
  return node;
}

/// The outlets of `flow.outlets.file`, each at the network end it names (by name) or lies at (a
/// deck's outlet node, within a tenth of the end's radius); the scene's own named outlets win.
/// Every other end needs a condition: from the file, the scene, or a default the scene states.
void add_file_outlets(const Config& cfg, const Network& net, FlowSpec& s) {
  const std::string key = "flow.outlets.file";
  const std::string path = cfg.resolve_path(cfg.string(key));
  const std::string unit = cfg.string_or("vessels.length_unit", "");
  const double factor = units::length_unit_factor(unit.empty() ? "cm" : unit, cfg.where("vessels.length_unit"));
  std::vector<FileOutlet> file;
  try {
    file = read_outlet_file(path, factor);
  } catch (const Error& e) {
    if (e.kind() != ErrorKind::Input) throw;
    throw_input_error(cfg.where(key), e.what());
  }
  const auto taken = [&](int node) {
    return std::any_of(s.outlets.begin(), s.outlets.end(), [node](const OutletBC& o) { return o.node == node; });
  };
  const auto is_inlet = [&](int e) {
    return std::any_of(s.inlets.begin(), s.inlets.end(), [e](const InletBC& in) { return in.node == e; });
  };
  for (const FileOutlet& f : file) {
    int node = -1;
    if (f.has_position) {
      double best = std::numeric_limits<double>::infinity();
      for (int e : net.ends()) {
        const double d = (net.node(e) - f.position).norm();
        if (d < best) best = d, node = e;
      }
      const auto& seg = net.segment(*net.node_segments(node).first);
      if (!(best <= 0.1 * seg.radius) || is_inlet(node))
        throw_input_error(cfg.where(key),
                          fmt::format("{}: the outlet of {} at ({:.6g}, {:.6g}, {:.6g}) m is not an outlet of the "
                                      "network (the nearest end, node {}, is {:.3g} mm away{})",
                                      f.where, f.name, f.position.x(), f.position.y(), f.position.z(), node, 1e3 * best,
                                      is_inlet(node) ? ", and it is the inlet" : ""));
    } else {
      // The first of its names the network knows (a branch name or node id), else an error naming the first.
      std::string name = f.name;
      for (const auto& n : f.aliases)
        if (std::none_of(net.branches().begin(), net.branches().end(), [&](const auto& b) { return b.name == name; }))
          name = std::any_of(net.branches().begin(), net.branches().end(), [&](const auto& b) { return b.name == n; })
                     ? n
                     : name;
      try {
        node = outlet_node(cfg, key, name, net, s.inlets);
      } catch (const Error& e) {
        if (e.kind() != ErrorKind::Input) throw;
        throw_input_error(f.where,
                          fmt::format("outlet '{}' of the file does not match the network: {}", name, e.what()));
      }
    }
    if (taken(node)) continue;  // the scene names this outlet itself
    OutletBC bc = f.bc;
    bc.node = node;
    s.outlets.push_back(bc);
  }
  const bool stated_default = cfg.has("flow.outlets.pressure") || cfg.has("flow.outlets.resistance") ||
                              cfg.has("flow.outlets.flow") || cfg.has_section("flow.outlets.rcr") ||
                              cfg.has_section("flow.outlets.coronary");
  std::string missing;
  for (int e : net.ends())
    if (!is_inlet(e) && !taken(e)) missing += (missing.empty() ? "" : ", ") + std::to_string(e);
  if (!missing.empty() && !stated_default)
    throw_input_error(cfg.where(key), fmt::format("{}: the network's outlets {} have no condition in the file; give "
                                                  "them one (flow.outlets.NAME) or a default for the rest",
                                                  path, missing));
}

}  // namespace

// The keys from_config reads, declared where they are read.
void declare_scene_keys(config::Schema& s) {
  using config::Type;
  using D = units::Dimension;
  s.add("flow", Type::Section, "", D::None, "blood flow in the network (absent: no flow is computed)");
  s.add("flow.model", Type::Enum, "poiseuille", D::None,
        "poiseuille: resistances only; rlc: also inertance and wall compliance", {"poiseuille", "rlc"});
  s.add("flow.solver", Type::Enum, "superposition", D::None,
        "superposition (factor once, affine in the sources) | dense_inverse (the published precomputed K^-1) | sparse "
        "(a direct solve per frame) | petsc (distributed)",
        {"superposition", "dense_inverse", "sparse", "petsc"});
  s.add("flow.viscosity", Type::Number, "3.5e-3", D::Viscosity, "blood dynamic viscosity").positive();
  s.add("flow.density", Type::Number, "1060", D::Density, "blood density").positive();
  s.add("flow.inertance", Type::Enum, "poiseuille", D::None,
        "rlc: inertance per segment, poiseuille = rho*l/(pi*r^2), womersley = 4*rho*l/(3*pi*r^2)",
        {"poiseuille", "womersley"});
  s.add("flow.wall", Type::Section, "", D::None, "rlc: the vessel wall (compliance C = 3 pi r^3 l / (2 E h))");
  s.add("flow.wall.youngs_modulus", Type::Number, "0.4 MPa", D::Pressure, "rlc: vessel wall Young's modulus")
      .positive();
  s.add("flow.wall.thickness_ratio", Type::Number, "0.1", D::None, "rlc: wall thickness / radius").positive();
  s.add(
      "flow.wall.*", Type::Section, "", D::None,
      "NAME (a branch name): that branch's own wall, with the keys below; the keys above apply to every other branch");
  s.add("flow.wall.*.youngs_modulus", Type::Number, "", D::Pressure, "this branch: wall Young's modulus").positive();
  s.add("flow.wall.*.thickness", Type::Number, "", D::Length, "this branch: wall thickness").positive();
  s.add("flow.wall.*.thickness_ratio", Type::Number, "", D::None, "this branch: wall thickness / radius").positive();
  s.add("flow.losses", Type::Section, "", D::None,
        "losses beyond Poiseuille's law taken from the network's own geometry, each a published model "
        "(docs/flow-losses.md); they make the network nonlinear (solved by Newton's method)");
  s.add("flow.losses.stenosis", Type::Enum, "none", D::None,
        "young_tsai: every narrowing of a branch's radius (a local minimum) loses K_t rho/2 (A0/As - 1)^2 U0|U0| "
        "where its jet expands (Young & Tsai 1973, K_t = 1.52; U0 = Q/A0, A0 the lower shoulder's area, As the "
        "throat's) | borda_carnot: the same with K_t = 1, the loss of a sudden expansion (closer to 3D laminar flow "
        "through smooth stenoses, docs/flow-losses.md) | none",
        {"none", "young_tsai", "borda_carnot"});
  s.add("flow.losses.stenosis_threshold", Type::Number, "0.2", D::None,
        "a radius minimum is a stenosis from this area reduction 1 - As/A0 against its lower shoulder")
      .at_least(0.0)
      .below(1.0);
  s.add("flow.losses.expansion_coefficient", Type::Number, "", D::None,
        "K_t of the stenosis loss in place of the model's own (young_tsai 1.52, borda_carnot 1)")
      .positive();
  s.add("flow.losses.curvature", Type::Enum, "none", D::None,
        "white: every curved segment's resistance times White's ratio phi(De) for fully developed flow in a bend "
        "(1929; De = Re sqrt(a/R), R from the centerline's turning angles) | none",
        {"none", "white"});
  s.add("flow.losses.entrance", Type::Enum, "none", D::None,
        "shah: flow develops again from a uniform profile in every branch leaving a junction (and at the inlet with "
        "flow.losses.inlet_profile: flat): the excess drop of Shah's entrance correlation (1978), up to 1.25 "
        "rho/2 U^2 beyond Poiseuille's | none",
        {"none", "shah"});
  s.add("flow.losses.junction", Type::Enum, "none", D::None,
        "unified: at every junction each collecting branch's static pressure is below the supplying ones' by "
        "C rho U^2, C from the flows' shares, areas and angles (Mynard & Valen-Sendstad 2015; negative where the "
        "flow slows into a wider branch) | none",
        {"none", "unified"});
  s.add("flow.losses.inlet_profile", Type::Enum, "developed", D::None,
        "with flow.losses.entrance: developed (the inlet's flow is already Poiseuille's) | flat (it develops from "
        "the inlet too)",
        {"developed", "flat"});
  s.add("flow.profile", Type::Enum, "laminar", D::None,
        "velocity profile across a segment: laminar (the parabola of the current flow) | womersley (periodic inlets: "
        "the first 10 harmonics of each segment's flow with their own Womersley profiles; use it from alpha ~ 3, "
        "docs/blood-drag.md)",
        {"laminar", "womersley"});
  s.add("flow.inlet", Type::Section, "{}", D::None, "inlet boundary condition");
  s.add("flow.inlet.node", Type::StringOrInteger, "", D::None,
        "inlet node id (default: the network end with the largest radius)");
  // The inlet: a pressure (by default the 120/80 mmHg sine, declared here once) or a flow.
  // A flow has no default amplitude: a flow sine needs its systolic and diastolic values.
  // Under flow.inlets[] (several inlets) nothing has a default: each says its whole condition.
  auto declare_inlet = [&s](const std::string& prefix, bool defaults) {
    for (const char* what : {"pressure", "flow"}) {
      const bool p = std::string_view(what) == "pressure";
      const D dim = p ? D::Pressure : D::FlowRate;
      const std::string base = prefix + "." + what;
      const std::string q = p ? "P" : "Q";
      if (p)
        s.add(base, Type::NumberOrSection, defaults ? "{waveform: sine}" : "", dim,
              defaults ? "inlet pressure: a constant, or a waveform section (default: the sine with the defaults below)"
                       : "inlet pressure: a constant, or a waveform section");
      else
        s.add(base, Type::NumberOrSection, "", dim,
              "prescribed inlet flow instead of a pressure: a constant or a waveform section");
      s.add(base + ".waveform", Type::Enum, "", D::None,
            "sine: (" + q + "1-" + q + "2)/2 sin(2 pi t/T) + (" + q + "1+" + q +
                "2)/2; constant; table (default: table if file is given, else sine)",
            {"sine", "constant", "table"});
      s.add(base + ".systolic", Type::Number, p && defaults ? "120 mmHg" : "", dim,
            p ? "sine: P1, the highest pressure" : "sine: Q1, the highest flow (required: a flow has no default)");
      s.add(base + ".diastolic", Type::Number, p && defaults ? "80 mmHg" : "", dim,
            p ? "sine: P2, the lowest pressure" : "sine: Q2, the lowest flow (required: a flow has no default)");
      s.add(base + ".period", Type::Number, defaults ? "0.8 s" : "", D::Time, "sine: period T").positive();
      s.add(base + ".value", Type::Number, "", dim, "constant: the value");
      s.add(base + ".file", Type::String, "", D::None,
            "table: CSV with a header and columns time,value (SI), periodic");
    }
  };
  declare_inlet("flow.inlet", true);
  s.add("flow.inlets", Type::List, "", D::None,
        "several inlets (a circle of Willis, a bypass): each {node, pressure | flow} as flow.inlet, which is the "
        "one-inlet form; give one or the other");
  s.add("flow.inlets[].node", Type::StringOrInteger, "", D::None,
        "this inlet's end: node id or branch name (required)");
  declare_inlet("flow.inlets[]", false);
  s.add("flow.outlets", Type::Section, "{}", D::None, "boundary condition at every other network end");
  s.add("flow.outlets.pressure", Type::Number, "", D::Pressure,
        "fixed outlet pressure (default 0 when nothing else is given)");
  s.add("flow.outlets.resistance", Type::Number, "", D::Resistance, "outlet resistance to a distal pressure")
      .positive();
  s.add("flow.outlets.distal_pressure", Type::Number, "0", D::Pressure, "pressure behind the outlet resistance");
  s.add("flow.outlets.file", Type::String, "", D::None,
        "outlet conditions from a patient model's file: an svOneDSolver deck (.in: each outlet SEGMENT's RCR, "
        "RESISTANCE or PRESSURE table, matched to the network end at its outlet node), SimVascular's rcrt.dat (an "
        "RCR per name, a branch name or node id of the network), an svZeroDSolver model (.json: the boundary condition "
        "each vessel names as its outlet, any kind), all three in the CGS units those tools write, or an openBF model "
        "(.yaml, SI: each outlet vessel's condition by its label); the outlets named in the scene win "
        "(docs/flow-conditions.md)");
  s.add("flow.outlets.scaling", Type::Enum, "none", D::None,
        "none: every outlet gets the values above; murray: they are the total of all outlets in parallel, split so "
        "each outlet flow is proportional to r^3",
        {"none", "murray"});
  // The windkessel and coronary sections, at every outlet and at one named outlet.
  const auto declare_dynamic = [&](const std::string& base, const char* whose) {
    s.add(base + ".rcr", Type::Section, "", D::None, fmt::format("RCR windkessel {}", whose));
    s.add(base + ".rcr.Rp", Type::Number, "", D::Resistance, "proximal resistance").non_negative();
    s.add(base + ".rcr.C", Type::Number, "", D::Compliance, "capacitance").non_negative();
    s.add(base + ".rcr.Rd", Type::Number, "", D::Resistance, "distal resistance").non_negative();
    s.add(base + ".rcr.Pd", Type::Number, "", D::Pressure, "distal pressure (default 0)");
    s.add(base + ".coronary", Type::Section, "", D::None,
          fmt::format("open-loop coronary bed {} (Kim et al. 2010; svZeroDSolver's CORONARY): Ra, then Ca, Ram, then "
                      "Cim against the intramyocardial pressure Pim, then Rv to Pv",
                      whose));
    s.add(base + ".coronary.Ra", Type::Number, "", D::Resistance, "arterial resistance").non_negative();
    s.add(base + ".coronary.Ca", Type::Number, "", D::Compliance, "arterial compliance").non_negative();
    s.add(base + ".coronary.Ram", Type::Number, "", D::Resistance, "microvascular resistance").non_negative();
    s.add(base + ".coronary.Cim", Type::Number, "", D::Compliance, "intramyocardial compliance").non_negative();
    s.add(base + ".coronary.Rv", Type::Number, "", D::Resistance, "venous resistance").positive();
    s.add(base + ".coronary.Pv", Type::Number, "", D::Pressure, "venous pressure (default 0)");
    s.add(base + ".coronary.Pim", Type::Number, "", D::Pressure,
          "intramyocardial pressure, constant (default 0; or Pim_file)");
    s.add(base + ".coronary.Pim_file", Type::String, "", D::None,
          "intramyocardial pressure over the cycle: CSV time,value (SI), periodic");
  };
  declare_dynamic("flow.outlets", "at every outlet");
  s.add("flow.outlets.flow", Type::Number, "", D::FlowRate, "a fixed flow leaving every outlet");
  // One outlet's own condition, under its branch name or node id; the keys above are the
  // default for the rest (and Murray's split is over the rest only).
  s.add("flow.outlets.*", Type::Section, "", D::None,
        "NAME (a branch name or an end's node id): that outlet's own condition, with the keys below; the keys above "
        "apply to every other outlet");
  s.add("flow.outlets.*.pressure", Type::Number, "", D::Pressure, "this outlet: fixed pressure");
  s.add("flow.outlets.*.resistance", Type::Number, "", D::Resistance, "this outlet: resistance to a distal pressure")
      .positive();
  s.add("flow.outlets.*.distal_pressure", Type::Number, "", D::Pressure,
        "this outlet: pressure behind its resistance (default 0)");
  s.add("flow.outlets.*.flow", Type::Number, "", D::FlowRate, "this outlet: a fixed flow leaving it");
  declare_dynamic("flow.outlets.*", "at this outlet");
}

FlowSpec from_config(const config::Config& cfg, const Network& net) {
  FlowSpec s;
  if (cfg.has("flow.model")) {
    const auto& m = cfg.string("flow.model");
    if (m == "poiseuille")
      s.model = Model::Poiseuille;
    else if (m == "rlc")
      s.model = Model::Rlc;
    else
      throw_input_error(cfg.where("flow.model"), fmt::format("'{}' is not one of: poiseuille, rlc", m));
  }
  if (cfg.has("flow.solver")) {
    const auto& m = cfg.string("flow.solver");
    if (m == "superposition")
      s.solver = SolverKind::Superposition;
    else if (m == "dense_inverse")
      s.solver = SolverKind::DenseInverse;
    else if (m == "sparse")
      s.solver = SolverKind::Sparse;
    else if (m == "petsc")
      s.solver = SolverKind::Petsc;
    else
      throw_input_error(cfg.where("flow.solver"),
                        fmt::format("'{}' is not one of: superposition, dense_inverse, sparse, petsc", m));
  }
  if (cfg.has("flow.inertance"))
    s.inertance = cfg.string("flow.inertance") == "womersley" ? Inertance::Womersley : Inertance::Poiseuille;
  if (cfg.has("flow.profile"))
    s.profile = cfg.string("flow.profile") == "womersley" ? Profile::Womersley : Profile::Laminar;
  s.viscosity = cfg.number_or("flow.viscosity", s.viscosity);
  s.density = cfg.number_or("flow.density", s.density);
  if (!(s.viscosity > 0.0)) throw_input_error(cfg.where("flow.viscosity"), "viscosity must be positive");
  if (!(s.density > 0.0)) throw_input_error(cfg.where("flow.density"), "density must be positive");
  s.wall_youngs_modulus = cfg.number_or("flow.wall.youngs_modulus", s.wall_youngs_modulus);
  s.wall_thickness_ratio = cfg.number_or("flow.wall.thickness_ratio", s.wall_thickness_ratio);
  if (cfg.has("solve.dt")) s.dt = cfg.number("solve.dt");
  // Branches with a wall of their own.
  for (const auto& [path, value] : cfg.values()) {
    if (value.type != config::Type::Section || path.rfind("flow.wall.", 0) != 0) continue;
    const std::string name = path.substr(std::string("flow.wall.").size());
    if (name.find('.') != std::string::npos) continue;
    BranchWall w;
    w.branch = net.branch_named(name);
    if (w.branch < 0)
      throw_input_error(cfg.where(path), fmt::format("no branch named '{}' (branches: {})", name, net.branch_names()));
    if (cfg.has(path + ".thickness") && cfg.has(path + ".thickness_ratio"))
      throw_input_error(cfg.where(path), fmt::format("{}: give thickness or thickness_ratio, not both", path));
    w.youngs_modulus = cfg.number_or(path + ".youngs_modulus", s.wall_youngs_modulus);
    w.thickness = cfg.number_or(path + ".thickness", 0.0);
    w.thickness_ratio = cfg.number_or(path + ".thickness_ratio", s.wall_thickness_ratio);
    s.branch_walls.push_back(w);
  }

  // The schema declares the default inlet (a pressure sine); a flow given replaces it.
  const auto given = [&](const std::string& path) {
    if (!(cfg.has(path) || cfg.has_section(path))) return false;
    const auto it = cfg.values().find(path);
    return it == cfg.values().end() || it->second.where != "default";
  };
  if (cfg.count("flow.inlets") > 0) {
    for (const char* k : {"flow.inlet.node", "flow.inlet.pressure", "flow.inlet.flow"})
      if (given(k)) throw_input_error(cfg.where(k), "give flow.inlet (one inlet) or flow.inlets (several), not both");
    for (int i = 0; i < cfg.count("flow.inlets"); ++i) {
      const std::string p = fmt::format("flow.inlets[{}]", i);
      if (!cfg.has(p + ".node")) throw_input_error(cfg.where(p), fmt::format("{}: an inlet needs its node", p));
      InletBC in;
      in.node = node_from(cfg, p + ".node", net);
      if (net.degree(in.node) != 1)
        throw_input_error(cfg.where(p + ".node"), fmt::format("{}: node {} is not a network end", p, in.node));
      for (const auto& other : s.inlets)
        if (other.node == in.node)
          throw_input_error(cfg.where(p + ".node"), fmt::format("{}: node {} is already an inlet", p, in.node));
      const bool q = given(p + ".flow"), pr = given(p + ".pressure");
      if (q == pr) throw_input_error(cfg.where(p), fmt::format("{}: give its pressure or its flow (one of them)", p));
      in.type = q ? InletBC::Type::Flow : InletBC::Type::Pressure;
      in.waveform = waveform_from(cfg, p + (q ? ".flow" : ".pressure"));
      s.inlets.push_back(in);
    }
  } else {
    InletBC in;
    in.node = cfg.has("flow.inlet.node") ? node_from(cfg, "flow.inlet.node", net) : net.widest_end();
    const bool has_q = given("flow.inlet.flow");
    const bool has_p = cfg.has("flow.inlet.pressure") || cfg.has_section("flow.inlet.pressure");
    if (given("flow.inlet.pressure") && has_q)
      throw_input_error(cfg.where("flow.inlet.flow"), "give either flow.inlet.pressure or flow.inlet.flow, not both");
    if (has_q) {
      in.type = InletBC::Type::Flow;
      in.waveform = waveform_from(cfg, "flow.inlet.flow");
    } else if (has_p) {
      in.waveform = waveform_from(cfg, "flow.inlet.pressure");
    } else {
      throw_input_error(cfg.where("flow.inlet"), "no inlet condition: give flow.inlet.pressure or flow.inlet.flow");
    }
    s.inlets.push_back(in);
  }

  const OutletBC o = outlet_from(cfg, "flow.outlets");  // template for every end not named
  // Outlets named under flow.outlets (branch names or node ids) with their own condition.
  for (const auto& [path, value] : cfg.values()) {
    if (value.type != config::Type::Section || path.rfind("flow.outlets.", 0) != 0) continue;
    const std::string name = path.substr(std::string("flow.outlets.").size());
    if (name.find('.') != std::string::npos || name == "rcr") continue;
    OutletBC named = outlet_from(cfg, path);
    named.node = outlet_node(cfg, path, name, net, s.inlets);
    for (const auto& other : s.outlets)
      if (other.node == named.node)
        throw_input_error(cfg.where(path),
                          fmt::format("outlet '{}' is node {}, which is already given a condition", name, named.node));
    s.outlets.push_back(named);
  }
  if (cfg.has("flow.outlets.file")) add_file_outlets(cfg, net, s);
  s.outlets.push_back(o);
  resolve_nodes(s, net);

  // Murray scaling: the given resistance / RCR is the total of all outlets in parallel,
  // split so that each outlet's flow is proportional to r³.
  if (cfg.string("flow.outlets.scaling") == "murray" && o.type != OutletBC::Type::Pressure) {
    auto end_radius = [&](int node) {
      const auto [b, e] = net.node_segments(node);
      if (b == e) return 0.0;
      const auto& seg = net.segment(*b);
      return seg.radius_at(node);  // the vessel's radius at the outlet
    };
    double sum = 0.0;
    for (const auto& x : s.outlets)
      if (x.defaulted) sum += std::pow(end_radius(x.node), 3);
    for (auto& x : s.outlets) {
      if (!x.defaulted) continue;  // a named outlet has its own values
      const double f = sum / std::pow(end_radius(x.node), 3);
      x.resistance *= f;
      x.rp *= f;
      x.rd *= f;
      x.c /= f;
    }
  }
  if (const std::string model = cfg.string_or("flow.losses.stenosis", "none"); model != "none") {
    s.stenoses = find_stenoses(net, s.density, cfg.number_or("flow.losses.stenosis_threshold", 0.2),
                               cfg.number_or("flow.losses.expansion_coefficient", model == "young_tsai" ? 1.52 : 1.0));
    add_stenosis_losses(net, s.stenoses, s.segment_laws);
  }
  if (cfg.string_or("flow.losses.curvature", "none") == "white")
    s.curved_segments = add_curvature_losses(net, s.density, s.viscosity, s.segment_laws);
  if (cfg.string_or("flow.losses.entrance", "none") == "shah") {
    // Flow leaves every junction (three segments or more meet) with a new boundary layer.
    std::vector<char> entrance(static_cast<size_t>(net.num_nodes()), 0);
    for (int n = 0; n < net.num_nodes(); ++n) entrance[static_cast<size_t>(n)] = net.degree(n) >= 3 ? 1 : 0;
    if (cfg.string_or("flow.losses.inlet_profile", "developed") == "flat")
      for (const auto& in : s.inlets) entrance[static_cast<size_t>(in.node)] = 1;
    s.entrances = add_entrance_losses(net, s.density, s.viscosity, entrance, s.segment_laws);
  }
  if (cfg.string_or("flow.losses.junction", "none") == "unified") s.junctions = find_junctions(net);
  return s;
}

}  // namespace flowire::flow
