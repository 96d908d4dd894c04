#pragma once
/// @file mesh.hpp
/// @brief The quadratic tetrahedral mesh of flowire/mesh/tet_mesh.hpp under the FEM's names.
#include "flowire/mesh/tet_mesh.hpp"

namespace flowire::flow::fem {

using mesh::BoundaryGroup;
using mesh::MeshOptions;
using mesh::Network;
using mesh::TetMesh;
using mesh::Vec3;

}  // namespace flowire::flow::fem
