// One mesh for every MPI rank: rank 0 meshes and broadcasts the mesh (nodes, elements,
// faces, groups with their names) or its error, which every rank then throws.
#include "mesh_broadcast.hpp"

#include <mpi.h>

#include <string>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/flow/petsc_runtime.hpp"

namespace flowire::flow::fem::detail {
namespace {

/// Broadcast a vector of trivially copyable values from rank 0 (its size first).
template <class T>
void bcast_vector(std::vector<T>& v, int rank) {
  unsigned long long n = v.size();
  MPI_Bcast(&n, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
  if (rank != 0) v.resize(static_cast<size_t>(n));
  if (n > 0) MPI_Bcast(v.data(), static_cast<int>(n * sizeof(T)), MPI_BYTE, 0, MPI_COMM_WORLD);
}

}  // namespace

/// Mesh on rank 0 with `build`; under MPI with more than one rank every rank receives
/// the mesh (or rank 0's error).
TetMesh build_shared(const std::function<TetMesh()>& build) {
  const int size = flow::mpi_size(), rank = flow::mpi_rank();
  if (size == 1) return build();

  // Rank 0 meshes; the outcome (or the error) goes to every rank.
  TetMesh mesh;
  int status = 0;  // 0 ok, else 1 + ErrorKind
  std::string message;
  if (rank == 0) {
    try {
      mesh = build();
    } catch (const Error& e) {
      status = 1 + static_cast<int>(e.kind());
      message = e.what();
    }
  }
  MPI_Bcast(&status, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (status != 0) {
    std::vector<char> text(message.begin(), message.end());
    bcast_vector(text, rank);
    throw Error(static_cast<ErrorKind>(status - 1), std::string(text.begin(), text.end()));
  }
  std::vector<double> xyz;
  if (rank == 0)
    for (const Vec3& x : mesh.nodes) xyz.insert(xyz.end(), {x.x(), x.y(), x.z()});
  bcast_vector(xyz, rank);
  bcast_vector(mesh.tets, rank);
  bcast_vector(mesh.faces, rank);
  bcast_vector(mesh.face_group, rank);
  bcast_vector(mesh.vertex_index, rank);
  std::vector<int> groups;
  std::vector<char> names;  // group names, each ended by a 0
  if (rank == 0)
    for (const auto& g : mesh.groups) {
      groups.insert(groups.end(), {static_cast<int>(g.kind), g.node});
      names.insert(names.end(), g.name.begin(), g.name.end());
      names.push_back('\0');
    }
  bcast_vector(groups, rank);
  bcast_vector(names, rank);
  MPI_Bcast(&mesh.num_vertices, 1, MPI_INT, 0, MPI_COMM_WORLD);
  MPI_Bcast(&mesh.mesh_seconds, 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  if (rank != 0) {
    mesh.nodes.resize(xyz.size() / 3);
    for (size_t i = 0; i < mesh.nodes.size(); ++i) mesh.nodes[i] = Vec3(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    mesh.groups.clear();
    const char* name = names.data();
    for (size_t k = 0; k + 1 < groups.size(); k += 2) {
      mesh.groups.push_back({static_cast<BoundaryGroup::Kind>(groups[k]), groups[k + 1], std::string(name)});
      name += mesh.groups.back().name.size() + 1;
    }
  }
  return mesh;
}

}  // namespace flowire::flow::fem::detail
