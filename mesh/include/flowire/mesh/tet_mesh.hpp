#pragma once
/// @file tet_mesh.hpp
/// @brief The quadratic tetrahedral mesh every finite-element solve runs on (the flow check of
/// flow/fem, the vessel wall of solid/), its boundary groups, and the options its builders share.
///
/// Builders: the lumen of a vessel network (flow/fem/network_mesh.hpp), a domain built in code
/// from boxes and cylinders (shape_domain.hpp), a real lumen given as a surface (lumen.hpp),
/// the wall of a tube (solid/wall_mesh.hpp). All
/// mesh with gmsh into 10-node tetrahedra whose boundary nodes lie on the curved surface,
/// on one thread, so that the same input gives the same mesh every run; under MPI rank 0
/// meshes and every rank receives the mesh.
#include <array>
#include <string>
#include <vector>

#include "flowire/vessels/network.hpp"

namespace flowire::mesh {

using vessels::Network;
using vessels::Vec3;

/// @brief Options of the mesh builders (sizes, the inlet of a network, gmsh's settings).
struct MeshOptions {
  double mesh_size = 0.0;    ///< target tet size (m); <= 0: size_factor × local radius
  double size_factor = 0.3;  ///< h = size_factor · r of the nearest piece when mesh_size <= 0
  int algorithm3d = 1;       ///< gmsh Mesh.Algorithm3D: 1 Delaunay, 10 HXT
  int inlet_node = -1;       ///< network end taken as inlet; -1: Network::widest_end()
  bool verbose = false;      ///< let gmsh print its log
  std::string save_msh;      ///< if not empty: also write the gmsh mesh (.msh) here
};

/// @brief A boundary part: a no-slip wall, the inlet, or one outlet. A network mesh has
/// one wall, group 0; a ShapeDomain may have several no-slip groups (`wall`, `obstacle`).
struct BoundaryGroup {
  enum class Kind { Wall, Inlet, Outlet };
  Kind kind = Kind::Wall;
  int node = -1;     ///< network end node (inlet / outlet), -1 for a wall or a ShapeDomain group
  std::string name;  ///< network: "wall", "inlet", "outlet_<node>"; ShapeDomain: its own names
  [[nodiscard]] bool no_slip() const { return kind == Kind::Wall; }
};

/// @brief Quadratic tetrahedral mesh.
///
/// Local node order of a tetrahedron: vertices 0–3, then the edge nodes of
/// (0,1), (1,2), (0,2), (0,3), (1,3), (2,3); vertices are ordered so that the straight
/// tetrahedron has positive volume. A boundary triangle: vertices 0–2, then the edge
/// nodes of (0,1), (1,2), (0,2), ordered so that the normal (x1−x0)×(x2−x0) points out.
struct TetMesh {
  std::vector<Vec3> nodes;                ///< (num_nodes) all nodes, vertices and edge nodes
  std::vector<std::array<int, 10>> tets;  ///< (num_tets)
  std::vector<std::array<int, 6>> faces;  ///< (num_faces) boundary triangles
  std::vector<int> face_group;            ///< (num_faces) index into `groups`
  std::vector<BoundaryGroup> groups;      ///< network: 0 wall, 1 inlet, then the outlets in end-node order
  std::vector<int> vertex_index;          ///< (num_nodes) pressure unknown of a vertex, -1 for edge nodes
  int num_vertices = 0;
  double mesh_seconds = 0.0;  ///< geometry + meshing wall time

  [[nodiscard]] int num_nodes() const { return static_cast<int>(nodes.size()); }
  [[nodiscard]] int num_tets() const { return static_cast<int>(tets.size()); }
  /// @brief Index of the group of an end node, or -1.
  [[nodiscard]] int group_of_node(int network_node) const;
  /// @brief Index of the group called `name`, or -1.
  [[nodiscard]] int group_named(const std::string& name) const;
  /// @brief Total volume (curved elements, by quadrature).
  [[nodiscard]] double volume() const;
  /// @brief Area of a boundary group (curved faces, by quadrature).
  [[nodiscard]] double area(int group) const;
};

}  // namespace flowire::mesh
