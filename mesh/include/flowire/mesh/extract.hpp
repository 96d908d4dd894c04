#pragma once
// The meshed gmsh model read into a TetMesh (nodes, positively oriented 10-node tetrahedra in
// our local node order, outward boundary triangles by group), shared by every mesh builder.
// Installed with the mesh part; a program including it links gmsh.
#include <gmsh.h>

#include <string>
#include <vector>

#include "flowire/mesh/tet_mesh.hpp"

namespace flowire::mesh {

/// Nodes, tetrahedra and boundary triangles (by group: `surf_group[k]` for surface
/// `surfs[k]`) of the meshed model into `mesh`.
/// @throws flowire::Error (numerical) naming `at` when gmsh produced no tetrahedra or a
/// boundary triangle that belongs to none.
void extract_mesh(TetMesh& mesh, const gmsh::vectorpair& surfs, const std::vector<int>& surf_group,
                  const std::string& at);

/// Edge nodes gmsh could not place on a curved surface (not finite, or farther from their
/// edge's midpoint than half its length) moved to the midpoint, and every tetrahedron whose
/// curved map folds (a non-positive Jacobian at a quadrature point or a vertex) given straight
/// edges, until none is left. Returns the number of tetrahedra straightened.
int repair_edge_nodes(TetMesh& mesh);

}  // namespace flowire::mesh
