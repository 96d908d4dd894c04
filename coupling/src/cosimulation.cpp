// The co-simulation (cosimulation.hpp): builds only what a scene has (vessels, flow, wire,
// catheter) and steps it. Each section's keys are read where they are declared
// (scene_sections.hpp); the set-up here puts the parts together.
#include <fmt/format.h>
#include <unistd.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/coupling/cosimulation.hpp"
#include "flowire/coupling/lumen.hpp"
#include "flowire/coupling/occlusion.hpp"
#include "flowire/coupling/paraview_script.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/coupling/tip_forces.hpp"
#include "flowire/coupling/vessel_forces.hpp"
#include "flowire/coupling/vessel_path.hpp"
#include "flowire/coupling/wire_output.hpp"
#include "flowire/flow/output.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire/vessels/spatial.hpp"
#include "run_output.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

}  // namespace

nlohmann::json counts_json(const vessels::NetworkCounts& n) {
  return {{"branches", n.branches},
          {"nodes", n.nodes},
          {"segments", n.segments},
          {"junctions", n.junctions},
          {"ends", n.ends},
          {"loops", n.loops},
          {"components", n.components},
          {"total_length", n.total_length},
          {"radius_min", n.radius_min},
          {"radius_max", n.radius_max}};
}

CoSimulation::CoSimulation(const config::Config& scene, nlohmann::json* facts) : scene_(scene) {
  const config::Config& c = scene_;
  nlohmann::json ignored;
  nlohmann::json& s = facts ? *facts : ignored;
  if ((c.has_section("flow") || c.has_section("contact") || (c.has_section("fem") && fem_on_network(c))) &&
      !c.has_section("vessels"))
    throw_input_error(c.where("flow"), "flow, contact and fem need a vessels: section");
  // Only what the scene has.
  if (c.has_section("vessels")) build_network(s);
  if (c.has_section("flow")) build_flow(s);
  if (c.has_section("fem")) check_fem(c, fsolver_.get(), network());  // before the run, not after it
  if (c.has_section("wire")) build_wire(s);
  plan_steps();
  couple_occlusion();
}

void CoSimulation::build_network(nlohmann::json& s) {
  SceneNetwork sn = build_scene_network_and_radii(scene_);
  net_ = std::move(sn.network);
  surface_ = std::move(sn.surface);  // read for the radii: the wall contact takes it as it is
  surface_info_ = std::move(sn.surface_info);
  surface_smoothing_ = sn.surface_smoothing;
  s["network"] = counts_json(net_->counts());
  s["network"]["radius"] = sn.radius;
}

void CoSimulation::build_flow(nlohmann::json& s) {
  fsolver_ = flow::make_solver(*net_, scene_flow(scene_, *net_));
  s["flow"] = {{"solver", std::string(fsolver_->name())},
               {"model", std::string(flow::to_string(fsolver_->spec().model))}};
  // A calibration in total pressure: the network's nodes hold p + ½ρū² (its outlets their static values).
  if (!fsolver_->spec().segment_laws.empty())
    s["flow"]["pressure"] = fsolver_->spec().total_pressure ? "total" : "static";
  if (scene_.string_or("flow.losses.stenosis", "none") != "none") {
    nlohmann::json list = nlohmann::json::array();
    for (const flow::Stenosis& st : fsolver_->spec().stenoses)
      list.push_back({{"branch", net_->branch(st.branch).name},
                      {"node", st.throat_node},
                      {"s", st.s},
                      {"throat_radius", st.throat_radius},
                      {"reference_radius", st.reference_radius},
                      {"area_reduction", st.area_reduction},
                      {"coefficient", st.coefficient},
                      {"segments", st.segments.size()}});
    s["flow"]["losses"]["stenosis"] = {{"model", scene_.string("flow.losses.stenosis")}, {"stenoses", std::move(list)}};
  }
  if (scene_.string_or("flow.losses.curvature", "none") != "none")
    s["flow"]["losses"]["curvature"] = {{"model", "white"}, {"curved_segments", fsolver_->spec().curved_segments}};
  if (scene_.string_or("flow.losses.entrance", "none") != "none")
    s["flow"]["losses"]["entrance"] = {{"model", "shah"},
                                       {"inlet_profile", scene_.string("flow.losses.inlet_profile")},
                                       {"entrances", fsolver_->spec().entrances}};
  if (scene_.string_or("flow.losses.junction", "none") != "none")
    s["flow"]["losses"]["junction"] = {{"model", "unified"}, {"junctions", fsolver_->spec().junctions.size()}};
}

void CoSimulation::build_wire(nlohmann::json& s) {
  const config::Config& c = scene_;
  rod::WireSpec spec = scene_wire_spec(c);
  int entry = -1;
  if (net_) {
    entry = enter_network(c, *net_, spec);
    s["wire_entry_node"] = entry;
  }
  sim_ = std::make_unique<rod::RodSimulator>(spec);
  sim_->set_integrator(scene_integrator(c));
  if (c.has_section("catheter")) build_catheter(spec);
  apply_loads(c, *sim_, cath_.get());
  drive_wire(c, *sim_);
  if (net_) {
    index_.emplace(*net_, 4);
    if (entry >= 0 && !c.has_section("wire.base")) lay_along_vessels(entry);
    add_wall_forces(spec, entry, s);
  }
  if (cath_) couple_catheter(s);
  tip_forces_ = make_tip_forces(c, network());
  if (tip_forces_) sim_->add_external(tip_forces_);
}

void CoSimulation::build_catheter(const rod::WireSpec& wire) {
  if (wire.adapt.enabled)
    throw_input_error(scene_.where("wire.adapt"),
                      "wire.adapt is not available with a catheter (both rods share one grid)");
  cath_spec_ = scene_catheter_spec(scene_, wire);
  cath_ = std::make_unique<rod::RodSimulator>(catheter_rod_spec(*cath_spec_, wire));
  cath_->set_integrator(sim_->settings().integrator);
  cath_->set_insertion_speed(cath_spec_->speed);
  cath_->set_rotation_speed(cath_spec_->rotation_speed);
  lumen_ = std::make_shared<LumenContact>(cath_spec_->inner_radius - wire.radius, cath_spec_->stiffness);
  lumen_->set_friction(cath_spec_->inner_friction, ContactParams{}.slip_speed);
}

void CoSimulation::lay_along_vessels(int entry) {
  // The inserted wire starts along the vessel path from its entry, whatever its length: laid
  // straight out of the entry it leaves any vessel that turns within its length (on the
  // AneuRisk siphon, 3 mm to 1 cm of wire laid straight ended 3-13 wire radii outside the
  // surface), and a check against the network's cylinders cannot see a lumen surface's bends.
  const config::Config& c = scene_;
  const VesselPath path(*net_, entry);
  if (sim_->inserted_length() > path.max_wire_length())
    throw_input_error(c.where("insertion.initial_length"),
                      fmt::format("{:.4g} m is longer than the vessel path from the entry and back ({:.4g} m)",
                                  sim_->inserted_length(), path.max_wire_length()));
  sim_->lay_along([&path](double a) { return path.wire_point(a); });
  if (cath_) {
    if (cath_->inserted_length() > path.max_wire_length())
      throw_input_error(c.where("catheter.initial_length"),
                        fmt::format("{:.4g} m is longer than the vessel path from the entry and back ({:.4g} m)",
                                    cath_->inserted_length(), path.max_wire_length()));
    cath_->lay_along([&path](double a) { return path.wire_point(a); });
  }
  initial_layout_ = "vessel_path";
}

void CoSimulation::add_wall_forces(const rod::WireSpec& spec, int entry, nlohmann::json& s) {
  const config::Config& c = scene_;
  double wall_smoothing = 0.0;
  // The introducer sheath's mouth at the entry: as wide as the entry vessel, twice over.
  auto introduce = [&](VesselForces& f) {
    if (entry < 0 || !contact_settings(c).introducer) return;
    const auto& es = net_->segment(*net_->node_segments(entry).first);
    f.set_introducer(spec.base_position, spec.base_direction, 2.0 * es.radius);
  };
  forces_ = make_vessel_forces(c, *index_, spec, fsolver_.get());
  if (forces_) {
    nlohmann::json info;
    if (!surface_)  // vessels.surface: the wall the wire touches
      surface_ = make_scene_surface(c, *net_, surface_info_, surface_smoothing_);
    info = surface_info_;
    wall_smoothing = surface_smoothing_;
    if (surface_) forces_->set_surface(surface_.get(), wall_smoothing), s["surface"] = info;
    // (checked before the wall is meshed: a scene refused should not cost the mesh)
    if (c.has_section("wall")) {
      wall_flow_radii_ = c.boolean("wall.flow_radii");
      if (wall_flow_radii_ && !fsolver_)
        throw_input_error(c.where("wall.flow_radii"), "the flow's radii need the scene's flow: section");
      if (wall_flow_radii_ && !fsolver_->supports_occlusion())
        throw_input_error(c.where("wall.flow_radii"),
                          fmt::format("the {} flow solver keeps its matrix: the wall's widening needs flow.solver "
                                      "superposition or sparse",
                                      fsolver_->name()));
      if (wall_flow_radii_ && c.string_or("flow.model", "") == "rlc")
        throw_input_error(c.where("wall.flow_radii"),
                          "flow.model rlc widens its segments by its own compliance already (flow.wall); the "
                          "wall's widening is for the quasi-steady model");
    }
    std::span<const flow::BranchWall> flow_walls;
    if (fsolver_) flow_walls = fsolver_->spec().branch_walls;
    wall_ = make_scene_wall(c, *net_, surface_.get(), s, flow_walls);
    if (wall_) {
      if (!forces_->contact().enabled)
        throw_input_error(c.where("wall"), "a deformable wall needs the wall contact (contact.enabled: true)");
      forces_->set_deformable(wall_.get());
      wall_blood_pressure_ = c.boolean("wall.blood_pressure");
      wall_reference_pressure_ = c.number("wall.reference_pressure");
      if (wall_blood_pressure_ && !fsolver_)
        throw_input_error(c.where("wall.blood_pressure"), "the blood pressure needs the scene's flow: section");
    }
    introduce(*forces_);
    sim_->add_external(forces_);
  }
  if (cath_) {  // the catheter against the walls, with its outer radius
    cath_forces_ = make_vessel_forces(c, *index_, catheter_rod_spec(*cath_spec_, spec), fsolver_.get());
    if (cath_forces_) {
      if (surface_) cath_forces_->set_surface(surface_.get(), wall_smoothing);
      if (wall_) cath_forces_->set_deformable(wall_.get());  // the same wall as the wire's
      introduce(*cath_forces_);
      cath_->add_external(cath_forces_);
    }
  }
}

void CoSimulation::couple_catheter(nlohmann::json& s) {
  lumen_->hold_catheter(*cath_);
  lumen_->hold_wire(*sim_);
  sim_->add_external(std::make_shared<LumenContactSide>(lumen_, LumenContactSide::Side::Wire));
  cath_->add_external(std::make_shared<LumenContactSide>(lumen_, LumenContactSide::Side::Catheter));
  s["catheter"] = {{"clearance", lumen_->clearance()},
                   {"lumen_stiffness", lumen_->stiffness()},
                   {"inner_friction", lumen_->friction()}};
}

void CoSimulation::plan_steps() {
  const SolveSettings solve = solve_settings(scene_);
  is_static_ = solve.is_static;
  dt_ = solve.dt;
  steps_ = solve.steps;
  flow_every_ = coupling_settings(scene_).flow_every;
  InsertionPlan plan = insertion_plan(scene_, sim_ != nullptr);
  max_length_ = plan.max_length;
  insertion_speed_ = plan.speed;
  rotation_speed_ = plan.rotation_speed;
  schedule_ = std::move(plan.schedule);
}

void CoSimulation::couple_occlusion() {
  // The wire acts on the blood (occlusion.hpp): set before every flow evaluation from the
  // wire of the last accepted step (staggered: the flow of step n+1 sees the wire of step n).
  if (!(fsolver_ && forces_ && sim_)) return;
  const CouplingSettings k = coupling_settings(scene_);
  if (k.occlusion && fsolver_->supports_occlusion()) {
    occlusion_ = std::make_unique<WireOcclusion>(*fsolver_);
  } else if (k.occlusion && k.occlusion_given) {
    throw_input_error(scene_.where("coupling.occlusion"),
                      fmt::format("annulus needs flow.solver superposition or sparse (or flow.model rlc); the {} "
                                  "solver keeps its matrix",
                                  fsolver_->name()));
  }
}

void CoSimulation::shield_wire() {
  // The wire inside the catheter is out of the blood: no drag there (the catheter's own
  // VesselForces drags on its outer radius), and the catheter occludes in its place.
  if (cath_ && forces_) forces_->set_shielded(lumen_->inside());
}

void CoSimulation::occlude() {
  if (!occlusion_ && !wall_flow_radii_) return;
  std::vector<flow::SegmentOcclusion>& o = segment_factors_;  // (kept: no allocation a frame)
  o.clear();
  if (occlusion_) {
    const auto positions = sim_->positions();
    std::span<const flow::SegmentOcclusion> wire;
    if (cath_ && cath_forces_) {
      // The catheter, and the wire up to the first vertex inside it (the part beyond its tip).
      shield_wire();
      const auto& inside = forces_->shielded();
      int exposed = 0;
      while (exposed < sim_->first_clamped_vertex() &&
             !(static_cast<size_t>(exposed) < inside.size() && inside[static_cast<size_t>(exposed)]))
        ++exposed;
      wire = occlusion_->update({{positions, exposed, forces_->segments(), sim_->discretization().edge_radius},
                                 {cath_->positions(), cath_->first_clamped_vertex(), cath_forces_->segments(),
                                  cath_->discretization().edge_radius}});
    } else {
      wire = occlusion_->update(positions, sim_->first_clamped_vertex(), forces_->segments(),
                                sim_->discretization().edge_radius);
    }
    o.assign(wire.begin(), wire.end());
  }
  if (wall_flow_radii_) {
    // The wall's last state widens each segment from r to r + u: Poiseuille's resistance by
    // (r/(r + u))⁴, the inertance by (r/(r + u))² (staggered, as the occlusion: the flow of a
    // step sees the wall of the last).
    const std::vector<double> widening = wall_->segment_widening();
    if (o.empty()) o.assign(static_cast<size_t>(net_->num_segments()), flow::SegmentOcclusion{});
    for (size_t k = 0; k < o.size(); ++k) {
      const double r = net_->segment(static_cast<int>(k)).radius;
      const double scale = r / std::max(r + widening[k], 0.05 * r);
      o[k].resistance_factor *= std::pow(scale, 4);
      o[k].inertance_factor *= scale * scale;
      max_widening_ = std::max(max_widening_, std::abs(widening[k]) / r);
    }
  }
  fsolver_->set_occlusion(o);
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
  if (fsolver_) {
    const auto tf = Clock::now();
    occlude();  // the vertices are located once the wire has settled or stepped
    fsolver_->advance(0.0);
    t_flow_ += seconds_since(tf);
    press_wall();
  }
  if (sim_ && is_static_) {
    const auto tr = Clock::now();
    const auto rep = solve_static_all();
    t_rod_ += seconds_since(tr);
    if (rep.status == rod::SolveStatus::NonFinite || rep.status == rod::SolveStatus::SingularMatrix)
      throw_numerical_error(fmt::format("static solve failed: {}", rod::to_string(rep.status)));
    if (!rep.converged()) ++failures_;
  }
  if (sim_ && !is_static_ && forces_ && forces_->contact().enabled && contact_settings(scene_).settle) {
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
    press_wall();
  }
}

void CoSimulation::press_wall() {
  if (!wall_ || !wall_blood_pressure_) return;
  const auto tf = Clock::now();  // counted with the flow frame it belongs to
  std::vector<double> p(static_cast<size_t>(net_->num_nodes()));
  fsolver_->node_pressures(p);
  wall_->set_blood_pressure(p, wall_reference_pressure_);
  t_flow_ += seconds_since(tf);
}

void CoSimulation::step() {
  const long step = step_;
  const double t1 = (static_cast<double>(step) + 1.0) * dt_;
  if (fsolver_ && (step % flow_every_ == 0 || !sim_)) {
    const auto tf = Clock::now();
    occlude();
    fsolver_->advance(t1);
    t_flow_ += seconds_since(tf);
    press_wall();
  }
  if (sim_) {
    if (schedule_) {
      // The step at the schedule's mean speeds: its integrals are met at every step's end.
      schedule_->mean_over(t1 - dt_, t1, insertion_speed_, rotation_speed_);
      sim_->set_rotation_speed(rotation_speed_);
      sim_->set_insertion_speed(insertion_speed_);
    }
    if (insertion_speed_ > 0.0 && std::isfinite(max_length_)) {
      // The step that reaches insertion.max_length ends on it (fed only what is left), not a
      // step's feed beyond it.
      const double room = max_length_ - sim_->inserted_length();
      if (room <= 1e-12 * std::max(1.0, std::abs(max_length_)))
        sim_->set_insertion_speed(insertion_speed_ = 0.0);
      else if (insertion_speed_ * dt_ > room)
        sim_->set_insertion_speed(room / dt_);
    }
    if (sim_->inserted_length() >= max_length_ && sim_->push_force() > 0.0) sim_->set_push_force(0.0);  // held there
    const auto tr = Clock::now();
    rod::StepReport rep;
    if (cath_) {
      // Wire and catheter together (catheter.hpp, step_pair).
      shield_wire();
      // One Newton over both rods (implicit Euler, kinematic feeding); the block sweeps otherwise.
      const bool joint = sim_->settings().integrator == rod::Integrator::ImplicitEuler && !(sim_->push_force() > 0.0) &&
                         !(cath_->push_force() > 0.0);
      const PairStepReport pair =
          joint ? step_pair_newton(*sim_, *cath_, *lumen_, dt_) : step_pair(*sim_, *cath_, *lumen_, dt_);
      rep = pair.wire;
      pair_sweeps_ += pair.sweeps;
      if (!pair.converged && pair.wire.converged() && pair.catheter.converged()) ++pair_unconverged_;
      const auto& crep = pair.catheter;
      if (crep.status == rod::SolveStatus::NonFinite || crep.status == rod::SolveStatus::SingularMatrix)
        throw_numerical_error(
            fmt::format("catheter step {} (t = {:.6g} s) failed: {}", step + 1, t1, rod::to_string(crep.status)));
      if (!crep.converged()) ++cath_failures_;
    } else {
      rep = sim_->step(dt_);
    }
    t_rod_ += seconds_since(tr);
    if (rep.status == rod::SolveStatus::NonFinite || rep.status == rod::SolveStatus::SingularMatrix)
      throw_numerical_error(
          fmt::format("rod step {} (t = {:.6g} s) failed: {}", step + 1, t1, rod::to_string(rep.status)));
    if (!rep.converged()) ++failures_;
  }
  ++step_;
}

rod::StepReport CoSimulation::solve_static_all() {
  if (!cath_) return sim_->solve_static();
  const PairStaticReport pair = solve_static_pair(*sim_, *cath_, *lumen_, 100, 1e-3 * sim_->model().h);
  pair_static_ = pair;
  rod::StepReport rep = sim_->last_report();
  if (rep.converged() && (!pair.converged || !cath_->last_report().converged()))
    rep.status = rod::SolveStatus::MaxIterations;
  if (!pair.converged)
    warn(
        fmt::format("the static solve of wire and catheter together did not converge in {} sweeps: the wire's "
                    "residual against the catheter is {:.3g} times its tolerance",
                    pair.sweeps, pair.imbalance));
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

}  // namespace flowire::coupling
