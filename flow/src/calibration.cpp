// The calibration file (calibration.hpp): written by `flowire calibrate`, read by
// `vessels.calibration`.
#include "flowire/flow/calibration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/flow/solver.hpp"

namespace flowire::flow {

void identify(Calibration& c, const Network& net) {
  c.network_source = net.source();
  c.nodes = net.num_nodes();
  c.segments = net.num_segments();
  c.branches = net.num_branches();
  c.total_length = 0.0;
  c.resistance_sum = 0.0;
  for (const auto& s : net.segments()) {
    c.total_length += s.length;
    c.resistance_sum += segment_resistance(1.0, s);
  }
}

void write_calibration(const std::string& path, const Calibration& c) {
  using nlohmann::json;
  json fits = json::array();
  for (const auto& f : c.fits)
    fits.push_back({{"branch", f.branch},
                    {"name", f.name},
                    {"poiseuille_resistance", f.poiseuille_resistance},
                    {"linear", f.linear},
                    {"quadratic", f.quadratic},
                    {"resistance_factor", f.linear / f.poiseuille_resistance},
                    {"flows", f.flows},
                    {"drops", f.drops},
                    {"residual", f.residual},
                    {"bounded", f.bounded},
                    {"pieces", f.pieces}});
  json alpha = json::array();  // [node, α] of the outlets whose α is not 1
  for (size_t n = 0; n < c.end_alpha.size(); ++n)
    if (c.end_alpha[n] != 1.0) alpha.push_back({n, c.end_alpha[n]});
  json segs = json::array();
  for (const auto& l : c.laws) segs.push_back({{"resistance_factor", l.resistance_factor}, {"quadratic", l.quadratic}});
  const json j = {{"format", "flowire-calibration"},
                  {"version", 1},
                  {"network",
                   {{"source", c.network_source},
                    {"nodes", c.nodes},
                    {"segments", c.segments},
                    {"branches", c.branches},
                    {"total_length", c.total_length},
                    {"resistance_sum", c.resistance_sum}}},
                  {"fem",
                   {{"equations", c.equations},
                    {"pressure", c.pressure},
                    {"inlet_flows", c.inlet_flows},
                    {"check_inlet_flow", c.check_inlet_flow}}},
                  {"branches", fits},
                  {"end_alpha", alpha},
                  {"segments", segs}};
  write_text_atomically(path, j.dump(2) + "\n");
}

Calibration read_calibration(const std::string& path, const Network& net, const std::string& where) {
  using nlohmann::json;
  const std::string place = where.empty() ? path : fmt::format("{}: {}", where, path);
  std::ifstream in(path);
  if (!in) throw_input_error(place, "cannot open the calibration file");
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& e) {
    throw_input_error(place, fmt::format("not a JSON file ({})", e.what()));
  }
  if (!j.is_object() || j.value("format", std::string()) != "flowire-calibration")
    throw_input_error(place, "not a calibration file (format: flowire-calibration, as `flowire calibrate` writes)");
  Calibration c;
  try {
    if (j.at("version").get<int>() != 1)
      throw_input_error(place, fmt::format("calibration version {} (this flowire reads 1)", j.at("version").dump()));
    const json& n = j.at("network");
    c.network_source = n.value("source", std::string());
    c.nodes = n.at("nodes").get<int>();
    c.segments = n.at("segments").get<int>();
    c.branches = n.at("branches").get<int>();
    c.total_length = n.at("total_length").get<double>();
    c.resistance_sum = n.at("resistance_sum").get<double>();
    const json& f = j.at("fem");
    c.equations = f.value("equations", std::string());
    c.pressure = f.value("pressure", std::string("static"));
    if (c.pressure != "static" && c.pressure != "total")
      throw_input_error(place, fmt::format("fem.pressure '{}' (static or total)", c.pressure));
    c.inlet_flows = f.value("inlet_flows", std::vector<double>{});
    c.check_inlet_flow = f.value("check_inlet_flow", 0.0);
    for (const json& b : j.at("branches")) {
      BranchFit fit;
      fit.branch = b.at("branch").get<int>();
      fit.name = b.value("name", std::string());
      fit.poiseuille_resistance = b.at("poiseuille_resistance").get<double>();
      fit.linear = b.at("linear").get<double>();
      fit.quadratic = b.at("quadratic").get<double>();
      fit.flows = b.value("flows", std::vector<double>{});
      fit.drops = b.value("drops", std::vector<double>{});
      fit.residual = b.value("residual", 0.0);
      fit.bounded = b.value("bounded", false);
      fit.pieces = b.value("pieces", 1);
      c.fits.push_back(std::move(fit));
    }
    if (j.contains("end_alpha") && !j.at("end_alpha").empty()) {
      c.end_alpha.assign(static_cast<size_t>(std::max(c.nodes, 0)), 1.0);
      for (const json& a : j.at("end_alpha")) {
        const int node = a.at(0).get<int>();
        const double v = a.at(1).get<double>();
        if (node < 0 || node >= c.nodes || !(v >= 1.0) || !std::isfinite(v))
          throw_input_error(place, fmt::format("end_alpha [{}, {}]: a node of the network and α >= 1", node, v));
        c.end_alpha[static_cast<size_t>(node)] = v;
      }
    }
    const json& segs = j.at("segments");
    for (size_t s = 0; s < segs.size(); ++s) {
      SegmentLaw law{segs[s].at("resistance_factor").get<double>(), segs[s].at("quadratic").get<double>()};
      if (!(law.resistance_factor > 0.0) || !std::isfinite(law.resistance_factor) || !(law.quadratic >= 0.0) ||
          !std::isfinite(law.quadratic))
        throw_input_error(fmt::format("{}: segments[{}]", place, s),
                          fmt::format("resistance_factor {} must be > 0 and quadratic {} >= 0", law.resistance_factor,
                                      law.quadratic));
      c.laws.push_back(law);
    }
  } catch (const json::exception& e) {
    throw_input_error(place, fmt::format("a malformed calibration file ({})", e.what()));
  }
  Calibration here;
  identify(here, net);
  if (c.nodes != here.nodes || c.segments != here.segments || c.branches != here.branches ||
      !(std::abs(c.total_length - here.total_length) <= 1e-9 * here.total_length) ||
      !(std::abs(c.resistance_sum - here.resistance_sum) <= 1e-9 * here.resistance_sum) ||
      c.laws.size() != static_cast<size_t>(here.segments))
    throw_input_error(place, fmt::format("the calibration was made for another network ({} nodes, {} segments, {} "
                                         "branches, {:.6g} m, resistance sum {:.6g} /m³, from {}); the scene's has {} "
                                         "nodes, {} segments, {} branches, {:.6g} m, {:.6g} /m³ (from {})",
                                         c.nodes, c.segments, c.branches, c.total_length, c.resistance_sum,
                                         c.network_source, here.nodes, here.segments, here.branches, here.total_length,
                                         here.resistance_sum, here.network_source));
  return c;
}

}  // namespace flowire::flow
