// The steady comparison: the network's pressures and flows against the FEM solution's,
// sampled along the centerlines (cross-section means and fluxes), per outlet and per branch;
// and the whole comparison at one instant (mesh, FEM solve, network solve, compare, files).
#include "flowire/flow/fem/compare.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <queue>
#include <span>
#include <tuple>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/fem/cap_cut.hpp"
#include "flowire/flow/fem/compare_output.hpp"
#include "flowire/flow/fem/lumen.hpp"
#include "flowire/flow/fem/network_mesh.hpp"
#include "flowire/flow/fem/obstacle.hpp"
#include "flowire/flow/fem/sample.hpp"
#include "flowire/flow/solver.hpp"

namespace flowire::flow::fem {
namespace {

/// Distance along the network from `source` to every node (Dijkstra).
std::vector<double> path_distances(const Network& net, int source) {
  std::vector<double> d(static_cast<size_t>(net.num_nodes()), std::numeric_limits<double>::infinity());
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> pq;
  d[static_cast<size_t>(source)] = 0.0;
  pq.push({0.0, source});
  while (!pq.empty()) {
    const auto [du, u] = pq.top();
    pq.pop();
    if (du > d[static_cast<size_t>(u)]) continue;
    const auto [b, e] = net.node_segments(u);
    for (const int* s = b; s != e; ++s) {
      const auto& seg = net.segment(*s);
      const int v = seg.node_from == u ? seg.node_to : seg.node_from;
      if (du + seg.length < d[static_cast<size_t>(v)]) {
        d[static_cast<size_t>(v)] = du + seg.length;
        pq.push({d[static_cast<size_t>(v)], v});
      }
    }
  }
  return d;
}

/// FEM flux along `axis` through the lumen's cross-section at `c`: polar midpoint rule on
/// the plane normal to the axis, each ray from the centre stopping where it first leaves
/// the mesh (so a neighbouring vessel cut by the plane does not count), at most 2 r.
double section_flow(const FieldSampler& fs, const Vec3& c, const Vec3& axis, double r, double& area) {
  const Vec3 t = axis.normalized();
  const Vec3 a = (std::abs(t.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(t).normalized();
  const Vec3 b = t.cross(a);
  constexpr int kRings = 40, kAngles = 48;
  const double rmax = 2.0 * r, dr = rmax / kRings, dphi = 2.0 * std::numbers::pi / kAngles;
  double q = 0.0;
  area = 0.0;
  if (!fs.at(c, 1e-6)) {
    area = std::numeric_limits<double>::quiet_NaN();
    return area;
  }
  for (int k = 0; k < kAngles; ++k) {
    const double phi = (k + 0.5) * dphi;
    const Vec3 dir = std::cos(phi) * a + std::sin(phi) * b;
    for (int i = 0; i < kRings; ++i) {
      const double rho = (i + 0.5) * dr;
      const auto v = fs.at(c + rho * dir, 1e-6);
      if (!v) break;
      q += v->velocity.dot(t) * rho * dr * dphi;
      area += rho * dr * dphi;
    }
  }
  return q;
}

/// The mesh options of a comparison: its sizes, and the inlet end of its boundary values.
MeshOptions mesh_options(const FemOptions& opt, const BoundaryValues& bv) {
  MeshOptions mo;
  mo.mesh_size = opt.mesh_size;
  mo.size_factor = opt.size_factor;
  mo.inlet_node = bv.inlet_node;
  return mo;
}

}  // namespace

std::string branch_label(const Network& net, int b) {
  const auto& n = net.branch(b).name;
  return n.empty() ? fmt::format("branch_{}", b) : n;
}

CompareResult compare_fields(const Network& net, const TetMesh& mesh, const StokesSolution& sol,
                             const NetworkFlow& flow, int inlet_node, int samples_per_branch) {
  if (samples_per_branch < 2) throw_usage_error("fem.samples_per_branch must be at least 2");
  if (flow.node_pressure.size() != static_cast<size_t>(net.num_nodes()) ||
      flow.segment_flow.size() != static_cast<size_t>(net.num_segments()))
    throw_usage_error("fem: the network flow does not match the network");
  const int inlet = inlet_node >= 0 ? inlet_node : net.widest_end();
  CompareResult res;
  res.tets = mesh.num_tets();
  res.unknowns = sol.unknowns;
  res.reynolds = sol.reynolds;
  res.newton_iterations = sol.newton_iterations;
  const FieldSampler fs(mesh, sol);
  const std::vector<double> dist = path_distances(net, inlet);
  // A network in total pressure (NetworkFlow::kinetic_density) is compared in total pressure: the
  // FEM's section carries p + ½ρ|u|² weighted by the flux (section_total_pressure), the network's
  // nodes hold it (its outlets their static values, to which their flat-profile ½ρ(Q/A)² is added).
  const double rho = flow.kinetic_density;
  res.total_pressure = rho > 0.0;
  std::vector<double> node_value = flow.node_pressure;  // the outlets' total: static + ½ρ(Q/A)²
  if (rho > 0.0)
    for (int e : net.ends()) {
      if (e == inlet) continue;
      const int s = *net.node_segments(e).first;
      const auto& seg = net.segment(s);
      const double r = seg.radius_at(e);
      const double u = flow.segment_flow[static_cast<size_t>(s)] / (std::numbers::pi * r * r);
      const double alpha = flow.end_alpha.empty() ? 1.0 : flow.end_alpha[static_cast<size_t>(e)];
      node_value[static_cast<size_t>(e)] += alpha * 0.5 * rho * u * u;
    }
  double pmin_out = std::numeric_limits<double>::infinity();
  for (int e : net.ends())
    if (e != inlet) pmin_out = std::min(pmin_out, flow.node_pressure[static_cast<size_t>(e)]);
  const double drive = std::abs(flow.node_pressure[static_cast<size_t>(inlet)] - pmin_out);
  const double pscale = drive > 0.0 ? drive : 1.0;
  // Junctions: nodes with three or more segments, and their largest radius.
  std::vector<std::pair<Vec3, double>> junctions;
  for (int n = 0; n < net.num_nodes(); ++n) {
    if (net.degree(n) < 3) continue;
    double r = 0.0;
    const auto [b, e] = net.node_segments(n);
    for (const int* s = b; s != e; ++s) r = std::max(r, net.segment(*s).radius);
    junctions.push_back({net.node(n), r});
  }
  for (int b = 0; b < net.num_branches(); ++b) {
    const auto& br = net.branch(b);
    if (br.segments.empty()) continue;
    std::vector<double> s_at(br.nodes.size(), 0.0);
    for (size_t k = 0; k + 1 < br.nodes.size(); ++k)
      s_at[k + 1] = s_at[k] + (net.node(br.nodes[k + 1]) - net.node(br.nodes[k])).norm();
    const double len = s_at.back();
    auto sample = [&](double s, SamplePoint& sp) {
      size_t k = 0;
      while (k + 2 < br.nodes.size() && s > s_at[k + 1]) ++k;
      const Vec3 a = net.node(br.nodes[k]), c = net.node(br.nodes[k + 1]);
      const double seg_len = s_at[k + 1] - s_at[k];
      const double w = seg_len > 0.0 ? std::clamp((s - s_at[k]) / seg_len, 0.0, 1.0) : 0.0;
      sp.branch = b;
      sp.s = s;
      sp.x = a + w * (c - a);
      // A junction's collecting branch starts below the junction's pressure (junction.hpp).
      double drop_a = 0.0, drop_c = 0.0;
      if (!flow.segment_end_drop.empty()) {
        const auto& sd = net.segment(br.segments[k]);
        const auto& d = flow.segment_end_drop[static_cast<size_t>(br.segments[k])];
        drop_a = d[sd.node_from == br.nodes[k] ? 0 : 1];
        drop_c = d[sd.node_from == br.nodes[k] ? 1 : 0];
      }
      const double pa = node_value[static_cast<size_t>(br.nodes[k])] - drop_a;
      const double pc = node_value[static_cast<size_t>(br.nodes[k + 1])] - drop_c;
      sp.pressure_network = pa + w * (pc - pa);
      const double da = dist[static_cast<size_t>(br.nodes[k])], dc = dist[static_cast<size_t>(br.nodes[k + 1])];
      sp.path_distance = da + w * (dc - da);
      const double r = net.segment(br.segments[k]).radius;
      auto [mean, centre, found] = section_pressure(fs, sp.x, c - a, r);
      sp.found = found;
      if (rho > 0.0 && found)
        if (const auto t = section_total_pressure(fs, sp.x, c - a, r, rho)) mean = *t;
      sp.pressure_fem = mean;
      sp.pressure_fem_centre = centre;
      const double diff = mean - sp.pressure_network;
      sp.rel_diff = std::abs(sp.pressure_network) > 1e-12 * pscale ? diff / std::abs(sp.pressure_network) : 0.0;
      sp.rel_diff_drop = diff / pscale;
      const auto& seg = net.segment(br.segments[k]);
      sp.flow_network = seg.node_from == br.nodes[k] ? flow.segment_flow[static_cast<size_t>(br.segments[k])]
                                                     : -flow.segment_flow[static_cast<size_t>(br.segments[k])];
      sp.radius_network = r;
      double area = std::numeric_limits<double>::quiet_NaN();
      sp.flow_fem = found ? section_flow(fs, sp.x, c - a, r, area) : std::numeric_limits<double>::quiet_NaN();
      sp.radius_fem = std::sqrt(area / std::numbers::pi);
      sp.rel_diff_flow = sp.flow_network != 0.0 ? (sp.flow_fem - sp.flow_network) / std::abs(sp.flow_network) : 0.0;
      for (const auto& [jx, jr] : junctions)
        if ((sp.x - jx).norm() < 2.0 * jr) sp.near_junction = true;
    };
    for (int i = 0; i < samples_per_branch; ++i) {
      SamplePoint sp;
      sample(len * i / (samples_per_branch - 1), sp);
      if (!sp.found) {
        warn(fmt::format("fem: sample at s = {:.4g} m of {} is outside the mesh", sp.s, branch_label(net, b)));
        continue;
      }
      res.samples.push_back(sp);
      // A sample on an open end lies on the cap, where the FEM's section pressure is its normal
      // traction less the viscous normal stress (the imposed value is the traction): it is written
      // but not counted in the maxima.
      const bool on_cap = (i == 0 && net.degree(br.nodes.front()) == 1) ||
                          (i == samples_per_branch - 1 && net.degree(br.nodes.back()) == 1);
      if (on_cap) continue;
      const double a = std::abs(sp.rel_diff_drop);
      if (sp.near_junction)
        res.max_rel_diff_drop_junction = std::max(res.max_rel_diff_drop_junction, a);
      else
        res.max_rel_diff_drop_away = std::max(res.max_rel_diff_drop_away, a);
    }
    // The drop between the first and the last sample inside the mesh (a real lumen's caps
    // may lie inside the centerline's ends).
    const SamplePoint* first = nullptr;
    const SamplePoint* last = nullptr;
    for (const auto& sp : res.samples)
      if (sp.branch == b) {
        if (!first) first = &sp;
        last = &sp;
      }
    if (first && last != first)
      res.branches.push_back(
          {b, first->pressure_network - last->pressure_network, first->pressure_fem - last->pressure_fem});
  }
  double qn_total = 0.0, qf_total = 0.0;
  for (int e : net.ends()) {
    if (e == inlet) continue;
    const int s = *net.node_segments(e).first;
    const double qn = net.segment(s).node_to == e ? flow.segment_flow[static_cast<size_t>(s)]
                                                  : -flow.segment_flow[static_cast<size_t>(s)];
    const int g = mesh.group_of_node(e);
    const double qf = g >= 0 ? sol.group_flow[static_cast<size_t>(g)] : 0.0;
    const double pf = g >= 0 && static_cast<size_t>(g) < sol.group_pressure.size()
                          ? sol.group_pressure[static_cast<size_t>(g)]
                          : std::numeric_limits<double>::quiet_NaN();
    res.outlets.push_back({e, qn, qf, flow.node_pressure[static_cast<size_t>(e)], pf});
    qn_total += qn;
    qf_total += qf;
  }
  {
    const int s = *net.node_segments(inlet).first;
    res.inlet_flow_network = net.segment(s).node_from == inlet ? flow.segment_flow[static_cast<size_t>(s)]
                                                               : -flow.segment_flow[static_cast<size_t>(s)];
    res.inlet_pressure_network = flow.node_pressure[static_cast<size_t>(inlet)];
    const int g = mesh.group_of_node(inlet);
    if (g >= 0) {
      res.inlet_flow_fem = -sol.group_flow[static_cast<size_t>(g)];
      res.inlet_pressure_fem = static_cast<size_t>(g) < sol.group_pressure.size()
                                   ? sol.group_pressure[static_cast<size_t>(g)]
                                   : std::numeric_limits<double>::quiet_NaN();
      if (rho > 0.0) {  // the energy the inlet section carries
        const auto& seg = net.segment(s);
        const int next = seg.node_from == inlet ? seg.node_to : seg.node_from;
        const double r_in = seg.radius_at(inlet);
        if (const auto t = section_total_pressure(fs, net.node(inlet), net.node(next) - net.node(inlet), r_in, rho))
          res.inlet_pressure_fem = *t;
      }
    }
  }
  for (const auto& o : res.outlets) {
    if (qn_total != 0.0 && qf_total != 0.0)
      res.max_flow_split_error =
          std::max(res.max_flow_split_error, std::abs(o.flow_fem / qf_total - o.flow_network / qn_total));
    if (o.flow_network != 0.0)
      res.max_flow_error = std::max(res.max_flow_error, std::abs(o.flow_fem / o.flow_network - 1.0));
  }
  res.mesh_seconds = mesh.mesh_seconds;
  res.assemble_seconds = sol.assemble_seconds;
  res.solve_seconds = sol.solve_seconds;
  return res;
}

std::vector<flow::SegmentLaw> ComparisonDomain::laws(const Network& input,
                                                     std::span<const flow::SegmentLaw> laws) const {
  if (laws.empty()) return {};
  if (laws.size() != segment.size())
    throw_usage_error(fmt::format("fem: {} segment laws for {} segments", laws.size(), segment.size()));
  std::vector<flow::SegmentLaw> out(static_cast<size_t>(network.num_segments()));
  for (size_t s = 0; s < segment.size(); ++s) {
    const int c = segment[s];
    if (c < 0) continue;
    flow::SegmentLaw law = laws[s];
    law.quadratic *= flow::segment_resistance(1.0, network.segment(c)) /
                     flow::segment_resistance(1.0, input.segment(static_cast<int>(s)));
    out[static_cast<size_t>(c)] = law;
  }
  return out;
}

std::vector<double> ComparisonDomain::nodal(std::span<const double> values, double fill) const {
  if (values.empty()) return {};
  std::vector<double> out(static_cast<size_t>(network.num_nodes()), fill);
  for (size_t i = 0; i < node.size() && i < values.size(); ++i)
    if (node[i] >= 0) out[static_cast<size_t>(node[i])] = values[i];
  return out;
}

ComparisonDomain comparison_domain(const Network& net, const FemOptions& opt, const BoundaryValues& bv) {
  ComparisonDomain d;
  if (opt.surface.empty()) {
    d.mesh = build_mesh(net, mesh_options(opt, bv));
    d.network = net;
    d.node.resize(static_cast<size_t>(net.num_nodes()));
    std::iota(d.node.begin(), d.node.end(), 0);
    d.segment.resize(static_cast<size_t>(net.num_segments()));
    std::iota(d.segment.begin(), d.segment.end(), 0);
    d.bv = bv;
    d.bv.inlet_node = inlet_of(net, bv);
    return d;
  }
  const LumenSurface lumen = prepare_lumen(net, read_surface(opt.surface, opt.surface_length_factor));
  d.mesh = build_mesh(net, lumen, mesh_options(opt, bv));
  CapCut cut = cut_at_caps(net, lumen.caps, opt.surface);
  d.network = std::move(cut.network);
  d.node = std::move(cut.node);
  d.segment = std::move(cut.segment);
  d.cut_length = std::move(cut.cut_length);
  d.lumen_ends_recut = lumen.recut_ends;
  for (auto& g : d.mesh.groups)
    if (g.node >= 0) g.node = d.node[static_cast<size_t>(g.node)];
  d.bv = renumbered(bv, net, d.node);
  return d;
}

StokesOptions comparison_stokes_options(const FemOptions& opt, const BoundaryValues& bv) {
  StokesOptions so;
  so.viscosity = bv.viscosity;
  so.density = bv.density;
  so.equations = opt.equations;
  so.solver = opt.solver;
  so.velocity_pc = opt.velocity_pc;
  so.stabilization = opt.stabilization;
  so.inlet = opt.inlet;
  so.flat_inlet = opt.flat_inlet;
  so.backflow = opt.backflow;
  return so;
}

CompareResult compare(const Network& net, const BoundaryValues& bv, const FemOptions& opt, const std::string& out_dir) {
  const auto t0 = std::chrono::steady_clock::now();
  initialize();  // MPI up before meshing, so that rank 0 meshes for everyone
  const ComparisonDomain d = comparison_domain(net, opt, bv);
  const auto cond = group_conditions(d.mesh, d.bv);
  const StokesSolution sol =
      solve_stokes(d.mesh, std::span<const GroupCondition>(cond), comparison_stokes_options(opt, d.bv));
  NetworkFlow nf = network_flow(d.network, d.bv, d.laws(net, opt.segment_laws), opt.junction_losses);
  if (opt.total_pressure) {
    nf.kinetic_density = d.bv.density;
    nf.end_alpha = d.nodal(opt.end_alpha, 1.0);
  }
  CompareResult res = compare_fields(d.network, d.mesh, sol, nf, d.bv.inlet_node, opt.samples_per_branch);
  res.forces = named_forces(d.mesh, sol, comparison_stokes_options(opt, d.bv));
  res.cut_length = d.cut_length;
  res.lumen_ends_recut = d.lumen_ends_recut;
  res.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!out_dir.empty()) write_outputs(out_dir, d.network, d.mesh, sol, res, opt);
  return res;
}

}  // namespace flowire::flow::fem
