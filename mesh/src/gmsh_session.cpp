// The gmsh session the mesh builders share: one gmsh initialization per process, a model per
// build, the physical groups and meshing options every builder sets, the size bounds,
// second-order generation, and gmsh's exceptions turned into flowire errors.
#include "flowire/mesh/gmsh_session.hpp"

#include <fmt/format.h>

#include <exception>

#include "flowire/common/error.hpp"

namespace flowire::mesh {

GmshModel::GmshModel(bool verbose) {
  static bool initialized = false;
  if (!initialized) {
    gmsh::initialize(0, nullptr, false);
    initialized = true;
  }
  gmsh::option::setNumber("General.Terminal", verbose ? 1 : 0);
  gmsh::option::setNumber("General.Verbosity", verbose ? 5 : 0);
  gmsh::model::add("flowire_fem");
}

GmshModel::~GmshModel() {
  try {
    gmsh::model::mesh::removeSizeCallback();
    gmsh::model::remove();
  } catch (...) {  // NOLINT(bugprone-empty-catch): nothing to do while unwinding
  }
}

void tag_groups_and_set_options(int volume, const char* volume_name, const std::vector<BoundaryGroup>& groups,
                                const gmsh::vectorpair& surfs, const std::vector<int>& surf_group, int algorithm3d) {
  gmsh::model::addPhysicalGroup(3, {volume}, 1);
  gmsh::model::setPhysicalName(3, 1, volume_name);
  for (size_t gi = 0; gi < groups.size(); ++gi) {
    std::vector<int> tags;
    for (size_t k = 0; k < surfs.size(); ++k)
      if (surf_group[k] == static_cast<int>(gi)) tags.push_back(surfs[k].second);
    const int tag = static_cast<int>(gi) + 1;
    gmsh::model::addPhysicalGroup(2, tags, tag);
    gmsh::model::setPhysicalName(2, tag, groups[gi].name);
  }
  set_common_options(algorithm3d);
}

void set_common_options(int algorithm3d) {
  gmsh::option::setNumber("General.NumThreads", 1);
  gmsh::option::setNumber("Mesh.Algorithm3D", algorithm3d);
  gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
  gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
  gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
  gmsh::option::setNumber("Mesh.ElementOrder", 1);
  gmsh::option::setNumber("Mesh.SecondOrderLinear", 0);
  gmsh::option::setNumber("Mesh.LcIntegrationPrecision", 1e-3);
  gmsh::option::setNumber("Mesh.RandomSeed", 1);
}

bool set_size_bounds(double mesh_size, double size_factor) {
  if (mesh_size > 0.0) {
    gmsh::option::setNumber("Mesh.MeshSizeMin", mesh_size);
    gmsh::option::setNumber("Mesh.MeshSizeMax", mesh_size);
    return true;
  }
  if (!(size_factor > 0.0)) throw_usage_error("fem: size_factor must be > 0 when mesh_size is not set");
  gmsh::option::setNumber("Mesh.MeshSizeMin", 0.0);
  gmsh::option::setNumber("Mesh.MeshSizeMax", 1e22);
  return false;
}

/// Second-order tetrahedra of the current model (one thread), written to `save_msh`.
void generate(const MeshOptions& opt) {
  gmsh::model::mesh::generate(3);
  gmsh::model::mesh::setOrder(2);
  if (!opt.save_msh.empty()) gmsh::write(opt.save_msh);
}

/// Run `build` with gmsh's exceptions turned into flowire errors naming `at`.
TetMesh guarded(const std::string& at, const std::function<TetMesh()>& build) {
  try {
    return build();
  } catch (const Error&) {
    throw;
  } catch (const std::string& s) {
    throw_numerical_error(fmt::format("{}: gmsh failed: {}", at, s));
  } catch (const std::exception& e) {
    throw_numerical_error(fmt::format("{}: gmsh failed: {}", at, e.what()));
  } catch (...) {
    throw_numerical_error(fmt::format("{}: gmsh failed", at));
  }
}

}  // namespace flowire::mesh
