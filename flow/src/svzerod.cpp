#include "flowire/flow/svzerod.hpp"

#include <fmt/format.h>

#include <Eigen/Sparse>
#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <sstream>

#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/flow/solver.hpp"

namespace flowire::flow::svzerod {
namespace {

using json = nlohmann::json;

/// A block parameter: a number, or a table over time repeated with its period.
struct Param {
  bool constant = true;
  double value = 0.0;
  std::vector<double> t, v;
  double cycle = 0.0;
  bool steady = false;  // replaced by the arithmetic mean of the table (steady initial state)
  double mean = 0.0;

  [[nodiscard]] double get(double time) const {
    if (constant) return value;
    if (steady) return mean;
    const double rt = std::fmod(time, cycle);
    auto k = static_cast<size_t>(std::lower_bound(t.begin(), t.end(), rt) - t.begin());
    if (k == t.size()) k = t.size() - 1;
    else if (t[k] == rt) return v[k];
    const size_t m = k ? k - 1 : 1;
    return v[m] + (v[k] - v[m]) / (t[k] - t[m]) * (rt - t[m]);
  }
};

enum class Kind { Vessel, VesselCrl, Junction, VesselJunction, Flow, Pressure, Resistance, Rcr, Coronary };

struct Node {
  std::string name;
  int q = -1, p = -1;  // unknown indices
};

struct Block {
  Kind kind = Kind::Vessel;
  std::string name;
  std::vector<int> in, out;  // node indices
  std::vector<Param> par;
  int internal = -1;  // P_c of an RCR, V_im of a coronary
  bool zero_capacitance = false;  // RCR in the steady initial phase
  bool steady = false;            // coronary: steady equations in the steady initial phase
  double pim0 = 0.0, pcim0 = 0.0;  // coronary: initial-state dependent constants
  int vessel_type = 0;            // vessel: 1 inlet BC, 2 outlet BC, 3 both
  bool varres = false;            // coronary: Ram varies over the cycle (CORONARY_VAR_RES)
};

constexpr double kPi = 3.14159265358979323846;

/// Coronary microvascular resistance Ram at time t: constant, or for CORONARY_VAR_RES
/// √Ram = √Ram_min + (√Ram_max − √Ram_min)·e(t) with the contraction/relaxation cosine
/// ramps e(t) of durations T_vc and T_vr within each cycle (parameters [6..9]).
double coronary_ram(const Block& b, double t, double period) {
  if (!b.varres) return b.par[6].get(t);
  const double lo = std::sqrt(b.par[6].get(t)), hi = std::sqrt(b.par[7].get(t));
  const double tvc = b.par[8].get(t), tvr = b.par[9].get(t);
  const double tc = std::fmod(t, period);
  double e = 0.0;
  if (tc <= tvc) e = 0.5 * (1.0 - std::cos(kPi * tc / tvc));
  else if (tc <= tvc + tvr) e = 0.5 * (1.0 + std::cos(kPi * (tc - tvc) / tvr));
  const double r = lo + (hi - lo) * e;
  return r * r;
}

struct SimParams {
  int cycles = 1, pts = 2;
  double atol = 1e-8;
  int max_iter = 30;
  bool steady_initial = true;
  double rho = 0.5;
  bool variable_based = false, mean_only = false, derivative = false, all_cycles = false;
  int output_interval = 1;
  double period = -1.0;
  bool cycle_error = false;
  double cycle_error_value = 0.01;
};

struct Model {
  std::string file;
  std::vector<Block> blocks;
  std::vector<Node> nodes;
  std::vector<std::string> dofs;
  std::vector<int> vessels;  // block indices in input order
  int n = 0;
  double period = -1.0;
  double max_tau = 0.0;
  bool has_rcr = false;
  int junctions = 0, bcs = 0;
};

[[noreturn]] void bad(const Model& m, const std::string& what) { throw_input_error(m.file, what); }

Param read_param(const Model& m, const json& values, const std::string& key, const std::string& block, bool optional,
                 double fallback = 0.0) {
  Param p;
  if (!values.contains(key)) {
    if (!optional) bad(m, fmt::format("block '{}': parameter '{}' is missing", block, key));
    p.value = fallback;
    return p;
  }
  const json& x = values.at(key);
  if (x.is_number()) {
    p.value = x.get<double>();
    return p;
  }
  if (!x.is_array() || x.empty()) bad(m, fmt::format("block '{}': parameter '{}' must be a number or a list", block, key));
  p.v = x.get<std::vector<double>>();
  if (p.v.size() == 1) {
    p.value = p.v[0];
    return p;
  }
  if (!values.contains("t")) bad(m, fmt::format("block '{}': the list '{}' needs a time list 't'", block, key));
  p.t = values.at("t").get<std::vector<double>>();
  if (p.t.size() != p.v.size())
    bad(m, fmt::format("block '{}': '{}' has {} values but 't' has {}", block, key, p.v.size(), p.t.size()));
  for (size_t i = 1; i < p.t.size(); ++i)
    if (!(p.t[i] > p.t[i - 1])) bad(m, fmt::format("block '{}': times 't' must increase", block));
  p.constant = false;
  p.cycle = p.t.back() - p.t.front();
  p.mean = std::accumulate(p.v.begin(), p.v.end(), 0.0) / static_cast<double>(p.v.size());
  return p;
}

void check_keys(const Model& m, const json& values, const std::string& block, const std::vector<std::string>& allowed) {
  for (const auto& [k, v] : values.items()) {
    (void)v;
    if (!k.empty() && k[0] == '_') continue;
    if (std::find(allowed.begin(), allowed.end(), k) == allowed.end())
      bad(m, fmt::format("block '{}': unknown parameter '{}'", block, k));
  }
}

void note_period(Model& m, const Param& p) {
  if (p.constant) return;
  if (m.period > 0.0 && p.cycle != m.period)
    bad(m, fmt::format("inconsistent cardiac cycle period defined in parameters ({} and {})", m.period, p.cycle));
  m.period = p.cycle;
}

SimParams read_sim(const Model& m, const json& cfg) {
  if (!cfg.contains("simulation_parameters")) bad(m, "simulation_parameters is missing");
  if (!cfg.contains("boundary_conditions")) bad(m, "define at least one boundary condition");
  const json& s = cfg.at("simulation_parameters");
  SimParams p;
  if (s.value("coupled_simulation", false)) bad(m, "coupled_simulation is not supported");
  if (!s.contains("number_of_cardiac_cycles") || !s.contains("number_of_time_pts_per_cardiac_cycle"))
    bad(m, "simulation_parameters needs number_of_cardiac_cycles and number_of_time_pts_per_cardiac_cycle");
  p.cycles = s.at("number_of_cardiac_cycles").get<int>();
  p.pts = s.at("number_of_time_pts_per_cardiac_cycle").get<int>();
  if (p.cycles < 1 || p.pts < 2) bad(m, "need at least 1 cycle and 2 time points per cycle");
  p.cycle_error = s.value("use_cycle_to_cycle_error", false);
  p.cycle_error_value = s.value("sim_cycle_to_cycle_percent_error", 1.0) / 100.0;
  p.atol = s.value("absolute_tolerance", 1e-8);
  p.max_iter = s.value("maximum_nonlinear_iterations", 30);
  p.steady_initial = s.value("steady_initial", true);
  p.rho = s.value("rho_infty", 0.5);
  p.variable_based = s.value("output_variable_based", false);
  p.output_interval = std::max(1, s.value("output_interval", 1));
  p.mean_only = s.value("output_mean_only", false);
  p.derivative = s.value("output_derivative", false);
  p.all_cycles = s.value("output_all_cycles", false);
  p.period = s.value("cardiac_period", -1.0);
  return p;
}

Model read_model(const json& cfg, const std::string& file) {
  Model m;
  m.file = file;
  std::vector<std::pair<std::string, std::string>> connections;
  std::map<int, std::string> vessel_ids;
  std::map<std::string, int> by_name;
  auto add_block = [&](Block b) {
    if (by_name.count(b.name)) bad(m, fmt::format("two blocks are named '{}'", b.name));
    by_name[b.name] = static_cast<int>(m.blocks.size());
    m.blocks.push_back(std::move(b));
    return static_cast<int>(m.blocks.size()) - 1;
  };
  if (cfg.contains("vessels")) {
    for (const auto& v : cfg.at("vessels")) {
      const std::string name = v.at("vessel_name").get<std::string>();
      const std::string type = v.value("zero_d_element_type", std::string("BloodVessel"));
      if (type != "BloodVessel" && type != "BloodVesselCRL")
        bad(m, fmt::format("vessel '{}': block type '{}' is not supported (supported: BloodVessel, BloodVesselCRL)",
                           name, type));
      const json& vals = v.at("zero_d_element_values");
      check_keys(m, vals, name, {"R_poiseuille", "C", "L", "stenosis_coefficient"});
      Block b;
      b.kind = type == "BloodVessel" ? Kind::Vessel : Kind::VesselCrl;
      b.name = name;
      b.par = {read_param(m, vals, "R_poiseuille", name, false), read_param(m, vals, "C", name, true),
               read_param(m, vals, "L", name, true), read_param(m, vals, "stenosis_coefficient", name, true)};
      for (const auto& p : b.par) note_period(m, p);
      vessel_ids[v.at("vessel_id").get<int>()] = name;
      m.vessels.push_back(add_block(std::move(b)));
      if (v.contains("boundary_conditions")) {
        const json& bc = v.at("boundary_conditions");
        auto& vt = m.blocks.back().vessel_type;
        if (bc.contains("inlet")) {
          connections.emplace_back(bc.at("inlet").get<std::string>(), name);
          vt = bc.contains("outlet") ? 3 : 1;
        }
        if (bc.contains("outlet")) {
          connections.emplace_back(name, bc.at("outlet").get<std::string>());
          vt = 2;  // as the peer: an outlet BC marks the vessel as an outlet vessel
        }
      }
    }
  }
  for (const auto& bc : cfg.at("boundary_conditions")) {
    const std::string name = bc.at("bc_name").get<std::string>();
    const std::string type = bc.at("bc_type").get<std::string>();
    const json& vals = bc.at("bc_values");
    Block b;
    b.name = name;
    if (type == "FLOW") {
      check_keys(m, vals, name, {"Q", "t"});
      b.kind = Kind::Flow;
      b.par = {read_param(m, vals, "Q", name, false)};
    } else if (type == "PRESSURE") {
      check_keys(m, vals, name, {"P", "t"});
      b.kind = Kind::Pressure;
      b.par = {read_param(m, vals, "P", name, false)};
    } else if (type == "RESISTANCE") {
      check_keys(m, vals, name, {"R", "Pd", "t"});
      b.kind = Kind::Resistance;
      b.par = {read_param(m, vals, "R", name, false), read_param(m, vals, "Pd", name, true)};
    } else if (type == "RCR") {
      check_keys(m, vals, name, {"Rp", "C", "Rd", "Pd", "t"});
      b.kind = Kind::Rcr;
      b.par = {read_param(m, vals, "Rp", name, false), read_param(m, vals, "C", name, false),
               read_param(m, vals, "Rd", name, false), read_param(m, vals, "Pd", name, true)};
      m.has_rcr = true;
      m.max_tau = std::max(m.max_tau, b.par[2].get(0.0) * b.par[1].get(0.0));
    } else if (type == "CORONARY_VAR_RES") {
      check_keys(m, vals, name, {"Ra1", "Rv1", "Ca", "Cc", "t", "Pim", "P_v", "Ra2_min", "Ra2_max", "T_vc", "T_vr",
                                 "closed_loop_outlet"});
      if (vals.value("closed_loop_outlet", false)) bad(m, fmt::format("'{}': closed-loop coronary outlets are not supported", name));
      b.kind = Kind::Coronary;
      b.varres = true;
      b.par = {read_param(m, vals, "Ra1", name, false),     read_param(m, vals, "Rv1", name, false),
               read_param(m, vals, "Ca", name, false),      read_param(m, vals, "Cc", name, false),
               read_param(m, vals, "Pim", name, false),     read_param(m, vals, "P_v", name, false),
               read_param(m, vals, "Ra2_min", name, false), read_param(m, vals, "Ra2_max", name, false),
               read_param(m, vals, "T_vc", name, false),    read_param(m, vals, "T_vr", name, false)};
    } else if (type == "CORONARY") {
      check_keys(m, vals, name, {"Ra1", "Rv1", "Ca", "Cc", "t", "Pim", "P_v", "Ra2", "closed_loop_outlet"});
      if (vals.value("closed_loop_outlet", false)) bad(m, fmt::format("'{}': closed-loop coronary outlets are not supported", name));
      b.kind = Kind::Coronary;
      b.par = {read_param(m, vals, "Ra1", name, false), read_param(m, vals, "Rv1", name, false),
               read_param(m, vals, "Ca", name, false),  read_param(m, vals, "Cc", name, false),
               read_param(m, vals, "Pim", name, false), read_param(m, vals, "P_v", name, false),
               read_param(m, vals, "Ra2", name, false)};
    } else {
      bad(m, fmt::format(
                 "boundary condition '{}': type '{}' is not supported (supported: FLOW, PRESSURE, RESISTANCE, RCR, CORONARY, "
                 "CORONARY_VAR_RES)",
                 name, type));
    }
    for (const auto& p : b.par) note_period(m, p);
    add_block(std::move(b));
    ++m.bcs;
  }
  if (cfg.contains("junctions")) {
    for (const auto& j : cfg.at("junctions")) {
      const std::string name = j.at("junction_name").get<std::string>();
      const std::string type = j.at("junction_type").get<std::string>();
      if (type != "NORMAL_JUNCTION" && type != "BloodVesselJunction")
        bad(m, fmt::format("junction '{}': type '{}' is not supported (supported: NORMAL_JUNCTION, BloodVesselJunction)",
                           name, type));
      Block b;
      b.kind = type == "NORMAL_JUNCTION" ? Kind::Junction : Kind::VesselJunction;
      b.name = name;
      if (b.kind == Kind::VesselJunction) {
        // One R, L, stenosis coefficient per outlet: parameters [R..., L..., S...].
        const json vals = j.value("junction_values", json::object());
        check_keys(m, vals, name, {"R_poiseuille", "L", "stenosis_coefficient"});
        for (const char* key : {"R_poiseuille", "L", "stenosis_coefficient"}) {
          if (!vals.contains(key)) bad(m, fmt::format("junction '{}': list '{}' is missing", name, key));
          for (const auto& x : vals.at(key)) {
            Param p;
            p.value = x.get<double>();
            b.par.push_back(p);
          }
        }
      }
      add_block(std::move(b));
      ++m.junctions;
      if (j.contains("inlet_vessels") && j.contains("outlet_vessels")) {
        auto vessel = [&](int id) {
          const auto it = vessel_ids.find(id);
          if (it == vessel_ids.end()) bad(m, fmt::format("junction '{}': no vessel with id {}", name, id));
          return it->second;
        };
        for (int id : j.at("inlet_vessels")) connections.emplace_back(vessel(id), name);
        for (int id : j.at("outlet_vessels")) connections.emplace_back(name, vessel(id));
      } else if (j.contains("inlet_blocks") && j.contains("outlet_blocks")) {
        for (const auto& b2 : j.at("inlet_blocks")) connections.emplace_back(b2.get<std::string>(), name);
        for (const auto& b2 : j.at("outlet_blocks")) connections.emplace_back(name, b2.get<std::string>());
      } else {
        bad(m, fmt::format("junction '{}' needs inlet_vessels/outlet_vessels or inlet_blocks/outlet_blocks", name));
      }
    }
  }
  for (const char* unsupported : {"closed_loop_blocks", "valves", "chambers", "external_solver_coupling_blocks"})
    if (cfg.contains(unsupported)) bad(m, fmt::format("'{}' is not supported", unsupported));
  // One node (P, Q) per connection, in connection order.
  for (const auto& [a, b] : connections) {
    const auto ia = by_name.find(a), ib = by_name.find(b);
    if (ia == by_name.end()) bad(m, fmt::format("connection to an unknown block '{}'", a));
    if (ib == by_name.end()) bad(m, fmt::format("connection to an unknown block '{}'", b));
    Node nd;
    nd.name = a + ":" + b;
    nd.q = m.n++;
    nd.p = m.n++;
    m.dofs.push_back("flow:" + nd.name);
    m.dofs.push_back("pressure:" + nd.name);
    const int id = static_cast<int>(m.nodes.size());
    m.nodes.push_back(nd);
    m.blocks[static_cast<size_t>(ia->second)].out.push_back(id);
    m.blocks[static_cast<size_t>(ib->second)].in.push_back(id);
  }
  for (auto& b : m.blocks) {
    const size_t nodes = b.in.size() + b.out.size();
    switch (b.kind) {
      case Kind::VesselJunction:
        if (b.in.size() != 1) bad(m, fmt::format("junction '{}': a BloodVesselJunction has exactly one inlet", b.name));
        if (b.par.size() != 3 * b.out.size())
          bad(m, fmt::format("junction '{}': R_poiseuille, L and stenosis_coefficient need one value per outlet ({})",
                             b.name, b.out.size()));
        break;
      case Kind::Vessel:
      case Kind::VesselCrl:
        if (b.in.size() != 1 || b.out.size() != 1)
          bad(m, fmt::format("vessel '{}' must have one inlet and one outlet connection (has {} and {})", b.name,
                             b.in.size(), b.out.size()));
        break;
      case Kind::Junction:
        if (b.in.empty() || b.out.empty()) bad(m, fmt::format("junction '{}' needs inlets and outlets", b.name));
        break;
      default:
        if (nodes != 1) bad(m, fmt::format("boundary condition '{}' is connected {} times (needs 1)", b.name, nodes));
        break;
    }
  }
  for (auto& b : m.blocks) {
    if (b.kind == Kind::Rcr) {
      b.internal = m.n++;
      m.dofs.push_back("pressure_c:" + b.name);
    } else if (b.kind == Kind::Coronary) {
      b.internal = m.n++;
      m.dofs.push_back("volume_im:" + b.name);
    }
  }
  return m;
}

/// Residual f(y, ẏ, t) and its Jacobian ae·∂f/∂ẏ + af·∂f/∂y.
class System {
 public:
  explicit System(const Model& m) : m_(m) {}

  void evaluate(double t, const Eigen::VectorXd& y, const Eigen::VectorXd& yd, double ae, double af, Eigen::VectorXd& f,
                std::vector<Eigen::Triplet<double>>* jac) const {
    f.setZero(m_.n);
    if (jac) jac->clear();
    int row = 0;
    auto dy = [&](int r, int c, double v) {
      if (jac && v != 0.0) jac->emplace_back(r, c, af * v);
    };
    auto dyd = [&](int r, int c, double v) {
      if (jac && v != 0.0) jac->emplace_back(r, c, ae * v);
    };
    for (const auto& b : m_.blocks) {
      switch (b.kind) {
        case Kind::Vessel: {
          const auto& a = m_.nodes[static_cast<size_t>(b.in[0])];
          const auto& o = m_.nodes[static_cast<size_t>(b.out[0])];
          const double r = b.par[0].get(t), c = b.par[1].get(t), l = b.par[2].get(t), s = b.par[3].get(t);
          const double qin = y[a.q], aq = std::abs(qin), sg = (0.0 < qin) - (qin < 0.0);
          f[row] = y[a.p] - r * qin - y[o.p] - l * yd[o.q] - s * aq * qin;
          dy(row, a.p, 1.0);
          dy(row, a.q, -r - 2.0 * s * aq);
          dy(row, o.p, -1.0);
          dyd(row, o.q, -l);
          ++row;
          f[row] = qin - y[o.q] - c * yd[a.p] + c * r * yd[a.q] + 2.0 * s * aq * c * yd[a.q];
          dy(row, a.q, 1.0 + 2.0 * s * sg * c * yd[a.q]);
          dy(row, o.q, -1.0);
          dyd(row, a.p, -c);
          dyd(row, a.q, c * r + 2.0 * s * aq * c);
          ++row;
          break;
        }
        case Kind::VesselCrl: {
          // C at the inlet, then R and L: P_in − R Q_out − P_out − L Q̇_out − S|Q_out|Q_out = 0,
          // Q_in − Q_out − C Ṗ_in = 0.
          const auto& a = m_.nodes[static_cast<size_t>(b.in[0])];
          const auto& o = m_.nodes[static_cast<size_t>(b.out[0])];
          const double r = b.par[0].get(t), c = b.par[1].get(t), l = b.par[2].get(t), s = b.par[3].get(t);
          const double qo = y[o.q], aq = std::abs(qo);
          f[row] = y[a.p] - r * qo - y[o.p] - l * yd[o.q] - s * aq * qo;
          dy(row, a.p, 1.0);
          dy(row, o.q, -r - 2.0 * s * aq);
          dy(row, o.p, -1.0);
          dyd(row, o.q, -l);
          ++row;
          f[row] = y[a.q] - qo - c * yd[a.p];
          dy(row, a.q, 1.0);
          dy(row, o.q, -1.0);
          dyd(row, a.p, -c);
          ++row;
          break;
        }
        case Kind::VesselJunction: {
          // Q_in = sum Q_out; per outlet i: P_in − P_i − R_i Q_i − L_i Q̇_i − S_i|Q_i|Q_i = 0.
          const auto& a = m_.nodes[static_cast<size_t>(b.in[0])];
          const size_t n = b.out.size();
          f[row] = y[a.q];
          dy(row, a.q, 1.0);
          for (int k : b.out) {
            f[row] -= y[m_.nodes[static_cast<size_t>(k)].q];
            dy(row, m_.nodes[static_cast<size_t>(k)].q, -1.0);
          }
          ++row;
          for (size_t i = 0; i < n; ++i) {
            const auto& o = m_.nodes[static_cast<size_t>(b.out[i])];
            const double r = b.par[i].get(t), l = b.par[n + i].get(t), s = b.par[2 * n + i].get(t);
            const double qo = y[o.q], aq = std::abs(qo);
            f[row] = y[a.p] - y[o.p] - r * qo - l * yd[o.q] - s * aq * qo;
            dy(row, a.p, 1.0);
            dy(row, o.p, -1.0);
            dy(row, o.q, -r - 2.0 * s * aq);
            dyd(row, o.q, -l);
            ++row;
          }
          break;
        }
        case Kind::Junction: {
          std::vector<int> all(b.in);
          all.insert(all.end(), b.out.begin(), b.out.end());
          const auto& n0 = m_.nodes[static_cast<size_t>(all[0])];
          for (size_t i = 1; i < all.size(); ++i) {
            const auto& ni = m_.nodes[static_cast<size_t>(all[i])];
            f[row] = y[n0.p] - y[ni.p];
            dy(row, n0.p, 1.0);
            dy(row, ni.p, -1.0);
            ++row;
          }
          for (int k : b.in) {
            f[row] += y[m_.nodes[static_cast<size_t>(k)].q];
            dy(row, m_.nodes[static_cast<size_t>(k)].q, 1.0);
          }
          for (int k : b.out) {
            f[row] -= y[m_.nodes[static_cast<size_t>(k)].q];
            dy(row, m_.nodes[static_cast<size_t>(k)].q, -1.0);
          }
          ++row;
          break;
        }
        case Kind::Coronary: {
          // Open-loop coronary: Ra, Ca, Ram, Cim (intramyocardial volume V_im), Rv to P_v.
          const auto& nd = m_.nodes[static_cast<size_t>(b.in.empty() ? b.out[0] : b.in[0])];
          const double ra = b.par[0].get(t), rv = b.par[1].get(t), ca = b.par[2].get(t), cim = b.par[3].get(t);
          const double pim = b.par[4].get(t), pv = b.par[5].get(t);
          const int v = b.internal;
          if (b.steady) {
            const double ram = coronary_ram(b, 0.0, m_.period);
            f[row] = y[v];
            dy(row, v, 1.0);
            ++row;
            f[row] = -y[nd.p] + (ra + ram + rv) * y[nd.q] + pv;
            dy(row, nd.p, -1.0);
            dy(row, nd.q, ra + ram + rv);
            ++row;
            break;
          }
          const double ram = coronary_ram(b, t, m_.period);
          f[row] = cim * rv * y[nd.q] - y[v] - ca * cim * rv * yd[nd.p] + ra * ca * cim * rv * yd[nd.q] -
                   cim * rv * yd[v] + cim * (-pim + pv + b.pim0 - b.pcim0);
          dy(row, nd.q, cim * rv);
          dy(row, v, -1.0);
          dyd(row, nd.p, -ca * cim * rv);
          dyd(row, nd.q, ra * ca * cim * rv);
          dyd(row, v, -cim * rv);
          ++row;
          f[row] = cim * rv * y[nd.p] - cim * rv * ra * y[nd.q] - (rv + ram) * y[v] - cim * rv * ram * yd[v] +
                   ram * cim * pv - cim * (rv + ram) * (pim + b.pcim0 - b.pim0);
          dy(row, nd.p, cim * rv);
          dy(row, nd.q, -cim * rv * ra);
          dy(row, v, -(rv + ram));
          dyd(row, v, -cim * rv * ram);
          ++row;
          break;
        }
        case Kind::Flow:
        case Kind::Pressure:
        case Kind::Resistance:
        case Kind::Rcr: {
          const auto& nd = m_.nodes[static_cast<size_t>(b.in.empty() ? b.out[0] : b.in[0])];
          if (b.kind == Kind::Flow) {
            f[row] = y[nd.q] - b.par[0].get(t);
            dy(row, nd.q, 1.0);
          } else if (b.kind == Kind::Pressure) {
            f[row] = y[nd.p] - b.par[0].get(t);
            dy(row, nd.p, 1.0);
          } else if (b.kind == Kind::Resistance) {
            const double r = b.par[0].get(t);
            f[row] = y[nd.p] - r * y[nd.q] - b.par[1].get(t);
            dy(row, nd.p, 1.0);
            dy(row, nd.q, -r);
          } else {
            const double rp = b.par[0].get(t), c = b.zero_capacitance ? 0.0 : b.par[1].get(t), rd = b.par[2].get(t);
            const int pc = b.internal;
            f[row] = y[nd.p] - rp * y[nd.q] - y[pc];
            dy(row, nd.p, 1.0);
            dy(row, nd.q, -rp);
            dy(row, pc, -1.0);
            ++row;
            f[row] = rd * y[nd.q] - y[pc] - rd * c * yd[pc] + b.par[3].get(t);
            dy(row, nd.q, rd);
            dy(row, pc, -1.0);
            dyd(row, pc, -rd * c);
          }
          ++row;
          break;
        }
      }
    }
    if (row != m_.n)
      throw_input_error(m_.file, fmt::format("the model has {} equations for {} unknowns; check the connections", row, m_.n));
  }

 private:
  const Model& m_;
};

struct State {
  Eigen::VectorXd y, yd;
};

/// Generalized-α step with Newton iterations, as svZeroDSolver's integrator.
class Integrator {
 public:
  Integrator(const Model& m, double dt, double rho, double atol, int max_iter)
      : sys_(m), n_(m.n), dt_(dt), atol_(atol), max_iter_(max_iter), file_(m.file) {
    am_ = 0.5 * (3.0 - rho) / (1.0 + rho);
    af_ = 1.0 / (1.0 + rho);
    gamma_ = 0.5 + am_ - af_;
  }

  State step(const State& old, double time) {
    State s{old.y, old.yd * (1.0 - 1.0 / gamma_)};
    const double t = time + af_ * dt_;
    Eigen::VectorXd yaf(n_), ydam(n_), f(n_);
    ++steps_;
    for (int i = 0; i < max_iter_; ++i) {
      ydam = old.yd + (s.yd - old.yd) * am_;
      yaf = old.y + (s.y - old.y) * af_;
      sys_.evaluate(t, yaf, ydam, am_, af_ * gamma_ * dt_, f, &trip_);
      if (f.cwiseAbs().maxCoeff() < atol_) break;
      if (i == max_iter_ - 1)
        throw_numerical_error(fmt::format("{}: maximum number of non-linear iterations reached at time {}", file_, time));
      Eigen::SparseMatrix<double> j(n_, n_);
      j.setFromTriplets(trip_.begin(), trip_.end());
      lu_.compute(j);
      if (lu_.info() != Eigen::Success)
        throw_numerical_error(fmt::format("{}: the system is singular; check the model's connections, boundary "
                                          "conditions and parameters",
                                          file_));
      const Eigen::VectorXd dyd = lu_.solve(-f);
      s.yd += dyd;
      s.y += dyd * (gamma_ * dt_);
      ++newton_;
    }
    if (!s.y.allFinite()) throw_numerical_error(fmt::format("{}: the solution is not finite at time {}", file_, time));
    return s;
  }
  [[nodiscard]] double newton_per_step() const { return steps_ ? static_cast<double>(newton_) / steps_ : 0.0; }

 private:
  System sys_;
  int n_;
  double dt_, atol_;
  int max_iter_;
  std::string file_;
  double am_ = 1, af_ = 1, gamma_ = 0.5;
  std::vector<Eigen::Triplet<double>> trip_;
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu_;
  long steps_ = 0, newton_ = 0;
};

State initial_state(const Model& m, const json& cfg) {
  State s{Eigen::VectorXd::Zero(m.n), Eigen::VectorXd::Zero(m.n)};
  if (!cfg.contains("initial_condition")) return s;
  const json& ic = cfg.at("initial_condition");
  for (int i = 0; i < m.n; ++i) {
    const auto& name = m.dofs[static_cast<size_t>(i)];
    if (ic.contains(name)) {
      s.y[i] = ic.at(name).get<double>();
    } else if (ic.contains("pressure_all") && (name.rfind("pressure", 0) == 0)) {
      s.y[i] = ic.at("pressure_all").get<double>();
    } else if (ic.contains("flow_all") && name.rfind("flow:", 0) == 0) {
      s.y[i] = ic.at("flow_all").get<double>();
    }
  }
  return s;
}

}  // namespace

Result simulate(const std::string& json_path, Summary* summary) {
  Stopwatch sw;
  json cfg;
  {
    std::ifstream in(json_path);
    if (!in) throw_input_error(json_path, "cannot open the svZeroDSolver model");
    try {
      cfg = json::parse(in);
    } catch (const json::parse_error& e) {
      throw_input_error(json_path, fmt::format("not valid JSON: {}", e.what()));
    }
  }
  Model m;
  SimParams sp;
  try {
    m = read_model(cfg, json_path);
    sp = read_sim(m, cfg);
  } catch (const json::exception& e) {
    throw_input_error(json_path, fmt::format("unexpected content: {}", e.what()));
  }
  // Period: from the time tables, or simulation_parameters.cardiac_period, else 1.
  if (sp.period < 0.0 && m.period < 0.0) {
    m.period = 1.0;
  } else if (m.period >= 0.0) {
    if (sp.period >= 0.0 && m.period != sp.period)
      throw_input_error(json_path, fmt::format("inconsistent cardiac cycle period: {} in the time tables, {} in "
                                               "simulation_parameters.cardiac_period",
                                               m.period, sp.period));
  } else {
    m.period = sp.period;
  }
  if (sp.cycle_error && m.has_rcr)
    sp.cycles = static_cast<int>(std::ceil(-m.max_tau / m.period * std::log(sp.cycle_error_value)));
  const int num_steps = (sp.pts - 1) * sp.cycles + 1;
  const double dt = m.period / (static_cast<double>(sp.pts) - 1.0);

  State state = initial_state(m, cfg);
  if (sp.steady_initial) {
    // Steady: tables at their mean, RCR capacitors removed; 31 steps of a tenth of the period.
    for (auto& b : m.blocks) {
      for (auto& p : b.par) p.steady = true;
      if (b.kind == Kind::Rcr) b.zero_capacitance = true;
      b.steady = b.kind == Kind::Coronary;
    }
    Integrator steady(m, m.period / 10.0, sp.rho, sp.atol, sp.max_iter);
    for (int i = 0; i < 31; ++i) state = steady.step(state, m.period / 10.0 * i);
    for (auto& b : m.blocks) {
      for (auto& p : b.par) p.steady = false;
      b.zero_capacitance = false;
      b.steady = false;
    }
  }
  // Constants that depend on the initial state (coronary: pressure behind Ram at t = 0).
  for (auto& b : m.blocks) {
    if (b.kind != Kind::Coronary) continue;
    const auto& nd = m.nodes[static_cast<size_t>(b.in.empty() ? b.out[0] : b.in[0])];
    const auto& pim = b.par[4];
    const double ra = b.par[0].get(0.0), ca = b.par[2].get(0.0), ram = coronary_ram(b, 0.0, m.period);
    const double p_ca = state.y[nd.p] - ra * state.y[nd.q];
    const double p_ca_dot = state.yd[nd.p] - ra * state.yd[nd.q];
    const double q_am = state.y[nd.q] - ca * p_ca_dot;
    b.pcim0 = p_ca - ram * q_am;
    b.pim0 = pim.constant ? pim.value : (sp.steady_initial ? pim.mean : pim.get(0.0));
  }
  Integrator integ(m, dt, sp.rho, sp.atol, sp.max_iter);
  std::vector<double> times;
  std::vector<State> states;
  const int start_last = num_steps - sp.pts;
  double time = 0.0;
  if (sp.all_cycles || 0 >= start_last) {
    times.push_back(time);
    states.push_back(state);
  }
  int counter = 0;
  std::vector<State> last_states;  // the states of the last two cycles (cycle-to-cycle error)
  const int keep_from = num_steps - (2 * (sp.pts - 1) + 1);
  if (sp.cycle_error && keep_from <= 0) last_states.push_back(state);
  auto run_steps = [&](int from, int to) {
    for (int i = from; i < to; ++i) {
      if (sp.cycle_error && i == keep_from + 1 && keep_from > 0) last_states.push_back(state);
      state = integ.step(state, time);
      if (sp.cycle_error && i > keep_from) last_states.push_back(state);
      ++counter;
      time = dt * i;
      if (counter == sp.output_interval || (!sp.all_cycles && i == start_last)) {
        if (sp.all_cycles || i >= start_last) {
          times.push_back(time);
          states.push_back(state);
        }
        counter = 0;
      }
    }
  };
  run_steps(1, num_steps);
  int cycles = sp.cycles;
  if (sp.cycle_error && !m.has_rcr) {
    // Extra cycles until the mean flow and pressure at the vessel caps (inlet node of
    // inlet vessels, outlet node of outlet vessels) change by less than the tolerance.
    std::vector<std::pair<int, int>> caps;
    for (int vi : m.vessels) {
      const auto& b = m.blocks[static_cast<size_t>(vi)];
      if (b.vessel_type == 1 || b.vessel_type == 3)
        caps.emplace_back(m.nodes[static_cast<size_t>(b.in[0])].q, m.nodes[static_cast<size_t>(b.in[0])].p);
      else if (b.vessel_type == 2)
        caps.emplace_back(m.nodes[static_cast<size_t>(b.out[0])].q, m.nodes[static_cast<size_t>(b.out[0])].p);
    }
    const auto two = static_cast<size_t>(2 * (sp.pts - 1) + 1);
    auto converged = [&]() {
      if (last_states.size() < two) return true;
      const size_t base = last_states.size() - two;
      for (const auto& [qd, pd] : caps) {
        double q0 = 0, p0 = 0, q1 = 0, p1 = 0;
        for (int i = 0; i < sp.pts; ++i) {
          q0 += last_states[base + static_cast<size_t>(i)].y[qd];
          p0 += last_states[base + static_cast<size_t>(i)].y[pd];
          q1 += last_states[base + static_cast<size_t>(sp.pts - 1 + i)].y[qd];
          p1 += last_states[base + static_cast<size_t>(sp.pts - 1 + i)].y[pd];
        }
        if (std::abs((q1 - q0) / q0) > sp.cycle_error_value || std::abs((p1 - p0) / p0) > sp.cycle_error_value)
          return false;
      }
      return true;
    };
    for (int extra = 0; extra < 10000 && !converged(); ++extra) {
      ++cycles;
      for (int i = 1; i < sp.pts; ++i) {
        state = integ.step(state, time);
        last_states.push_back(state);
        ++counter;
        time = dt * i;
        if (counter == sp.output_interval || (!sp.all_cycles && i == start_last)) {
          if (sp.all_cycles || i >= start_last) {
            times.push_back(time);
            states.push_back(state);
          }
          counter = 0;
        }
      }
    }
  }
  if (!sp.all_cycles && !times.empty()) {
    const double t0 = times[0];
    for (auto& t : times) t -= t0;
  }

  Result r;
  r.variable_based = sp.variable_based;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (sp.variable_based) {
    r.columns = {"name", "time", "y"};
    if (sp.derivative) r.columns.push_back("ydot");
    for (int i = 0; i < m.n; ++i) {
      if (sp.mean_only) {
        double my = 0, myd = 0;
        for (const auto& s : states) my += s.y[i], myd += s.yd[i];
        r.names.push_back(m.dofs[static_cast<size_t>(i)]);
        r.times.push_back(nan);
        std::vector<double> row = {my / static_cast<double>(states.size())};
        if (sp.derivative) row.push_back(myd / static_cast<double>(states.size()));
        r.data.push_back(row);
        continue;
      }
      for (size_t k = 0; k < states.size(); ++k) {
        r.names.push_back(m.dofs[static_cast<size_t>(i)]);
        r.times.push_back(times[k]);
        std::vector<double> row = {states[k].y[i]};
        if (sp.derivative) row.push_back(states[k].yd[i]);
        r.data.push_back(row);
      }
    }
  } else {
    r.columns = {"name", "time", "flow_in", "flow_out", "pressure_in", "pressure_out"};
    if (sp.derivative)
      for (const char* c : {"d_flow_in", "d_flow_out", "d_pressure_in", "d_pressure_out"}) r.columns.emplace_back(c);
    for (int vi : m.vessels) {
      const auto& b = m.blocks[static_cast<size_t>(vi)];
      const auto& a = m.nodes[static_cast<size_t>(b.in[0])];
      const auto& o = m.nodes[static_cast<size_t>(b.out[0])];
      auto row_of = [&](const State& s) {
        std::vector<double> row = {s.y[a.q], s.y[o.q], s.y[a.p], s.y[o.p]};
        if (sp.derivative) row.insert(row.end(), {s.yd[a.q], s.yd[o.q], s.yd[a.p], s.yd[o.p]});
        return row;
      };
      if (sp.mean_only) {
        std::vector<double> mean(sp.derivative ? 8 : 4, 0.0);
        for (const auto& s : states) {
          const auto row = row_of(s);
          for (size_t c = 0; c < mean.size(); ++c) mean[c] += row[c];
        }
        for (auto& x : mean) x /= static_cast<double>(states.size());
        r.names.push_back(b.name);
        r.times.push_back(nan);
        r.data.push_back(mean);
        continue;
      }
      for (size_t k = 0; k < states.size(); ++k) {
        r.names.push_back(b.name);
        r.times.push_back(times[k]);
        r.data.push_back(row_of(states[k]));
      }
    }
  }
  if (summary) {
    summary->model = json_path;
    summary->vessels = static_cast<int>(m.vessels.size());
    summary->junctions = m.junctions;
    summary->boundary_conditions = m.bcs;
    summary->unknowns = m.n;
    summary->cycles = cycles;
    summary->steps = num_steps - 1;
    summary->rows = static_cast<int>(r.names.size());
    summary->period = m.period;
    summary->dt = dt;
    summary->newton_iterations_per_step = integ.newton_per_step();
    summary->seconds = sw.seconds();
  }
  return r;
}

void write_result_csv(const Result& r, const std::filesystem::path& path) {
  std::ostringstream out;
  out << std::scientific << std::setprecision(16);
  for (size_t c = 0; c < r.columns.size(); ++c) out << (c ? "," : "") << r.columns[c];
  out << "\n";
  for (size_t i = 0; i < r.names.size(); ++i) {
    out << r.names[i] << ",";
    if (!std::isnan(r.times[i])) out << r.times[i];
    for (double x : r.data[i]) out << "," << x;
    out << "\n";
  }
  write_text_atomically(path, out.str());
}

Summary run(const std::string& json_path, const std::filesystem::path& out_dir) {
  Summary s;
  const Result r = simulate(json_path, &s);
  std::filesystem::create_directories(out_dir);
  s.result_file = (out_dir / "svzerod_result.csv").string();
  write_result_csv(r, s.result_file);
  return s;
}

}  // namespace flowire::flow::svzerod
