// The scene run's outputs: frames captured while stepping and written at the end, the
// pictures, the ParaView script, and the summary's end-of-run entries.
#include "run_output.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <limits>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/common/steps.hpp"
#include "flowire/coupling/catheter.hpp"
#include "flowire/coupling/drag.hpp"
#include "flowire/coupling/occlusion.hpp"
#include "flowire/coupling/paraview_script.hpp"
#include "flowire/coupling/schedule.hpp"
#include "flowire/coupling/tip_forces.hpp"
#include "flowire/coupling/vessel_forces.hpp"
#include "flowire/coupling/wire_output.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire/vessels/io.hpp"
#include "flowire/vessels/spatial.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {

// The output: keys: what RunRecorder writes and run_scene where and how often.
void declare_output_keys(config::Schema& s) {
  using config::Type;
  using D = units::Dimension;
  s.add("output", Type::Section, "{}", D::None, "what is written and where");
  s.add("output.dir", Type::String, "out", D::None, "output folder (relative to the working directory)");
  s.add("output.every", Type::Number, "0", D::Time, "output interval of simulated time (0: only the final state)")
      .non_negative();
  s.add("output.vtk", Type::Bool, "true", D::None, "write .vtp/.pvd files");
  s.add("output.csv", Type::Bool, "true", D::None, "write .csv files");
  s.add("output.png", Type::Bool, "false", D::None, "render PNG pictures (needs an X server, e.g. xvfb-run)");
}

long output_every_steps(const config::Config& c, double dt) {
  const double every = c.number("output.every");
  if (!(every > 0.0)) return 0;
  return std::max(1L, step_count(every, dt, c.where("output.every"), "output.every / solve.dt"));
}

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// A rod's Newton work over its dynamic steps, totals and per step.
nlohmann::json solver_totals_json(const rod::SolverTotals& t) {
  const double n = t.steps > 0 ? static_cast<double>(t.steps) : 1.0;
  return {{"steps", t.steps},
          {"newton_iterations", t.newton_iterations},
          {"newton_iterations_per_step", static_cast<double>(t.newton_iterations) / n},
          {"factorizations_per_step", static_cast<double>(t.factorizations) / n},
          {"chord_iterations", t.chord_iterations},
          {"line_search_cuts", t.line_search_cuts},
          {"subdivided_steps", t.subdivided_steps}};
}

/// output.png: the network coloured by pressure (or plain, without flow) with the wire over
/// it. network.png looks along the network's thinnest direction (its shape in the plane it
/// spreads in: the arch of an aorta, the fork of a Y), network_side.png across it. With a
/// periodic inlet the pressure is that of the instant of peak inlet pressure (or flow) in the
/// cycle after the run's end (systole: the range of pressures that drives the flow; the
/// quasi-steady model), else of the end. A catheter (@p cath, may be null) is drawn as a wider
/// orange tube around the wire, which shows where it has left the catheter's tip.
void render_pictures(const config::Config& c, const vessels::Network& net, flow::FlowSolver* fs,
                     const rod::RodSimulator* sim, const rod::RodSimulator* cath, const std::filesystem::path& out) {
  std::vector<double> p(static_cast<size_t>(net.num_nodes()), 0.0);
  flow::RenderOptions ro;
  ro.title = c.string_or("name", "flowire");
  if (fs) {
    const double period = fs->spec().cycle();
    double t_show = fs->time();
    // The quasi-steady model goes to any instant and back; the rlc model only forwards.
    const bool quasi_steady = fs->spec().model == flow::Model::Poiseuille;
    if (quasi_steady && period > 0.0 && !fs->spec().inlets.empty()) {
      const auto& inlet = fs->spec().inlets.front().waveform;
      double best = -std::numeric_limits<double>::infinity();
      for (int k = 0; k < 256; ++k) {
        const double t = fs->time() + period * k / 256.0;
        if (inlet(t) > best) best = inlet(t), t_show = t;
      }
      ro.title += fmt::format("  (peak inlet, t = {:.3f} s)", t_show);
    }
    const double t_end = fs->time();
    std::vector<double> q(static_cast<size_t>(net.num_segments()));
    fs->solve_at(t_show, p, q);
    if (t_show != t_end) fs->advance(t_end);
  } else {
    ro.scalar_name = "no flow";
  }
  auto overlay = [](const rod::RodSimulator& rod) {
    flow::RenderOverlay o;
    const auto x = rod.positions();
    for (int i = 0; i <= std::min(rod.first_clamped_vertex(), rod.vertex_count() - 1); ++i)
      o.points.push_back(x[static_cast<size_t>(i)]);
    o.radius = std::max(3.0 * rod.model().edge_radius.front(), 1.2e-3);  // drawn thicker to be seen
    return o;
  };
  if (sim) ro.overlays.push_back(overlay(*sim));
  if (sim && cath) {
    flow::RenderOverlay tube = overlay(*cath);
    tube.radius = std::max(tube.radius, 1.6 * ro.overlays.back().radius);  // around the wire
    tube.color = {0.95, 0.55, 0.1};
    ro.overlays.push_back(std::move(tube));
  }
  // Principal directions of the network's nodes: look along the smallest.
  vessels::Vec3 mean = vessels::Vec3::Zero();
  for (int i = 0; i < net.num_nodes(); ++i) mean += net.node(i);
  mean /= std::max(1, net.num_nodes());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i = 0; i < net.num_nodes(); ++i) cov += (net.node(i) - mean) * (net.node(i) - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);  // ascending eigenvalues
  const vessels::Vec3 thin = eig.eigenvectors().col(0), middle = eig.eigenvectors().col(1),
                      along = eig.eigenvectors().col(2);
  // Up: the longest direction, pointing to +z where it has a z part (a body stands upright).
  ro.view_up = along.z() < 0.0 ? vessels::Vec3(-along) : along;
  ro.view_direction = thin;
  flow::render_network_png(net, p, out / "network.png", ro);
  ro.view_direction = middle;
  flow::render_network_png(net, p, out / "network_side.png", ro);
}

/// What view.py shows: the files of this run's VTK output that were written.
ParaViewScene paraview_scene(const config::Config& c, const std::filesystem::path& out, bool network_series,
                             bool wire) {
  ParaViewScene pv;
  const std::string network = network_series ? "network.pvd" : "network.vtp";
  if (c.has_section("vessels") && std::filesystem::exists(out / network)) pv.network = network;
  if (wire && std::filesystem::exists(out / "wire.pvd")) pv.wire = "wire.pvd", pv.wire_radius = c.number("wire.radius");
  if (c.has_section("wall") && std::filesystem::exists(out / "wall.pvd")) pv.wall = "wall.pvd";
  pv.title = c.string_or("name", "");
  return pv;
}

}  // namespace

RunRecorder::RunRecorder(const config::Config& scene, const CoSimulation& cosim, std::filesystem::path out)
    : c_(scene),
      cosim_(cosim),
      out_(std::move(out)),
      csv_(scene.boolean("output.csv")),
      vtk_(scene.boolean("output.vtk")) {
  if (cosim_.rod() && (csv_ || vtk_)) wire_.emplace(out_, csv_, vtk_);
  if (cosim_.catheter() && (csv_ || vtk_)) catheter_.emplace(out_, csv_, vtk_, "catheter");
}

void RunRecorder::record(double t) {
  const auto t0 = Clock::now();
  if (cosim_.flow() && (csv_ || vtk_)) flow_frames_.push_back(flow::capture_frame(*cosim_.flow()));
  if (wire_) {
    WireFrame f = cosim_.wire_frame();
    f.time = t;
    wire_->add_frame(f);
  }
  if (catheter_) {
    WireFrame f = cosim_.catheter_frame();
    f.time = t;
    catheter_->add_frame(f);
  }
  if (cosim_.wall() && vtk_) wall_frames_.emplace_back(t, cosim_.wall()->state());
  seconds_ += seconds_since(t0);
}

void RunRecorder::after_step() {
  const rod::RodSimulator* sim = cosim_.rod();
  if (!sim || !wire_) return;
  wire_->add_tip(sim->time(), sim->inserted_length(), sim->tip_position());
  wire_->add_base(sim->time(), sim->base_force(), sim->base_torque());
}

void RunRecorder::finish(bool series) {
  const auto t0 = Clock::now();
  const vessels::Network* net = cosim_.network();
  flow::FlowSolver* fsolver = cosim_.flow();
  const rod::RodSimulator* sim = cosim_.rod();
  if (fsolver && (csv_ || vtk_)) {
    if (csv_) {
      flow::write_nodes_csv(*net, flow_frames_, out_ / "nodes.csv");
      flow::write_segments_csv(*fsolver, flow_frames_, out_ / "segments.csv");
    }
    if (vtk_) {
      if (series)
        flow::write_network_series(*fsolver, flow_frames_, out_, "network");
      else
        flow::write_network_vtp(*fsolver, flow_frames_.back(), out_ / "network.vtp");
    }
  }
  if (c_.boolean("output.png") && net) render_pictures(c_, *net, fsolver, sim, cosim_.catheter(), out_);
  if (wire_) wire_->finish();
  if (catheter_) catheter_->finish();
  if (cosim_.wall() && !wall_frames_.empty()) {
    // wall.pvd: the wall's displacement at every output frame (warp by `displacement`).
    std::vector<std::pair<double, std::string>> files;
    for (size_t k = 0; k < wall_frames_.size(); ++k) {
      const std::string name = fmt::format("wall_{:05d}.vtu", k);
      cosim_.wall()->write_vtu(out_ / name, wall_frames_[k].second);
      files.emplace_back(wall_frames_[k].first, name);
    }
    write_pvd(out_ / "wall.pvd", files);
  }
  if (net && !fsolver && csv_) {
    // Without flow: the network's geometry in the same columns, the flow columns empty.
    std::string csv =
        "time,segment,node_from,node_to,length,radius,resistance,flow_rate,mean_velocity,wall_shear_stress,reynolds,"
        "occupied_fraction,resistance_factor\n";
    for (int i = 0; i < net->num_segments(); ++i) {
      const auto& seg = net->segment(i);
      csv += fmt::format("0,{},{},{},{:.17g},{:.17g},,,,,,,\n", i, seg.node_from, seg.node_to, seg.length, seg.radius);
    }
    write_text_atomically(out_ / "segments.csv", csv);
  }
  if (net && !fsolver && vtk_) vessels::write_network_vtp(*net, (out_ / "network.vtp").string());
  if (vtk_) write_paraview_script(out_, paraview_scene(c_, out_, net && fsolver && series, sim != nullptr));
  seconds_ += seconds_since(t0);
}

RunSeconds add_run_summary(const config::Config& c, const CoSimulation& cosim, nlohmann::json& s) {
  const flow::FlowSolver* fsolver = cosim.flow();
  const rod::RodSimulator* sim = cosim.rod();
  const VesselForces* forces = cosim.forces();
  const TipForces* tip_forces = cosim.tip_forces();
  const vessels::SpatialIndex* index = cosim.index();
  const WireOcclusion* occlusion = cosim.occlusion();
  if (fsolver) {
    const auto& ft = fsolver->timings();
    s["flow"]["assemble_seconds"] = ft.assemble;
    s["flow"]["factor_seconds"] = ft.factor;
    s["flow"]["frames"] = ft.frame_count;
    s["flow"]["seconds_per_frame"] = ft.frame_count ? ft.frames / static_cast<double>(ft.frame_count) : 0.0;
    if (occlusion) {
      const auto& os = occlusion->stats();
      s["occlusion"] = {{"model", "annulus"},
                        {"occupied_segments", os.occupied_segments},
                        {"max_resistance_factor", os.max_resistance_factor},
                        {"updates", ft.occlusion_updates},
                        {"seconds", ft.occlusion},
                        {"radius_ratio_clamped", os.radius_ratio_clamped}};
    } else if (sim && forces) {
      s["occlusion"] = {{"model", "none"}};
    }
  }
  RunSeconds split;
  {
    // How often each phase ran: a scene that does not use a phase makes none of its calls.
    nlohmann::json& calls = s["calls"];
    calls["flow_frames"] = fsolver ? fsolver->timings().frame_count : 0;
    calls["occlusion_updates"] = fsolver && occlusion ? fsolver->timings().occlusion_updates : 0;
    const auto& fst = forces ? forces->stats() : InteractionStats{};
    calls["vertex_lookups"] = fst.lookups;
    calls["wall_queries"] = fst.wall_queries;
    calls["drag_evaluations"] = fst.drag_evaluations;
    calls["rod_steps"] = sim ? sim->solver_totals().steps : 0;
    calls["catheter_steps"] = cosim.catheter() ? cosim.catheter()->solver_totals().steps : 0;
  }
  if (cosim.wall()) {
    s["wall"].update(cosim.wall()->summary());
    s["wall"]["flow_radii"] = cosim.wall_widens_flow();
    if (cosim.wall_widens_flow()) s["wall"]["flow_max_relative_widening"] = cosim.max_flow_widening();
  }
  if (sim) {
    s["wire"] = {{"vertices", sim->vertex_count()},
                 {"inserted_length", sim->inserted_length()},
                 {"tip", {sim->tip_position().x(), sim->tip_position().y(), sim->tip_position().z()}},
                 {"base_force", {sim->base_force().x(), sim->base_force().y(), sim->base_force().z()}},
                 {"base_torque", {sim->base_torque().x(), sim->base_torque().y(), sim->base_torque().z()}},
                 {"length_drift", sim->length_drift()},
                 {"unconverged_steps", cosim.unconverged_steps()}};
    if (!cosim.settle().is_null()) s["wire"]["settle"] = cosim.settle();
    s["wire"]["solver"] = solver_totals_json(sim->solver_totals());
    s["wire"]["initial_layout"] = cosim.initial_layout();
    if (c.has("insertion.max_force")) s["wire"]["held_steps"] = sim->held_steps();
    if (c.has("insertion.force"))
      s["wire"]["force_feed"] = nlohmann::json{{"force", c.number("insertion.force")},
                                               {"last_speed", sim->force_feed_speed()},
                                               {"extra_solves", sim->force_feed_iterations()},
                                               {"unbalanced_steps", sim->force_feed_unbalanced()}};
    if (const DriveSchedule* schedule = cosim.schedule()) {
      double length = 0.0, angle = 0.0;
      schedule->integral_to(cosim.time(), length, angle);
      s["wire"]["schedule"] = nlohmann::json{{"file", c.string("insertion.schedule")},
                                             {"rows", schedule->rows().size()},
                                             {"driven_length", length},
                                             {"driven_angle", angle}};
    }
    if (const rod::RodSimulator* cath = cosim.catheter()) {
      nlohmann::json& k = s["catheter"];
      k["vertices"] = cath->vertex_count();
      k["inserted_length"] = cath->inserted_length();
      k["tip"] = {cath->tip_position().x(), cath->tip_position().y(), cath->tip_position().z()};
      k["base_force"] = {cath->base_force().x(), cath->base_force().y(), cath->base_force().z()};
      k["length_drift"] = cath->length_drift();
      k["unconverged_steps"] = cosim.catheter_unconverged_steps();
      k["solver"] = solver_totals_json(cath->solver_totals());
      if (cosim.pair_sweeps() > 0)
        k["pair"] = {{"sweeps_per_step",
                      static_cast<double>(cosim.pair_sweeps()) / static_cast<double>(std::max(1L, cosim.step_count()))},
                     {"unbalanced_steps", cosim.pair_unconverged_steps()}};
      if (const PairStaticReport& p = cosim.pair_static_report(); p.sweeps > 0)
        k["static_pair"] = {{"converged", p.converged}, {"sweeps", p.sweeps}, {"imbalance", p.imbalance}};
      // The shaft's EI: the largest over the vertices (the end vertices carry none, a tapered
      // tip less).
      const auto& ei = cath->model().bend_stiffness;
      k["bending_stiffness"] = ei.empty() ? 0.0 : *std::max_element(ei.begin(), ei.end());
      if (const VesselForces* cf = cosim.catheter_forces())
        k["contact"] = {{"max_penetration", cf->stats().max_penetration}, {"max_outside", cf->stats().max_outside}};
      // The wire's farthest excursion from the catheter's axis inside the lumen.
      const LumenContact& lc = *cosim.lumen_contact();
      double worst = 0.0;
      for (size_t i = 0; i < lc.wire_snapshot.size(); ++i) {
        const int j = lc.nearest_edge(lc.wire_snapshot[i], lc.wire_arc[i], lc.catheter_snapshot, lc.catheter_arc);
        if (j >= 0)
          worst = std::max(worst, lumen_penalty(lc.wire_snapshot[i], lc.catheter_snapshot[j],
                                                lc.catheter_snapshot[j + 1], lc.clearance(), lc.stiffness(), j == 0)
                                      .distance);
      }
      k["max_wire_offset"] = worst;
      k["max_wire_offset_over_clearance"] = lc.clearance() > 0 ? worst / lc.clearance() : 0.0;
    }
    if (sim->model().adapt.enabled)
      s["wire"]["adapt"] = {{"splits", sim->adapt_splits()}, {"merges", sim->adapt_merges()}};
    if (tip_forces)
      s["tip_forces"] = {{"obstacle_steps", tip_forces->obstacle_steps()},
                         {"steering_steps", tip_forces->steering_steps()}};
    if (forces) {
      const auto& st = forces->stats();
      s["lookup"] = {{"window_hits", index->stats().window_hits}, {"fallbacks", index->stats().fallbacks}};
      s["contact"] = {{"max_penetration", st.max_penetration},
                      {"max_outside", st.max_outside},
                      {"max_outside_over_wire_radius", st.max_outside / sim->discretization().edge_radius.front()},
                      {"contact_evaluations", st.contacts},
                      {"introducer_contacts", forces->introducer_contacts()}};
      if (st.outside_time >= 0.0) {
        const double a = sim->discretization().edge_radius.front();
        s["contact"]["outside"] = {
            {"time", st.outside_time},
            {"arc_length", st.outside_arc_length},
            {"position", {st.outside_position.x(), st.outside_position.y(), st.outside_position.z()}},
            {"wire_radii", st.outside_distance / a},
            {"message", fmt::format("the wire left the lumen: at t = {:.4g} s the vertex {:.4g} m from the entry, at "
                                    "({:.4g}, {:.4g}, {:.4g}) m, was {:.3g} wire radii outside the wall",
                                    st.outside_time, st.outside_arc_length, st.outside_position.x(),
                                    st.outside_position.y(), st.outside_position.z(), st.outside_distance / a)}};
      }
      if (forces->drag().law != DragLaw::None) {
        const auto total = forces->total_drag();
        s["drag"] = {{"law", given_or_declared(c, "coupling").string("coupling.drag")},
                     {"total", {total.x(), total.y(), total.z()}},
                     {"max_normal_reynolds", st.max_reynolds}};
        if (forces->drag().law == DragLaw::Cylinder && st.max_reynolds > kCylinderDragMaxReynolds)
          warn(
              fmt::format("drag: the normal Reynolds number reached {:.3g}, beyond the cylinder drag curve's range "
                          "(up to {:.0e})",
                          st.max_reynolds, kCylinderDragMaxReynolds));
      }
      split.contact = st.seconds_lookup + st.seconds_contact;
      split.coupling = st.seconds_drag;
    }
  }
  return split;
}

}  // namespace flowire::coupling
