#pragma once
/// @file tube_wall.hpp
/// @brief The wall of a straight circular tube, or of a vessel network's tubes, as a quadratic
/// tetrahedral mesh (gmsh).
///
/// The tube's axis is z, from z = 0 to z = length, its wall between inner_radius (the lumen)
/// and outer_radius. A quarter tube (x ≥ 0, y ≥ 0) has two symmetry planes more; it is how
/// an axisymmetric load is solved at a quarter of the cost (Lamé's check).
/// Boundary groups, by name: `lumen`, `outer`, `end_0` (z = 0), `end_1` (z = length), and for
/// a quarter `symmetry_x` (the plane x = 0) and `symmetry_y` (y = 0).
#include "flowire/mesh/tet_mesh.hpp"
#include "flowire/solid/wall_thickness.hpp"
#include "flowire/vessels/network.hpp"

namespace flowire::solid {

/// @brief The tube's geometry and mesh size.
struct TubeWall {
  double inner_radius = 0.0;  ///< lumen radius (m)
  double outer_radius = 0.0;  ///< outer radius (m), > inner_radius
  double length = 0.0;        ///< along z (m)
  double mesh_size = 0.0;     ///< target tetrahedron size (m)
  bool quarter = false;       ///< only x ≥ 0, y ≥ 0
  /// Finer about one point (where a load acts; a mesh study): the size is `refine_size` within
  /// `refine_radius` of `refine_at` and grows by half the distance beyond, up to mesh_size
  /// (refine_size 0: uniform).
  double refine_size = 0.0;
  double refine_radius = 0.0;
  vessels::Vec3 refine_at = vessels::Vec3::Zero();
};

/// @brief Mesh the wall into 10-node tetrahedra whose boundary nodes lie on the cylinders.
/// @throws flowire::Error (usage) for a non-positive size or radii out of order.
mesh::TetMesh mesh_tube_wall(const TubeWall& tube);

/// @brief The wall around a network's lumen: the lumen is the union of the network's capsules
/// (mesh/network_solids.hpp: a cylinder per run of collinear segments, a sphere at each bend and
/// junction — the surface the wire's contact sees), the outer surface the same grown by the
/// wall's thickness, which is the piece's branch's own where `branches` gives one, else
/// `thickness` where > 0, else `thickness_ratio` × each piece's radius (a junction's sphere takes
/// the thickness of its widest branch; where two collinear pieces differ, the outer surface steps).
/// Boundary groups: `lumen`, `outer`, and `end_<node>` for each end of the network (an annulus).
struct NetworkWall {
  double thickness = 0.0;                 ///< (m) > 0: the same everywhere
  double thickness_ratio = 0.0;           ///< used where thickness is 0: a fraction of the local radius
  double mesh_size = 0.0;                 ///< target tetrahedron size (m)
  std::vector<BranchThickness> branches;  ///< branches whose wall differs
};
/// @throws flowire::Error (usage) for a non-positive size or thickness; (input) naming the
/// network for a network a tube cannot be built along (make_network_solids).
mesh::TetMesh mesh_network_wall(const vessels::Network& net, const NetworkWall& wall);

}  // namespace flowire::solid
