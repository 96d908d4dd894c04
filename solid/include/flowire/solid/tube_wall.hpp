#pragma once
/// @file tube_wall.hpp
/// @brief The wall of a straight circular tube as a quadratic tetrahedral mesh (gmsh).
///
/// The tube's axis is z, from z = 0 to z = length, its wall between inner_radius (the lumen)
/// and outer_radius. A quarter tube (x ≥ 0, y ≥ 0) has two symmetry planes more; it is how
/// an axisymmetric load is solved at a quarter of the cost (Lamé's check).
/// Boundary groups, by name: `lumen`, `outer`, `end_0` (z = 0), `end_1` (z = length), and for
/// a quarter `symmetry_x` (the plane x = 0) and `symmetry_y` (y = 0).
#include "flowire/mesh/tet_mesh.hpp"

namespace flowire::solid {

/// @brief The tube's geometry and mesh size.
struct TubeWall {
  double inner_radius = 0.0;  ///< lumen radius (m)
  double outer_radius = 0.0;  ///< outer radius (m), > inner_radius
  double length = 0.0;        ///< along z (m)
  double mesh_size = 0.0;     ///< target tetrahedron size (m)
  bool quarter = false;       ///< only x ≥ 0, y ≥ 0
};

/// @brief Mesh the wall into 10-node tetrahedra whose boundary nodes lie on the cylinders.
/// @throws flowire::Error (usage) for a non-positive size or radii out of order.
mesh::TetMesh mesh_tube_wall(const TubeWall& tube);

}  // namespace flowire::solid
