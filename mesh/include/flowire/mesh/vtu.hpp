#pragma once
/// @file vtu.hpp
/// @brief A quadratic tetrahedral mesh with point data as a VTK unstructured grid (.vtu,
/// VTK_QUADRATIC_TETRA), written atomically: ParaView opens it as it is.
#include <filesystem>
#include <string>
#include <vector>

#include "flowire/mesh/tet_mesh.hpp"

namespace flowire::mesh {

/// @brief One point-data array: `components` values per node, node after node.
struct PointField {
  std::string name;
  int components = 1;
  std::vector<double> values;  ///< (nodes × components)
};

/// @brief Write @p mesh with @p fields (the first scalar and the first vector are ParaView's
/// defaults).
/// @throws flowire::Error (usage) when a field's size is not nodes × components.
void write_vtu(const std::filesystem::path& path, const TetMesh& mesh, const std::vector<PointField>& fields);

}  // namespace flowire::mesh
