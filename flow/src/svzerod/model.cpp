#include "flowire/flow/svzerod/model.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>

#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"
#include "flowire/common/steps.hpp"

namespace flowire::flow::svzerod {
namespace {

using json = nlohmann::json;

SimulationParameters read_sim(const std::string& file, const json& cfg) {
  if (!cfg.contains("simulation_parameters")) throw_input_error(file, "simulation_parameters is missing");
  const json& s = cfg.at("simulation_parameters");
  SimulationParameters p;
  if (s.value("coupled_simulation", false)) throw_input_error(file, "coupled_simulation is not supported");
  if (!s.contains("number_of_cardiac_cycles") || !s.contains("number_of_time_pts_per_cardiac_cycle"))
    throw_input_error(file,
                      "simulation_parameters needs number_of_cardiac_cycles and number_of_time_pts_per_cardiac_cycle");
  // Numbers read as doubles and checked before they become ints: a value no int holds, or
  // out of its range, is refused naming the key, never wrapped or clamped.
  auto number = [&](const char* key, double fallback, bool ok(double), const char* requirement) {
    if (!s.contains(key)) return fallback;
    if (!s.at(key).is_number()) throw_input_error(file, fmt::format("simulation_parameters.{} must be a number", key));
    const double v = s.at(key).get<double>();
    if (!ok(v)) throw_input_error(file, fmt::format("simulation_parameters.{} = {}: {}", key, v, requirement));
    return v;
  };
  auto whole = [&](const char* key, double fallback, bool ok(double), const char* requirement) {
    const double v = number(key, fallback, ok, requirement);
    if (v != std::floor(v))
      throw_input_error(file, fmt::format("simulation_parameters.{} = {}: {}", key, v, requirement));
    return static_cast<int>(v);
  };
  constexpr auto positive = [](double v) { return v > 0.0; };
  constexpr auto at_least_one = [](double v) { return v >= 1.0 && v <= 1e9; };
  constexpr auto unit_interval = [](double v) { return v >= 0.0 && v <= 1.0; };
  constexpr auto cycles_ok = [](double v) { return v >= 1.0 && v == std::floor(v); };
  constexpr auto pts_ok = [](double v) { return v >= 2.0 && v == std::floor(v); };
  // Each at least its minimum, and their product at most kMaxSteps (so that both fit an int).
  const double cycles = number("number_of_cardiac_cycles", 1, cycles_ok, "must be a whole number >= 1");
  const double pts = number("number_of_time_pts_per_cardiac_cycle", 2, pts_ok, "must be a whole number >= 2");
  check_time_steps(file, pts, cycles, "number_of_cardiac_cycles");
  p.cycles = static_cast<int>(cycles);
  p.pts = static_cast<int>(pts);
  p.cycle_error = s.value("use_cycle_to_cycle_error", false);
  p.cycle_error_value = number("sim_cycle_to_cycle_percent_error", 1.0, positive, "must be positive (> 0)") / 100.0;
  p.atol = number("absolute_tolerance", 1e-8, positive, "must be positive (> 0)");
  p.max_iter = whole("maximum_nonlinear_iterations", 30, at_least_one, "must be a whole number in [1, 1e9]");
  p.steady_initial = s.value("steady_initial", true);
  p.rho = number("rho_infty", 0.5, unit_interval, "must be in [0, 1]");
  p.variable_based = s.value("output_variable_based", false);
  p.output_interval = whole("output_interval", 1, at_least_one, "must be a whole number in [1, 1e9]");
  p.mean_only = s.value("output_mean_only", false);
  p.derivative = s.value("output_derivative", false);
  p.all_cycles = s.value("output_all_cycles", false);
  p.period = s.contains("cardiac_period") ? number("cardiac_period", 1.0, positive, "must be positive (> 0)") : -1.0;
  return p;
}

void read_blocks(Model& m, const json& cfg, const Options& options) {
  const auto& registry = Registry::instance();
  std::vector<std::pair<std::string, std::string>> connections;
  std::map<int, std::string> vessel_ids;
  std::map<std::string, size_t> by_name;
  double period = -1.0;
  const json empty = json::object();
  auto add = [&](std::unique_ptr<Block> b) {
    if (by_name.count(b->name())) throw_input_error(m.file, fmt::format("two blocks are named '{}'", b->name()));
    by_name[b->name()] = m.blocks.size();
    m.blocks.push_back(std::move(b));
    return m.blocks.back().get();
  };
  if (!cfg.contains("boundary_conditions")) throw_input_error(m.file, "define at least one boundary condition");
  if (cfg.contains("vessels")) {
    for (const auto& v : cfg.at("vessels")) {
      const std::string name = v.at("vessel_name").get<std::string>();
      const std::string type = v.value("zero_d_element_type", std::string("BloodVessel"));
      BlockInput in(v.contains("zero_d_element_values") ? v.at("zero_d_element_values") : empty, m.file, name, period);
      const Block* b = add(registry.create(Section::Vessel, type, in));
      vessel_ids[v.at("vessel_id").get<int>()] = name;
      Vessel out{b, 0};
      if (v.contains("boundary_conditions")) {
        const json& bc = v.at("boundary_conditions");
        if (bc.contains("inlet")) {
          connections.emplace_back(bc.at("inlet").get<std::string>(), name);
          out.cap = bc.contains("outlet") ? 3 : 1;
        }
        if (bc.contains("outlet")) {
          connections.emplace_back(name, bc.at("outlet").get<std::string>());
          out.cap = 2;  // as the peer: an outlet BC marks the vessel as an outlet vessel
        }
      }
      m.vessels.push_back(out);
    }
  }
  for (const auto& bc : cfg.at("boundary_conditions")) {
    const std::string name = bc.at("bc_name").get<std::string>();
    const std::string type = bc.at("bc_type").get<std::string>();
    BlockInput in(bc.contains("bc_values") ? bc.at("bc_values") : empty, m.file, name, period);
    const Block* b = add(registry.create(Section::BoundaryCondition, type, in));
    if (type == "RCR") {
      m.has_rcr = true;
      m.max_tau = std::max(m.max_tau, b->time_constant());
    }
    ++m.boundary_conditions;
  }
  if (cfg.contains("junctions")) {
    for (const auto& j : cfg.at("junctions")) {
      const std::string name = j.at("junction_name").get<std::string>();
      const std::string type = j.at("junction_type").get<std::string>();
      BlockInput in(j.contains("junction_values") ? j.at("junction_values") : empty, m.file, name, period);
      add(registry.create(Section::Junction, type, in));
      ++m.junctions;
      if (j.contains("inlet_vessels") && j.contains("outlet_vessels")) {
        auto vessel = [&](int id) {
          const auto it = vessel_ids.find(id);
          if (it == vessel_ids.end())
            throw_input_error(m.file, fmt::format("junction '{}': no vessel with id {}", name, id));
          return it->second;
        };
        for (int id : j.at("inlet_vessels")) connections.emplace_back(vessel(id), name);
        for (int id : j.at("outlet_vessels")) connections.emplace_back(name, vessel(id));
      } else if (j.contains("inlet_blocks") && j.contains("outlet_blocks")) {
        for (const auto& b2 : j.at("inlet_blocks")) connections.emplace_back(b2.get<std::string>(), name);
        for (const auto& b2 : j.at("outlet_blocks")) connections.emplace_back(name, b2.get<std::string>());
      } else {
        throw_input_error(
            m.file,
            fmt::format("junction '{}' needs inlet_vessels/outlet_vessels or inlet_blocks/outlet_blocks", name));
      }
    }
  }
  for (const char* unsupported : {"closed_loop_blocks", "valves", "chambers", "external_solver_coupling_blocks"})
    if (cfg.contains(unsupported)) throw_input_error(m.file, fmt::format("'{}' is not supported", unsupported));

  // Period: from the time tables, or simulation_parameters.cardiac_period, else 1.
  const double sp = m.sim.period;
  if (period < 0.0 && sp < 0.0) {
    m.period = 1.0;
  } else if (period >= 0.0) {
    if (sp >= 0.0 && period != sp)
      throw_input_error(m.file, fmt::format("inconsistent cardiac cycle period: {} in the time tables, {} in "
                                            "simulation_parameters.cardiac_period",
                                            period, sp));
    m.period = period;
  } else {
    m.period = sp;
  }

  // One node (P, Q) per connection, in connection order. The connections of a block that
  // makes their pressures equal (a NORMAL_JUNCTION) share one pressure unknown, found by
  // union-find over the connections (junctions may be connected to each other).
  std::vector<std::pair<size_t, size_t>> ends;  // (upstream, downstream) block of each connection
  for (const auto& [a, b] : connections) {
    const auto ia = by_name.find(a), ib = by_name.find(b);
    if (ia == by_name.end()) throw_input_error(m.file, fmt::format("connection to an unknown block '{}'", a));
    if (ib == by_name.end()) throw_input_error(m.file, fmt::format("connection to an unknown block '{}'", b));
    ends.emplace_back(ia->second, ib->second);
  }
  std::vector<size_t> parent(connections.size());
  for (size_t k = 0; k < parent.size(); ++k) parent[k] = k;
  auto root = [&](size_t k) {
    while (parent[k] != k) k = parent[k] = parent[parent[k]];
    return k;
  };
  if (options.share_junction_pressures) {
    std::vector<size_t> first(m.blocks.size(), connections.size());  // first connection of each equal-pressure block
    for (size_t k = 0; k < connections.size(); ++k)
      for (const size_t blk : {ends[k].first, ends[k].second}) {
        if (!m.blocks[blk]->equal_pressures()) continue;
        if (first[blk] == connections.size())
          first[blk] = k;
        else
          parent[root(k)] = root(first[blk]);
      }
  }
  std::vector<int> pressure_of(connections.size(), -1);  // by root connection
  for (size_t k = 0; k < connections.size(); ++k) {
    const auto& [a, b] = connections[k];
    Node nd;
    nd.name = a + ":" + b;
    nd.q = m.unknowns++;
    int& p = pressure_of[root(k)];
    if (p < 0) p = m.unknowns++;
    nd.p = p;
    m.dofs.push_back("flow:" + nd.name);
    m.dof_unknown.push_back(nd.q);
    m.dofs.push_back("pressure:" + nd.name);
    m.dof_unknown.push_back(nd.p);
    m.nodes.push_back(nd);
    m.blocks[ends[k].first]->add_outlet(nd);
    m.blocks[ends[k].second]->add_inlet(nd);
  }
  for (const auto& b : m.blocks) {
    const std::string why = b->check_connections();
    if (!why.empty()) throw_input_error(m.file, why);
  }
  int row = 0;
  for (auto& b : m.blocks) {
    b->place(row, m.unknowns);
    row += b->num_equations();
    for (const auto& prefix : b->internal_unknowns()) {
      m.dofs.push_back(prefix + ":" + b->name());
      m.dof_unknown.push_back(m.unknowns++);
    }
  }
  if (row != m.unknowns)
    throw_input_error(
        m.file, fmt::format("the model has {} equations for {} unknowns; check the connections", row, m.unknowns));
}

State read_initial(const Model& m, const json& cfg) {
  State s{Eigen::VectorXd::Zero(m.unknowns), Eigen::VectorXd::Zero(m.unknowns)};
  if (!cfg.contains("initial_condition")) return s;
  const json& ic = cfg.at("initial_condition");
  // A shared junction pressure takes the value of the last of its names that has one.
  for (size_t k = 0; k < m.dofs.size(); ++k) {
    const auto& name = m.dofs[k];
    const int i = m.dof_unknown[k];
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

void check_time_steps(const std::string& file, double pts, double cycles, std::string_view cycles_from) {
  const double steps = (pts - 1.0) * cycles;
  if (!(steps <= kMaxSteps))
    throw_input_error(file, fmt::format("simulation_parameters: (number_of_time_pts_per_cardiac_cycle - 1) x {} = "
                                        "({} - 1) x {} = {:.3g} time steps, more than the {:.0e} a run may plan",
                                        cycles_from, pts, cycles, steps, kMaxSteps));
}

std::vector<Block*> Model::block_pointers() const {
  std::vector<Block*> out;
  out.reserve(blocks.size());
  for (const auto& b : blocks) out.push_back(b.get());
  return out;
}

Model read_model(const std::string& json_path, const Options& options) {
  json cfg;
  {
    const std::string text = read_input(json_path, input_limit::kTable, "an svZeroDSolver model (JSON)");
    try {
      cfg = json::parse(text);
    } catch (const json::exception& e) {  // syntax, or a number no double holds (1e400)
      throw_input_error(json_path, fmt::format("not valid JSON: {}", e.what()));
    }
  }
  return read_model(cfg, json_path, options);
}

Model read_model(const nlohmann::json& cfg, const std::string& json_path, const Options& options) {
  Model m;
  m.file = json_path;
  try {
    m.sim = read_sim(json_path, cfg);
    m.sim.last_cycles = std::clamp(options.last_cycles, 1, std::max(m.sim.cycles, 1));
    read_blocks(m, cfg, options);
    m.initial = read_initial(m, cfg);
  } catch (const json::exception& e) {
    throw_input_error(json_path, fmt::format("unexpected content: {}", e.what()));
  }
  return m;
}

}  // namespace flowire::flow::svzerod
