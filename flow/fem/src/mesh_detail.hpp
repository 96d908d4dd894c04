#pragma once
// Pieces of the gmsh mesh builders shared by mesh.cpp (network and ShapeDomain lumens) and
// lumen.cpp (a lumen given as a triangulated surface). Not installed.
#include <gmsh.h>

#include <functional>
#include <string>
#include <vector>

#include "flowire/fem/mesh.hpp"

namespace flowire::fem::detail {

/// gmsh is initialized once per process and kept; each build uses its own model.
class GmshModel {
 public:
  explicit GmshModel(bool verbose) {
    static bool initialized = false;
    if (!initialized) {
      gmsh::initialize(0, nullptr, false);
      initialized = true;
    }
    gmsh::option::setNumber("General.Terminal", verbose ? 1 : 0);
    gmsh::option::setNumber("General.Verbosity", verbose ? 5 : 0);
    gmsh::model::add("flowire_fem");
  }
  ~GmshModel() {
    try {
      gmsh::model::mesh::removeSizeCallback();
      gmsh::model::remove();
    } catch (...) {  // NOLINT(bugprone-empty-catch): nothing to do while unwinding
    }
  }
  GmshModel(const GmshModel&) = delete;
  GmshModel& operator=(const GmshModel&) = delete;
};

/// The physical groups every mesh builder needs (the volume, and every boundary group under
/// its name, tagged group index + 1) and their common meshing options (one thread, so the
/// same geometry gives the same mesh; first order here, raised to second order later).
void tag_groups_and_set_options(int volume, const char* volume_name, const std::vector<BoundaryGroup>& groups,
                                const gmsh::vectorpair& surfs, const std::vector<int>& surf_group, int algorithm3d);

/// Mesh size bounds: `mesh_size` everywhere when it is > 0 (returns true); otherwise open
/// bounds for a size callback of `size_factor` × the local radius (returns false).
/// @throws flowire::Error (usage) when neither is positive.
bool set_size_bounds(double mesh_size, double size_factor);

/// Second-order tetrahedra of the current model (one thread), written to `opt.save_msh`.
void generate(const MeshOptions& opt);

/// Nodes, tetrahedra and boundary triangles (by group: `surf_group[k]` for surface
/// `surfs[k]`) of the meshed model into `mesh`.
void extract_mesh(TetMesh& mesh, const gmsh::vectorpair& surfs, const std::vector<int>& surf_group,
                  const std::string& at);

/// Run `build` with gmsh's exceptions turned into flowire errors naming `at`.
TetMesh guarded(const std::string& at, const std::function<TetMesh()>& build);

/// Mesh on rank 0 with `build`; under MPI with more than one rank every rank receives
/// the mesh (or rank 0's error). Collective.
TetMesh build_shared(const std::function<TetMesh()>& build);

}  // namespace flowire::fem::detail
