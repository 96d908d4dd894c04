// The files of a network-vs-FEM comparison: the samples and outlets as CSV, the Markdown
// report, the solution as VTU (and a ParaView series for the frames of a pulsatile run),
// the pressure plot as PNG (by a Python script). Rank 0 writes; every file atomically.
#include "flowire/flow/fem/compare_output.hpp"

#include <fmt/format.h>

#include <array>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <vector>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/flow/fem/element.hpp"
#include "flowire/flow/fem/obstacle.hpp"
#include "flowire/flow/petsc_runtime.hpp"
#include "flowire/mesh/vtu.hpp"

namespace flowire::flow::fem {
namespace {

using flow::mpi_rank;

double pressure_at_node(const TetMesh& mesh, const StokesSolution& sol, size_t n,
                        const std::vector<std::array<int, 2>>& ev) {
  const int v = mesh.vertex_index[n];
  if (v >= 0) return sol.pressure[static_cast<size_t>(v)];
  return 0.5 * (sol.pressure[static_cast<size_t>(mesh.vertex_index[static_cast<size_t>(ev[n][0])])] +
                sol.pressure[static_cast<size_t>(mesh.vertex_index[static_cast<size_t>(ev[n][1])])]);
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

/// The output folder, created if needed.
std::filesystem::path output_folder(const std::string& out_dir) {
  const std::filesystem::path dir(out_dir);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw_input_error(out_dir, fmt::format("cannot create the output folder: {}", ec.message()));
  return dir;
}

}  // namespace

void write_vtu(const std::string& path, const TetMesh& mesh, const StokesSolution& sol) {
  // Edge nodes take the mean pressure of their two vertices (the P1 field).
  std::vector<std::array<int, 2>> ev(mesh.nodes.size(), {-1, -1});
  for (const auto& t : mesh.tets)
    for (size_t e = 0; e < 6; ++e)
      ev[static_cast<size_t>(t[4 + e])] = {t[static_cast<size_t>(kTetEdges[e][0])],
                                           t[static_cast<size_t>(kTetEdges[e][1])]};
  mesh::PointField pressure{"pressure", 1, {}}, velocity{"velocity", 3, {}};
  for (size_t n = 0; n < mesh.nodes.size(); ++n) pressure.values.push_back(pressure_at_node(mesh, sol, n, ev));
  for (const Vec3& u : sol.velocity) velocity.values.insert(velocity.values.end(), {u.x(), u.y(), u.z()});
  mesh::write_vtu(path, mesh, {pressure, velocity});
}

void write_outputs(const std::string& out_dir, const Network& net, const TetMesh& mesh, const StokesSolution& sol,
                   const CompareResult& res, const FemOptions& opt) {
  if (mpi_rank() != 0) return;
  const std::filesystem::path dir = output_folder(out_dir);
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

void write_pulsatile_outputs(const std::string& out_dir, const Network& net, const TetMesh& mesh,
                             std::span<const CompareResult> frames, std::span<const StokesSolution> fields) {
  if (mpi_rank() != 0) return;
  const std::filesystem::path dir = output_folder(out_dir);
  {
    std::ostringstream o;
    o.precision(10);
    o << "time," << kSampleHeader << '\n';
    for (const auto& r : frames)
      for (const auto& sp : r.samples) o << r.time << ',' << sample_row(net, sp) << '\n';
    write_text_atomically(dir / "fem_pulsatile.csv", o.str());
  }
  {
    std::ostringstream o;
    o.precision(10);
    o << "time,outlet,flow_network,flow_fem,rel_diff,pressure_network,pressure_fem\n";
    for (const auto& r : frames)
      for (const auto& q : r.outlets) o << r.time << ',' << outlet_row(q) << '\n';
    write_text_atomically(dir / "fem_pulsatile_outlets.csv", o.str());
  }
  if (!fields.empty()) {
    std::ostringstream pvd;
    pvd.precision(10);
    pvd << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
           "<Collection>\n";
    for (size_t i = 0; i < fields.size(); ++i) {
      const std::string name = fmt::format("fem_{:04d}.vtu", i);
      write_vtu((dir / name).string(), mesh, fields[i]);
      pvd << "<DataSet timestep=\"" << frames[i].time << "\" part=\"0\" file=\"" << name << "\"/>\n";
    }
    pvd << "</Collection>\n</VTKFile>\n";
    write_text_atomically(dir / "fem.pvd", pvd.str());
  }
}

}  // namespace flowire::flow::fem
