#pragma once
/// @file network_solids.hpp
/// @brief A vessel network's tube as solids for gmsh's OpenCASCADE kernel: one cylinder per run
/// of collinear segments of one radius (a piece), one sphere at each bend and junction, sized by
/// the widest piece there. Their union is the network's lumen (the capsules the wire's contact
/// sees); grown by a wall thickness it is the wall's outer surface. Shared by the flow check's
/// lumen (flow/fem) and the vessel wall (solid/).
#include <gmsh.h>

#include <functional>
#include <string>
#include <vector>

#include "flowire/vessels/network.hpp"

namespace flowire::mesh {

/// @brief A run of collinear segments of one radius: one cylinder from node a to node b.
struct NetworkPiece {
  int a = -1, b = -1;
  double radius = 0.0;
  int branch = -1;
};

/// @brief A sphere at a bend or junction node, of the widest radius there.
struct NetworkSphere {
  int node = -1;
  double radius = 0.0;
  int branch = -1;  ///< the branch of the widest piece there
};

struct NetworkSolids {
  std::vector<NetworkPiece> pieces;
  std::vector<NetworkSphere> spheres;
  std::vector<double> sphere_at;  ///< (num_nodes) sphere radius at a node, 0 if none
};

/// @brief The pieces and spheres of @p net, checked: no zero length or radius, no bend so sharp
/// or radius so large that the tube's inner side folds, no end piece shorter than the sphere
/// behind it, no two vessels that intersect away from their junction.
/// @throws flowire::Error (input) naming @p at and the node, segment or branches at fault.
[[nodiscard]] NetworkSolids make_network_solids(const vessels::Network& net, const std::string& at);

/// @brief A solid's radius as built from its radius r and its branch (a wall's outer surface: r
/// plus that branch's thickness).
using GrownRadius = std::function<double(double radius, int branch)>;

/// @brief Add the solids to the current gmsh model (OpenCASCADE), each radius r of branch b as
/// @p grown(r, b), and fuse them: the dim-tags of the union.
gmsh::vectorpair add_network_solids(const vessels::Network& net, const NetworkSolids& solids, const GrownRadius& grown);

/// @brief Distance from @p x to the nearest of the solids' own surfaces (each cylinder's side,
/// each sphere), grown by @p grown: 0 on any of them, also where another solid covers that part
/// (a point of a face's untrimmed surface tells which surfaces the face belongs to).
[[nodiscard]] double distance_to_network_solid_surfaces(const vessels::Network& net, const NetworkSolids& solids,
                                                        const vessels::Vec3& x, const GrownRadius& grown);

}  // namespace flowire::mesh
