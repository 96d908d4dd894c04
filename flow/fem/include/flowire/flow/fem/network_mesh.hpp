#pragma once
/// @file network_mesh.hpp
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
/// the same network gives the same mesh every run. Groups: 0 wall, 1 inlet, then the
/// outlets in end-node order.
#include "flowire/flow/fem/mesh.hpp"

namespace flowire::flow::fem {

/// @brief Build and mesh the lumen of `net`.
///
/// Under MPI (initialized, more than one rank) rank 0 meshes and every rank receives the
/// same mesh; the call is then collective.
/// @throws flowire::Error (input) when the geometry cannot be built (see the file comment),
/// (numerical) when gmsh fails to mesh it.
TetMesh build_mesh(const Network& net, const MeshOptions& opt = {});

}  // namespace flowire::flow::fem
