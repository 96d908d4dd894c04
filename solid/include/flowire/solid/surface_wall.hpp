#pragma once
/// @file surface_wall.hpp
/// @brief The wall around an image-derived lumen surface (a scene's `vessels.surface`) as a
/// quadratic tetrahedral mesh (gmsh): the region between the lumen and the lumen offset
/// outwards by the wall's thickness, closed at every open end by the ring between the end's
/// loop and its offset.
///
/// The lumen. Each open end is first cut square to its vessel (by the plane normal to the
/// network end's axis just inside the rim's innermost point), and the lumen triangulated anew by
/// gmsh at the wall's element size (the image's triangles are small and uneven, and their offset
/// folds).
///
/// The offset. Each lumen vertex moves along its normal (the angle-weighted mean of its faces'
/// outward normals, smoothed over its neighbours twice so that the facets' noise does not crease
/// the outer surface; at an open end turned into the end's plane, so that the end ring is that
/// plane) by its thickness t: that of the branch of the network segment nearest to it where
/// `branches` gives one, else `thickness`, or `thickness_ratio` × that segment's radius. Where the lumen's own shape
/// leaves no room for t — between two branches near their carina, or inside a bend tighter than t — the offset sheets
/// of the two sides would cross; there t is reduced until the point 1.25 t out along the normal still lies at least 0.9
/// × 1.25 t from the lumen (each side then keeps to its half of the tissue between them), and the thickness field is
/// made to vary by at most 30% between neighbours.
///
/// Boundary groups: `lumen`, `outer`, and `end_<node>` for each open end, named by the
/// network's end node whose point lies nearest to the end's loop.
#include "flowire/mesh/tet_mesh.hpp"
#include "flowire/solid/wall_thickness.hpp"
#include "flowire/vessels/network.hpp"
#include "flowire/vessels/surface.hpp"

namespace flowire::solid {

struct SurfaceWall {
  double thickness = 0.0;        ///< (m) > 0: the same everywhere
  double thickness_ratio = 0.0;  ///< used where thickness is 0: a fraction of the local radius
  /// Target tetrahedron size (m); ≤ 0: `size_per_thickness` × the local nominal thickness.
  double mesh_size = 0.0;
  double size_per_thickness = 2.0;
  std::vector<BranchThickness> branches;  ///< branches whose wall differs
};

/// @brief What the offset did.
struct SurfaceWallStats {
  int lumen_vertices = 0;
  int thinned_vertices = 0;    ///< vertices whose thickness was reduced for room
  double min_thickness = 0.0;  ///< (m) after reduction
  double max_thickness = 0.0;  ///< (m)
};

/// @brief Mesh the wall around @p lumen (normals out of the lumen, open at the network's ends).
/// The last four walls built in the process are kept: the same surface, network and sizes give
/// the same mesh again (mesh_seconds 0), which gmsh alone does not in one process.
/// @throws flowire::Error (usage) for a non-positive thickness or size; (input) naming the
/// surface for a non-manifold edge, a pinched open end, an open end no network end lies near or
/// two open ends at one network end, an open end whose ring cannot be told from the lumen.
mesh::TetMesh mesh_surface_wall(const vessels::LumenSurface& lumen, const vessels::Network& net,
                                const SurfaceWall& wall, SurfaceWallStats* stats = nullptr);

/// @brief Forget the kept walls (the next call builds anew).
void forget_kept_walls();

}  // namespace flowire::solid
