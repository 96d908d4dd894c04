#include "flowire/flow/openbf.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <sstream>
#include <unordered_map>

#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"
#include "flowire/common/output.hpp"
#include "flowire/common/union_find.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/flow/svzerod/simulate.hpp"

namespace flowire::flow::openbf {

namespace {
constexpr double kPi = std::numbers::pi;

std::string at(const std::string& file, const YAML::Node& node) {
  if (node.Mark().is_null() || node.Mark().line < 0) return file;
  return fmt::format("{}:{}", file, node.Mark().line + 1);
}

double number(const std::string& file, const YAML::Node& map, const std::string& key, const std::string& what) {
  const YAML::Node n = map[key];
  double v = 0.0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    throw_input_error(at(file, n), fmt::format("{}: {} is not a number", what, key));
  }
  if (!std::isfinite(v)) throw_input_error(at(file, n), fmt::format("{}: {} = {} is not finite", what, key, v));
  return v;
}

double positive(const std::string& file, const YAML::Node& map, const std::string& key, const std::string& what) {
  const double v = number(file, map, key, what);
  if (!(v > 0.0)) throw_input_error(at(file, map[key]), fmt::format("{}: {} = {} must be > 0", what, key, v));
  return v;
}

// Keys of a vessel openBF reads, and the 1D solver's own (not used here).
const std::set<std::string>& vessel_keys() {
  static const std::set<std::string> keys = {"label",
                                             "sn",
                                             "tn",
                                             "L",
                                             "E",
                                             "R0",
                                             "Rp",
                                             "Rd",
                                             "h0",
                                             "gamma_profile",
                                             "Pext",
                                             "R1",
                                             "R2",
                                             "Cc",
                                             "Pout",
                                             "Rt",
                                             "outlet",
                                             "inlet_impedance_matching",
                                             "M",
                                             "initial_pressure",
                                             "initial_flow",
                                             "visco-elastic",
                                             "inlet",
                                             "inlet_file",
                                             "inlet_number"};
  return keys;
}

std::vector<std::pair<double, double>> read_inlet_table(const std::string& path, const std::string& model_file) {
  const std::string text = read_input(path, input_limit::kTable, "an openBF inlet table");
  std::istringstream in(text);
  std::string line;
  std::vector<std::pair<double, double>> rows;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream ls(line);
    std::string a, b;
    ls >> a >> b;
    char* end = nullptr;
    const double t = std::strtod(a.c_str(), &end);
    const bool ok_t = !a.empty() && *end == '\0';
    const double q = std::strtod(b.c_str(), &end);
    const bool ok_q = !b.empty() && *end == '\0';
    if (!ok_t || !ok_q || !std::isfinite(t) || !std::isfinite(q))
      throw_input_error(fmt::format("{}:{}", path, n), "expected two numbers: time (s) and flow (m^3/s)");
    if (!rows.empty() && !(t > rows.back().first))
      throw_input_error(fmt::format("{}:{}", path, n),
                        fmt::format("time {} does not increase (previous {})", t, rows.back().first));
    rows.emplace_back(t, q);
  }
  if (rows.size() < 2)
    throw_input_error(path, fmt::format("an inlet table needs two rows at least (for {})", model_file));
  return rows;
}
int segment_count(const Vessel& v, const Options& o) {
  return std::max(1, static_cast<int>(std::ceil(v.length / o.max_segment_length - 1e-9)));
}
}  // namespace

bool is_model(const std::string& path) {
  try {
    const YAML::Node root = YAML::LoadFile(path);
    if (!root.IsMap() || !root["network"] || !root["network"].IsSequence() || root["network"].size() == 0) return false;
    const YAML::Node first = root["network"][0];
    return first.IsMap() && first["sn"] && first["tn"];
  } catch (const std::exception&) {
    return false;
  }
}

Model read(const std::string& path) {
  const std::string text = read_input(path, input_limit::kScene, "an openBF model (YAML)");
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw_input_error(fmt::format("{}:{}", path, e.mark.line + 1), fmt::format("not valid YAML: {}", e.msg));
  }
  Model m;
  m.file = path;
  if (!root.IsMap() || !root["network"] || !root["network"].IsSequence())
    throw_input_error(path, "an openBF model needs a `network:` list of vessels");
  static const std::set<std::string> top = {"project_name", "inlet_file", "write_results",   "blood",
                                            "solver",       "network",    "output_directory"};
  for (const auto& kv : root) {
    const auto key = kv.first.as<std::string>();
    if (!top.count(key)) throw_input_error(at(path, kv.first), fmt::format("unknown key `{}`", key));
  }
  m.name = root["project_name"] ? root["project_name"].as<std::string>() : std::filesystem::path(path).stem().string();
  if (const YAML::Node b = root["blood"]) {
    if (b["rho"]) m.rho = positive(path, b, "rho", "blood");
    if (b["mu"]) m.mu = positive(path, b, "mu", "blood");
  }
  if (const YAML::Node s = root["solver"]; s && s["cycles"]) {
    const double c = positive(path, s, "cycles", "solver");
    if (c != std::floor(c) || c > 1e5)
      throw_input_error(at(path, s["cycles"]), fmt::format("solver: cycles = {} must be a whole number <= 1e5", c));
    m.cycles = static_cast<int>(c);
  }
  // Vessels.
  std::set<std::string> labels;
  for (const auto& node : root["network"]) {
    Vessel v;
    v.line = node.Mark().line + 1;
    const std::string where = fmt::format("{}:{}", path, v.line);
    if (!node.IsMap()) throw_input_error(where, "a vessel is a map of keys");
    v.label = node["label"] ? node["label"].as<std::string>() : fmt::format("vessel{}", m.vessels.size() + 1);
    const std::string what = fmt::format("vessel `{}`", v.label);
    if (!labels.insert(v.label).second) throw_input_error(where, fmt::format("{}: the label is used twice", what));
    for (const auto& kv : node) {
      const auto key = kv.first.as<std::string>();
      if (key == "gamma profile") {
        m.warnings.push_back(fmt::format(
            "{}: `gamma profile` (with a space) is not a key openBF reads (it takes gamma_profile = 2); read the same",
            at(path, kv.first)));
        continue;
      }
      if (!vessel_keys().count(key))
        throw_input_error(at(path, kv.first), fmt::format("{}: unknown key `{}`", what, key));
    }
    for (const char* k : {"sn", "tn", "L", "E"})
      if (!node[k]) throw_input_error(where, fmt::format("{}: `{}` is missing", what, k));
    const double sn = number(path, node, "sn", what), tn = number(path, node, "tn", what);
    if (sn != std::floor(sn) || tn != std::floor(tn) || sn < 1 || tn < 1 || sn == tn)
      throw_input_error(where, fmt::format("{}: sn = {} and tn = {} must be distinct node ids >= 1", what, sn, tn));
    v.sn = static_cast<int>(sn);
    v.tn = static_cast<int>(tn);
    v.length = positive(path, node, "L", what);
    v.youngs_modulus = positive(path, node, "E", what);
    if (node["R0"]) {
      v.rp = v.rd = positive(path, node, "R0", what);
    } else {
      if (!node["Rp"] || !node["Rd"]) throw_input_error(where, fmt::format("{}: give R0, or Rp and Rd", what));
      v.rp = positive(path, node, "Rp", what);
      v.rd = positive(path, node, "Rd", what);
    }
    if (node["h0"]) v.h0 = positive(path, node, "h0", what);
    if (node["gamma_profile"]) v.gamma = positive(path, node, "gamma_profile", what);
    if (node["R1"]) v.r1 = positive(path, node, "R1", what);
    if (node["R2"]) v.r2 = positive(path, node, "R2", what);
    if (node["Cc"]) v.cc = positive(path, node, "Cc", what);
    if (node["Pout"]) v.pout = number(path, node, "Pout", what);
    if (node["Rt"]) {
      v.rt = number(path, node, "Rt", what);
      if (!(v.rt > -1.0 && v.rt < 1.0))
        throw_input_error(at(path, node["Rt"]), fmt::format("{}: Rt = {} must lie in (-1, 1)", what, v.rt));
    }
    if ((v.r2 > 0.0 || v.cc > 0.0) && !(v.r1 > 0.0))
      throw_input_error(where, fmt::format("{}: a windkessel needs R1 (proximal resistance)", what));
    if (v.r1 > 0.0 && !(v.cc > 0.0)) throw_input_error(where, fmt::format("{}: a windkessel needs Cc", what));
    m.vessels.push_back(v);
  }
  if (m.vessels.empty()) throw_input_error(path, "the network has no vessel");
  // Topology: node 1 is the inlet; one connected piece; every end but the inlet an outlet
  // vessel (its tn nobody's sn) with a condition.
  std::map<int, int> index;
  for (const auto& v : m.vessels) index.emplace(v.sn, 0), index.emplace(v.tn, 0);
  int k = 0;
  for (auto& [id, i] : index) i = k++;
  UnionFind uf(static_cast<std::size_t>(k));
  std::map<int, int> out_degree, in_degree;
  for (const auto& v : m.vessels) {
    uf.unite(index[v.sn], index[v.tn]);
    ++out_degree[v.sn];
    ++in_degree[v.tn];
  }
  if (!index.count(1)) throw_input_error(path, "no vessel starts at node 1 (the inlet)");
  if (in_degree.count(1)) throw_input_error(path, "node 1 is the inlet: no vessel may end there (tn = 1)");
  for (const auto& v : m.vessels)
    if (uf.find(index[v.sn]) != uf.find(index[1]))
      throw_input_error(fmt::format("{}:{}", path, v.line),
                        fmt::format("vessel `{}` is not connected to the inlet (node 1)", v.label));
  for (const auto& v : m.vessels) {
    if (v.sn != 1 && !in_degree.count(v.sn))
      throw_input_error(fmt::format("{}:{}", path, v.line),
                        fmt::format("vessel `{}` starts at node {}, which no vessel ends at and is not the inlet "
                                    "(node 1): openBF has one inlet",
                                    v.label, v.sn));
    const bool outlet = !out_degree.count(v.tn);
    if (!outlet && v.r1 > 0.0)
      throw_input_error(
          fmt::format("{}:{}", path, v.line),
          fmt::format("vessel `{}` has a windkessel but node {} continues into other vessels", v.label, v.tn));
  }
  // Inlet table.
  std::filesystem::path inlet = root["inlet_file"] ? root["inlet_file"].as<std::string>() : m.name + "_inlet.dat";
  if (inlet.is_relative()) inlet = std::filesystem::path(path).parent_path() / inlet;
  const auto rows = read_inlet_table(inlet.string(), path);
  for (const auto& [t, q] : rows) m.inlet_time.push_back(t), m.inlet_flow.push_back(q);
  return m;
}

double wall_thickness(const Vessel& v, double r) {
  if (v.h0 > 0.0) return v.h0;
  return r * (0.2802 * std::exp(-505.3 * r) + 0.1324 * std::exp(-11.14 * r));
}

double characteristic_impedance(const Model& m, const Vessel& v, double r) {
  const double c = std::sqrt(2.0 * v.youngs_modulus * wall_thickness(v, r) / (3.0 * m.rho * r));
  return m.rho * c / (kPi * r * r);
}

flow::OutletBC outlet_condition(const Model& m, const Vessel& v) {
  flow::OutletBC bc;
  bc.distal_pressure = v.pout;
  const double r = v.rd;
  if (v.r1 > 0.0) {
    double r2 = v.r2;
    if (!(r2 > 0.0)) r2 = v.r1 - characteristic_impedance(m, v, r);  // openBF's reading
    if (!(r2 > 0.0))
      throw_input_error(fmt::format("{}:{}", m.file, v.line),
                        fmt::format("vessel `{}`: without R2 openBF takes R2 = R1 - Z0 = {:.4g}, not positive "
                                    "(Z0 = {:.4g} Pa s/m^3)",
                                    v.label, r2, characteristic_impedance(m, v, r)));
    bc.type = flow::OutletBC::Type::Rcr;
    bc.rp = v.r1;
    bc.c = v.cc;
    bc.rd = r2;
  } else {
    bc.type = flow::OutletBC::Type::Resistance;
    bc.resistance = characteristic_impedance(m, v, r) * (1.0 + v.rt) / (1.0 - v.rt);
  }
  return bc;
}

nlohmann::json to_svzerod(const Model& m, const Options& o) {
  using nlohmann::json;
  json vessels = json::array(), junctions = json::array(), bcs = json::array();
  // Per vessel its segments; per node the first segment of each vessel leaving it and the last
  // of each vessel ending there.
  std::map<int, std::vector<std::string>> into, out_of;
  int id = 0;
  const std::array<double, 3> gx = {-std::sqrt(0.6), 0.0, std::sqrt(0.6)};
  const std::array<double, 3> gw = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
  for (const auto& v : m.vessels) {
    const int n = segment_count(v, o);
    const double dx = v.length / n;
    auto radius = [&](double x) { return v.rp + (v.rd - v.rp) * x / v.length; };
    // ∫ f(r(x)) dx over [a, b] by three-point Gauss–Legendre (r is linear, f smooth).
    auto integral = [&](double a, double b, auto f) {
      double sum = 0.0;
      for (int q = 0; q < 3; ++q) sum += 0.5 * gw[q] * (b - a) * f(radius(0.5 * (a + b) + 0.5 * (b - a) * gx[q]));
      return sum;
    };
    auto Rp = [&](double r) { return 2.0 * (v.gamma + 2.0) * m.mu / (kPi * std::pow(r, 4)); };
    auto Lp = [&](double r) { return m.rho / (kPi * r * r); };
    auto Cp = [&](double r) { return 3.0 * kPi * r * r * r / (2.0 * v.youngs_modulus * wall_thickness(v, r)); };
    // A staggered line: pressures at the nodes x_k = k dx (k = 0..n), each with the compliance
    // of [x_k − dx/2, x_k + dx/2] within the vessel; flows between them through the R and L of
    // [x_k, x_k+1]. Cell k is a BloodVesselCRL (C at its inlet node, then R and L); a last
    // cell of C alone holds the node x_n. Second order in dx, like the 1D model's own schemes.
    for (int s = 0; s <= n; ++s) {
      const double x = s * dx;
      const double C = integral(std::max(0.0, x - 0.5 * dx), std::min(v.length, x + 0.5 * dx), Cp);
      const double R = s < n ? integral(x, x + dx, Rp) : 0.0;
      const double L = s < n ? integral(x, x + dx, Lp) : 0.0;
      const std::string name = fmt::format("{}#{}", v.label, s);
      json vessel = {{"vessel_id", id++},
                     {"vessel_name", name},
                     {"vessel_length", s < n ? dx : 0.0},
                     {"zero_d_element_type", "BloodVesselCRL"},
                     {"zero_d_element_values", {{"R_poiseuille", R}, {"C", C}, {"L", L}}}};
      json bc = json::object();
      if (s == 0 && v.sn == 1) bc["inlet"] = "INFLOW";
      const bool last = s == n;
      const bool outlet =
          last && std::none_of(m.vessels.begin(), m.vessels.end(), [&](const Vessel& w) { return w.sn == v.tn; });
      if (outlet) bc["outlet"] = "OUT_" + v.label;
      if (!bc.empty()) vessel["boundary_conditions"] = bc;
      vessels.push_back(vessel);
      if (s == 0) out_of[v.sn].push_back(name);
      if (last) into[v.tn].push_back(name);
      if (s > 0)
        junctions.push_back({{"junction_name", "J_" + name},
                             {"junction_type", "NORMAL_JUNCTION"},
                             {"inlet_vessels", {id - 2}},
                             {"outlet_vessels", {id - 1}}});
    }
    if (std::none_of(m.vessels.begin(), m.vessels.end(), [&](const Vessel& w) { return w.sn == v.tn; })) {
      bcs.push_back(outlet_condition(m, v).to_svzerod("OUT_" + v.label));
    }
  }
  // Junctions at the network's nodes (ids of the blocks by name).
  std::unordered_map<std::string, int> ids;
  for (const auto& v : vessels) ids[v["vessel_name"].get<std::string>()] = v["vessel_id"].get<int>();
  for (const auto& [node, ins] : into) {
    const auto it = out_of.find(node);
    if (it == out_of.end()) continue;  // an outlet
    json in = json::array(), out = json::array();
    for (const auto& name : ins) in.push_back(ids[name]);
    for (const auto& name : it->second) out.push_back(ids[name]);
    junctions.push_back({{"junction_name", fmt::format("N{}", node)},
                         {"junction_type", "NORMAL_JUNCTION"},
                         {"inlet_vessels", in},
                         {"outlet_vessels", out}});
  }
  // The inlet: one cycle of the table, from t = 0.
  std::vector<double> t = m.inlet_time, q = m.inlet_flow;
  const double t0 = t.front();
  for (auto& x : t) x -= t0;
  bcs.push_back({{"bc_name", "INFLOW"}, {"bc_type", "FLOW"}, {"bc_values", {{"Q", q}, {"t", t}}}});
  const int interval = std::max(1, o.steps_per_cycle / 100);
  json model = {{"simulation_parameters",
                 {{"number_of_cardiac_cycles", m.cycles},
                  {"number_of_time_pts_per_cardiac_cycle", o.steps_per_cycle + 1},
                  {"output_all_cycles", false},
                  {"output_interval", interval},
                  {"steady_initial", true}}},
                {"vessels", vessels},
                {"junctions", junctions},
                {"boundary_conditions", bcs}};
  return model;
}

Waveforms simulate(const Model& m, const Options& o) {
  const nlohmann::json model = to_svzerod(m, o);
  svzerod::Summary s;
  svzerod::Options so;
  so.last_cycles = m.cycles >= 2 ? 2 : 1;  // the last and the one before: how periodic the run became
  const svzerod::Result r = svzerod::simulate(model, m.file, &s, so);
  Waveforms w;
  w.cycles = s.cycles;
  w.steps = s.steps;
  w.segments = static_cast<int>(model["vessels"].size());
  w.unknowns = s.unknowns;
  w.seconds = s.seconds;
  const double period = s.period;
  // Rows by block name, in time order as recorded.
  std::unordered_map<std::string, std::vector<size_t>> rows;
  for (size_t i = 0; i < r.names.size(); ++i) rows[r.names[i]].push_back(i);
  auto col = [&](const char* name) {
    const auto it = std::find(r.columns.begin(), r.columns.end(), name);
    if (it == r.columns.end()) throw_numerical_error(fmt::format("svZeroDSolver result without column {}", name));
    return static_cast<size_t>(it - r.columns.begin()) - 2;  // after name,time
  };
  const size_t qi = col("flow_in"), qo = col("flow_out"), pi = col("pressure_in"), po = col("pressure_out");
  // Times from the first output cycle: [0, T) the one before the last (if two), then the last.
  const double t_end = period * so.last_cycles;
  const double last_start = t_end - period - 1e-9 * period;
  for (const auto& v : m.vessels) {
    const auto& first = rows.at(fmt::format("{}#0", v.label));
    const auto& last = rows.at(fmt::format("{}#{}", v.label, segment_count(v, o)));
    double mean_last = 0.0, mean_prev = 0.0;
    int count_last = 0, count_prev = 0;
    for (size_t j = 0; j < first.size(); ++j) {
      const double t = r.times[first[j]];
      const double p = r.data[first[j]][pi];
      if (t >= last_start) {
        if (t < t_end - 1e-9 * period || count_last == 0) {  // one cycle: [start, end)
          mean_last += p, ++count_last;
        }
        w.names.push_back(v.label);
        w.times.push_back(t - (t_end - period));
        w.flow_in.push_back(r.data[first[j]][qi]);
        w.pressure_in.push_back(p);
        w.flow_out.push_back(r.data[last[j]][qo]);
        w.pressure_out.push_back(r.data[last[j]][po]);
      } else if (t >= last_start - period && t < last_start) {
        mean_prev += p, ++count_prev;
      }
    }
    if (count_last > 0 && count_prev > 0) {
      mean_last /= count_last, mean_prev /= count_prev;
      w.periodicity = std::max(w.periodicity, std::abs(mean_last - mean_prev) / std::max(std::abs(mean_last), 1e-300));
    }
  }
  return w;
}

void write_vessels_csv(const Waveforms& w, const std::filesystem::path& path) {
  std::string out = "name,time,flow_in,flow_out,pressure_in,pressure_out\n";
  out.reserve(w.names.size() * 110 + 64);
  for (size_t i = 0; i < w.names.size(); ++i)
    out += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}\n", w.names[i], w.times[i], w.flow_in[i], w.flow_out[i],
                       w.pressure_in[i], w.pressure_out[i]);
  write_text_atomically(path, out);
}

std::vector<WaveformSeries> path_waveforms(const Model& m, const Waveforms& w, int count) {
  // Longest path (in length) from node 1 to an outlet: the tree's vessels by their source node.
  std::map<int, std::vector<size_t>> from;
  for (size_t k = 0; k < m.vessels.size(); ++k) from[m.vessels[k].sn].push_back(k);
  std::vector<size_t> best, path;
  double best_length = -1.0;
  std::set<int> seen;
  std::function<void(int, double)> walk = [&](int node, double length) {
    if (!seen.insert(node).second) return;  // a loop: each node once
    const auto it = from.find(node);
    if (it == from.end() || it->second.empty()) {
      if (length > best_length) best_length = length, best = path;
    } else {
      for (size_t k : it->second) {
        path.push_back(k);
        walk(m.vessels[k].tn, length + m.vessels[k].length);
        path.pop_back();
      }
    }
    seen.erase(node);
  };
  walk(1, 0.0);
  // count vessels evenly spaced in length along it, the first and the last included.
  std::vector<size_t> chosen;
  double s = 0.0;
  std::vector<double> start;
  for (size_t k : best) start.push_back(s), s += m.vessels[k].length;
  for (int i = 0; i < count && !best.empty(); ++i) {
    const double target = count > 1 ? best_length * i / (count - 1) : 0.0;
    size_t pick = 0;
    for (size_t j = 0; j < best.size(); ++j)
      if (start[j] <= target + 1e-12) pick = j;
    if (i == count - 1) pick = best.size() - 1;
    if (chosen.empty() || chosen.back() != best[pick]) chosen.push_back(best[pick]);
  }
  std::vector<WaveformSeries> out;
  for (size_t k : chosen) {
    WaveformSeries ser;
    ser.name = m.vessels[k].label;
    for (size_t r = 0; r < w.names.size(); ++r)
      if (w.names[r] == ser.name) {
        ser.time.push_back(w.times[r]);
        ser.pressure.push_back(w.pressure_in[r]);
        ser.flow.push_back(w.flow_in[r]);
      }
    out.push_back(std::move(ser));
  }
  return out;
}

}  // namespace flowire::flow::openbf
