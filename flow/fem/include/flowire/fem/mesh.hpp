#pragma once
/// @file mesh.hpp
/// @brief The lumen of a vessel network as a tetrahedral mesh (gmsh, OpenCASCADE kernel).
///
/// Geometry: every branch is cut into *pieces*, runs of consecutive collinear segments of
/// one radius, and each piece becomes a cylinder along its axis. A sphere of the largest
/// incident radius is placed at every junction and at every bend (a node where the
/// centerline turns) so that the pieces join smoothly; a collinear radius change is a
/// step. All solids are fused into one volume. The planar end disks of the network ends
/// are the inlet / outlet faces, everything else is wall.
///
/// Checks before anything is built (flowire::Error, input):
/// - a bend whose radius is too large for its turning angle: the inner walls of the two
///   cylinders meet at \f$ r\tan(\theta/2) \f$ from the node, which must be shorter than
///   both adjacent pieces, and \f$ \theta < 170^\circ \f$;
/// - an end piece shorter than the sphere at its other end (the sphere would cut the
///   inlet/outlet face);
/// - self-intersecting branches: two pieces without a common node whose axes come closer
///   than the sum of their radii while the path between them along the network is longer
///   than twice that sum.
///
/// Mesh: tetrahedra of order 2 (10 nodes, boundary nodes on the curved surface), size
/// `mesh_size` or `size_factor` times the radius of the nearest piece; one thread, so
/// the same network gives the same mesh every run.
///
/// Besides a network, a `ShapeDomain` made in code can be meshed: a box or a cylinder
/// with cylinders cut out of it (a channel around an obstacle, a tube around a wire),
/// every face of every solid assigned to a named boundary group. Groups of kind `Wall`
/// are no-slip, as many as wanted (e.g. `wall` and `obstacle`); the others are inlets
/// and outlets with the conditions of stokes.hpp.
#include <array>
#include <string>
#include <vector>

#include "flowire/vessels/network.hpp"

namespace flowire::fem {

using vessels::Network;
using vessels::Vec3;

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

/// @brief Build and mesh the lumen of `net`.
///
/// Under MPI (initialized, more than one rank) rank 0 meshes and every rank receives the
/// same mesh; the call is then collective.
/// @throws flowire::Error (input) when the geometry cannot be built (see the file comment),
/// (numerical) when gmsh fails to mesh it.
TetMesh build_mesh(const Network& net, const MeshOptions& opt = {});

/// @brief A solid of a ShapeDomain: a box or a circular cylinder.
struct Solid {
  enum class Shape { Box, Cylinder };
  /// Faces of a box: −x, +x, −y, +y, −z, +z; of a cylinder: lateral surface, base disk
  /// (at `a`), top disk (at `b`).
  static constexpr int kMaxFaces = 6;
  Shape shape = Shape::Box;
  Vec3 a = Vec3::Zero();  ///< box: lowest corner; cylinder: centre of the base disk
  Vec3 b = Vec3::Zero();  ///< box: highest corner; cylinder: centre of the top disk
  double radius = 0.0;    ///< cylinder radius (m)
  /// Group (index into ShapeDomain::groups) of each face that bounds the fluid; -1: group 0.
  std::array<int, kMaxFaces> face_group{-1, -1, -1, -1, -1, -1};
  /// Holes: target element size on their surface (m); <= 0: the domain's mesh_size.
  double mesh_size = 0.0;

  static Solid box(const Vec3& lo, const Vec3& hi) { return {Shape::Box, lo, hi, 0.0, {-1, -1, -1, -1, -1, -1}, 0.0}; }
  static Solid cylinder(const Vec3& base, const Vec3& top, double r) {
    return {Shape::Cylinder, base, top, r, {-1, -1, -1, -1, -1, -1}, 0.0};
  }
};

/// @brief A fluid domain built in code: `outer` minus the `holes` (obstacles; a hole may
/// reach past the outer solid, e.g. a wire across a tube or along all of it).
///
/// Every face of the fluid boundary lies on a face of one of the solids and gets that
/// face's group (the outer solid is tested first). Element size: `mesh_size` far away,
/// a hole's own `mesh_size` on its surface, growing linearly with the distance d from
/// it: h = min(mesh_size, h_hole + growth·d).
struct ShapeDomain {
  std::string name = "shape domain";  ///< for messages
  Solid outer;
  std::vector<Solid> holes;
  std::vector<BoundaryGroup> groups;  ///< at least one; the first must be a no-slip wall
  double mesh_size = 0.0;             ///< far-field element size (m), > 0
  double growth = 0.3;                ///< size increase per unit distance from a hole (> 0)
};

/// @brief Build and mesh a ShapeDomain (quadratic tetrahedra, boundary nodes on the
/// curved surfaces; one gmsh thread). `opt.mesh_size`, `size_factor` and `inlet_node` are
/// not used. Collective under MPI as the network version.
/// @throws flowire::Error (input) for an invalid domain (sizes, groups, a fluid face on
/// no solid's face, not one connected volume), (numerical) when gmsh fails.
TetMesh build_mesh(const ShapeDomain& domain, const MeshOptions& opt = {});

}  // namespace flowire::fem
