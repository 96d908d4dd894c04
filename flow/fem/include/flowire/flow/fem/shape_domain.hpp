#pragma once
/// @file shape_domain.hpp
/// @brief A fluid domain built in code and its tetrahedral mesh (gmsh, OpenCASCADE kernel):
/// a box or a cylinder with cylinders cut out of it (a channel around an obstacle, a tube
/// around a wire), every face of every solid assigned to a named boundary group.
///
/// Groups of kind `Wall` are no-slip, as many as wanted (e.g. `wall` and `obstacle`); the
/// others are inlets and outlets with the conditions of stokes.hpp. Each fluid face is
/// classified by a point of it (the middle of its parameter range, which lies on the
/// underlying plane or cylinder even where the face is trimmed).
#include <array>
#include <string>
#include <vector>

#include "flowire/flow/fem/mesh.hpp"

namespace flowire::flow::fem {

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

}  // namespace flowire::flow::fem
