#pragma once
// One mesh for every MPI rank: rank 0 meshes, the others receive the mesh (or rank 0's
// error). Shared by every mesh builder. Not installed.
#include <functional>

#include "flowire/flow/fem/mesh.hpp"

namespace flowire::flow::fem::detail {

/// Mesh on rank 0 with `build`; under MPI with more than one rank every rank receives
/// the mesh (or rank 0's error, of the same kind). Collective.
TetMesh build_shared(const std::function<TetMesh()>& build);

}  // namespace flowire::flow::fem::detail
