// Outlet boundary conditions from svOneDSolver decks and SimVascular rcrt.dat (outlet_file.hpp).
#include "flowire/flow/outlet_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "flowire/common/error.hpp"
#include "flowire/flow/openbf.hpp"

namespace flowire::flow {

namespace {

constexpr double kResistanceCgs = 1e5;   // dyn s/cm⁵ → Pa s/m³
constexpr double kComplianceCgs = 1e-5;  // cm⁵/dyn → m³/Pa
constexpr double kPressureCgs = 0.1;     // dyn/cm² → Pa
constexpr double kFlowCgs = 1e-6;        // cm³/s → m³/s

std::vector<std::string> tokens(const std::string& line) {
  std::vector<std::string> t;
  std::istringstream in(line.substr(0, line.find('#')));
  for (std::string w; in >> w;) t.push_back(w);
  return t;
}

double number(const std::string& where, const std::string& tok, const std::string& what) {
  try {
    size_t used = 0;
    const double v = std::stod(tok, &used);
    if (used == tok.size() && std::isfinite(v)) return v;
  } catch (const std::logic_error&) {
  }
  throw_input_error(where, fmt::format("{}: '{}' is not a number", what, tok));
}

std::vector<std::string> lines_of(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw_input_error(path, "cannot open the outlet file");
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

/// A deck's DATATABLE: its (time, value) rows and where it starts.
struct Table {
  std::vector<std::pair<double, double>> rows;
  std::string where;
};

/// One value for the whole run from a table whose values do not change in time.
double constant_of(const Table& t, const std::string& name, const std::string& what) {
  if (t.rows.empty()) throw_input_error(t.where, fmt::format("DATATABLE {} is empty", name));
  for (const auto& r : t.rows)
    if (r.second != t.rows.front().second)
      throw_input_error(t.where, fmt::format("DATATABLE {}: the {} changes in time ({} then {}); a constant one only",
                                             name, what, t.rows.front().second, r.second));
  return t.rows.front().second;
}

std::vector<FileOutlet> read_deck(const std::string& path, double length_factor) {
  const auto lines = lines_of(path);
  std::map<long long, Eigen::Vector3d> nodes;
  std::map<std::string, Table> tables;
  struct Pending {
    std::string name, kind, table, where;
    long long out = 0;
  };
  std::vector<Pending> outlets;
  std::string table;  // the DATATABLE being read
  for (size_t i = 0; i < lines.size(); ++i) {
    const auto t = tokens(lines[i]);
    if (t.empty()) continue;
    const std::string where = fmt::format("{}:{}", path, i + 1);
    if (!table.empty()) {
      if (t[0] == "ENDDATATABLE") {
        table.clear();
      } else if (t.size() >= 2) {
        tables[table].rows.emplace_back(number(where, t[0], "DATATABLE time"), number(where, t[1], "DATATABLE value"));
      }
      continue;
    }
    if (t[0] == "DATATABLE" && t.size() >= 2) {
      table = t[1];
      tables[table].where = where;
    } else if (t[0] == "NODE" && t.size() >= 5) {
      nodes[std::llround(number(where, t[1], "NODE id"))] =
          length_factor *
          Eigen::Vector3d(number(where, t[2], "NODE x"), number(where, t[3], "NODE y"), number(where, t[4], "NODE z"));
    } else if (t[0] == "SEGMENT" && t.size() >= 16 && t[15] != "NOBOUND") {
      if (t.size() < 17)
        throw_input_error(where, fmt::format("SEGMENT {}: bcType {} without a DATATABLE", t[1], t[15]));
      outlets.push_back({t[1], t[15], t[16], where, std::llround(number(where, t[6], "SEGMENT outlet node"))});
    }
  }
  std::vector<FileOutlet> out;
  for (const auto& p : outlets) {
    FileOutlet o;
    o.name = p.name;
    o.where = p.where;
    const auto n = nodes.find(p.out);
    if (n == nodes.end())
      throw_input_error(p.where, fmt::format("SEGMENT {}: its outlet node {} is not defined", p.name, p.out));
    o.has_position = true;
    o.position = n->second;
    const auto tb = tables.find(p.table);
    if (tb == tables.end())
      throw_input_error(p.where, fmt::format("SEGMENT {}: no DATATABLE {} in the file", p.name, p.table));
    const Table& tab = tb->second;
    if (p.kind == "RCR") {
      // Rows Rp, C, Rd (the value column).
      if (tab.rows.size() != 3)
        throw_input_error(tab.where, fmt::format("DATATABLE {}: an RCR outlet needs 3 rows (Rp, C, Rd), not {}",
                                                 p.table, tab.rows.size()));
      o.bc.type = OutletBC::Type::Rcr;
      o.bc.rp = kResistanceCgs * tab.rows[0].second;
      o.bc.c = kComplianceCgs * tab.rows[1].second;
      o.bc.rd = kResistanceCgs * tab.rows[2].second;
      if (o.bc.rp < 0.0 || o.bc.c < 0.0 || o.bc.rd < 0.0 || !(o.bc.rp + o.bc.rd > 0.0))
        throw_input_error(tab.where, fmt::format("DATATABLE {}: Rp, C and Rd must be >= 0 and Rp + Rd > 0", p.table));
    } else if (p.kind == "RESISTANCE") {
      o.bc.type = OutletBC::Type::Resistance;
      o.bc.resistance = kResistanceCgs * constant_of(tab, p.table, "resistance");
      if (!(o.bc.resistance > 0.0))
        throw_input_error(tab.where, fmt::format("DATATABLE {}: the resistance must be positive", p.table));
    } else if (p.kind == "PRESSURE") {
      o.bc = OutletBC::at_pressure(kPressureCgs * constant_of(tab, p.table, "pressure"));
    } else {
      throw_input_error(
          p.where, fmt::format("SEGMENT {}: outlet kind {} is not read (RCR, RESISTANCE, PRESSURE)", p.name, p.kind));
    }
    out.push_back(o);
  }
  if (out.empty()) throw_input_error(path, "no SEGMENT with an outlet condition (bcType RCR, RESISTANCE, PRESSURE)");
  return out;
}

std::vector<FileOutlet> read_rcrt(const std::string& path) {
  // SimVascular rcrt.dat: a first line with the number of distal-pressure points, then per
  // outlet: the points count, the face name, Rp, C, Rd, and that many "time Pd" lines.
  const auto lines = lines_of(path);
  std::vector<std::pair<std::string, std::string>> t;  // (token line, where), blank lines skipped
  for (size_t i = 0; i < lines.size(); ++i) {
    const auto tk = tokens(lines[i]);
    if (!tk.empty()) t.emplace_back(lines[i], fmt::format("{}:{}", path, i + 1));
  }
  auto field = [&](size_t k, const char* what) -> const std::pair<std::string, std::string>& {
    if (k >= t.size()) throw_input_error(path, fmt::format("the file ends where {} was expected", what));
    return t[k];
  };
  std::vector<FileOutlet> out;
  size_t k = 1;
  while (k < t.size()) {
    const auto& cnt = field(k, "an outlet's point count");
    const double points = number(cnt.second, tokens(cnt.first)[0], "point count");
    FileOutlet o;
    o.name = tokens(field(k + 1, "a face name").first)[0];
    o.where = field(k + 1, "a face name").second;
    auto value = [&](size_t at, const char* what) {
      const auto& f = field(at, what);
      return number(f.second, tokens(f.first)[0], what);
    };
    o.bc.type = OutletBC::Type::Rcr;
    o.bc.rp = kResistanceCgs * value(k + 2, "Rp");
    o.bc.c = kComplianceCgs * value(k + 3, "C");
    o.bc.rd = kResistanceCgs * value(k + 4, "Rd");
    if (o.bc.rp < 0.0 || o.bc.c < 0.0 || o.bc.rd < 0.0 || !(o.bc.rp + o.bc.rd > 0.0))
      throw_input_error(o.where, fmt::format("{}: Rp, C and Rd must be >= 0 and Rp + Rd > 0", o.name));
    if (!(points >= 1.0) || std::floor(points) != points)
      throw_input_error(cnt.second, fmt::format("{}: point count '{}' is not a whole number >= 1", o.name, points));
    std::vector<double> pd;
    for (int p = 0; p < static_cast<int>(points); ++p) {
      const auto& f = field(k + 5 + static_cast<size_t>(p), "a time and distal pressure");
      const auto tk = tokens(f.first);
      if (tk.size() < 2) throw_input_error(f.second, "expected a time and a distal pressure");
      pd.push_back(number(f.second, tk[1], "distal pressure"));
    }
    for (double v : pd)
      if (v != pd.front())
        throw_input_error(o.where, fmt::format("{}: the distal pressure changes in time; a constant one only", o.name));
    o.bc.distal_pressure = kPressureCgs * pd.front();
    out.push_back(o);
    k += 5 + static_cast<size_t>(points);
  }
  if (out.empty()) throw_input_error(path, "no outlet in the file");
  return out;
}

Waveform scaled(Waveform w, double f) {
  w.value *= f;
  w.systolic *= f;
  w.diastolic *= f;
  for (double& v : w.values) v *= f;
  return w;
}

/// An outlet condition of an svZeroDSolver model, from its CGS values to SI.
OutletBC si_of_cgs(OutletBC o) {
  o.pressure = scaled(o.pressure, kPressureCgs);
  o.flow = scaled(o.flow, kFlowCgs);
  o.resistance *= kResistanceCgs;
  o.distal_pressure *= kPressureCgs;
  o.rp *= kResistanceCgs;
  o.rd *= kResistanceCgs;
  o.c *= kComplianceCgs;
  auto& k = o.coronary;
  k.ra *= kResistanceCgs;
  k.ram *= kResistanceCgs;
  k.rv *= kResistanceCgs;
  k.ca *= kComplianceCgs;
  k.cim *= kComplianceCgs;
  k.pv *= kPressureCgs;
  k.pim = scaled(k.pim, kPressureCgs);
  return o;
}

std::vector<FileOutlet> read_svzerod_outlets(const std::string& path) {
  // An svZeroDSolver model: its vessels name their outlet's boundary condition
  // (`boundary_conditions: {outlet: NAME}`), the conditions are listed by bc_name.
  using nlohmann::json;
  json model;
  try {
    std::ifstream in(path);
    model = json::parse(in);
  } catch (const json::exception& e) {
    throw_input_error(path, fmt::format("not valid JSON: {}", e.what()));
  }
  if (!model.is_object() || !model.contains("boundary_conditions") || !model.at("boundary_conditions").is_array())
    throw_input_error(path, "an svZeroDSolver model needs its boundary_conditions list");
  std::map<std::string, std::vector<std::string>> vessel_of;  // bc_name → the vessels it ends
  if (model.contains("vessels") && model.at("vessels").is_array())
    for (const auto& v : model.at("vessels")) {
      if (!v.is_object() || !v.contains("boundary_conditions") || !v.contains("vessel_name")) continue;
      const auto& b = v.at("boundary_conditions");
      if (b.is_object() && b.contains("outlet") && b.at("outlet").is_string() && v.at("vessel_name").is_string())
        vessel_of[b.at("outlet").get<std::string>()].push_back(v.at("vessel_name").get<std::string>());
    }
  std::vector<FileOutlet> out;
  const auto& list = model.at("boundary_conditions");
  for (size_t i = 0; i < list.size(); ++i) {
    const auto& bc = list[i];
    const std::string where = fmt::format("{}: boundary_conditions[{}]", path, i);
    if (!bc.is_object() || !bc.contains("bc_name") || !bc.at("bc_name").is_string())
      throw_input_error(where, "a boundary condition needs its bc_name");
    const std::string name = bc.at("bc_name").get<std::string>();
    const auto v = vessel_of.find(name);
    if (v == vessel_of.end()) continue;  // an inlet's condition, or one no vessel uses
    FileOutlet o;
    o.name = name;
    o.where = where;
    // The outlet by its condition's name, else by the vessel ending there (SimVascular's
    // `branchN_segK` blocks are branch N's pieces).
    for (const auto& vessel : v->second) {
      o.aliases.push_back(vessel);
      const std::string branch = std::regex_replace(vessel, std::regex("_seg[0-9]+$"), "");
      if (branch != vessel) o.aliases.push_back(branch);
    }
    o.bc = si_of_cgs(OutletBC::from_svzerod(bc, where));
    o.bc.check(where);
    out.push_back(std::move(o));
  }
  if (out.empty()) throw_input_error(path, "no vessel of the model ends in an outlet condition");
  return out;
}

}  // namespace

std::vector<FileOutlet> read_outlet_file(const std::string& path, double length_factor) {
  if (openbf::is_model(path)) {
    // An openBF model: each outlet vessel's condition (SI, as openBF's files are), by its label.
    const openbf::Model m = openbf::read(path);
    std::vector<FileOutlet> out;
    for (const auto& v : m.vessels) {
      if (std::any_of(m.vessels.begin(), m.vessels.end(), [&](const openbf::Vessel& w) { return w.sn == v.tn; }))
        continue;
      FileOutlet o;
      o.name = v.label;
      o.where = fmt::format("{}:{}", path, v.line);
      o.bc = openbf::outlet_condition(m, v);
      out.push_back(std::move(o));
    }
    return out;
  }
  const auto lines = lines_of(path);
  for (const auto& l : lines) {
    const auto first = l.find_first_not_of(" \t\r");
    if (first == std::string::npos) continue;
    if (l[first] == '{') return read_svzerod_outlets(path);
    break;
  }
  for (const auto& l : lines) {
    const auto t = tokens(l);
    if (t.empty()) continue;
    // rcrt.dat opens with a single integer; a deck with cards.
    if (t.size() == 1 && t[0].find_first_not_of("0123456789") == std::string::npos) return read_rcrt(path);
    break;
  }
  for (const auto& l : lines)
    if (l.rfind("SEGMENT ", 0) == 0) return read_deck(path, length_factor);
  throw_input_error(path,
                    "not an outlet file flowire reads (an svOneDSolver deck .in, SimVascular rcrt.dat, an "
                    "svZeroDSolver model .json or an openBF model .yaml)");
}

}  // namespace flowire::flow
