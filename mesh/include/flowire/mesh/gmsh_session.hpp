#pragma once
// The gmsh session the mesh builders share (the flow check's lumens in flow/fem, the wall in solid/):
// the model's lifetime, the physical groups and meshing options, the size bounds, second-order
// generation, and gmsh's exceptions turned into flowire errors.
#include <gmsh.h>

#include <functional>
#include <string>
#include <vector>

#include "flowire/mesh/tet_mesh.hpp"

namespace flowire::mesh {

/// gmsh is initialized once per process and kept; each build uses its own model, removed
/// (with any size callback) when the build ends, also by an exception.
class GmshModel {
 public:
  explicit GmshModel(bool verbose);
  ~GmshModel();
  GmshModel(const GmshModel&) = delete;
  GmshModel& operator=(const GmshModel&) = delete;
};

/// The physical groups every mesh builder needs (the volume, and every boundary group under
/// its name, tagged group index + 1) and their common meshing options (one thread, so the
/// same geometry gives the same mesh; first order here, raised to second order later).
void tag_groups_and_set_options(int volume, const char* volume_name, const std::vector<BoundaryGroup>& groups,
                                const gmsh::vectorpair& surfs, const std::vector<int>& surf_group, int algorithm3d);

/// The meshing options every build sets (gmsh keeps its options from one model to the next in a
/// process: a build that left any of them unset would mesh differently after another build).
void set_common_options(int algorithm3d);

/// Mesh size bounds: `mesh_size` everywhere when it is > 0 (returns true); otherwise open
/// bounds for a size callback of `size_factor` × the local radius (returns false).
/// @throws flowire::Error (usage) when neither is positive.
bool set_size_bounds(double mesh_size, double size_factor);

/// Second-order tetrahedra of the current model (one thread), written to `opt.save_msh`.
void generate(const MeshOptions& opt);

/// Run `build` with gmsh's exceptions turned into flowire errors (numerical) naming `at`;
/// flowire errors pass through.
TetMesh guarded(const std::string& at, const std::function<TetMesh()>& build);

}  // namespace flowire::mesh
