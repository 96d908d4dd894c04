// The network fitted to the 3D solution (calibrate.hpp).
#include "flowire/flow/fem/calibrate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <sstream>

#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/flow/fem/sample.hpp"
#include "flowire/flow/solver.hpp"

namespace flowire::flow::fem {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

BoundaryValues scaled(const BoundaryValues& bv, double f) {
  BoundaryValues b = bv;
  if (b.inlet_type == BoundaryValues::Inlet::Flow)
    b.inlet_flow *= f;
  else
    b.inlet_pressure *= f;
  return b;
}

/// Each branch oriented away from the inlet (upstream and downstream end node), the branches in
/// an order where every branch comes before those downstream of it.
struct Tree {
  std::vector<int> up, down, order;
};

Tree branch_tree(const Network& net, int inlet) {
  const auto nb = static_cast<size_t>(net.num_branches());
  std::vector<std::vector<int>> at(static_cast<size_t>(net.num_nodes()));
  for (int b = 0; b < net.num_branches(); ++b) {
    at[static_cast<size_t>(net.branch(b).nodes.front())].push_back(b);
    at[static_cast<size_t>(net.branch(b).nodes.back())].push_back(b);
  }
  Tree t;
  t.up.assign(nb, -1);
  t.down.assign(nb, -1);
  std::vector<char> seen_node(static_cast<size_t>(net.num_nodes()), 0);
  std::vector<int> stack{inlet};
  seen_node[static_cast<size_t>(inlet)] = 1;
  while (!stack.empty()) {
    const int u = stack.back();
    stack.pop_back();
    for (int b : at[static_cast<size_t>(u)]) {
      if (t.up[static_cast<size_t>(b)] >= 0) continue;  // the branch we came along
      const auto& br = net.branch(b);
      const int v = br.nodes.front() == u ? br.nodes.back() : br.nodes.front();
      if (seen_node[static_cast<size_t>(v)])
        throw_input_error(net.source(), fmt::format("the calibration needs a tree: the branch '{}' closes a loop",
                                                    br.name.empty() ? fmt::format("branch_{}", b) : br.name));
      t.up[static_cast<size_t>(b)] = u;
      t.down[static_cast<size_t>(b)] = v;
      t.order.push_back(b);
      seen_node[static_cast<size_t>(v)] = 1;
      stack.push_back(v);
    }
  }
  if (t.order.size() != nb) throw_input_error(net.source(), "the calibration needs one connected network");
  return t;
}

/// ½ρ/A² of an end of radius r: the dynamic pressure of a flat profile per Q², which the last
/// segment of a network in total pressure carries so that its outlet node keeps the static value.
double outlet_dynamic_pressure(double rho, double r) {
  const double area = std::numbers::pi * r * r;
  return 0.5 * rho / (area * area);
}

/// The radius of the network at an end node (of its one segment).
double end_radius(const Network& net, int e) { return net.segment(*net.node_segments(e).first).radius_at(e); }

/// The 3D solution reduced to the network: a flow per branch (the outlets' 3D flows summed
/// downstream) and a pressure per node (NaN where the section falls outside the mesh): static, or,
/// with `rho` > 0, total: each section's mean pressure plus the dynamic pressure of its branch's
/// flow through the network's section there (at a junction, the section of the branch that flows
/// into it; at the ends the group pressure plus the dynamic pressure through the end).
struct Reduced {
  std::vector<double> branch_flow;    // (branches) downstream
  std::vector<double> node_pressure;  // (nodes)
  std::vector<double> alpha;          // (nodes) at an outlet in total pressure: the energy's α, else 1
};

Reduced reduce(const Network& net, const Tree& t, const TetMesh& mesh, const StokesSolution& sol,
               const CompareResult& r, int inlet, double rho) {
  Reduced red;
  const auto nn = static_cast<size_t>(net.num_nodes());
  red.node_pressure.assign(nn, kNaN);
  std::vector<double> out_flow(nn, 0.0), sum(nn, 0.0);
  std::vector<int> count(nn, 0);
  for (const auto& o : r.outlets) out_flow[static_cast<size_t>(o.node)] = o.flow_fem;
  red.branch_flow.assign(static_cast<size_t>(net.num_branches()), 0.0);
  for (auto it = t.order.rbegin(); it != t.order.rend(); ++it) {
    const auto b = static_cast<size_t>(*it);
    red.branch_flow[b] = out_flow[static_cast<size_t>(t.down[b])];
    out_flow[static_cast<size_t>(t.up[b])] += red.branch_flow[b];
  }
  // Every node but the ends: the section normal to the branch there.
  const FieldSampler fs(mesh, sol);
  for (int b = 0; b < net.num_branches(); ++b) {
    const auto& br = net.branch(b);
    const size_t n = br.nodes.size();
    for (size_t k = 0; k < n; ++k) {
      const int node = br.nodes[k];
      if (net.degree(node) < 2) continue;
      // A junction takes the pressure of the branch that flows into it: each branch leaving it
      // then carries the junction's loss into it in its first piece.
      if (net.degree(node) > 2 && t.down[static_cast<size_t>(b)] != node) continue;
      const Vec3 axis = net.node(br.nodes[std::min(k + 1, n - 1)]) - net.node(br.nodes[k > 0 ? k - 1 : 0]);
      const double radius = k == 0 ? net.segment(br.segments.front()).radius_from
                            : k == n - 1
                                ? net.segment(br.segments.back()).radius_to
                                : 0.5 * (net.segment(br.segments[k - 1]).radius + net.segment(br.segments[k]).radius);
      double value = 0.0;
      if (rho > 0.0) {
        const auto total = section_total_pressure(fs, net.node(node), axis, radius, rho);
        if (!total) continue;
        value = *total;
      } else {
        const auto [mean, centre, found] = section_pressure(fs, net.node(node), axis, radius);
        (void)centre;
        if (!found) continue;
        value = mean;
      }
      sum[static_cast<size_t>(node)] += value;
      ++count[static_cast<size_t>(node)];
    }
  }
  for (size_t n = 0; n < nn; ++n)
    if (count[n] > 0) red.node_pressure[n] = sum[n] / count[n];
  // The inlet: its group pressure, and in total pressure the energy its section carries (the
  // section through the inlet node, where the imposed profile enters); the outlets: their static
  // values, plus in total pressure ½ρ(Q/A)², which the outlet's segment carries in its law.
  red.node_pressure[static_cast<size_t>(inlet)] = r.inlet_pressure_fem;
  if (rho > 0.0) {
    const auto& seg = net.segment(*net.node_segments(inlet).first);
    const int next = seg.node_from == inlet ? seg.node_to : seg.node_from;
    const auto total =
        section_total_pressure(fs, net.node(inlet), net.node(next) - net.node(inlet), end_radius(net, inlet), rho);
    if (total) red.node_pressure[static_cast<size_t>(inlet)] = *total;
  }
  // An outlet: its static value, and in total pressure the energy leaving through its section,
  // p + α½ρ(Q/A)² (α of the 3D profile there, between 1 and 3), which its last segment carries.
  red.alpha.assign(nn, 1.0);
  for (const auto& o : r.outlets) {
    const auto e = static_cast<size_t>(o.node);
    red.node_pressure[e] = o.pressure_fem;
    if (!(rho > 0.0)) continue;
    const double kinetic = outlet_dynamic_pressure(rho, end_radius(net, o.node)) * o.flow_fem * o.flow_fem;
    const auto& seg = net.segment(*net.node_segments(o.node).first);
    const int prev = seg.node_from == o.node ? seg.node_to : seg.node_from;
    // The section through the outlet node, on the cap plane (the points of the disk inside the mesh).
    const auto total =
        section_total_pressure(fs, net.node(o.node), net.node(o.node) - net.node(prev), end_radius(net, o.node), rho);
    if (total && kinetic > 0.0) red.alpha[e] = std::clamp((*total - o.pressure_fem) / kinetic, 1.0, 3.0);
    red.node_pressure[e] += red.alpha[e] * kinetic;
  }
  for (int b : t.order)
    for (int n : {t.up[static_cast<size_t>(b)], t.down[static_cast<size_t>(b)]})
      if (!std::isfinite(red.node_pressure[static_cast<size_t>(n)]))
        throw_numerical_error(fmt::format(
            "calibrate: no 3D pressure at node {} (a junction whose sections all fall outside the mesh)", n));
  return red;
}

/// Least squares of Δp = a Q + K|Q|Q with a ≥ a_min, K ≥ 0, relative to each drop (weights 1/Δp²,
/// so that every fitted flow is matched to the same fraction, not the largest best).
void fit(flow::BranchFit& f, double a_min) {
  const size_t n = f.flows.size();
  double pmax = 0.0;
  for (double p : f.drops) pmax = std::max(pmax, std::abs(p));
  std::vector<double> w(n);
  for (size_t i = 0; i < n; ++i) {
    const double p = std::max(std::abs(f.drops[i]), 1e-3 * pmax);
    w[i] = p > 0.0 ? 1.0 / (p * p) : 1.0;
  }
  auto sse = [&](double a, double k) {
    double e = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const double q = f.flows[i], r = a * q + k * std::abs(q) * q - f.drops[i];
      e += w[i] * r * r;
    }
    return e;
  };
  double sqq = 0, sqg = 0, sgg = 0, sqp = 0, sgp = 0, sp = 0;
  for (size_t i = 0; i < n; ++i) {
    const double q = f.flows[i], g = std::abs(q) * q, p = f.drops[i];
    sqq += w[i] * q * q, sqg += w[i] * q * g, sgg += w[i] * g * g, sqp += w[i] * q * p, sgp += w[i] * g * p;
    sp += w[i] * p * p;
  }
  double a = kNaN, k = 0.0;
  const double det = sqq * sgg - sqg * sqg;
  if (n >= 2 && det > 1e-12 * sqq * sgg) {
    a = (sgg * sqp - sqg * sgp) / det;
    k = (sqq * sgp - sqg * sqp) / det;
  }
  const bool interior = a >= a_min && k >= 0.0;
  const double sse_free = std::isfinite(a) ? sse(a, k) : sp;
  if (!interior) {
    // On the bounds: K = 0 with a free, or a at its floor with K free; the better of the two.
    const double a0 = sqq > 0.0 ? std::max(a_min, sqp / sqq) : a_min;
    const double k1 = n >= 2 && sgg > 0.0 ? std::max(0.0, (sgp - a_min * sqg) / sgg) : 0.0;
    if (sse(a0, 0.0) <= sse(a_min, k1)) {
      a = a0, k = 0.0;
    } else {
      a = a_min, k = k1;
    }
  }
  // A bound counts as active where it costs the fit more than round-off: a linear law fitted to
  // linear data (Stokes) leaves K a little either side of 0.
  f.bounded = !interior && sse(a, k) - sse_free > 1e-8 * sp;
  f.linear = a;
  f.quadratic = k;
  f.residual = sp > 0.0 ? std::sqrt(sse(a, k) / sp) : 0.0;
}

}  // namespace

CalibrationResult calibrate(const Network& net, const BoundaryValues& bv, const FemOptions& opt,
                            const CalibrateOptions& co) {
  if (co.factors.empty()) throw_input_error("calibrate", "needs at least one inlet factor");
  for (double f : co.factors)
    if (!(f > 0.0) || !std::isfinite(f)) throw_input_error("calibrate", fmt::format("inlet factor {} must be > 0", f));
  if (!(co.check_factor >= 0.0) || !std::isfinite(co.check_factor))
    throw_input_error("calibrate", fmt::format("check factor {} must be >= 0", co.check_factor));
  const double inlet_value = bv.inlet_type == BoundaryValues::Inlet::Flow ? bv.inlet_flow : bv.inlet_pressure;
  if (!(std::abs(inlet_value) > 0.0))
    throw_input_error("calibrate", "the inlet value is 0: there is no flow to calibrate at");
  initialize();
  CalibrationResult res;
  const ComparisonDomain d = comparison_domain(net, opt, bv);
  res.mesh_seconds = d.mesh.mesh_seconds;
  const Network& dn = d.network;
  const int inlet = d.bv.inlet_node;
  const Tree tree = branch_tree(dn, inlet);
  // The solutions in increasing order (Navier–Stokes: each from the last), the check last.
  std::vector<double> factors = co.factors;
  std::sort(factors.begin(), factors.end());
  factors.erase(std::unique(factors.begin(), factors.end()), factors.end());
  const size_t fitted = factors.size();
  if (co.check_factor > 0.0) factors.push_back(co.check_factor);
  std::vector<StokesSolution> sols(factors.size());
  std::vector<BoundaryValues> values(factors.size());
  const StokesSolution* previous = nullptr;
  for (size_t i = 0; i < factors.size(); ++i) {
    values[i] = scaled(d.bv, factors[i]);
    StokesOptions so = comparison_stokes_options(opt, values[i]);
    if (previous) so.initial_guess = previous;
    const auto cond = group_conditions(d.mesh, values[i]);
    sols[i] = solve_stokes(d.mesh, std::span<const GroupCondition>(cond), so);
    previous = &sols[i];
    CalibrationRun run;
    run.factor = factors[i];
    run.fitted = i < fitted;
    run.before = compare_fields(dn, d.mesh, sols[i], network_flow(dn, values[i]), inlet, opt.samples_per_branch);
    run.inlet_flow = run.before.inlet_flow_fem;
    res.runs.push_back(std::move(run));
  }
  // The fit, branch by branch, on the domain's network.
  flow::Calibration& cal = res.calibration;
  flow::identify(cal, net);
  cal.equations = opt.equations == Equations::NavierStokes ? "navier_stokes" : "stokes";
  // Total pressure for Navier–Stokes where the inlet is a flow (the network's nodes then hold
  // p + ½ρū²; a pressure inlet's value is static, and its dynamic pressure would need a law of
  // negative resistance; Stokes flow has no dynamic pressure).
  const double rho =
      co.total_pressure && bv.inlet_type == BoundaryValues::Inlet::Flow && opt.equations == Equations::NavierStokes
          ? bv.density
          : 0.0;
  cal.pressure = rho > 0.0 ? "total" : "static";
  std::vector<Reduced> reduced;
  for (size_t i = 0; i < fitted; ++i) {
    reduced.push_back(reduce(dn, tree, d.mesh, sols[i], res.runs[i].before, inlet, rho));
    cal.inlet_flows.push_back(res.runs[i].inlet_flow);
  }
  if (co.check_factor > 0.0) cal.check_inlet_flow = res.runs.back().inlet_flow;
  // Branch by branch from the inlet (tree order), each branch piece by piece downstream: a piece
  // runs from a node to the next node with a 3D pressure, merged with the following piece while a
  // bound of its fit is active (a drop that falls, or noise over a short piece). Each fit starts
  // from the pressure the fitted network will have there (the 3D one at the inlet, then the
  // upstream node's less the fitted law's drop), so that what one fit misses the next takes up and
  // the drops along every path from the inlet to an outlet stay the 3D solution's: a branch whose
  // 3D drop is negative (its end section's pressure above its start's, as at the arch's branch
  // ostia) gets the floor, and the branches after it the rest.
  const auto nseg = static_cast<size_t>(dn.num_segments());
  std::vector<double> factor(nseg, 1.0), kappa(nseg, 0.0);  // a/R_P and K/R_P of each domain segment
  std::vector<std::vector<double>> start(reduced.size());   // (solutions × nodes) the fitted network's pressures
  for (size_t i = 0; i < reduced.size(); ++i) start[i] = reduced[i].node_pressure;
  cal.fits.resize(static_cast<size_t>(dn.num_branches()));
  for (int b : tree.order) {
    const auto& br = dn.branch(b);
    std::vector<int> nodes = br.nodes, segs = br.segments;
    if (nodes.front() != tree.up[static_cast<size_t>(b)]) {
      std::reverse(nodes.begin(), nodes.end());
      std::reverse(segs.begin(), segs.end());
    }
    auto piece = [&](size_t k0, size_t k1) {  // nodes[k0] .. nodes[k1]
      flow::BranchFit f;
      f.branch = b;
      f.name = branch_label(dn, b);
      for (size_t k = k0; k < k1; ++k)
        f.poiseuille_resistance += flow::segment_resistance(bv.viscosity, dn.segment(segs[k]));
      for (size_t i = 0; i < reduced.size(); ++i) {
        f.flows.push_back(reduced[i].branch_flow[static_cast<size_t>(b)]);
        f.drops.push_back(start[i][static_cast<size_t>(nodes[k0])] -
                          reduced[i].node_pressure[static_cast<size_t>(nodes[k1])]);
      }
      fit(f, 0.1 * f.poiseuille_resistance);
      return f;
    };
    // The branch as a whole, from the fitted network's pressure at its start (reported; the law of
    // its segments beyond a cap).
    flow::BranchFit whole = piece(0, nodes.size() - 1);
    std::vector<size_t> cuts;  // the nodes with a 3D pressure, after the first
    for (size_t k = 1; k < nodes.size(); ++k)
      if (k + 1 == nodes.size() || std::all_of(reduced.begin(), reduced.end(), [&](const Reduced& red) {
            return std::isfinite(red.node_pressure[static_cast<size_t>(nodes[k])]);
          }))
        cuts.push_back(k);
    size_t k0 = 0;
    int pieces = 0;
    for (size_t j = 0; j < cuts.size(); ++j) {
      flow::BranchFit f = piece(k0, cuts[j]);
      if (f.bounded && j + 1 < cuts.size()) continue;  // merged with the next piece
      for (size_t k = k0; k < cuts[j]; ++k) {
        factor[static_cast<size_t>(segs[k])] = f.linear / f.poiseuille_resistance;
        kappa[static_cast<size_t>(segs[k])] = f.quadratic / f.poiseuille_resistance;
      }
      for (size_t i = 0; i < reduced.size(); ++i) {
        const double q = f.flows[i];
        start[i][static_cast<size_t>(nodes[cuts[j]])] =
            start[i][static_cast<size_t>(nodes[k0])] - (f.linear * q + f.quadratic * std::abs(q) * q);
      }
      k0 = cuts[j];
      ++pieces;
    }
    whole.pieces = pieces;
    cal.fits[static_cast<size_t>(b)] = std::move(whole);
  }
  // The laws: K_s = (K/R_P) R_P,s, on the domain's network and on the input network (a segment
  // cut away beyond a cap: its branch's as a whole).
  // In total pressure, a segment that ends at an outlet also carries α½ρ/A² of the outlet (α the
  // mean over the fitted solutions; an end of the input network takes its domain end's).
  std::vector<double> alpha(static_cast<size_t>(dn.num_nodes()), 1.0);
  for (int e = 0; e < dn.num_nodes(); ++e) {
    double sum = 0.0;
    for (const auto& red : reduced) sum += red.alpha[static_cast<size_t>(e)];
    if (!reduced.empty()) alpha[static_cast<size_t>(e)] = sum / static_cast<double>(reduced.size());
  }
  auto alpha_of = [&](const Network& n, int e) {
    if (&n == &dn) return alpha[static_cast<size_t>(e)];
    const int de = d.node[static_cast<size_t>(e)];
    return de >= 0 ? alpha[static_cast<size_t>(de)] : 1.0;
  };
  if (rho > 0.0) {
    cal.end_alpha.assign(static_cast<size_t>(net.num_nodes()), 1.0);
    for (int e : net.ends())
      if (d.node[static_cast<size_t>(e)] >= 0) cal.end_alpha[static_cast<size_t>(e)] = alpha_of(net, e);
  }
  auto with_outlet = [&](const Network& n, int n_inlet, int s, flow::SegmentLaw law) {
    for (int e : {n.segment(s).node_from, n.segment(s).node_to})
      if (n.degree(e) == 1 && e != n_inlet)
        law.quadratic += alpha_of(n, e) * outlet_dynamic_pressure(rho, end_radius(n, e));
    return law;
  };
  const int net_inlet = inlet_of(net, bv);
  std::vector<flow::SegmentLaw> on_domain(nseg);
  for (size_t c = 0; c < nseg; ++c)
    on_domain[c] =
        with_outlet(dn, inlet, static_cast<int>(c),
                    {factor[c], kappa[c] * flow::segment_resistance(bv.viscosity, dn.segment(static_cast<int>(c)))});
  cal.laws.resize(static_cast<size_t>(net.num_segments()));
  for (int b = 0; b < net.num_branches(); ++b) {
    const auto& whole = cal.fits[static_cast<size_t>(b)];
    for (int s : net.branch(b).segments) {
      const int c = d.segment[static_cast<size_t>(s)];
      const double rp = flow::segment_resistance(bv.viscosity, net.segment(s));
      cal.laws[static_cast<size_t>(s)] =
          with_outlet(net, net_inlet, s,
                      c >= 0 ? flow::SegmentLaw{factor[static_cast<size_t>(c)], kappa[static_cast<size_t>(c)] * rp}
                             : flow::SegmentLaw{whole.linear / whole.poiseuille_resistance,
                                                whole.quadratic / whole.poiseuille_resistance * rp});
    }
  }
  for (size_t i = 0; i < factors.size(); ++i) {
    NetworkFlow nf = network_flow(dn, values[i], on_domain);
    nf.kinetic_density = rho;
    if (rho > 0.0) nf.end_alpha = alpha;
    res.runs[i].after = compare_fields(dn, d.mesh, sols[i], nf, inlet, opt.samples_per_branch);
  }
  for (const auto& s : sols) res.solve_seconds += s.assemble_seconds + s.solve_seconds;
  return res;
}

void write_calibration_report(const std::string& dir, const Network& net, const CalibrationResult& r) {
  const auto& cal = r.calibration;
  std::ostringstream md;
  md << fmt::format("# Calibration of {} to the 3D solution ({})\n\n", cal.network_source, cal.equations);
  md << "Largest differences over the sample points, as fractions of the network's driving pressure drop, and of "
        "the outlet flows; before: Poiseuille segments, after: the calibrated laws.\n\n";
  md << "| inlet flow (mL/s) | fitted | Re | drop, away from junctions: before / after | near junctions: before / "
        "after | outlet flow: before / after | flow split: before / after |\n";
  md << "|---|---|---|---|---|---|---|\n";
  for (const auto& run : r.runs)
    md << fmt::format(
        "| {:.4g} | {} | {:.0f} | {:.2f}% / {:.2f}% | {:.2f}% / {:.2f}% | {:.2f}% / {:.2f}% | {:.2f}% / {:.2f}% |\n",
        run.inlet_flow * 1e6, run.fitted ? "yes" : "check", run.before.reynolds,
        100 * run.before.max_rel_diff_drop_away, 100 * run.after.max_rel_diff_drop_away,
        100 * run.before.max_rel_diff_drop_junction, 100 * run.after.max_rel_diff_drop_junction,
        100 * run.before.max_flow_error, 100 * run.after.max_flow_error, 100 * run.before.max_flow_split_error,
        100 * run.after.max_flow_split_error);
  md << "\nPer branch: Δp = a Q + K|Q|Q fitted to the 3D drops between the branch's end nodes (R_P: its Poiseuille "
        "resistance in the 3D domain); the segments take the laws of the pieces between the nodes with a 3D section "
        "pressure, merged where a bound was active.\n\n";
  md << "| branch | a / R_P | K (Pa·s²/m⁶) | K Q / a at the largest flow | residual | bound active | pieces fitted "
        "|\n|---|---|---|---|---|---|---|\n";
  for (const auto& f : cal.fits) {
    const double qmax = f.flows.empty() ? 0.0 : *std::max_element(f.flows.begin(), f.flows.end());
    md << fmt::format("| {} | {:.3f} | {:.4g} | {:.3f} | {:.2e} | {} | {} |\n", f.name,
                      f.linear / f.poiseuille_resistance, f.quadratic,
                      f.linear > 0.0 ? f.quadratic * qmax / f.linear : 0.0, f.residual, f.bounded ? "yes" : "no",
                      f.pieces);
  }
  md << fmt::format("\nMesh {:.1f} s, 3D solves {:.1f} s ({} solutions).\n", r.mesh_seconds, r.solve_seconds,
                    r.runs.size());
  write_text_atomically(std::filesystem::path(dir) / "calibration.md", md.str());
  std::ostringstream csv;
  csv << "inlet_flow,fitted,branch,s,pressure_fem,pressure_before,pressure_fem_after,pressure_after,near_junction\n";
  for (const auto& run : r.runs)
    for (size_t i = 0; i < run.before.samples.size() && i < run.after.samples.size(); ++i) {
      const auto& b = run.before.samples[i];
      const auto& a = run.after.samples[i];
      csv << fmt::format("{:.9g},{},{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{}\n", run.inlet_flow, run.fitted ? 1 : 0,
                         branch_label(net, b.branch), b.s, b.pressure_fem, b.pressure_network, a.pressure_fem,
                         a.pressure_network, b.near_junction ? 1 : 0);
    }
  write_text_atomically(std::filesystem::path(dir) / "calibration.csv", csv.str());
}

}  // namespace flowire::flow::fem
