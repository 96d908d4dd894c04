// The scene's fem: section: its keys, their checks at setup, and the finite-element
// comparison they configure (run after the co-simulation).
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/common/units.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/flow/solver.hpp"
#include "scene_sections.hpp"
#ifdef FLOWIRE_HAVE_FEM
#include "flowire/flow/fem/boundary_values.hpp"
#include "flowire/flow/fem/calibrate.hpp"
#include "flowire/flow/fem/compare.hpp"
#include "flowire/flow/fem/lumen.hpp"
#include "flowire/flow/fem/obstacle.hpp"
#include "flowire/flow/fem/pulsatile.hpp"
#endif

namespace flowire::coupling {

void declare_fem_keys(config::Schema& s) {
  using config::Type;
  using D = units::Dimension;
  s.add("fem", Type::Section, "", D::None, "finite-element comparison of the flow (needs FLOWIRE_WITH_FEM)");
  s.add("fem.geometry", Type::Enum, "network", D::None,
        "network: the lumen of the vessels (compared with the flow); dfg_3d_1z: the DFG benchmark 3D-1Z channel "
        "around a cylinder with its own fluid and inflow (needs no vessels or flow; writes fem_forces.csv, c_D, c_L "
        "and the pressure difference in summary.json); lumen: the real lumen of vessels.surface, its open ends "
        "tagged by the nearest centerline ends, compared with the flow as network is",
        {"network", "dfg_3d_1z", "lumen"});
  s.add("fem.mesh_size", Type::Number, "", D::Length,
        "target tetrahedron size (network: default from the smallest radius; dfg_3d_1z: far field, default 0.08 m)")
      .positive();
  s.add("fem.size_factor", Type::Number, "0.3", D::None,
        "network / lumen without fem.mesh_size: tetrahedron size = this times the radius of the nearest vessel")
      .positive();
  s.add("fem.obstacle_mesh_size", Type::Number, "", D::Length,
        "dfg_3d_1z: tetrahedron size on the cylinder (default a quarter of fem.mesh_size), growing with the distance "
        "from it by fem.mesh_growth")
      .positive();
  s.add("fem.mesh_growth", Type::Number, "0.3", D::None,
        "dfg_3d_1z: increase of the tetrahedron size per unit distance from the obstacle")
      .positive();
  s.add("fem.equations", Type::Enum, "stokes", D::None, "stokes | navier_stokes", {"stokes", "navier_stokes"});
  s.add("fem.solver", Type::Enum, "mumps", D::None, "direct (mumps) or iterative (fieldsplit, Stokes only)",
        {"mumps", "fieldsplit"});
  s.add("fem.stabilization", Type::Enum, "supg", D::None,
        "navier_stokes: supg (SUPG + grad-div, consistent) or none (plain Galerkin)", {"supg", "none"});
  s.add("fem.inlet", Type::Enum, "profile", D::None,
        "navier_stokes: profile (a Poiseuille velocity profile scaled to the inlet pressure or flow) or traction",
        {"profile", "traction"});
  s.add("fem.inlet_profile", Type::Enum, "poiseuille", D::None,
        "navier_stokes with fem.inlet: profile: poiseuille (developed flow enters) | flat (a uniform velocity enters "
        "and develops: the entrance of docs/flow-losses.md)",
        {"poiseuille", "flat"});
  s.add("fem.backflow", Type::Number, "1", D::None, "navier_stokes: outlet backflow stabilization coefficient (0: off)")
      .non_negative();
  s.add("fem.time_dependent", Type::Bool, "false", D::None,
        "frames from time-dependent Stokes (BDF2, inertia included) instead of quasi-steady solves; needs fem.frames");
  s.add("fem.steps_per_period", Type::Integer, "200", D::None,
        "time steps per period of a time-dependent series or of windkessel outlets (rounded up to a multiple of "
        "fem.frames)")
      .at_least(1)
      .at_most(1e6);
  s.add("fem.samples_per_branch", Type::Integer, "10", D::None, "comparison points per branch").at_least(2);
  s.add("fem.frames", Type::Integer, "0", D::None,
        "0: steady comparison only; N: also N quasi-steady frames over one inlet period (fem_pulsatile*.csv, fem.pvd)")
      .at_least(0)
      .at_most(1e5);
}

bool fem_on_network(const config::Config& c) {
  return !c.has_section("fem") || c.string("fem.geometry") == "network" || c.string("fem.geometry") == "lumen";
}

namespace {

#ifdef FLOWIRE_HAVE_FEM
nlohmann::json fem_result_json(const flow::fem::CompareResult& r) {
  nlohmann::json j = {{"tets", r.tets},
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
  // A real lumen: the length of centerline cut beyond each cap (m, network end order; < 0: the
  // network was lengthened to reach the cap), so that both models end at the caps.
  if (!r.cut_length.empty()) j["network_cut_at_caps"] = r.cut_length;
  // Open ends cut so obliquely that they were cut again square to their vessel (lumen.hpp).
  if (r.lumen_ends_recut > 0) j["lumen_ends_recut"] = r.lumen_ends_recut;
  return j;
}

/// The comparison's options from the scene's fem: section (and the lumen of vessels.surface).
flow::fem::FemOptions fem_options(const config::Config& c) {
  flow::fem::FemOptions fo;
  if (c.has("fem.mesh_size")) fo.mesh_size = c.number("fem.mesh_size");
  fo.equations =
      c.string("fem.equations") == "navier_stokes" ? flow::fem::Equations::NavierStokes : flow::fem::Equations::Stokes;
  fo.solver =
      c.string("fem.solver") == "fieldsplit" ? flow::fem::LinearSolver::Fieldsplit : flow::fem::LinearSolver::Mumps;
  fo.stabilization =
      c.string("fem.stabilization") == "none" ? flow::fem::Stabilization::None : flow::fem::Stabilization::Supg;
  fo.inlet =
      c.string("fem.inlet") == "traction" ? flow::fem::InletCondition::Traction : flow::fem::InletCondition::Profile;
  fo.flat_inlet = c.string("fem.inlet_profile") == "flat";
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
  return fo;
}
#endif

/// Input checks of a fem: section on a built-in geometry (no network), done at setup. The
/// values' own ranges are declared with their keys.
void check_fem_geometry(const config::Config& c) {
  if (c.integer("fem.frames") != 0) throw_input_error(c.where("fem.frames"), "is for fem.geometry: network");
  if (c.string("fem.solver") == "fieldsplit")
    throw_input_error(c.where("fem.solver"),
                      "navier_stokes needs mumps (the fieldsplit Schur approximation ignores convection)");
}

}  // namespace

/// The DFG benchmark 3D-1Z (fem.geometry: dfg_3d_1z): forces, c_D, c_L, Δp.
nlohmann::json run_fem_geometry(const config::Config& c, const std::filesystem::path& out) {
#ifdef FLOWIRE_HAVE_FEM
  flow::fem::ObstacleMesh sizes;
  sizes.mesh_size = c.has("fem.mesh_size") ? c.number("fem.mesh_size") : 0.08;
  sizes.obstacle_mesh_size =
      c.has("fem.obstacle_mesh_size") ? c.number("fem.obstacle_mesh_size") : 0.25 * sizes.mesh_size;
  sizes.growth = c.number("fem.mesh_growth");
  const auto stab =
      c.string("fem.stabilization") == "none" ? flow::fem::Stabilization::None : flow::fem::Stabilization::Supg;
  const flow::fem::ObstacleResult r = flow::fem::dfg_3d_1z(sizes, stab, out.string(), c.boolean("output.vtk"));
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
void check_fem(const config::Config& c, const flow::FlowSolver* fs, [[maybe_unused]] const vessels::Network* net) {
  if (!fem_on_network(c)) return check_fem_geometry(c);
  if (!fs) throw_input_error(c.where("fem"), "fem: compares the flow, so the scene needs a flow: section");
  if (c.string("fem.geometry") == "lumen") {
    if (!c.has("vessels.surface")) throw_input_error(c.where("fem.geometry"), "lumen needs vessels.surface");
    const std::string surface = c.resolve_path(c.string("vessels.surface"));
    if (!std::filesystem::is_regular_file(surface))
      throw_input_error(fmt::format("{}: {}", c.where("vessels.surface"), surface),
                        "the lumen surface file does not exist");
#ifdef FLOWIRE_HAVE_FEM
    // Read it and match its open ends now (cheap), so that bad input stops the run before any output.
    if (net)
      (void)flow::fem::prepare_lumen(
          *net, flow::fem::read_surface(surface, units::length_unit_factor(c.string_or("vessels.length_unit", "m"),
                                                                           c.where("vessels.length_unit"))));
#endif
  }
  // frames, backflow, steps_per_period and size_factor have declared ranges.
  const int frames = c.integer("fem.frames");
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
    throw_input_error(c.where("fem"),
                      fmt::format("the comparison needs exactly one inlet; the flow has {}", fs->spec().inlets.size()));
}

/// The FEM reference on the same geometry with the network's own boundary conditions (the
/// flow spec): inlet pressure or flow, outlets at a pressure or through a resistance (RCR:
/// Rp + Rd, quasi-steady), at the flow's current time; with fem.frames = N also N
/// quasi-steady frames over one inlet period from one factorization.
nlohmann::json run_fem(const config::Config& c, const vessels::Network& net, const flow::FlowSolver& fs,
                       const std::filesystem::path& out) {
#ifdef FLOWIRE_HAVE_FEM
  const flow::FlowSpec& spec = fs.spec();
  const flow::fem::BoundaryValues bv = flow::fem::boundary_values(spec, net, fs.time());
  const bool has_rcr = std::any_of(spec.outlets.begin(), spec.outlets.end(),
                                   [](const flow::OutletBC& o) { return o.type == flow::OutletBC::Type::Rcr; });
  if (std::any_of(spec.outlets.begin(), spec.outlets.end(),
                  [](const flow::OutletBC& o) { return o.type == flow::OutletBC::Type::Coronary; }))
    warn(
        "fem: the finite-element side takes coronary outlets as their steady resistance Ra + Ram + Rv to Pv (its "
        "series integrates RCR windkessels only)");
  const bool time_dependent = c.boolean("fem.time_dependent");
  // Windkessel dynamics on both sides when the network integrates them (rlc model).
  const bool dynamic_rcr = has_rcr && spec.model == flow::Model::Rlc;
  if (has_rcr && !dynamic_rcr)
    warn(
        "fem: RCR outlets are compared quasi-steadily, as the resistance Rp + Rd to Pd (the poiseuille flow model "
        "has no capacitor; use flow.model: rlc with fem.frames for the windkessel dynamics)");
  flow::fem::FemOptions fo = fem_options(c);
  fo.segment_laws = spec.segment_laws;
  fo.junction_losses = !spec.junctions.empty();
  fo.total_pressure = spec.total_pressure;
  fo.end_alpha = spec.end_alpha;
  const long frames = c.integer("fem.frames");  // checked by check_fem
  if (frames == 0) {
    auto j = fem_result_json(flow::fem::compare(net, bv, fo, out.string()));
    j["time"] = fs.time();
    return j;
  }
  const double period = spec.cycle();
  std::vector<double> times;
  std::vector<flow::fem::BoundaryValues> values;
  for (long i = 0; i < frames; ++i) {
    times.push_back(period * static_cast<double>(i) / static_cast<double>(frames));
    values.push_back(flow::fem::boundary_values(spec, net, times.back()));
  }
  flow::fem::DynamicOptions dyn;
  std::unique_ptr<flow::FlowSolver> periodic;  // the network over enough periods to be periodic
  const bool dynamic = dynamic_rcr || time_dependent;
  if (dynamic) {
    dyn.period = period;
    dyn.time_dependent = time_dependent;
    dyn.steps_per_period = static_cast<int>(c.integer("fem.steps_per_period"));
    dyn.values_at = [&spec, &net](double t) { return flow::fem::boundary_values(spec, net, t); };
    if (dynamic_rcr)
      for (const auto& o : spec.outlets)
        if (o.type == flow::OutletBC::Type::Rcr) dyn.windkessels.push_back(o);
    if (spec.model == flow::Model::Rlc) {
      periodic = flow::make_solver(net, spec);
      const double start = 30.0 * period;
      dyn.network_at = [&periodic, &net, start](double t) {
        flow::fem::NetworkFlow nf;
        nf.node_pressure.resize(static_cast<size_t>(net.num_nodes()));
        nf.segment_flow.resize(static_cast<size_t>(net.num_segments()));
        periodic->solve_at(start + t, nf.node_pressure, nf.segment_flow);
        return nf;
      };
    }
  }
  const auto p =
      flow::fem::compare_pulsatile(net, times, values, bv, fs.time(), fo, out.string(), dynamic ? &dyn : nullptr);
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

nlohmann::json calibrate_scene(const config::Config& c, const CalibrateOptions& options) {
  if (!c.has_section("fem"))
    throw_input_error(c.file(),
                      "calibrate fits the network to the 3D solution of the scene's fem: section, and the "
                      "scene has none (fem: {geometry: lumen, equations: navier_stokes})");
  if (!fem_on_network(c))
    throw_input_error(c.where("fem.geometry"),
                      "calibrate needs the network's own lumen or a real one (network, lumen)");
  if (!c.has_section("flow"))
    throw_input_error(c.file(), "calibrate needs a flow: section (the inlet and the outlets)");
#ifdef FLOWIRE_HAVE_FEM
  const auto t0 = std::chrono::steady_clock::now();
  (void)take_warnings();
  const vessels::Network net = build_scene_network(c);
  flow::FlowSpec spec = scene_flow(c, net);
  if (!spec.segment_laws.empty() || !spec.junctions.empty()) {
    warn(fmt::format("calibrate: the scene's {} set aside; the fit starts from Poiseuille segments",
                     c.has("vessels.calibration") ? "vessels.calibration is" : "flow.losses are"));
    spec.segment_laws.clear();
    spec.stenoses.clear();
    spec.junctions.clear();
    spec.total_pressure = false;
    spec.end_alpha.clear();
  }
  const auto fs = flow::make_solver(net, spec);
  check_fem(c, fs.get(), &net);
  if (c.integer("fem.frames") != 0)
    warn("calibrate: fem.frames is set aside; the fit uses steady solutions at scaled inlet values");
  const flow::fem::BoundaryValues bv = flow::fem::boundary_values(fs->spec(), net, 0.0);
  const flow::fem::FemOptions fo = fem_options(c);
  const std::filesystem::path out(c.string("output.dir"));
  const OutputFolder folder(out);
  const flow::fem::CalibrationResult r = flow::fem::calibrate(net, bv, fo, {options.factors, options.check_factor});
  flow::write_calibration((out / "calibration.json").string(), r.calibration);
  flow::fem::write_calibration_report(out.string(), net, r);
  nlohmann::json runs = nlohmann::json::array();
  for (const auto& run : r.runs)
    runs.push_back({{"inlet_flow", run.inlet_flow},
                    {"factor", run.factor},
                    {"fitted", run.fitted},
                    {"before", fem_result_json(run.before)},
                    {"after", fem_result_json(run.after)}});
  int bounded = 0;
  for (const auto& f : r.calibration.fits) bounded += f.bounded ? 1 : 0;
  nlohmann::json s = {{"status", "ok"},
                      {"scene", c.file()},
                      {"calibration",
                       {{"file", "calibration.json"},
                        {"equations", r.calibration.equations},
                        {"branches", r.calibration.fits.size()},
                        {"bounded_branches", bounded},
                        {"runs", runs}}},
                      {"timings",
                       {{"mesh", r.mesh_seconds},
                        {"fem", r.solve_seconds},
                        {"total", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()}}}};
  s["warnings"] = take_warnings();
  write_text_atomically(out / "summary.json", s.dump(2) + "\n");
  return s;
#else
  (void)options;
  throw_input_error(c.where("fem"),
                    "this flowire was built without the FEM path (FLOWIRE_WITH_FEM needs gmsh and PETSc)");
#endif
}

}  // namespace flowire::coupling
