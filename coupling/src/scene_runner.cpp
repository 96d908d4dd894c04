#include <fmt/format.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/vessels/generators.hpp"
#include "flowire/vessels/io.hpp"

namespace flowire::coupling {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

nlohmann::json resolved_scene(const config::Config& c) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [path, v] : c.values()) {
    switch (v.type) {
      case config::Type::Section:
      case config::Type::List: break;
      case config::Type::Number:
      case config::Type::Integer:
      case config::Type::NumberOrSection: j[path] = v.number; break;
      case config::Type::Bool: j[path] = v.boolean; break;
      case config::Type::Vector3:
      case config::Type::NumberList: j[path] = v.list; break;
      default: j[path] = v.text;
    }
  }
  return j;
}

nlohmann::json counts_json(const vessels::NetworkCounts& n) {
  return {{"branches", n.branches}, {"nodes", n.nodes},       {"segments", n.segments},
          {"junctions", n.junctions}, {"ends", n.ends},       {"loops", n.loops},
          {"components", n.components}, {"total_length", n.total_length},
          {"radius_min", n.radius_min}, {"radius_max", n.radius_max}};
}

}  // namespace

config::Config load_scene(const std::string& file, const std::vector<std::string>& overrides,
                          const std::string& out_dir) {
  auto sets = overrides;
  if (!out_dir.empty()) sets.push_back("output.dir=" + out_dir);
  return config::load_config(file, scene_schema(), sets);
}

vessels::Network build_scene_network(const config::Config& c) {
  vessels::BuildOptions build;
  build.max_segment_length = c.number("vessels.max_segment_length");
  build.radius_change = c.number("vessels.radius_change");
  const bool has_file = c.has("vessels.file");
  const bool has_gen = c.has_section("vessels.generator");
  if (has_file == has_gen)
    throw_input_error(c.where("vessels"), "give exactly one of vessels.file or vessels.generator");
  if (has_file) {
    vessels::ReadOptions ro;
    ro.length_unit = c.string_or("vessels.length_unit", "");
    ro.build = build;
    ro.keep_inlet_piece = c.boolean("vessels.keep_inlet_piece");
    return vessels::read_network(c.resolve_path(c.string("vessels.file")), ro);
  }
  if (!c.has("vessels.generator.type")) throw_input_error(c.where("vessels.generator"), "generator.type is required");
  const std::string type = c.string("vessels.generator.type");
  auto g = [&](const char* key) { return c.number(std::string("vessels.generator.") + key); };
  if (type == "straight_tube")
    return vessels::Network::build(vessels::straight_tube({.length = g("length"), .radius = g("radius")}), build);
  if (type == "y_bifurcation")
    return vessels::Network::build(vessels::y_bifurcation({.parent_radius = g("parent_radius"),
                                                           .parent_length = g("parent_length"),
                                                           .child_length = g("child_length"),
                                                           .angle = g("angle"),
                                                           .asymmetry = g("asymmetry")}),
                                   build);
  if (type == "aortic_arch") return vessels::Network::build(vessels::aortic_arch({.scale = g("scale")}), build);
  if (type == "arterial_tree") return vessels::Network::build(vessels::arterial_tree({.scale = g("scale")}), build);
  // binary_tree: one segment per vessel, built directly as a graph.
  return vessels::binary_tree({.depth = c.integer("vessels.generator.depth"),
                               .root_radius = g("root_radius"),
                               .root_length = g("root_length"),
                               .radius_ratio = g("radius_ratio"),
                               .length_ratio = g("length_ratio"),
                               .angle = g("angle")});
}

RunResult run_scene(const config::Config& c) {
  const auto t_start = Clock::now();
  (void)take_warnings();
  RunResult result;
  result.out_dir = c.string("output.dir");
  const bool write_csv = c.boolean("output.csv");
  const bool write_vtk = c.boolean("output.vtk");
  nlohmann::json& s = result.summary;
  s["status"] = "ok";
  s["steps"] = 0;
  s["scene"] = resolved_scene(c);
  if (c.has("name")) s["name"] = c.string("name");
  nlohmann::json timings = {{"setup", 0.0}, {"flow", 0.0},   {"rod", 0.0},  {"contact", 0.0},
                            {"coupling", 0.0}, {"output", 0.0}, {"total", 0.0}};
  const std::filesystem::path out(result.out_dir);

  auto finish = [&](const std::string& status) {
    s["status"] = status;
    timings["total"] = seconds_since(t_start);
    s["timings"] = timings;
    s["warnings"] = take_warnings();
    write_text_atomically(out / "summary.json", s.dump(2) + "\n");
  };

  try {
    auto t0 = Clock::now();
    std::optional<vessels::Network> net;
    if (c.has_section("vessels")) {
      net = build_scene_network(c);
      s["network"] = counts_json(net->counts());
    }
    timings["setup"] = seconds_since(t0);

    t0 = Clock::now();
    if (net && write_csv) {
      std::ostringstream csv;
      csv << "time,segment,node_from,node_to,length,radius,resistance,flow_rate,mean_velocity,wall_shear_stress,reynolds\n";
      for (int i = 0; i < net->num_segments(); ++i) {
        const auto& seg = net->segment(i);
        csv << fmt::format("0,{},{},{},{:.17g},{:.17g},,,,,\n", i, seg.node_from, seg.node_to, seg.length, seg.radius);
      }
      write_text_atomically(out / "segments.csv", csv.str());
    }
    if (net && write_vtk) vessels::write_network_vtp(*net, (out / "network.vtp").string());
    timings["output"] = seconds_since(t0);
  } catch (const Error& e) {
    if (e.kind() == ErrorKind::Numerical) {
      s["error"] = e.what();
      finish("error");
    }
    throw;
  }
  finish("ok");
  return result;
}

}  // namespace flowire::coupling
