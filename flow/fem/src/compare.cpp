// Network vs FEM: sampling along the centerlines, outlet flows, branch drops, and the
// output files (CSV, Markdown, VTU, PNG).
#include "flowire/fem/compare.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <optional>
#include <queue>
#include <sstream>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/fem/element.hpp"
#include "flowire/fem/lumen.hpp"
#include "flowire/fem/network_mesh.hpp"
#include "flowire/fem/obstacle.hpp"
#include "flowire/fem/sample.hpp"
#include "flowire/flow/petsc_runtime.hpp"
#include "flowire/flow/solver.hpp"

namespace flowire::fem {
namespace {

using flow::mpi_rank;

OutletValue outlet_value_of(const BoundaryValues& bv, int node) {
  for (const auto& o : bv.outlets)
    if (o.node == node) return o;
  OutletValue o;
  o.node = node;
  o.pressure = bv.outlet_pressure;
  for (const auto& [n, p] : bv.outlet_pressures)
    if (n == node) o.pressure = p;
  return o;
}

int inlet_of(const Network& net, const BoundaryValues& bv) {
  return bv.inlet_node >= 0 ? bv.inlet_node : net.widest_end();
}

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

/// FEM pressure over a disk of 0.95 r normal to `axis` at `c`: (mean, centre, found).
std::tuple<double, double, bool> section_pressure(const FieldSampler& fs, const Vec3& c, const Vec3& axis, double r) {
  const Vec3 t = axis.normalized();
  const Vec3 a = (std::abs(t.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(t).normalized();
  const Vec3 b = t.cross(a);
  // Equal-area rings (midpoints in ρ²) times 12 angles, plus the centre.
  constexpr int kRings = 4, kAngles = 12;
  const double rmax = 0.95 * r;
  double sum = 0.0, weight = 0.0, centre = std::numeric_limits<double>::quiet_NaN();
  const double tol = 1e-6;
  if (auto v = fs.at(c, tol)) centre = v->pressure;
  for (int i = 0; i < kRings; ++i) {
    const double rho = rmax * std::sqrt((i + 0.5) / kRings);
    for (int k = 0; k < kAngles; ++k) {
      const double phi = 2.0 * std::numbers::pi * (k + 0.5 * (i % 2)) / kAngles;
      const Vec3 x = c + rho * (std::cos(phi) * a + std::sin(phi) * b);
      if (auto v = fs.at(x, tol)) {
        sum += v->pressure;
        weight += 1.0;
      }
    }
  }
  if (weight == 0.0 && std::isnan(centre)) return {0.0, 0.0, false};
  const double mean = weight > 0.0 ? sum / weight : centre;
  return {mean, std::isnan(centre) ? mean : centre, true};
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

double pressure_at_node(const TetMesh& mesh, const StokesSolution& sol, size_t n,
                        const std::vector<std::array<int, 2>>& ev) {
  const int v = mesh.vertex_index[n];
  if (v >= 0) return sol.pressure[static_cast<size_t>(v)];
  return 0.5 * (sol.pressure[static_cast<size_t>(mesh.vertex_index[static_cast<size_t>(ev[n][0])])] +
                sol.pressure[static_cast<size_t>(mesh.vertex_index[static_cast<size_t>(ev[n][1])])]);
}

std::string branch_label(const Network& net, int b) {
  const auto& n = net.branch(b).name;
  return n.empty() ? fmt::format("branch_{}", b) : n;
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string sample_row(const Network& net, const SamplePoint& sp) {
  std::ostringstream o;
  o.precision(10);
  o << csv_field(branch_label(net, sp.branch)) << ',' << sp.s << ',' << sp.x.x() << ',' << sp.x.y() << ',' << sp.x.z()
    << ',' << sp.pressure_network << ',' << sp.pressure_fem << ',' << sp.rel_diff << ',' << sp.pressure_fem_centre
    << ',' << sp.rel_diff_drop << ',' << sp.path_distance << ',' << (sp.near_junction ? 1 : 0) << ',' << sp.flow_network
    << ',' << sp.flow_fem << ',' << sp.rel_diff_flow << ',' << sp.radius_network << ',' << sp.radius_fem;
  return o.str();
}

constexpr const char* kSampleHeader =
    "branch,s,x,y,z,pressure_network,pressure_fem,rel_diff,pressure_fem_centre,rel_diff_drop,path_distance,"
    "near_junction,flow_network,flow_fem,rel_diff_flow,radius_network,radius_fem";

std::string outlet_row(const OutletFlow& q) {
  std::ostringstream o;
  o.precision(10);
  o << q.node << ',' << q.flow_network << ',' << q.flow_fem << ','
    << (q.flow_network != 0.0 ? q.flow_fem / q.flow_network - 1.0 : 0.0) << ',' << q.pressure_network << ','
    << q.pressure_fem;
  return o.str();
}

std::string plot_script() {
  if (const char* env = std::getenv("FLOWIRE_FEM_PLOT_SCRIPT")) return env;
  for (const char* dir : {FLOWIRE_FEM_SCRIPT_DIR, FLOWIRE_FEM_INSTALLED_SCRIPT_DIR}) {
    const auto p = std::filesystem::path(dir) / "plot_fem_compare.py";
    if (std::filesystem::exists(p)) return p.string();
  }
  return {};
}

void write_png(const std::filesystem::path& png, const std::filesystem::path& csv) {
  const std::string script = plot_script();
  if (script.empty()) {
    warn("fem: plot_fem_compare.py not found; fem_compare.png not written");
    return;
  }
  try {
    write_atomically(png, [&](const std::filesystem::path& tmp) {
      // The system interpreter has Debian's python3-matplotlib; a python3 earlier in PATH
      // (pyenv, venv) may not. FLOWIRE_PYTHON overrides.
      std::string python = std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
      if (const char* env = std::getenv("FLOWIRE_PYTHON")) python = env;
      const std::string cmd =
          fmt::format("'{}' '{}' '{}' '{}' > /dev/null 2>&1", python, script, csv.string(), tmp.string());
      if (std::system(cmd.c_str()) != 0 || !std::filesystem::exists(tmp))
        throw_input_error(png.string(), "the plot script failed (python3 with matplotlib needed)");
    });
  } catch (const Error& e) {
    warn(fmt::format("fem: fem_compare.png not written: {}", e.what()));
  }
}

}  // namespace

void write_vtu(const std::string& path, const TetMesh& mesh, const StokesSolution& sol) {
  // Edge nodes take the mean pressure of their two vertices (the P1 field).
  std::vector<std::array<int, 2>> ev(mesh.nodes.size(), {-1, -1});
  for (const auto& t : mesh.tets)
    for (size_t e = 0; e < 6; ++e)
      ev[static_cast<size_t>(t[4 + e])] = {t[static_cast<size_t>(kTetEdges[e][0])],
                                           t[static_cast<size_t>(kTetEdges[e][1])]};
  write_stream_atomically(path, [&](std::ostream& f) {
    f.precision(10);
    f << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      << "<UnstructuredGrid>\n<Piece NumberOfPoints=\"" << mesh.nodes.size() << "\" NumberOfCells=\""
      << mesh.tets.size() << "\">\n<PointData Scalars=\"pressure\" Vectors=\"velocity\">\n"
      << "<DataArray type=\"Float64\" Name=\"pressure\" format=\"ascii\">\n";
    for (size_t n = 0; n < mesh.nodes.size(); ++n) f << pressure_at_node(mesh, sol, n, ev) << '\n';
    f << "</DataArray>\n<DataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    for (const Vec3& u : sol.velocity) f << u.x() << ' ' << u.y() << ' ' << u.z() << '\n';
    f << "</DataArray>\n</PointData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" "
         "format=\"ascii\">\n";
    for (const Vec3& x : mesh.nodes) f << x.x() << ' ' << x.y() << ' ' << x.z() << '\n';
    f << "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
    // VTK_QUADRATIC_TETRA edge order: (0,1), (1,2), (0,2), (0,3), (1,3), (2,3) — the same as ours.
    for (const auto& t : mesh.tets) {
      for (int k = 0; k < 10; ++k) f << t[static_cast<size_t>(k)] << (k == 9 ? '\n' : ' ');
    }
    f << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
    for (size_t e = 0; e < mesh.tets.size(); ++e) f << 10 * (e + 1) << '\n';
    f << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
    for (size_t e = 0; e < mesh.tets.size(); ++e) f << "24\n";
    f << "</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
  });
}

BoundaryValues boundary_values(const flow::FlowSpec& spec, const Network& net, double t) {
  if (spec.inlets.size() != 1)
    throw_input_error("fem",
                      fmt::format("the comparison needs exactly one inlet; the flow has {}", spec.inlets.size()));
  BoundaryValues bv;
  const auto& in = spec.inlets.front();
  bv.inlet_node = in.node >= 0 ? in.node : net.widest_end();
  if (in.type == flow::InletBC::Type::Flow) {
    bv.inlet_type = BoundaryValues::Inlet::Flow;
    bv.inlet_flow = in.waveform(t);
  } else {
    bv.inlet_pressure = in.waveform(t);
  }
  for (const auto& o : spec.outlets) {
    OutletValue v;
    v.node = o.node;
    switch (o.type) {
      case flow::OutletBC::Type::Pressure:
        v.pressure = o.pressure(t);
        break;
      case flow::OutletBC::Type::Resistance:
      case flow::OutletBC::Type::Rcr:  // quasi-steady: the capacitors carry no flow
      case flow::OutletBC::Type::Coronary:
        v.type = OutletValue::Type::Resistance;
        v.pressure = o.steady_pressure();
        v.resistance = o.steady_resistance();
        break;
      case flow::OutletBC::Type::Flow:
        throw_input_error("fem", fmt::format("outlet node {}: a fixed outflow is not a condition the comparison "
                                             "takes (pressure, resistance, RCR or coronary)",
                                             o.node));
    }
    bv.outlets.push_back(v);
  }
  for (int e : net.ends()) {
    if (e == bv.inlet_node) continue;
    if (std::none_of(bv.outlets.begin(), bv.outlets.end(), [&](const OutletValue& o) { return o.node == e; }))
      throw_input_error("fem",
                        fmt::format("network end node {} has no outlet condition (the FEM mesh opens every end)", e));
  }
  bv.viscosity = spec.viscosity;
  bv.density = spec.density;
  return bv;
}

NetworkFlow network_flow(const Network& net, const BoundaryValues& bv) {
  flow::FlowSpec spec;
  spec.solver = flow::SolverKind::Sparse;
  spec.viscosity = bv.viscosity;
  spec.density = bv.density;
  const int inlet = inlet_of(net, bv);
  flow::InletBC in;
  in.node = inlet;
  if (bv.inlet_type == BoundaryValues::Inlet::Flow) {
    in.type = flow::InletBC::Type::Flow;
    in.waveform = flow::Waveform::constant(bv.inlet_flow);
  } else {
    in.type = flow::InletBC::Type::Pressure;
    in.waveform = flow::Waveform::constant(bv.inlet_pressure);
  }
  spec.inlets.push_back(in);
  for (int e : net.ends()) {
    if (e == inlet) continue;
    const OutletValue v = outlet_value_of(bv, e);
    flow::OutletBC out = v.type == OutletValue::Type::Resistance
                             ? flow::OutletBC::with_resistance(v.resistance, v.pressure)
                             : flow::OutletBC::at_pressure(v.pressure);
    out.node = e;
    spec.outlets.push_back(out);
  }
  auto solver = flow::make_solver(net, spec);
  NetworkFlow nf;
  nf.node_pressure.resize(static_cast<size_t>(net.num_nodes()));
  nf.segment_flow.resize(static_cast<size_t>(net.num_segments()));
  solver->solve_at(0.0, nf.node_pressure, nf.segment_flow);
  return nf;
}

std::vector<GroupCondition> group_conditions(const TetMesh& mesh, const BoundaryValues& bv) {
  std::vector<GroupCondition> c(mesh.groups.size());
  for (size_t g = 0; g < mesh.groups.size(); ++g) {
    const auto& grp = mesh.groups[g];
    if (grp.kind == BoundaryGroup::Kind::Inlet) {
      // The FEM flux is outward: an inflow into the network is a negative outward flow.
      c[g] = bv.inlet_type == BoundaryValues::Inlet::Flow ? GroupCondition::with_flow(-bv.inlet_flow)
                                                          : GroupCondition::at_pressure(bv.inlet_pressure);
    } else if (grp.kind == BoundaryGroup::Kind::Outlet) {
      const OutletValue v = outlet_value_of(bv, grp.node);
      if (v.type == OutletValue::Type::Resistance && !(v.resistance >= 0.0))
        throw_usage_error(fmt::format("fem: outlet {} has a negative resistance", grp.node));
      c[g] = v.type == OutletValue::Type::Resistance ? GroupCondition::with_resistance(v.resistance, v.pressure)
                                                     : GroupCondition::at_pressure(v.pressure);
    }
  }
  return c;
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
      const double pa = flow.node_pressure[static_cast<size_t>(br.nodes[k])];
      const double pc = flow.node_pressure[static_cast<size_t>(br.nodes[k + 1])];
      sp.pressure_network = pa + w * (pc - pa);
      const double da = dist[static_cast<size_t>(br.nodes[k])], dc = dist[static_cast<size_t>(br.nodes[k + 1])];
      sp.path_distance = da + w * (dc - da);
      const double r = net.segment(br.segments[k]).radius;
      auto [mean, centre, found] = section_pressure(fs, sp.x, c - a, r);
      sp.found = found;
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

void write_outputs(const std::string& out_dir, const Network& net, const TetMesh& mesh, const StokesSolution& sol,
                   const CompareResult& res, const FemOptions& opt) {
  if (mpi_rank() != 0) return;
  const std::filesystem::path dir(out_dir);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw_input_error(out_dir, fmt::format("cannot create the output folder: {}", ec.message()));
  {
    std::ostringstream o;
    o.precision(10);
    o << kSampleHeader << '\n';
    for (const auto& sp : res.samples) o << sample_row(net, sp) << '\n';
    write_text_atomically(dir / "fem_compare.csv", o.str());
  }
  {
    std::ostringstream o;
    o.precision(10);
    o << "outlet,flow_network,flow_fem,rel_diff,pressure_network,pressure_fem\n";
    for (const auto& q : res.outlets) o << outlet_row(q) << '\n';
    write_text_atomically(dir / "fem_outlets.csv", o.str());
  }
  {
    std::ostringstream o;
    o << "# Network model vs 3D finite elements\n\n"
      << fmt::format("Taylor–Hood P2/P1 {} on {} quadratic tetrahedra ({} unknowns), solver {}.\n\n",
                     opt.equations == Equations::Stokes ? "Stokes" : "Navier–Stokes", res.tets, res.unknowns,
                     opt.solver == LinearSolver::Mumps ? "MUMPS" : "fieldsplit Schur")
      << "Pressures in kPa at points equally spaced along each branch centerline (FEM: cross-section mean). "
         "Difference: (FEM − network) / network; in brackets, as a fraction of the driving pressure drop. "
         "`*`: within two radii of a junction.\n\n";
    for (int b = 0; b < net.num_branches(); ++b) {
      std::vector<const SamplePoint*> pts;
      for (const auto& sp : res.samples)
        if (sp.branch == b) pts.push_back(&sp);
      if (pts.empty()) continue;
      o << "## " << branch_label(net, b) << "\n\n| Sampling |";
      for (size_t i = 0; i < pts.size(); ++i) o << " #" << i + 1 << (pts[i]->near_junction ? "*" : "") << " |";
      o << "\n|---|";
      for (size_t i = 0; i < pts.size(); ++i) o << "---|";
      o << "\n| s (mm) |";
      for (const auto* p : pts) o << fmt::format(" {:.2f} |", p->s * 1e3);
      o << "\n| Network |";
      for (const auto* p : pts) o << fmt::format(" {:.4f} |", p->pressure_network * 1e-3);
      o << "\n| FEM |";
      for (const auto* p : pts) o << fmt::format(" {:.4f} |", p->pressure_fem * 1e-3);
      o << "\n| Difference |";
      for (const auto* p : pts) o << fmt::format(" {:+.2f}% ({:+.2f}%) |", 100 * p->rel_diff, 100 * p->rel_diff_drop);
      o << "\n| Q network (mL/s) |";
      for (const auto* p : pts) o << fmt::format(" {:.4g} |", p->flow_network * 1e6);
      o << "\n| Q FEM (mL/s) |";
      for (const auto* p : pts) o << fmt::format(" {:.4g} |", p->flow_fem * 1e6);
      o << "\n| Q difference |";
      for (const auto* p : pts) o << fmt::format(" {:+.2f}% |", 100 * p->rel_diff_flow);
      o << "\n| r network / FEM (mm) |";
      for (const auto* p : pts) o << fmt::format(" {:.2f} / {:.2f} |", p->radius_network * 1e3, p->radius_fem * 1e3);
      o << "\n\n";
    }
    o << fmt::format(
        "## Boundary\n\nInlet: network {:.5g} Pa, {:.5g} mL/s; FEM {:.5g} Pa, {:.5g} mL/s (the "
        "imposed one of pressure / flow is the same in both).\n\n",
        res.inlet_pressure_network, res.inlet_flow_network * 1e6, res.inlet_pressure_fem, res.inlet_flow_fem * 1e6);
    o << "## Outlet flows\n\n| outlet node | network (mL/s) | FEM (mL/s) | difference | network p (Pa) | FEM p (Pa) "
         "|\n|---|---|---|---|---|---|\n";
    for (const auto& q : res.outlets)
      o << fmt::format("| {} | {:.5g} | {:.5g} | {:+.2f}% | {:.5g} | {:.5g} |\n", q.node, q.flow_network * 1e6,
                       q.flow_fem * 1e6, q.flow_network != 0.0 ? 100 * (q.flow_fem / q.flow_network - 1.0) : 0.0,
                       q.pressure_network, q.pressure_fem);
    o << "\n## Pressure drop per branch\n\n| branch | network (Pa) | FEM (Pa) | difference |\n|---|---|---|---|\n";
    for (const auto& d : res.branches)
      o << fmt::format("| {} | {:.5g} | {:.5g} | {:+.2f}% |\n", branch_label(net, d.branch), d.drop_network, d.drop_fem,
                       d.drop_network != 0.0 ? 100 * (d.drop_fem / d.drop_network - 1.0) : 0.0);
    o << fmt::format(
        "\nLargest difference away from junctions: {:.2f}% of the drop; near junctions: {:.2f}%. "
        "Largest flow-split difference: {:.3f}%.\n\nTimings: mesh {:.2f} s, assembly {:.2f} s, solve "
        "{:.2f} s.\n",
        100 * res.max_rel_diff_drop_away, 100 * res.max_rel_diff_drop_junction, 100 * res.max_flow_split_error,
        res.mesh_seconds, res.assemble_seconds, res.solve_seconds);
    write_text_atomically(dir / "fem_compare.md", o.str());
  }
  if (opt.write_vtu) write_vtu((dir / "fem.vtu").string(), mesh, sol);
  write_forces(dir.string(), res.forces);
  if (opt.write_png) write_png(dir / "fem_compare.png", dir / "fem_compare.csv");
}

namespace {

MeshOptions mesh_options(const FemOptions& opt, const BoundaryValues& bv) {
  MeshOptions mo;
  mo.mesh_size = opt.mesh_size;
  mo.size_factor = opt.size_factor;
  mo.inlet_node = bv.inlet_node;
  return mo;
}

/// The network's own lumen, or the real lumen of `opt.surface` tagged by the network's ends.
TetMesh mesh_for(const Network& net, const FemOptions& opt, const BoundaryValues& bv) {
  if (opt.surface.empty()) return build_mesh(net, mesh_options(opt, bv));
  return build_mesh(net, prepare_lumen(net, read_surface(opt.surface, opt.surface_length_factor)),
                    mesh_options(opt, bv));
}

StokesOptions stokes_options(const FemOptions& opt, const BoundaryValues& bv) {
  StokesOptions so;
  so.viscosity = bv.viscosity;
  so.density = bv.density;
  so.equations = opt.equations;
  so.solver = opt.solver;
  so.velocity_pc = opt.velocity_pc;
  so.stabilization = opt.stabilization;
  so.inlet = opt.inlet;
  so.backflow = opt.backflow;
  return so;
}

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

CompareResult compare(const Network& net, const BoundaryValues& bv, const FemOptions& opt, const std::string& out_dir) {
  const auto t0 = std::chrono::steady_clock::now();
  initialize();  // MPI up before meshing, so that rank 0 meshes for everyone
  const TetMesh mesh = mesh_for(net, opt, bv);
  const auto cond = group_conditions(mesh, bv);
  const StokesSolution sol = solve_stokes(mesh, std::span<const GroupCondition>(cond), stokes_options(opt, bv));
  const NetworkFlow nf = network_flow(net, bv);
  CompareResult res = compare_fields(net, mesh, sol, nf, inlet_of(net, bv), opt.samples_per_branch);
  res.forces = named_forces(mesh, sol, stokes_options(opt, bv));
  res.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!out_dir.empty()) write_outputs(out_dir, net, mesh, sol, res, opt);
  return res;
}

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
  const TetMesh mesh = mesh_for(net, opt, steady);
  const StokesOptions so = stokes_options(opt, steady);
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
      StokesOptions fso = stokes_options(opt, bv);
      if (!previous.velocity.empty()) fso.initial_guess = &previous;
      sol = solve_stokes(mesh, std::span<const GroupCondition>(cond), fso);
      previous = sol;
      out.factorizations += sol.factorizations;
      out.basis_seconds += sol.assemble_seconds + sol.solve_seconds;
    }
    return compare_fields(net, mesh, sol, network_flow(net, bv), inlet, opt.samples_per_branch);
  };
  const auto t_frames = std::chrono::steady_clock::now();
  StokesSolution steady_sol;
  out.steady = solve(steady, steady_sol);
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
      const NetworkFlow nf = dyn->network_at ? dyn->network_at(times[i]) : network_flow(net, frames[i]);
      r = compare_fields(net, mesh, dynamic[i], nf, inlet, opt.samples_per_branch);
      if (vtu) sols[i] = std::move(dynamic[i]);
    } else {
      r = solve(frames[i], vtu ? sols[i] : scratch);
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
  write_outputs(out_dir, net, mesh, steady_sol, out.steady, opt);  // rank 0 only
  if (mpi_rank() != 0) return out;
  const std::filesystem::path dir(out_dir);
  {
    std::ostringstream o;
    o.precision(10);
    o << "time," << kSampleHeader << '\n';
    for (const auto& r : out.frames)
      for (const auto& sp : r.samples) o << r.time << ',' << sample_row(net, sp) << '\n';
    write_text_atomically(dir / "fem_pulsatile.csv", o.str());
  }
  {
    std::ostringstream o;
    o.precision(10);
    o << "time,outlet,flow_network,flow_fem,rel_diff,pressure_network,pressure_fem\n";
    for (const auto& r : out.frames)
      for (const auto& q : r.outlets) o << r.time << ',' << outlet_row(q) << '\n';
    write_text_atomically(dir / "fem_pulsatile_outlets.csv", o.str());
  }
  if (vtu) {
    std::ostringstream pvd;
    pvd.precision(10);
    pvd << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
           "<Collection>\n";
    for (size_t i = 0; i < frames.size(); ++i) {
      const std::string name = fmt::format("fem_{:04d}.vtu", i);
      write_vtu((dir / name).string(), mesh, sols[i]);
      pvd << "<DataSet timestep=\"" << times[i] << "\" part=\"0\" file=\"" << name << "\"/>\n";
    }
    pvd << "</Collection>\n</VTKFile>\n";
    write_text_atomically(dir / "fem.pvd", pvd.str());
  }
  return out;
}

}  // namespace flowire::fem
