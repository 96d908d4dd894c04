// Flow past obstacles on meshes built in code: the DFG benchmark 3D-1Z and a wire in a
// tube (domains, solve, forces, outputs).
#include "flowire/flow/fem/obstacle.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <sstream>

#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/flow/fem/compare_output.hpp"
#include "flowire/flow/fem/sample.hpp"
#include "flowire/flow/petsc_runtime.hpp"

namespace flowire::flow::fem {
namespace {

bool rank0() { return flow::mpi_rank() == 0; }

// DFG 3D-1Z data (SI).
constexpr double kLength = 2.5, kHeight = 0.41, kDiameter = 0.1, kAxisX = 0.5, kAxisY = 0.2;
constexpr double kUm = 0.45, kNu = 1e-3, kRho = 1.0;
constexpr double kMeanVelocity = 4.0 * kUm / 9.0;

using Kind = BoundaryGroup::Kind;

}  // namespace

ShapeDomain dfg_3d_1z_domain(const ObstacleMesh& sizes) {
  ShapeDomain d;
  d.name = "fem geometry dfg_3d_1z";
  d.groups = {
      {Kind::Wall, -1, "wall"}, {Kind::Wall, -1, "obstacle"}, {Kind::Inlet, -1, "inlet"}, {Kind::Outlet, -1, "outlet"}};
  d.outer = Solid::box(Vec3(0, 0, 0), Vec3(kLength, kHeight, kHeight));
  d.outer.face_group = {2, 3, 0, 0, 0, 0};
  // The cylinder reaches past the floor and the ceiling: the cut leaves no coincident faces.
  Solid cyl =
      Solid::cylinder(Vec3(kAxisX, kAxisY, -0.1 * kHeight), Vec3(kAxisX, kAxisY, 1.1 * kHeight), 0.5 * kDiameter);
  cyl.face_group = {1, -1, -1, -1, -1, -1};
  cyl.mesh_size = sizes.obstacle_mesh_size;
  d.holes.push_back(cyl);
  d.mesh_size = sizes.mesh_size;
  d.growth = sizes.growth;
  return d;
}

ShapeDomain wire_in_tube_domain(double tube_radius, double length, double wire_radius, bool across, double wire_x,
                                const ObstacleMesh& sizes) {
  ShapeDomain d;
  d.name = across ? "wire across a tube" : "wire along a tube";
  d.groups = {
      {Kind::Wall, -1, "wall"}, {Kind::Wall, -1, "obstacle"}, {Kind::Inlet, -1, "inlet"}, {Kind::Outlet, -1, "outlet"}};
  d.outer = Solid::cylinder(Vec3(0, 0, 0), Vec3(length, 0, 0), tube_radius);
  d.outer.face_group = {0, 2, 3, -1, -1, -1};
  Solid wire =
      across ? Solid::cylinder(Vec3(wire_x, -1.2 * tube_radius, 0), Vec3(wire_x, 1.2 * tube_radius, 0), wire_radius)
             : Solid::cylinder(Vec3(-0.1 * length, 0, 0), Vec3(1.1 * length, 0, 0), wire_radius);
  wire.face_group = {1, -1, -1, -1, -1, -1};
  wire.mesh_size = sizes.obstacle_mesh_size;
  d.holes.push_back(wire);
  d.mesh_size = sizes.mesh_size;
  d.growth = sizes.growth;
  return d;
}

ShapeDomain wire_along_tube_domain(double tube_radius, double length, double wire_radius, double offset,
                                   const ObstacleMesh& sizes) {
  if (!(wire_radius > 0.0) || !(offset >= 0.0) || !(offset + wire_radius < tube_radius))
    throw_usage_error(
        fmt::format("wire_along_tube_domain: a wire of radius {} at offset {} does not fit in a tube of "
                    "radius {}",
                    wire_radius, offset, tube_radius));
  ShapeDomain d = wire_in_tube_domain(tube_radius, length, wire_radius, false, 0.0, sizes);
  d.holes.front() = Solid::cylinder(Vec3(-0.1 * length, offset, 0), Vec3(1.1 * length, offset, 0), wire_radius);
  d.holes.front().face_group = {1, -1, -1, -1, -1, -1};
  d.holes.front().mesh_size = sizes.obstacle_mesh_size;
  d.name = "wire along a tube, off axis";
  return d;
}

std::vector<std::pair<std::string, Vec3>> named_forces(const TetMesh& mesh, const StokesSolution& sol,
                                                       const StokesOptions& opt) {
  const std::vector<Vec3> f = boundary_forces(mesh, sol, opt);
  std::vector<std::pair<std::string, Vec3>> out;
  for (size_t g = 0; g < mesh.groups.size(); ++g)
    if (mesh.groups[g].no_slip()) out.emplace_back(mesh.groups[g].name, f[g]);
  return out;
}

void write_forces(const std::string& dir, const std::vector<std::pair<std::string, Vec3>>& forces) {
  if (!rank0()) return;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw_input_error(dir, fmt::format("cannot create the output folder: {}", ec.message()));
  std::ostringstream o;
  o.precision(12);
  o << "boundary,fx,fy,fz\n";
  for (const auto& [name, f] : forces) o << name << ',' << f.x() << ',' << f.y() << ',' << f.z() << '\n';
  write_text_atomically(std::filesystem::path(dir) / "fem_forces.csv", o.str());
}

ObstacleResult dfg_3d_1z(const ObstacleMesh& sizes, Stabilization stabilization, const std::string& out_dir,
                         bool write_vtu_file) {
  initialize();  // MPI up before meshing, so that rank 0 meshes for everyone
  const TetMesh mesh = build_mesh(dfg_3d_1z_domain(sizes));
  const int inlet = mesh.group_named("inlet"), obstacle = mesh.group_named("obstacle");
  StokesOptions so;
  so.viscosity = kNu * kRho;
  so.density = kRho;
  so.equations = Equations::NavierStokes;
  so.stabilization = stabilization;
  so.inlet = InletCondition::Profile;
  so.inlet_velocity = [](const Vec3& x) {
    const double h2 = kHeight * kHeight;
    return Vec3(16.0 * x.y() * x.z() * (kHeight - x.y()) * (kHeight - x.z()) / (h2 * h2), 0.0, 0.0);
  };
  // The inflow amplitude is fixed by the flow; the flow of U_m times the interpolated
  // shape makes the amplitude U_m exactly.
  std::vector<Vec3> shape(mesh.nodes.size(), Vec3::Zero());
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    if (mesh.face_group[f] == inlet)
      for (int n : mesh.faces[f]) shape[static_cast<size_t>(n)] = so.inlet_velocity(mesh.nodes[static_cast<size_t>(n)]);
  const double q_out = kUm * group_fluxes(mesh, shape)[static_cast<size_t>(inlet)];
  std::vector<GroupCondition> cond(mesh.groups.size(), GroupCondition::at_pressure(0.0));
  cond[static_cast<size_t>(inlet)] = GroupCondition::with_flow(q_out);
  const StokesSolution sol = solve_stokes(mesh, std::span<const GroupCondition>(cond), so);

  ObstacleResult r;
  r.forces = named_forces(mesh, sol, so);
  const Vec3 f = boundary_forces(mesh, sol, so)[static_cast<size_t>(obstacle)];
  const double scale = 2.0 / (kRho * kMeanVelocity * kMeanVelocity * kDiameter * kHeight);
  r.drag_coefficient = scale * f.x();
  r.lift_coefficient = scale * f.y();
  const FieldSampler sampler(mesh, sol);
  const auto front = sampler.at(Vec3(0.45, 0.2, 0.205)), back = sampler.at(Vec3(0.55, 0.2, 0.205));
  if (!front || !back) throw_numerical_error("fem dfg_3d_1z: the pressure points are outside the mesh");
  r.pressure_difference = front->pressure - back->pressure;
  r.tets = mesh.num_tets();
  r.unknowns = sol.unknowns;
  r.newton_iterations = sol.newton_iterations;
  r.mesh_seconds = mesh.mesh_seconds;
  r.solve_seconds = sol.assemble_seconds + sol.solve_seconds;
  if (!out_dir.empty()) {
    write_forces(out_dir, r.forces);
    if (write_vtu_file && rank0()) write_vtu((std::filesystem::path(out_dir) / "fem.vtu").string(), mesh, sol);
  }
  return r;
}

}  // namespace flowire::flow::fem
