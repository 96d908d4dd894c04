// The scene runner: builds only what a scene has (vessels, flow, wire) and steps it.
#include <fmt/format.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <map>
#include <numbers>
#include <sstream>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/coupling/cosimulation.hpp"
#include "flowire/coupling/occlusion.hpp"
#include "flowire/coupling/paraview_script.hpp"
#include "flowire/coupling/lumen.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/coupling/tip_forces.hpp"
#ifdef FLOWIRE_HAVE_FEM
#include "flowire/common/units.hpp"
#include "flowire/fem/compare.hpp"
#include "flowire/fem/lumen.hpp"
#include "flowire/fem/obstacle.hpp"
#endif
#include "flowire/coupling/vessel_forces.hpp"
#include "flowire/coupling/vessel_path.hpp"
#include "flowire/coupling/wire_output.hpp"
#include "run_output.hpp"
#include "flowire/flow/output.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire/vessels/generators.hpp"
#include "flowire/vessels/io.hpp"
#include "flowire/vessels/spatial.hpp"

namespace flowire::coupling {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

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
  return {{"branches", n.branches},   {"nodes", n.nodes}, {"segments", n.segments},         {"junctions", n.junctions},
          {"ends", n.ends},           {"loops", n.loops}, {"components", n.components},     {"total_length", n.total_length},
          {"radius_min", n.radius_min}, {"radius_max", n.radius_max}};
}

}  // namespace

std::shared_ptr<VesselForces> make_vessel_forces(const config::Config& c, const vessels::SpatialIndex& index,
                                                 const rod::WireSpec& spec, flow::FlowSolver* flow) {
  ContactParams cp;
  cp.enabled = !c.has("contact.enabled") || c.boolean("contact.enabled");
  cp.stiffness = c.number_or("contact.stiffness", 3e4);
  cp.friction = c.number_or("contact.friction", 0.1);
  cp.tip_friction = c.number_or("contact.tip_friction", cp.friction);
  cp.tip_length = spec.tip.length;  // the wire's tip (wire.tip.length); a catheter has none
  cp.viscous_friction = c.number_or("contact.viscous_friction", 0.0);
  DragModel dp;
  const std::string law = c.has_section("coupling") ? c.string("coupling.drag") : "cylinder";
  dp.law = !flow || law == "none"          ? DragLaw::None
           : law == "velocity_offset" ? DragLaw::VelocityOffset
           : law == "slender_body"    ? DragLaw::SlenderBody
                                      : DragLaw::Cylinder;
  dp.scale = c.number_or("coupling.drag_scale", 1.0);
  dp.viscosity = c.number_or("flow.viscosity", 3.5e-3);
  dp.density = c.number_or("flow.density", 1060.0);
  dp.wire_radius = spec.radius;
  dp.wire_length = spec.length;
  dp.mass_per_length = spec.density * std::numbers::pi * spec.radius * spec.radius;
  if (!cp.enabled && dp.law == DragLaw::None) return nullptr;
  VelocityField vf;
  if (flow) vf = [flow](int seg_id, const vessels::Vec3& p) { return flow->velocity_at(seg_id, p); };
  return std::make_shared<VesselForces>(index, spec.radius, cp, dp, vf);
}

rod::WireSpec scene_wire_spec(const config::Config& c) {
  rod::WireSpec w;
  w.length = c.number("wire.length");
  w.radius = c.number("wire.radius");
  w.youngs_modulus = c.number("wire.youngs_modulus");
  w.poisson_ratio = c.number("wire.poisson_ratio");
  if (c.has("wire.shear_modulus")) w.shear_modulus = c.number("wire.shear_modulus");
  w.density = c.number("wire.density");
  if (c.has("wire.segment_length")) {
    w.segments = 0;
    w.segment_length = c.number("wire.segment_length");
  } else {
    w.segments = c.integer("wire.segments");
  }
  w.damping = c.number("wire.damping");
  w.tip.length = 0.0;
  if (c.has_section("wire.tip")) {
    w.tip.length = c.number("wire.tip.length");
    w.tip.youngs_modulus = c.number("wire.tip.youngs_modulus");
    const auto& shape = c.string("wire.tip.shape");
    w.tip.shape = shape == "j" ? rod::TipShape::J : shape == "angled" ? rod::TipShape::Angled : rod::TipShape::Straight;
    w.tip.angle = c.number_or("wire.tip.angle", -1.0);  // < 0: the shape's own default (rod::TipSpec)
    w.tip.bend_radius = c.number("wire.tip.bend_radius");
  }
  if (c.has_section("wire.adapt")) {
    w.adapt.enabled = true;
    const double h = w.segments > 0 ? w.length / w.segments : w.segment_length;
    if (c.has("wire.adapt.min_segment_length")) {
      w.adapt.min_segment_length = c.number("wire.adapt.min_segment_length");
      if (!(w.adapt.min_segment_length > 0.0 && w.adapt.min_segment_length <= h))
        throw_input_error(c.where("wire.adapt.min_segment_length"),
                          fmt::format("min_segment_length must be in (0, {:g} m] (the segment length)", h));
    }
    if (c.has("wire.adapt.max_segment_length")) {
      w.adapt.max_segment_length = c.number("wire.adapt.max_segment_length");
      if (!(w.adapt.max_segment_length >= h))
        throw_input_error(c.where("wire.adapt.max_segment_length"),
                          fmt::format("max_segment_length must be at least the segment length ({:g} m)", h));
    }
    w.adapt.split_angle = c.number("wire.adapt.split_angle");
    if (!(w.adapt.split_angle > 0.0 && w.adapt.split_angle < 1.5))
      throw_input_error(c.where("wire.adapt.split_angle"), "split_angle must be in (0, 1.5) rad");
    if (c.has("wire.adapt.merge_angle")) {
      w.adapt.merge_angle = c.number("wire.adapt.merge_angle");
      if (!(w.adapt.merge_angle >= 0.0 && w.adapt.merge_angle < 0.5 * w.adapt.split_angle))
        throw_input_error(c.where("wire.adapt.merge_angle"), "merge_angle must be in [0, split_angle / 2) rad");
    }
  }
  if (c.has_section("wire.base")) {
    w.base_position = c.vector3("wire.base.position");
    w.base_direction = c.vector3("wire.base.direction");
    if (!(w.base_direction.norm() > 0)) throw_input_error(c.where("wire.base.direction"), "direction must be non-zero");
  }
  if (c.has_section("insertion")) w.inserted_length = c.number("insertion.initial_length");
  if (!(w.radius > 0) || !(w.length > 0) || !(w.youngs_modulus > 0) || !(w.density > 0))
    throw_input_error(c.where("wire"), "length, radius, youngs_modulus and density must be positive");
  return w;
}

CatheterSpec scene_catheter_spec(const config::Config& c, const rod::WireSpec& wire) {
  CatheterSpec k;
  k.length = c.number("catheter.length");
  k.outer_radius = c.number("catheter.outer_radius");
  k.inner_radius = c.number("catheter.inner_radius");
  k.youngs_modulus = c.number("catheter.youngs_modulus");
  k.density = c.number("catheter.density");
  k.initial_length = c.number("catheter.initial_length");
  k.stiffness = c.number("catheter.stiffness");
  if (c.has_section("catheter.insertion")) {
    k.speed = c.number("catheter.insertion.speed");
    k.rotation_speed = c.number("catheter.insertion.rotation_speed");
  }
  for (const char* key : {"length", "outer_radius", "inner_radius", "youngs_modulus", "density", "stiffness"}) {
    const std::string path = std::string("catheter.") + key;
    if (!(c.number(path) > 0.0)) throw_input_error(c.where(path), fmt::format("catheter.{} must be positive", key));
  }
  if (!(k.initial_length >= 0.0) || k.initial_length > k.length)
    throw_input_error(c.where("catheter.initial_length"), "catheter.initial_length must be in [0, catheter.length]");
  if (!(k.outer_radius > k.inner_radius))
    throw_input_error(c.where("catheter.outer_radius"),
                      fmt::format("catheter.outer_radius ({:.4g} m) must exceed catheter.inner_radius ({:.4g} m)",
                                  k.outer_radius, k.inner_radius));
  if (!c.has_section("wire"))
    throw_input_error(c.where("catheter"), "a catheter runs over a wire: the scene has no wire: section");
  if (!(k.inner_radius >= wire.radius))
    throw_input_error(c.where("catheter.inner_radius"),
                      fmt::format("catheter.inner_radius ({:.4g} m) is narrower than the wire (wire.radius {:.4g} m)",
                                  k.inner_radius, wire.radius));
  return k;
}

namespace {

/// Obstacles (clot resistance) and steering, if the scene has them.
std::shared_ptr<TipForces> make_tip_forces(const config::Config& c, const vessels::Network* net) {
  std::vector<Obstacle> obstacles;
  for (int i = 0; i < c.count("obstacles"); ++i) {
    const std::string p = fmt::format("obstacles[{}].", i);
    for (const char* k : {"center", "radius", "force"})
      if (!c.has(p + k)) throw_input_error(c.where(p.substr(0, p.size() - 1)), fmt::format("an obstacle needs {}", k));
    obstacles.push_back({c.vector3(p + "center"), c.number(p + "radius"), c.number(p + "force")});
  }
  Steering steer;
  if (c.has_section("coupling.steering")) {
    if (!net) throw_input_error(c.where("coupling.steering"), "steering needs a vessels: section");
    if (!c.has("coupling.steering.branch")) throw_input_error(c.where("coupling.steering"), "steering needs branch");
    const auto& name = c.string("coupling.steering.branch");
    const vessels::Branch* target = nullptr;
    std::string names;
    for (const auto& b : net->branches()) {
      if (b.name == name) target = &b;
      names += (names.empty() ? "" : ", ") + b.name;
    }
    if (!target)
      throw_input_error(c.where("coupling.steering.branch"), fmt::format("no branch '{}' (branches: {})", name, names));
    // The point `offset` along the branch from its first node.
    double left = c.number("coupling.steering.offset");
    vessels::Vec3 p = net->node(target->nodes.front());
    for (size_t k = 0; k + 1 < target->nodes.size() && left > 0; ++k) {
      const vessels::Vec3 a = net->node(target->nodes[k]), b = net->node(target->nodes[k + 1]);
      const double len = (b - a).norm();
      p = left >= len ? b : vessels::Vec3(a + (left / len) * (b - a));
      left -= len;
    }
    steer = {true, p, c.number("coupling.steering.force"), c.number("coupling.steering.range")};
  }
  if (obstacles.empty() && !steer.enabled) return nullptr;
  return std::make_shared<TipForces>(std::move(obstacles), steer);
}

void apply_loads(const config::Config& c, rod::RodSimulator& sim) {
  for (int i = 0; i < c.count("loads"); ++i) {
    const std::string p = fmt::format("loads[{}].", i);
    if (!c.has(p + "type") || !c.has(p + "value")) throw_input_error(c.where(p + "type"), "a load needs type and value");
    const auto& type = c.string(p + "type");
    const Eigen::Vector3d v = c.vector3(p + "value");
    if (type == "tip_force") sim.set_tip_force(v);
    else if (type == "tip_moment") sim.set_tip_moment(v);
    else if (type == "gravity") sim.set_gravity(v);
    else {
      if (!c.has(p + "s")) throw_input_error(c.where(p + "type"), "point_force needs s (arc length from the base)");
      sim.add_point_force(c.number(p + "s"), v);
    }
  }
}


#ifdef FLOWIRE_HAVE_FEM
nlohmann::json fem_result_json(const fem::CompareResult& r) {
  return {{"tets", r.tets},
          {"unknowns", r.unknowns},
          {"reynolds", r.reynolds},
          {"newton_iterations", r.newton_iterations},
          {"max_rel_diff_away_from_junctions", r.max_rel_diff_drop_away},
          {"max_rel_diff_near_junctions", r.max_rel_diff_drop_junction},
          {"max_flow_split_error", r.max_flow_split_error},
          {"max_flow_error", r.max_flow_error},
          {"inlet",
           {{"pressure_network", r.inlet_pressure_network},
            {"pressure_fem", r.inlet_pressure_fem},
            {"flow_network", r.inlet_flow_network},
            {"flow_fem", r.inlet_flow_fem}}},
          {"mesh_seconds", r.mesh_seconds},
          {"assemble_seconds", r.assemble_seconds},
          {"solve_seconds", r.solve_seconds}};
}
#endif


bool fem_on_network(const config::Config& c) {
  return !c.has_section("fem") || c.string("fem.geometry") == "network" || c.string("fem.geometry") == "lumen";
}

/// Input checks of a fem: section on a built-in geometry (no network), done at setup.
void check_fem_geometry(const config::Config& c) {
  for (const char* key : {"fem.mesh_size", "fem.obstacle_mesh_size"})
    if (c.has(key) && !(c.number(key) > 0.0)) throw_input_error(c.where(key), "must be > 0");
  if (!(c.number("fem.mesh_growth") > 0.0)) throw_input_error(c.where("fem.mesh_growth"), "must be > 0");
  if (c.integer("fem.frames") != 0) throw_input_error(c.where("fem.frames"), "is for fem.geometry: network");
  if (c.string("fem.solver") == "fieldsplit")
    throw_input_error(c.where("fem.solver"),
                      "navier_stokes needs mumps (the fieldsplit Schur approximation ignores convection)");
}

/// The DFG benchmark 3D-1Z (fem.geometry: dfg_3d_1z): forces, c_D, c_L, Δp.
nlohmann::json run_fem_geometry(const config::Config& c, const std::filesystem::path& out) {
#ifdef FLOWIRE_HAVE_FEM
  fem::ObstacleMesh sizes;
  sizes.mesh_size = c.has("fem.mesh_size") ? c.number("fem.mesh_size") : 0.08;
  sizes.obstacle_mesh_size = c.has("fem.obstacle_mesh_size") ? c.number("fem.obstacle_mesh_size") : 0.25 * sizes.mesh_size;
  sizes.growth = c.number("fem.mesh_growth");
  const auto stab = c.string("fem.stabilization") == "none" ? fem::Stabilization::None : fem::Stabilization::Supg;
  const fem::ObstacleResult r = fem::dfg_3d_1z(sizes, stab, out.string(), c.boolean("output.vtk"));
  nlohmann::json forces = nlohmann::json::object();
  for (const auto& [name, f] : r.forces) forces[name] = {f.x(), f.y(), f.z()};
  return {{"geometry", "dfg_3d_1z"},
          {"tets", r.tets},
          {"unknowns", r.unknowns},
          {"newton_iterations", r.newton_iterations},
          {"drag_coefficient", r.drag_coefficient},
          {"lift_coefficient", r.lift_coefficient},
          {"pressure_difference", r.pressure_difference},
          {"forces", forces},
          {"mesh_seconds", r.mesh_seconds},
          {"solve_seconds", r.solve_seconds}};
#else
  (void)out;
  throw_input_error(c.where("fem"),
                    "this flowire was built without the FEM path (FLOWIRE_WITH_FEM needs gmsh and PETSc)");
#endif
}

/// Input checks of the fem: section that need the flow spec, done at setup.
void check_fem(const config::Config& c, const flow::FlowSolver* fs, const vessels::Network* net = nullptr) {
  if (!fem_on_network(c)) return check_fem_geometry(c);
  if (!fs) throw_input_error(c.where("fem"), "fem: compares the flow, so the scene needs a flow: section");
  if (!(c.number("fem.size_factor") > 0.0)) throw_input_error(c.where("fem.size_factor"), "must be > 0");
  if (c.string("fem.geometry") == "lumen") {
    if (!c.has("vessels.surface")) throw_input_error(c.where("fem.geometry"), "lumen needs vessels.surface");
    const std::string surface = c.resolve_path(c.string("vessels.surface"));
    if (!std::filesystem::is_regular_file(surface))
      throw_input_error(fmt::format("{}: {}", c.where("vessels.surface"), surface), "the lumen surface file does not exist");
#ifdef FLOWIRE_HAVE_FEM
    // Read it and match its open ends now (cheap), so that bad input stops the run before any output.
    if (net)
      (void)fem::prepare_lumen(*net, fem::read_surface(surface, units::length_unit_factor(
                                                                    c.string_or("vessels.length_unit", "m"),
                                                                    c.where("vessels.length_unit"))));
#endif
  }
  const int frames = c.integer("fem.frames");
  if (frames < 0) throw_input_error(c.where("fem.frames"), "must be 0 (steady only) or a number of frames");
  if (frames > 100000) throw_input_error(c.where("fem.frames"), "too many frames (at most 100000)");
  if (!(c.number("fem.backflow") >= 0.0)) throw_input_error(c.where("fem.backflow"), "must be >= 0");
  if (c.integer("fem.steps_per_period") < 1 || c.integer("fem.steps_per_period") > 1000000)
    throw_input_error(c.where("fem.steps_per_period"), "must be between 1 and 1000000");
  if (c.boolean("fem.time_dependent") && frames == 0)
    throw_input_error(c.where("fem.time_dependent"), "needs fem.frames > 0 (a pulsatile series)");
  if (c.boolean("fem.time_dependent") && c.string("fem.equations") == "navier_stokes")
    throw_input_error(c.where("fem.time_dependent"), "is for equations: stokes");
  if (c.string("fem.equations") == "navier_stokes" && c.string("fem.solver") == "fieldsplit")
    throw_input_error(c.where("fem.solver"),
                      "navier_stokes needs mumps (the fieldsplit Schur approximation ignores convection)");
  if (frames > 0 && !(fs->spec().cycle() > 0.0))
    throw_input_error(c.where("fem.frames"), "a pulsatile comparison needs a periodic inlet waveform (sine or table)");
  if (fs->spec().inlets.size() != 1)
    throw_input_error(c.where("fem"), fmt::format("the comparison needs exactly one inlet; the flow has {}",
                                                  fs->spec().inlets.size()));
}

/// The FEM reference on the same geometry with the network's own boundary conditions (the
/// flow spec): inlet pressure or flow, outlets at a pressure or through a resistance (RCR:
/// Rp + Rd, quasi-steady), at the flow's current time; with fem.frames = N also N
/// quasi-steady frames over one inlet period from one factorization.
nlohmann::json run_fem(const config::Config& c, const vessels::Network& net, const flow::FlowSolver& fs,
                       const std::filesystem::path& out) {
#ifdef FLOWIRE_HAVE_FEM
  const flow::FlowSpec& spec = fs.spec();
  const fem::BoundaryValues bv = fem::boundary_values(spec, net, fs.time());
  const bool has_rcr = std::any_of(spec.outlets.begin(), spec.outlets.end(),
                                   [](const flow::OutletBC& o) { return o.type == flow::OutletBC::Type::Rcr; });
  const bool time_dependent = c.boolean("fem.time_dependent");
  // Windkessel dynamics on both sides when the network integrates them (rlc model).
  const bool dynamic_rcr = has_rcr && spec.model == flow::Model::Rlc;
  if (has_rcr && !dynamic_rcr)
    warn("fem: RCR outlets are compared quasi-steadily, as the resistance Rp + Rd to Pd (the poiseuille flow model "
         "has no capacitor; use flow.model: rlc with fem.frames for the windkessel dynamics)");
  fem::FemOptions fo;
  if (c.has("fem.mesh_size")) fo.mesh_size = c.number("fem.mesh_size");
  fo.equations = c.string("fem.equations") == "navier_stokes" ? fem::Equations::NavierStokes : fem::Equations::Stokes;
  fo.solver = c.string("fem.solver") == "fieldsplit" ? fem::LinearSolver::Fieldsplit : fem::LinearSolver::Mumps;
  fo.stabilization = c.string("fem.stabilization") == "none" ? fem::Stabilization::None : fem::Stabilization::Supg;
  fo.inlet = c.string("fem.inlet") == "traction" ? fem::InletCondition::Traction : fem::InletCondition::Profile;
  fo.backflow = c.number("fem.backflow");
  fo.samples_per_branch = c.integer("fem.samples_per_branch");
  fo.size_factor = c.number("fem.size_factor");
  if (c.string("fem.geometry") == "lumen") {  // the real lumen of vessels.surface (checked by check_fem)
    fo.surface = c.resolve_path(c.string("vessels.surface"));
    const std::string unit = c.string_or("vessels.length_unit", "m");
    fo.surface_length_factor = units::length_unit_factor(unit, c.where("vessels.length_unit"));
  }
  fo.write_vtu = c.boolean("output.vtk");
  fo.write_png = c.boolean("output.png");
  const long frames = c.integer("fem.frames");  // checked by check_fem
  if (frames == 0) {
    auto j = fem_result_json(fem::compare(net, bv, fo, out.string()));
    j["time"] = fs.time();
    return j;
  }
  const double period = spec.cycle();
  std::vector<double> times;
  std::vector<fem::BoundaryValues> values;
  for (long i = 0; i < frames; ++i) {
    times.push_back(period * static_cast<double>(i) / static_cast<double>(frames));
    values.push_back(fem::boundary_values(spec, net, times.back()));
  }
  fem::DynamicOptions dyn;
  std::unique_ptr<flow::FlowSolver> periodic;  // the network over enough periods to be periodic
  const bool dynamic = dynamic_rcr || time_dependent;
  if (dynamic) {
    dyn.period = period;
    dyn.time_dependent = time_dependent;
    dyn.steps_per_period = static_cast<int>(c.integer("fem.steps_per_period"));
    dyn.values_at = [&spec, &net](double t) { return fem::boundary_values(spec, net, t); };
    if (dynamic_rcr)
      for (const auto& o : spec.outlets)
        if (o.type == flow::OutletBC::Type::Rcr) dyn.windkessels.push_back({o.node, o.rp, o.c, o.rd, o.distal_pressure});
    if (spec.model == flow::Model::Rlc) {
      periodic = flow::make_solver(net, spec);
      const double start = 30.0 * period;
      dyn.network_at = [&periodic, &net, start](double t) {
        fem::NetworkFlow nf;
        nf.node_pressure.resize(static_cast<size_t>(net.num_nodes()));
        nf.segment_flow.resize(static_cast<size_t>(net.num_segments()));
        periodic->solve_at(start + t, nf.node_pressure, nf.segment_flow);
        return nf;
      };
    }
  }
  const auto p = fem::compare_pulsatile(net, times, values, bv, fs.time(), fo, out.string(), dynamic ? &dyn : nullptr);
  auto j = fem_result_json(p.steady);
  j["time"] = fs.time();
  j["pulsatile"] = {{"frames", frames},
                    {"period", period},
                    {"max_rel_diff_away_from_junctions", p.max_rel_diff_drop_away},
                    {"max_rel_diff_near_junctions", p.max_rel_diff_drop_junction},
                    {"max_flow_split_error", p.max_flow_split_error},
                    {"max_flow_error", p.max_flow_error},
                    {"factorizations", p.factorizations},
                    {"basis_seconds", p.basis_seconds},
                    {"frames_seconds", p.frames_seconds},
                    {"dynamic", dynamic},
                    {"time_dependent", time_dependent},
                    {"windkessels", dyn.windkessels.size()},
                    {"periods", p.periods},
                    {"steps_per_period", p.steps_per_period},
                    {"periodic_change", p.periodic_change}};
  return j;
#else
  (void)net, (void)fs, (void)out;
  throw_input_error(c.where("fem"),
                    "this flowire was built without the FEM path (FLOWIRE_WITH_FEM needs gmsh and PETSc)");
#endif
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
  if (has_file == has_gen) throw_input_error(c.where("vessels"), "give exactly one of vessels.file or vessels.generator");
  if (has_file) {
    vessels::ReadOptions ro;
    ro.length_unit = c.string_or("vessels.length_unit", "");
    ro.build = build;
    ro.keep_inlet_piece = c.boolean("vessels.keep_inlet_piece");
    return vessels::read_network(c.resolve_path(c.string("vessels.file")), ro);
  }
  if (!c.has("vessels.generator.type")) throw_input_error(c.where("vessels.generator"), "generator.type is required");
  const std::string type = c.string("vessels.generator.type");
  auto g = [&](const char* key) {
    const std::string path = std::string("vessels.generator.") + key;
    const double v = c.number(path);
    if (!(v > 0.0) && std::string_view(key) != "asymmetry") throw_input_error(c.where(path), "must be positive");
    return v;
  };
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

CoSimulation::CoSimulation(const config::Config& scene, nlohmann::json* facts) : scene_(scene) {
  const config::Config& c = scene_;
  nlohmann::json ignored;
  nlohmann::json& s = facts ? *facts : ignored;
  const bool has_flow = c.has_section("flow");
  const bool has_wire = c.has_section("wire");
  if ((has_flow || c.has_section("contact") || (c.has_section("fem") && fem_on_network(c))) && !c.has_section("vessels"))
    throw_input_error(c.where("flow"), "flow, contact and fem need a vessels: section");

  // ---------------- setup: only what the scene has
  auto& net = net_;
  auto& fsolver = fsolver_;
  auto& sim = sim_;
  auto& index = index_;
  auto& forces = forces_;
  auto& tip_forces = tip_forces_;
  auto& initial_layout = initial_layout_;
  if (c.has_section("vessels")) {
    net = build_scene_network(c);
    s["network"] = counts_json(net->counts());
  }
  if (has_flow) {
    fsolver = flow::make_solver(*net, flow::from_config(c, *net));
    s["flow"] = {{"solver", std::string(fsolver->name())}, {"model", c.string("flow.model")}};
  }
  if (c.has_section("fem")) check_fem(c, fsolver.get(), net ? &*net : nullptr);  // before the run, not after it
  int wire_entry = -1;
  if (has_wire) {
    auto spec = scene_wire_spec(c);
    if (net) {
      const int inlet = net->widest_end();
      int entry = -1;
      const auto entry_key = c.string("wire.entry");
      if (entry_key == "auto") {
        entry = net->farthest_end(inlet);
      } else {
        try {
          entry = std::stoi(entry_key);
        } catch (const std::exception&) {
          throw_input_error(c.where("wire.entry"), fmt::format("'{}' is not a node id or auto", entry_key));
        }
        if (entry < 0 || entry >= net->num_nodes() || net->degree(entry) != 1)
          throw_input_error(c.where("wire.entry"), fmt::format("node {} is not an end of the network", entry));
      }
      const auto& seg = net->segment(*net->node_segments(entry).first);
      const int other = seg.node_from == entry ? seg.node_to : seg.node_from;
      if (!c.has_section("wire.base")) {
        spec.base_position = net->node(entry);
        spec.base_direction = (net->node(other) - net->node(entry)).normalized();
      }
      if (spec.inserted_length < 0) spec.inserted_length = 0.02;
      s["wire_entry_node"] = entry;
      wire_entry = entry;
    }
    sim = std::make_unique<rod::RodSimulator>(spec);
    sim->set_integrator(c.string("solve.integrator") == "implicit_midpoint" ? rod::Integrator::ImplicitMidpoint
                                                                            : rod::Integrator::ImplicitEuler);
    std::optional<CatheterSpec> cat;
    if (c.has_section("catheter")) {
      if (spec.adapt.enabled)
        throw_input_error(c.where("wire.adapt"), "wire.adapt is not available with a catheter (both rods share one grid)");
      cat = scene_catheter_spec(c, spec);
      cath_ = std::make_unique<rod::RodSimulator>(catheter_rod_spec(*cat, spec));
      cath_->set_integrator(sim->settings().integrator);
      cath_->set_insertion_speed(cat->speed);
      cath_->set_rotation_speed(cat->rotation_speed);
      lumen_ = std::make_shared<LumenContact>(cat->inner_radius - spec.radius, cat->stiffness);
    }
    apply_loads(c, *sim);
    if (cath_)  // gravity acts on the catheter too (the other loads are the wire's)
      for (int i = 0; i < c.count("loads"); ++i)
        if (const std::string p = fmt::format("loads[{}].", i); c.string(p + "type") == "gravity")
          cath_->set_gravity(c.vector3(p + "value"));
    if (c.has_section("insertion")) {
      sim->set_insertion_speed(c.number("insertion.speed"));
      sim->set_rotation_speed(c.number("insertion.rotation_speed"));
      sim->set_base_angle(c.number("insertion.rotation_angle"));
      if (c.has("insertion.max_force")) {
        const double f = c.number("insertion.max_force");
        if (!(f > 0.0)) throw_input_error(c.where("insertion.max_force"), "max_force must be > 0 N");
        sim->set_max_insertion_force(f);
      }
      if (c.has("insertion.force")) {
        const double f = c.number("insertion.force");
        if (!(f > 0.0)) throw_input_error(c.where("insertion.force"), "insertion.force must be > 0 N");
        for (const char* key : {"insertion.speed", "insertion.schedule", "insertion.max_force"})
          if (c.has(key) && c.values().at(key).where != "default")
            throw_input_error(c.where(key), fmt::format("give either insertion.force (the feed follows from the force) or {}, not both", key));
        sim->set_push_force(f);
      }
    }
    if (net) {
      index.emplace(*net, 4);
      if (wire_entry >= 0 && !c.has_section("wire.base")) {
        // A wire inserted farther than the entry vessel runs straight leaves the lumen
        // when laid out straight (the shaft crosses the walls, centimetres deep, and no
        // penalty pulls it back in one step): lay it along the vessel path instead.
        const double shaft = sim->inserted_length() - spec.tip.length;
        bool leaves = false;
        for (double a = 0.0; a < shaft && !leaves; a += 0.5 * sim->model().h)
          leaves = index->wall_distance(spec.base_position + a * spec.base_direction) + spec.radius > 0.0;
        if (cath_)  // the catheter, as wide as its outer radius
          for (double a = 0.0; a < cath_->inserted_length() && !leaves; a += 0.5 * sim->model().h)
            leaves = index->wall_distance(spec.base_position + a * spec.base_direction) + cat->outer_radius > 0.0;
        if (leaves) {
          const VesselPath path(*net, wire_entry);
          if (sim->inserted_length() > path.max_wire_length())
            throw_input_error(c.where("insertion.initial_length"),
                              fmt::format("{:.4g} m is longer than the vessel path from the entry and back ({:.4g} m)",
                                          sim->inserted_length(), path.max_wire_length()));
          sim->lay_along([&path](double a) { return path.wire_point(a); });
          if (cath_) {
            if (cath_->inserted_length() > path.max_wire_length())
              throw_input_error(c.where("catheter.initial_length"),
                                fmt::format("{:.4g} m is longer than the vessel path from the entry and back ({:.4g} m)",
                                            cath_->inserted_length(), path.max_wire_length()));
            cath_->lay_along([&path](double a) { return path.wire_point(a); });
          }
          initial_layout = "vessel_path";
        }
      }
      double wall_smoothing = 0.0;
      forces = make_vessel_forces(c, *index, spec, fsolver.get());
      if (forces) {
        nlohmann::json info;
        double smoothing = 0.0;
        surface_ = make_scene_surface(c, *net, info, smoothing);  // vessels.surface: the wall the wire touches
        if (surface_) forces->set_surface(surface_.get(), smoothing), s["surface"] = info;
        wall_smoothing = smoothing;
        if (wire_entry >= 0 && (!c.has("contact.introducer") || c.boolean("contact.introducer"))) {
          // The introducer sheath's mouth: as wide as the entry vessel, twice over.
          const auto& es = net->segment(*net->node_segments(wire_entry).first);
          forces->set_introducer(spec.base_position, spec.base_direction, 2.0 * es.radius);
        }
        sim->add_external(forces);
      }
      if (cath_) {  // the catheter against the walls, with its outer radius
        cath_forces_ = make_vessel_forces(c, *index, catheter_rod_spec(*cat, spec), fsolver.get());
        if (cath_forces_) {
          if (surface_) cath_forces_->set_surface(surface_.get(), wall_smoothing);
          if (wire_entry >= 0 && (!c.has("contact.introducer") || c.boolean("contact.introducer"))) {
            const auto& es = net->segment(*net->node_segments(wire_entry).first);
            cath_forces_->set_introducer(spec.base_position, spec.base_direction, 2.0 * es.radius);
          }
          cath_->add_external(cath_forces_);
        }
      }
    }
    if (cath_) {
      lumen_->hold_catheter(*cath_);
      lumen_->hold_wire(*sim);
      sim->add_external(std::make_shared<LumenContactSide>(lumen_, LumenContactSide::Side::Wire));
      cath_->add_external(std::make_shared<LumenContactSide>(lumen_, LumenContactSide::Side::Catheter));
      s["catheter"] = {{"clearance", lumen_->clearance()}, {"lumen_stiffness", lumen_->stiffness()}};
    }
    tip_forces = make_tip_forces(c, net ? &*net : nullptr);
    if (tip_forces) sim->add_external(tip_forces);
  }

  // ---------------- stepping
  const double dt = c.number("solve.dt");
  const double duration = c.number("solve.duration");
  if (!(dt > 0)) throw_input_error(c.where("solve.dt"), "must be positive");
  if (duration < 0) throw_input_error(c.where("solve.duration"), "must not be negative");
  is_static_ = c.string("solve.mode") == "static";
  dt_ = dt;
  steps_ = is_static_ ? 0 : static_cast<long>(std::llround(duration / dt));
  flow_every_ = std::max(1, static_cast<int>(c.number_or("coupling.flow_every", 1)));
  max_length_ = c.number_or("insertion.max_length", std::numeric_limits<double>::infinity());
  if (sim && c.has_section("insertion")) {
    insertion_speed_ = c.number("insertion.speed");
    rotation_speed_ = c.number("insertion.rotation_speed");
  }
  if (c.has("insertion.schedule")) {
    for (const char* key : {"insertion.speed", "insertion.rotation_speed"})
      if (c.values().at(key).where != "default")
        throw_input_error(c.where(key), "give either insertion.schedule or insertion.speed and rotation_speed, not both");
    if (!sim) throw_input_error(c.where("insertion.schedule"), "a schedule drives the wire: the scene has none");
    schedule_ = std::make_unique<DriveSchedule>(DriveSchedule::read_csv(c.resolve_path(c.string("insertion.schedule"))));
  }

  // The wire acts on the blood (occlusion.hpp): set before every flow evaluation from the
  // wire of the last accepted step (staggered: the flow of step n+1 sees the wire of step n).
  if (fsolver && forces && sim) {
    const bool asked = c.has("coupling.occlusion");
    const bool annulus = !asked || c.string("coupling.occlusion") == "annulus";
    if (annulus && fsolver->supports_occlusion()) {
      occlusion_ = std::make_unique<WireOcclusion>(*fsolver);
    } else if (annulus && asked) {
      throw_input_error(c.where("coupling.occlusion"),
                        fmt::format("annulus needs flow.solver superposition or sparse (or flow.model rlc); the {} "
                                    "solver keeps its matrix",
                                    fsolver->name()));
    }
  }
}

void CoSimulation::occlude() {
  if (!occlusion_) return;
  const auto positions = sim_->positions();
  fsolver_->set_occlusion(occlusion_->update(positions, sim_->first_clamped_vertex(), forces_->segments(),
                                             sim_->discretization().edge_radius));
}

CoSimulation::~CoSimulation() = default;

void CoSimulation::set_insertion_speed(double speed) {
  if (!sim_) throw_usage_error("set_insertion_speed: the scene has no wire");
  sim_->set_insertion_speed(speed);
  insertion_speed_ = speed;
}

void CoSimulation::set_rotation_speed(double omega) {
  if (!sim_) throw_usage_error("set_rotation_speed: the scene has no wire");
  sim_->set_rotation_speed(omega);
  rotation_speed_ = omega;
}

void CoSimulation::start() {
  const config::Config& c = scene_;
  if (fsolver_) {
    const auto tf = Clock::now();
    occlude();  // the vertices are located once the wire has settled or stepped
    fsolver_->advance(0.0);
    t_flow_ += seconds_since(tf);
  }
  if (sim_ && is_static_) {
    const auto tr = Clock::now();
    const auto rep = solve_static_all();
    t_rod_ += seconds_since(tr);
    if (rep.status == rod::SolveStatus::NonFinite || rep.status == rod::SolveStatus::SingularMatrix)
      throw_numerical_error(fmt::format("static solve failed: {}", rod::to_string(rep.status)));
    if (!rep.converged()) ++failures_;
  }
  const bool settle_on = !c.has("contact.settle") || c.boolean("contact.settle");
  if (sim_ && !is_static_ && forces_ && forces_->contact().enabled && settle_on) {
    // The free initial shape may not fit the lumen (a J tip wider than the vessel): start
    // from its equilibrium against the walls, or the first steps take a large impulse.
    const auto tr = Clock::now();
    const auto rep = solve_static_all();
    t_rod_ += seconds_since(tr);
    settle_ = {{"converged", rep.converged()}, {"newton_iterations", rep.newton_iterations}};
    if (!rep.converged()) warn("the initial wire did not settle against the walls; starting from its last iterate");
  }
  if (occlusion_ && (is_static_ || !settle_.is_null())) {  // the flow around the settled wire
    const auto tf = Clock::now();
    occlude();
    fsolver_->advance(0.0);
    t_flow_ += seconds_since(tf);
  }
}

void CoSimulation::step() {
  const long step = step_;
  const double t1 = (static_cast<double>(step) + 1.0) * dt_;
  if (fsolver_ && (step % flow_every_ == 0 || !sim_)) {
    const auto tf = Clock::now();
    occlude();
    fsolver_->advance(t1);
    t_flow_ += seconds_since(tf);
  }
  if (sim_) {
    if (schedule_) {
      // The step at the schedule's mean speeds: its integrals are met at every step's end.
      schedule_->mean_over(t1 - dt_, t1, insertion_speed_, rotation_speed_);
      sim_->set_rotation_speed(rotation_speed_);
      sim_->set_insertion_speed(insertion_speed_);
    }
    if (sim_->inserted_length() >= max_length_ && insertion_speed_ > 0.0) sim_->set_insertion_speed(insertion_speed_ = 0.0);
    if (sim_->inserted_length() >= max_length_ && sim_->push_force() > 0.0) sim_->set_push_force(0.0);  // held there
    const auto tr = Clock::now();
    const auto rep = sim_->step(dt_);
    t_rod_ += seconds_since(tr);
    if (rep.status == rod::SolveStatus::NonFinite || rep.status == rod::SolveStatus::SingularMatrix)
      throw_numerical_error(fmt::format("rod step {} (t = {:.6g} s) failed: {}", step + 1, t1, rod::to_string(rep.status)));
    if (!rep.converged()) ++failures_;
    if (cath_) {
      // Staggered (catheter.hpp): the wire above stepped against the catheter of the last
      // step; now the catheter against that wire.
      lumen_->hold_wire(*sim_);
      const auto tc = Clock::now();
      const auto crep = cath_->step(dt_);
      t_rod_ += seconds_since(tc);
      if (crep.status == rod::SolveStatus::NonFinite || crep.status == rod::SolveStatus::SingularMatrix)
        throw_numerical_error(
            fmt::format("catheter step {} (t = {:.6g} s) failed: {}", step + 1, t1, rod::to_string(crep.status)));
      if (!crep.converged()) ++cath_failures_;
      lumen_->hold_catheter(*cath_);
    }
  }
  ++step_;
}

rod::StepReport CoSimulation::solve_static_all() {
  if (!cath_) return sim_->solve_static();
  const PairStaticReport pair = solve_static_pair(*sim_, *cath_, *lumen_, 100, 1e-3 * sim_->model().h);
  rod::StepReport rep = sim_->last_report();
  if (rep.converged() && (!pair.converged || !cath_->last_report().converged())) rep.status = rod::SolveStatus::MaxIterations;
  return rep;
}

namespace {
/// The frame of one rod as the outputs write it (free vertices from the base to the tip).
/// The frame of @p rod (empty, at @p time, when there is none).
WireFrame rod_frame(const rod::RodSimulator* rod_or_null, const VesselForces* forces, double time) {
  WireFrame f;
  f.time = time;
  if (!rod_or_null) return f;
  const rod::RodSimulator& rod = *rod_or_null;
  const auto x = rod.positions();
  const auto arc = rod.arc_lengths();
  for (int i = rod.first_clamped_vertex(); i >= 0; --i) {  // base → tip
    if (i >= rod.vertex_count()) continue;
    f.x.push_back(x[static_cast<size_t>(i)]);
    f.s.push_back(std::max(0.0, arc[static_cast<size_t>(i)]));
    f.force.push_back(forces && i < static_cast<int>(forces->force().size()) ? forces->force()[static_cast<size_t>(i)]
                                                                             : Eigen::Vector3d::Zero());
    auto part = [&](const std::vector<Eigen::Vector3d>& v) {
      return forces && i < static_cast<int>(v.size()) ? v[static_cast<size_t>(i)] : Eigen::Vector3d::Zero();
    };
    if (forces) f.drag.push_back(part(forces->drag_force())), f.contact.push_back(part(forces->contact_force()));
    f.flow_velocity.push_back(forces && i < static_cast<int>(forces->fluid_velocity().size())
                                  ? forces->fluid_velocity()[static_cast<size_t>(i)]
                                  : Eigen::Vector3d::Zero());
  }
  return f;
}
}  // namespace

WireFrame CoSimulation::wire_frame() const { return rod_frame(sim_.get(), forces_.get(), time()); }

WireFrame CoSimulation::catheter_frame() const { return rod_frame(cath_.get(), cath_forces_.get(), time()); }


RunResult run_scene(const config::Config& c, const RunOptions& options) {
  const auto t_start = Clock::now();
  (void)take_warnings();
  RunResult result;
  result.out_dir = c.string("output.dir");
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
    auto w = take_warnings();
    // Repeated numerical warnings (one per step) are summarised, not listed thousands of times.
    std::map<std::string, int> count;
    for (const auto& x : w) ++count[x];
    nlohmann::json list = nlohmann::json::array();
    for (const auto& [msg, k] : count) list.push_back(k > 1 ? fmt::format("{} (x{})", msg, k) : msg);
    s["warnings"] = list;
    write_text_atomically(out / "summary.json", s.dump(2) + "\n");
  };

  try {
    // ---------------- setup: only what the scene has
    auto t0 = Clock::now();
    CoSimulation cosim(c, &s);
    const vessels::Network* net = cosim.network();
    flow::FlowSolver* fsolver = cosim.flow();
    timings["setup"] = seconds_since(t0);

    // ---------------- stepping
    const double dt = cosim.dt();
    const double every = c.number("output.every");
    const long steps = cosim.planned_steps();
    const long out_every = every > 0 ? std::max(1L, static_cast<long>(std::llround(every / dt))) : 0;
    const bool series = out_every > 0;

    RunRecorder recorder(c, cosim, out);
    cosim.start();
    if (series || steps == 0) recorder.record(0.0);
    for (long step = 0; step < steps; ++step) {
      const double t1 = (static_cast<double>(step) + 1.0) * dt;
      cosim.step();
      recorder.after_step();
      if (series && (step + 1) % out_every == 0) recorder.record(t1);
      if (options.progress) options.progress({step + 1, steps, t1, static_cast<double>(steps) * dt, seconds_since(t_start)});
    }
    if (!series && steps > 0) recorder.record(static_cast<double>(steps) * dt);
    s["steps"] = steps;
    recorder.finish(series);
    const double t_out = recorder.seconds();

    // ---------------- finite-element comparison of the flow (fem:)
    if (c.has_section("fem") && !fem_on_network(c)) {
      const auto tf = Clock::now();
      s["fem"] = run_fem_geometry(c, out);
      timings["fem"] = seconds_since(tf);
    } else if (c.has_section("fem")) {
      if (!fsolver) throw_input_error(c.where("fem"), "fem: compares the flow, so the scene needs a flow: section");
      const auto tf = Clock::now();
      s["fem"] = run_fem(c, *net, *fsolver, out);
      timings["fem"] = seconds_since(tf);
    }

    // ---------------- summary
    const RunSeconds split = add_run_summary(c, cosim, s);
    timings["flow"] = cosim.flow_seconds();
    timings["rod"] = std::max(0.0, cosim.rod_seconds() - split.contact - split.coupling);
    timings["contact"] = split.contact;
    timings["coupling"] = split.coupling;
    timings["output"] = t_out;
  } catch (const Error& e) {
    if (e.kind() == ErrorKind::Numerical) {
      s["error"] = e.what();
      finish("error");
    }
    throw;
  }
  // A wire that left the lumen by more than its radius is no result to trust: said with
  // where and when, status "outside", and a numerical failure unless the scene allows it.
  if (const auto& o = result.summary["contact"]; o.contains("outside")) {
    const std::string msg = o["outside"]["message"];
    warn(msg);
    finish("outside");
    if (!(c.has("contact.allow_outside") && c.boolean("contact.allow_outside"))) throw_numerical_error(msg + " (contact.allow_outside: true accepts such a run)");
    return result;
  }
  finish("ok");
  return result;
}

}  // namespace flowire::coupling
