// The scene's vessels: section: its keys and the network they describe.
#include <fmt/format.h>

#include <numbers>
#include <string>

#include "flowire/common/error.hpp"
#include "flowire/coupling/lumen.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/flow/calibration.hpp"
#include "flowire/flow/openbf.hpp"
#include "flowire/vessels/generators.hpp"
#include "flowire/vessels/io.hpp"
#include "flowire/vessels/sections.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {

void declare_vessel_keys(config::Schema& s) {
  using config::Type;
  using D = units::Dimension;
  s.add("vessels", Type::Section, "", D::None, "the vessel network (required by flow, contact and fem)");
  s.add("vessels.file", Type::String, "", D::None,
        "centerline / network file: VMTK or SimVascular .vtp, legacy .vtk, flowire .vtp/.yaml, svOneDSolver .in");
  s.add("vessels.length_unit", Type::Enum, "", D::None,
        "unit of the file's coordinates and radii (default: the file's own, else m)", {"m", "cm", "mm", "um"});
  s.add("vessels.surface", Type::String, "", D::None,
        "lumen surface (.vtp, .stl, .obj; in length_unit): the wall the wire touches instead of the network's "
        "cylinders (signed distance to the triangles, open ends open, caps at the network's ends removed); the "
        "network still carries the flow; fem.geometry: lumen meshes it for the FEM comparison");
  s.add("vessels.surface_smoothing", Type::Number, "", D::Length,
        "width of the Gaussian weights of the smooth implicit surface (a weighted mean of the nearby triangles' "
        "planes) whose distance the contact uses (default 0.4 of the mean edge length; 0: the exact distance)")
      .non_negative();
  s.add(
      "vessels.radius", Type::Enum, "auto", D::None,
      "where the network's radii come from: surface: each branch's radius at each node is sqrt(A/pi) of the lumen "
      "surface's cross-section there (docs/fem-real-lumens.md; junctions and open ends take the nearest section's "
      "ratio); inscribed: the centerline file's (maximum inscribed sphere) radii; auto: surface where vessels.surface "
      "is given",
      {"auto", "surface", "inscribed"});
  s.add("vessels.calibration", Type::String, "", D::None,
        "a calibration file written by `flowire calibrate` for this network (calibration.json): each segment's "
        "pressure drop dp = f R_P Q + K|Q|Q fitted to the 3D solution (the quasi-steady flow is then solved by "
        "Newton's method every frame; rlc takes the factors f only when K = 0)");
  s.add("vessels.max_segment_length", Type::Number, "5 mm", D::Length,
        "branches are split into cylinders no longer than this")
      .positive();
  s.add("vessels.radius_change", Type::Number, "0.1", D::None,
        "also split where the radius changes by more than this fraction (0: by length only)")
      .non_negative();
  s.add("vessels.keep_inlet_piece", Type::Bool, "false", D::None,
        "if the network is in several pieces keep the one holding the inlet (with a warning) instead of failing");
  s.add("vessels.generator", Type::Section, "", D::None, "a built-in anatomy instead of a file");
  s.add("vessels.generator.type", Type::Enum, "", D::None, "which anatomy",
        {"straight_tube", "y_bifurcation", "aortic_arch", "binary_tree", "arterial_tree"});
  s.add("vessels.generator.length", Type::Number, "0.1", D::Length, "straight_tube: length").positive();
  s.add("vessels.generator.radius", Type::Number, "2 mm", D::Length, "straight_tube: radius").positive();
  s.add("vessels.generator.parent_radius", Type::Number, "5 mm", D::Length,
        "y_bifurcation: parent radius (daughters by Murray's law)")
      .positive();
  s.add("vessels.generator.parent_length", Type::Number, "40 mm", D::Length, "y_bifurcation: parent length").positive();
  s.add("vessels.generator.child_length", Type::Number, "40 mm", D::Length, "y_bifurcation: daughter length")
      .positive();
  s.add("vessels.generator.angle", Type::Number, "0.6 rad", D::Angle,
        "y_bifurcation / binary_tree: branching half-angle")
      .above(0.0)
      .below(std::numbers::pi / 2);
  s.add("vessels.generator.asymmetry", Type::Number, "0", D::None, "y_bifurcation: flow-split asymmetry")
      .above(-1.0)
      .below(1.0);
  s.add("vessels.generator.scale", Type::Number, "1", D::None, "aortic_arch / arterial_tree: size factor (1 = adult)")
      .positive();
  s.add("vessels.generator.depth", Type::Integer, "5", D::None, "binary_tree: generations (2^(depth+1) - 1 vessels)")
      .at_least(0)
      .at_most(24);
  s.add("vessels.generator.root_radius", Type::Number, "2 mm", D::Length, "binary_tree: root radius").positive();
  s.add("vessels.generator.root_length", Type::Number, "20 mm", D::Length, "binary_tree: root length").positive();
  s.add("vessels.generator.radius_ratio", Type::Number, "0.7937005259840998", D::None,
        "binary_tree: r(k+1)/r(k) (Murray 2^-1/3)")
      .positive();
  s.add("vessels.generator.length_ratio", Type::Number, "0.7937005259840998", D::None, "binary_tree: L(k+1)/L(k)")
      .positive();
}

namespace {
vessels::Network build_centerline_network(const config::Config& c);
}

vessels::Network build_scene_network(const config::Config& c) { return build_scene_network_and_radii(c).network; }

SceneNetwork build_scene_network_and_radii(const config::Config& c) {
  SceneNetwork out{build_centerline_network(c), nullptr, {}, 0.0, {}};
  const std::string mode = c.string("vessels.radius");
  const bool surface = c.has("vessels.surface");
  if (mode == "surface" && !surface)
    throw_input_error(c.where("vessels.radius"), "surface radii need a vessels.surface");
  if (mode == "inscribed" || !surface) {
    out.radius = {{"source", "inscribed"},
                  {"why", surface ? "vessels.radius: inscribed" : "no vessels.surface: the centerline file's radii"}};
    return out;
  }
  try {
    out.surface = make_scene_surface(c, out.network, out.surface_info, out.surface_smoothing);
  } catch (const Error& e) {
    if (e.kind() != ErrorKind::Input) throw;
    throw_input_error(c.where("vessels.surface"), e.what());  // the key as well as the file
  }
  vessels::SectionRadii r = vessels::section_radii(out.network, *out.surface);
  out.radius = {{"source", "surface"},
                {"points", r.points},
                {"measured", r.measured},
                {"filled", r.filled},
                {"branches_unmeasured", r.branches_unmeasured},
                {"median_ratio", r.median_ratio},
                {"median_shape", r.median_shape},
                {"max_shape", r.max_shape}};
  if (r.measured == 0)
    throw_input_error(c.where("vessels.surface"),
                      fmt::format("{}: no cross-section of the surface encloses the centerline ({} points cut): is it "
                                  "the lumen of vessels.file, in the same length unit?",
                                  c.string("vessels.surface"), r.points));
  out.network = std::move(r.network);
  return out;
}

namespace {
vessels::Network build_centerline_network(const config::Config& c) {
  vessels::BuildOptions build;
  build.max_segment_length = c.number("vessels.max_segment_length");
  build.radius_change = c.number("vessels.radius_change");
  const bool has_file = c.has("vessels.file");
  const bool has_gen = c.has_section("vessels.generator");
  if (has_file == has_gen)
    throw_input_error(c.where("vessels"), "give exactly one of vessels.file or vessels.generator");
  if (has_file && flow::openbf::is_model(c.resolve_path(c.string("vessels.file"))))
    return flow::openbf::network(flow::openbf::read(c.resolve_path(c.string("vessels.file"))), build);
  if (has_file) {
    vessels::ReadOptions ro;
    ro.length_unit = c.string_or("vessels.length_unit", "");
    ro.build = build;
    ro.keep_inlet_piece = c.boolean("vessels.keep_inlet_piece");
    return vessels::read_network(c.resolve_path(c.string("vessels.file")), ro);
  }
  if (!c.has("vessels.generator.type")) throw_input_error(c.where("vessels.generator"), "generator.type is required");
  const std::string type = c.string("vessels.generator.type");
  auto g = [&](const char* key) { return c.number(std::string("vessels.generator.") + key); };  // ranges declared
  try {
    if (type == "straight_tube")
      return vessels::Network::build(vessels::straight_tube({.length = g("length"), .radius = g("radius")}), build);
    if (type == "y_bifurcation")
      return vessels::Network::build(vessels::y_bifurcation({.parent_radius = g("parent_radius"),
                                                             .parent_length = g("parent_length"),
                                                             .child_length = g("child_length"),
                                                             .angle = g("angle"),
                                                             .asymmetry = c.number("vessels.generator.asymmetry")}),
                                     build);
    if (type == "aortic_arch") return vessels::Network::build(vessels::aortic_arch({.scale = g("scale")}), build);
    if (type == "arterial_tree") return vessels::Network::build(vessels::arterial_tree({.scale = g("scale")}), build);
    return vessels::binary_tree({.depth = c.integer("vessels.generator.depth"),
                                 .root_radius = g("root_radius"),
                                 .root_length = g("root_length"),
                                 .radius_ratio = g("radius_ratio"),
                                 .length_ratio = g("length_ratio"),
                                 .angle = g("angle")});
  } catch (const Error& e) {
    if (e.kind() == ErrorKind::Usage) throw_input_error(c.where("vessels.generator"), e.what());
    throw;
  }
}
}  // namespace

namespace {

/// The flow: section, with an openBF model's own conditions where the scene states none.
flow::FlowSpec scene_flow_conditions(const config::Config& c, const vessels::Network& net) {
  flow::FlowSpec spec = flow::from_config(c, net);
  if (!c.has("vessels.file")) return spec;
  const std::string path = c.resolve_path(c.string("vessels.file"));
  if (!flow::openbf::is_model(path)) return spec;
  // What the scene states itself (a value from the scene file or --set, not a default).
  const auto stated = [&](const std::string& prefix) {
    for (const auto& [key, value] : c.values())
      if (key.rfind(prefix, 0) == 0 && value.where != "default") return true;
    return false;
  };
  const flow::FlowSpec model = flow::openbf::flow_spec(flow::openbf::read(path), net);
  if (!stated("flow.model")) spec.model = model.model;
  if (!stated("flow.density")) spec.density = model.density;
  if (!stated("flow.viscosity")) spec.viscosity = model.viscosity;
  if (!stated("flow.inlet") && !stated("flow.inlets")) spec.inlets = model.inlets;
  // Every end of the model's that is no inlet: the outlet the scene names there, else the
  // model's own (the scene's default for the rest does not apply: the model has one for each).
  std::vector<flow::OutletBC> outlets;
  const auto is_inlet = [&](int node) {
    return std::any_of(spec.inlets.begin(), spec.inlets.end(),
                       [&](const flow::InletBC& in) { return in.node == node; });
  };
  for (const auto& m : model.outlets) {
    if (is_inlet(m.node)) continue;
    const auto named = std::find_if(spec.outlets.begin(), spec.outlets.end(),
                                    [&](const flow::OutletBC& o) { return o.node == m.node && !o.defaulted; });
    outlets.push_back(named != spec.outlets.end() ? *named : m);
  }
  spec.outlets = std::move(outlets);
  for (const auto& w : model.branch_walls)
    if (std::none_of(spec.branch_walls.begin(), spec.branch_walls.end(),
                     [&](const flow::BranchWall& x) { return x.branch == w.branch; }))
      spec.branch_walls.push_back(w);
  return spec;
}

}  // namespace

flow::FlowSpec scene_flow(const config::Config& c, const vessels::Network& net) {
  flow::FlowSpec spec = scene_flow_conditions(c, net);
  if (c.has("vessels.calibration")) {
    for (const char* key :
         {"flow.losses.stenosis", "flow.losses.curvature", "flow.losses.entrance", "flow.losses.junction"})
      if (c.string_or(key, "none") != "none")
        throw_input_error(c.where(key), fmt::format("vessels.calibration already holds the 3D solution's losses: {} "
                                                    "would count them twice (give one or the other)",
                                                    key));
    flow::Calibration cal =
        flow::read_calibration(c.resolve_path(c.string("vessels.calibration")), net, c.where("vessels.calibration"));
    spec.segment_laws = std::move(cal.laws);
    spec.total_pressure = cal.pressure == "total";
    spec.end_alpha = std::move(cal.end_alpha);
  }
  return spec;
}

}  // namespace flowire::coupling
