// A pulsatile series of network-vs-FEM comparisons: quasi-steady frames (one StokesBasis,
// or a Navier–Stokes solve per frame), or frames from a time integration of the FEM side
// with windkessel outlets (BDF2, quasi-steady fields or UnsteadyStokes) run period after
// period until the frames repeat.
#include "flowire/flow/fem/pulsatile.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <utility>

#include "flowire/common/error.hpp"
#include "flowire/flow/fem/compare_output.hpp"
#include "flowire/flow/fem/stokes.hpp"

namespace flowire::flow::fem {
namespace {

/// The frames of a dynamic series (see compare_pulsatile): the fields at times[i] of the
/// last period, once the frames' outlet flows repeat from one period to the next.
std::vector<StokesSolution> integrate_frames(const TetMesh& mesh, const StokesOptions& so, size_t nframes,
                                             const DynamicOptions& dyn, const StokesBasis* basis,
                                             PulsatileResult& out) {
  if (!(dyn.period > 0.0)) throw_usage_error("fem: a dynamic series needs a period > 0");
  if (!dyn.values_at) throw_usage_error("fem: a dynamic series needs the boundary values at any time");
  if (dyn.steps_per_period < 1 || dyn.max_periods < 1)
    throw_usage_error("fem: steps per period and periods must be >= 1");
  const auto n = static_cast<int>(nframes);
  const int m = (dyn.steps_per_period + n - 1) / n, steps = n * m;
  const double dt = dyn.period / steps;
  struct Cap {
    int group;
    flow::OutletBC w;
    double pc, pc_prev;
  };
  std::vector<Cap> caps;
  for (const auto& w : dyn.windkessels) {
    if (w.type != flow::OutletBC::Type::Rcr || !(w.c > 0.0) || !(w.rd > 0.0) || !(w.rp >= 0.0) ||
        !std::isfinite(w.c + w.rd + w.rp + w.distal_pressure))
      throw_usage_error(fmt::format("fem: windkessel at node {} needs C > 0, Rd > 0, Rp >= 0", w.node));
    const int g = mesh.group_of_node(w.node);
    if (g < 0) throw_usage_error(fmt::format("fem: windkessel node {} is not an outlet of the mesh", w.node));
    caps.push_back({g, w, w.distal_pressure, w.distal_pressure});
  }
  std::optional<UnsteadyStokes> unsteady;
  if (dyn.time_dependent) {
    unsteady.emplace(mesh, so, dt);
    out.factorizations += 1;
    out.basis_seconds += unsteady->current().assemble_seconds;
  } else if (basis) {
    // Start the capacitors at the quasi-steady state of t = 0 (R_p + R_d to P_d).
    const StokesSolution s0 = basis->solve(group_conditions(mesh, dyn.values_at(0.0)));
    for (auto& c : caps) c.pc = c.pc_prev = c.w.distal_pressure + c.w.rd * s0.group_flow[static_cast<size_t>(c.group)];
  } else {
    throw_usage_error("fem: a dynamic series is for Stokes");
  }
  std::vector<StokesSolution> result(nframes);
  std::vector<double> flows, last_flows;
  for (int period = 1; period <= dyn.max_periods; ++period) {
    flows.clear();
    for (int s = 1; s <= steps; ++s) {
      const double t = s * dt;  // time within the period (t = period: the next one's 0)
      std::vector<GroupCondition> cond = group_conditions(mesh, dyn.values_at(s == steps ? 0.0 : t));
      std::vector<double> hist(caps.size()), d(caps.size());
      for (size_t k = 0; k < caps.size(); ++k) {
        // BDF2: P_c = [(4P_c^n − P_c^{n−1})/(2Δt) + P_d/(R_d C) + Q/C] / D.
        const Cap& c = caps[k];
        d[k] = 1.5 / dt + 1.0 / (c.w.rd * c.w.c);
        hist[k] = ((4.0 * c.pc - c.pc_prev) / (2.0 * dt) + c.w.distal_pressure / (c.w.rd * c.w.c)) / d[k];
        cond[static_cast<size_t>(c.group)] = GroupCondition::with_resistance(c.w.rp + 1.0 / (c.w.c * d[k]), hist[k]);
      }
      StokesSolution sol = unsteady ? unsteady->step(cond) : basis->solve(cond);
      for (size_t k = 0; k < caps.size(); ++k) {
        Cap& c = caps[k];
        c.pc_prev = c.pc;
        c.pc = hist[k] + sol.group_flow[static_cast<size_t>(c.group)] / (c.w.c * d[k]);
      }
      if (s % m == 0) {
        const size_t frame = s == steps ? 0 : static_cast<size_t>(s / m);
        for (double q : sol.group_flow) flows.push_back(q);
        result[frame] = std::move(sol);
      }
    }
    out.periods = period;
    out.steps_per_period = steps;
    if (!last_flows.empty()) {
      double change = 0.0, scale = 0.0;
      for (size_t i = 0; i < flows.size(); ++i) {
        change = std::max(change, std::abs(flows[i] - last_flows[i]));
        scale = std::max(scale, std::abs(flows[i]));
      }
      out.periodic_change = scale > 0.0 ? change / scale : 0.0;
      if (out.periodic_change <= dyn.periodic_tolerance) return result;
    }
    last_flows = flows;
  }
  throw_numerical_error(
      fmt::format("fem: the dynamic series is not periodic after {} periods (change {:.3g} over "
                  "the last one, tolerance {:.3g})",
                  dyn.max_periods, out.periodic_change, dyn.periodic_tolerance));
}

void accumulate(PulsatileResult& p, const CompareResult& r) {
  p.max_rel_diff_drop_away = std::max(p.max_rel_diff_drop_away, r.max_rel_diff_drop_away);
  p.max_rel_diff_drop_junction = std::max(p.max_rel_diff_drop_junction, r.max_rel_diff_drop_junction);
  p.max_flow_split_error = std::max(p.max_flow_split_error, r.max_flow_split_error);
  p.max_flow_error = std::max(p.max_flow_error, r.max_flow_error);
}

}  // namespace

PulsatileResult compare_pulsatile(const Network& net, std::span<const double> times,
                                  std::span<const BoundaryValues> frames, const BoundaryValues& steady,
                                  double steady_time, const FemOptions& opt, const std::string& out_dir,
                                  const DynamicOptions* dyn) {
  if (times.size() != frames.size())
    throw_usage_error(fmt::format("fem: {} frame times for {} frames", times.size(), frames.size()));
  if (frames.empty()) throw_usage_error("fem: a pulsatile comparison needs at least one frame");
  const int inlet = inlet_of(net, steady);
  for (const auto& f : frames)
    if (inlet_of(net, f) != inlet) throw_usage_error("fem: every frame must have the same inlet node");
  const auto t_start = std::chrono::steady_clock::now();
  initialize();
  const ComparisonDomain domain = comparison_domain(net, opt, steady);
  const TetMesh& mesh = domain.mesh;
  const Network& dnet = domain.network;  // the network on the mesh's domain, numbered as its groups
  const std::vector<flow::SegmentLaw> laws = domain.laws(net, opt.segment_laws);
  auto on_domain = [&](const BoundaryValues& bv) { return domain.cut() ? renumbered(bv, net, domain.node) : bv; };
  // A dynamic series on a cut network: its boundary values and windkessels on the cut network's
  // nodes; a network series computed elsewhere is on the input network and cannot be compared.
  std::optional<DynamicOptions> dyn_domain;
  if (dyn && domain.cut()) {
    if (dyn->network_at)
      throw_input_error(opt.surface,
                        "fem: a dynamic network series (flow.model: rlc) is compared on the network's "
                        "own lumen only; on a real lumen use the quasi-steady frames");
    dyn_domain = *dyn;
    dyn_domain->values_at = [&, values_at = dyn->values_at](double t) { return on_domain(values_at(t)); };
    for (auto& w : dyn_domain->windkessels) w.node = domain.node[static_cast<size_t>(w.node)];
    dyn = &*dyn_domain;
  }
  const StokesOptions so = comparison_stokes_options(opt, steady);
  PulsatileResult out;
  std::optional<StokesBasis> basis;
  if (opt.equations == Equations::Stokes) {
    basis.emplace(mesh, so);
    out.factorizations = 1;
    out.basis_seconds = basis->assemble_seconds() + basis->solve_seconds();
  }
  StokesSolution previous;  // Navier–Stokes: each frame's Newton starts from the last frame
  auto solve = [&](const BoundaryValues& bv, StokesSolution& sol) {
    const auto cond = group_conditions(mesh, bv);
    if (basis) {
      sol = basis->solve(cond);
    } else {
      StokesOptions fso = comparison_stokes_options(opt, bv);
      if (!previous.velocity.empty()) fso.initial_guess = &previous;
      sol = solve_stokes(mesh, std::span<const GroupCondition>(cond), fso);
      previous = sol;
      out.factorizations += sol.factorizations;
      out.basis_seconds += sol.assemble_seconds + sol.solve_seconds;
    }
    NetworkFlow nf = network_flow(dnet, bv, laws, opt.junction_losses);
    if (opt.total_pressure) {
      nf.kinetic_density = bv.density;
      nf.end_alpha = domain.nodal(opt.end_alpha, 1.0);
    }
    return compare_fields(dnet, mesh, sol, nf, domain.bv.inlet_node, opt.samples_per_branch);
  };
  const auto t_frames = std::chrono::steady_clock::now();
  StokesSolution steady_sol;
  out.steady = solve(domain.bv, steady_sol);
  out.steady.cut_length = domain.cut_length;
  out.steady.time = steady_time;
  const bool vtu = opt.write_vtu && !out_dir.empty();
  std::vector<StokesSolution> sols(vtu ? frames.size() : 0);
  StokesSolution scratch;
  std::vector<StokesSolution> dynamic;
  if (dyn) {
    if (opt.equations != Equations::Stokes) throw_usage_error("fem: a dynamic series is for Stokes");
    dynamic = integrate_frames(mesh, so, frames.size(), *dyn, basis ? &*basis : nullptr, out);
  }
  for (size_t i = 0; i < frames.size(); ++i) {
    CompareResult r;
    if (dyn) {
      NetworkFlow nf = dyn->network_at ? dyn->network_at(times[i])
                                       : network_flow(dnet, on_domain(frames[i]), laws, opt.junction_losses);
      if (opt.total_pressure && !dyn->network_at) {
        nf.kinetic_density = frames[i].density;
        nf.end_alpha = domain.nodal(opt.end_alpha, 1.0);
      }
      r = compare_fields(dnet, mesh, dynamic[i], nf, domain.bv.inlet_node, opt.samples_per_branch);
      if (vtu) sols[i] = std::move(dynamic[i]);
    } else {
      r = solve(on_domain(frames[i]), vtu ? sols[i] : scratch);
    }
    r.time = times[i];
    accumulate(out, r);
    out.frames.push_back(std::move(r));
  }
  out.frames_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_frames).count();
  out.steady.mesh_seconds = mesh.mesh_seconds;
  out.steady.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  if (basis) {
    out.steady.assemble_seconds = basis->assemble_seconds();
    out.steady.solve_seconds = basis->solve_seconds();
  }
  if (out_dir.empty()) return out;
  write_outputs(out_dir, dnet, mesh, steady_sol, out.steady, opt);  // rank 0 only
  write_pulsatile_outputs(out_dir, dnet, mesh, out.frames, sols);   // rank 0 only
  return out;
}

}  // namespace flowire::flow::fem
