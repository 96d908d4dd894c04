#pragma once
/// @file lumen.hpp
/// @brief The lumen of a real anatomy: a triangulated surface (image-derived, e.g. a VMTK
/// or Feel++ STL/VTP) meshed into quadratic tetrahedra whose open ends are tagged by the
/// ends of the anatomy's own centerline network.
///
/// Steps (`prepare_lumen`, then `build_mesh`):
/// 1. The surface is read (`.stl`, `.vtp`, `.obj`, legacy `.vtk` polydata) with VTK,
///    polygons split into triangles, coincident points merged, scaled to metres.
/// 2. Its open ends are the loops of boundary edges (an edge of one triangle). A closed
///    surface (capped, or an image's level set rounded at its ends) has none: every vessel
///    is then cut by the plane normal to its centerline `LumenOptions::clip_back` end radii
///    before the centerline's end (triangles split on the plane, within a few radii of the
///    end only), which removes the file's cap and leaves a planar open end. An open end cut
///    so obliquely that the wall would meet its cap at less than 45° (the cap nearly continuing
///    the wall, which step 4 could not tell apart) is cut again the same way, by the plane
///    normal to its centerline just inside the loop's innermost point.
/// 3. Every open end is capped by a fan from its loop's centroid (a plane for a planar
///    loop; the loop's planarity is reported) and matched one to one to the network end
///    nearest its centroid. Their numbers must agree and every match must be closer than
///    `LumenOptions::match_factor` times the larger of the end's radius and the cap's
///    equivalent radius sqrt(area/π).
/// 4. gmsh classifies the closed triangulation into patches (sharp-edge angle 40°, one
///    parametrizable patch per piece), creates the geometry, bounds a volume by all
///    patches, and meshes it: surfaces remeshed to the target size (fixed `mesh_size`, or
///    `size_factor` times the radius of the nearest network segment), then 10-node
///    tetrahedra with the edge nodes on the reparametrized surface. The cap patches are
///    the inlet / outlet groups (named as for a network lumen: `inlet`, `outlet_<node>`),
///    all other patches the wall.
///
/// Errors (flowire::Error, input, naming the surface file and the place): a missing or
/// unreadable file, no triangles, a non-manifold edge, open ends that cross, a number of
/// open ends (or caps) different from the network's ends, a cap farther than allowed from
/// its end, two caps on one end.
#include <array>
#include <string>
#include <vector>

#include "flowire/flow/fem/mesh.hpp"

namespace flowire::flow::fem {

/// @brief A triangulated surface in metres.
struct SurfaceMesh {
  std::string source;                         ///< file it was read from (for messages)
  std::vector<Vec3> points;                   ///< (num_points)
  std::vector<std::array<int, 3>> triangles;  ///< (num_triangles) indices into points
};

/// @brief Read a surface file and scale it to metres (`length_factor`: metres per file unit).
/// @throws flowire::Error (input) naming the file: missing, unreadable, no triangles.
SurfaceMesh read_surface(const std::string& path, double length_factor = 1.0);

struct LumenOptions {
  double match_factor = 2.0;  ///< a cap may lie this many radii from its centerline end
  /// Closed surfaces: each vessel is cut this many end radii before its centerline end.
  double clip_back = 0.5;
};

/// @brief One open end of the lumen and the network end it belongs to.
struct LumenCap {
  int node = -1;                 ///< network end node
  Vec3 centroid = Vec3::Zero();  ///< of the boundary loop (length weighted)
  Vec3 normal = Vec3::Zero();    ///< unit, out of the lumen
  double radius = 0.0;           ///< equivalent radius sqrt(area / π) of the cap (m)
  double distance = 0.0;         ///< from the centroid to the network end node (m)
  double planarity = 0.0;        ///< max distance of the loop from its mean plane / radius
  int loop_points = 0;           ///< points of the boundary loop
  bool was_capped = false;       ///< the surface was closed: this end was cut (clip_back)
};

/// @brief A closed lumen ready to mesh: the wall triangles followed by the fan caps.
struct LumenSurface {
  SurfaceMesh surface;           ///< closed: wall, then the caps' fans
  int wall_triangles = 0;        ///< the first ones are wall
  std::vector<LumenCap> caps;    ///< one per network end, in the order of Network::ends()
  std::vector<int> cap_centre;   ///< (caps) index of the fan's centre point
  double enclosed_volume = 0.0;  ///< of the closed triangulation (divergence theorem), m³
  int recut_ends = 0;            ///< open ends cut again square to their vessel (step 2)
};

/// @brief Find the open ends of `surface`, cap them and match them to the ends of `net`.
/// @throws flowire::Error (input) naming the surface file (see the file comment).
LumenSurface prepare_lumen(const Network& net, SurfaceMesh surface, const LumenOptions& opt = {});

/// @brief Mesh a prepared lumen (see the file comment). Groups: 0 wall, 1 inlet
/// (`opt.inlet_node`, default Network::widest_end()), then the outlets in end-node order.
/// Collective under MPI, as the network version.
/// @throws flowire::Error (input) for bad tagging, (numerical) when gmsh fails.
TetMesh build_mesh(const Network& net, const LumenSurface& lumen, const MeshOptions& opt = {});

}  // namespace flowire::flow::fem
