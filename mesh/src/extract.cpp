// The meshed gmsh model read into a TetMesh: gmsh's node order mapped to ours by the
// reference coordinates of its element types, tetrahedra turned to positive volume, and the
// boundary triangles of each group oriented outwards by the tetrahedron behind them.
#include "flowire/mesh/extract.hpp"

#include <fmt/format.h>
#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

#include "flowire/common/element.hpp"
#include "flowire/common/error.hpp"

namespace flowire::mesh {

using element::kTetEdges;
using element::kTriEdges;
namespace {

/// Reference coordinates of the nodes of a gmsh element type -> our local node order.
std::vector<int> local_order(int gmsh_type, int dim) {
  std::string name;
  int d = 0, order = 0, nn = 0, np = 0;
  std::vector<double> coords;
  gmsh::model::mesh::getElementProperties(gmsh_type, name, d, order, nn, coords, np);
  const int nv = dim + 1;
  std::vector<std::array<double, 3>> ref(static_cast<size_t>(nn));
  std::vector<std::array<double, 3>> vert = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int k = 0; k < nn; ++k)
    for (int c = 0; c < 3; ++c)
      ref[static_cast<size_t>(k)][c] = c < dim ? coords[static_cast<size_t>(k * dim + c)] : 0.0;
  std::vector<std::array<double, 3>> ours;
  for (int i = 0; i < nv; ++i) ours.push_back(vert[static_cast<size_t>(i)]);
  if (dim == 3) {
    for (const auto& e : kTetEdges) {
      std::array<double, 3> mid{};
      for (int c = 0; c < 3; ++c) mid[c] = 0.5 * (vert[e[0]][c] + vert[e[1]][c]);
      ours.push_back(mid);
    }
  } else {
    for (const auto& e : kTriEdges) {
      std::array<double, 3> mid{};
      for (int c = 0; c < 3; ++c) mid[c] = 0.5 * (vert[e[0]][c] + vert[e[1]][c]);
      ours.push_back(mid);
    }
  }
  if (static_cast<size_t>(nn) != ours.size())
    throw_numerical_error(
        fmt::format("fem mesh: gmsh element type {} has {} nodes, expected {}", gmsh_type, nn, ours.size()));
  std::vector<int> perm(ours.size(), -1);  // perm[our k] = gmsh k
  for (size_t k = 0; k < ours.size(); ++k)
    for (int j = 0; j < nn; ++j) {
      const auto& r = ref[static_cast<size_t>(j)];
      if (std::abs(r[0] - ours[k][0]) + std::abs(r[1] - ours[k][1]) + std::abs(r[2] - ours[k][2]) < 1e-9) perm[k] = j;
    }
  for (int p : perm)
    if (p < 0) throw_numerical_error("fem mesh: unexpected gmsh reference element");
  return perm;
}

double tet_volume_linear(const TetMesh& m, const std::array<int, 10>& t) {
  const Vec3& x0 = m.nodes[static_cast<size_t>(t[0])];
  return (m.nodes[static_cast<size_t>(t[1])] - x0)
             .cross(m.nodes[static_cast<size_t>(t[2])] - x0)
             .dot(m.nodes[static_cast<size_t>(t[3])] - x0) /
         6.0;
}

}  // namespace

/// Nodes, tetrahedra and boundary triangles (by group: `surf_group[k]` for surface
/// `surfs[k]`) of the meshed model into `mesh`.
void extract_mesh(TetMesh& mesh, const gmsh::vectorpair& surfs, const std::vector<int>& surf_group,
                  const std::string& at) {
  // Nodes and tetrahedra.
  std::vector<std::size_t> node_tags;
  std::vector<double> coords, param;
  gmsh::model::mesh::getNodes(node_tags, coords, param, -1, -1, false, false);
  std::unordered_map<std::size_t, int> index;
  index.reserve(node_tags.size());
  const std::vector<int> tet_perm = local_order(11, 3);
  const std::vector<int> tri_perm = local_order(9, 2);
  std::vector<std::size_t> etags, enodes;
  gmsh::model::mesh::getElementsByType(11, etags, enodes);
  if (etags.empty()) throw_numerical_error(fmt::format("{}: gmsh produced no tetrahedra", at));
  std::unordered_map<std::size_t, size_t> coord_of;
  coord_of.reserve(node_tags.size());
  for (size_t k = 0; k < node_tags.size(); ++k) coord_of[node_tags[k]] = k;
  auto node_index = [&](std::size_t tag) {
    auto [it, inserted] = index.emplace(tag, static_cast<int>(mesh.nodes.size()));
    if (inserted) {
      const size_t k = coord_of.at(tag);
      mesh.nodes.emplace_back(coords[3 * k], coords[3 * k + 1], coords[3 * k + 2]);
    }
    return it->second;
  };
  mesh.tets.resize(etags.size());
  for (size_t e = 0; e < etags.size(); ++e) {
    auto& t = mesh.tets[e];
    for (int k = 0; k < 10; ++k)
      t[static_cast<size_t>(k)] = node_index(enodes[e * 10 + static_cast<size_t>(tet_perm[static_cast<size_t>(k)])]);
    if (tet_volume_linear(mesh, t) < 0.0) {
      // Swap vertices 1 and 2: edges (0,1)<->(0,2), (1,3)<->(2,3); (1,2) stays.
      std::swap(t[1], t[2]);
      std::swap(t[4], t[6]);
      std::swap(t[8], t[9]);
    }
  }
  mesh.vertex_index.assign(mesh.nodes.size(), -1);
  for (const auto& t : mesh.tets)
    for (int k = 0; k < 4; ++k) {
      int& v = mesh.vertex_index[static_cast<size_t>(t[static_cast<size_t>(k)])];
      if (v < 0) v = mesh.num_vertices++;
    }
  // Boundary triangles by group, oriented outwards.
  struct FaceKey {
    std::array<int, 3> v;
    bool operator==(const FaceKey& o) const { return v == o.v; }
  };
  struct FaceHash {
    size_t operator()(const FaceKey& k) const {
      return (static_cast<size_t>(k.v[0]) * 73856093u) ^ (static_cast<size_t>(k.v[1]) * 19349663u) ^
             (static_cast<size_t>(k.v[2]) * 83492791u);
    }
  };
  std::unordered_map<FaceKey, int, FaceHash> face_of;
  for (size_t k = 0; k < surfs.size(); ++k) {
    std::vector<std::size_t> ftags, fnodes;
    gmsh::model::mesh::getElementsByType(9, ftags, fnodes, surfs[k].second);
    for (size_t f = 0; f < ftags.size(); ++f) {
      std::array<int, 6> tri{};
      for (int j = 0; j < 6; ++j) {
        const auto it = index.find(fnodes[f * 6 + static_cast<size_t>(tri_perm[static_cast<size_t>(j)])]);
        if (it == index.end()) throw_numerical_error(fmt::format("{}: a boundary node belongs to no tetrahedron", at));
        tri[static_cast<size_t>(j)] = it->second;
      }
      FaceKey key{{tri[0], tri[1], tri[2]}};
      std::sort(key.v.begin(), key.v.end());
      face_of.emplace(key, static_cast<int>(mesh.faces.size()));
      mesh.faces.push_back(tri);
      mesh.face_group.push_back(surf_group[k]);
    }
  }
  std::vector<char> oriented(mesh.faces.size(), 0);
  static constexpr int kFaceVerts[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (const auto& t : mesh.tets) {
    for (int f = 0; f < 4; ++f) {
      FaceKey key{{t[static_cast<size_t>(kFaceVerts[f][0])], t[static_cast<size_t>(kFaceVerts[f][1])],
                   t[static_cast<size_t>(kFaceVerts[f][2])]}};
      std::sort(key.v.begin(), key.v.end());
      const auto it = face_of.find(key);
      if (it == face_of.end()) continue;
      auto& tri = mesh.faces[static_cast<size_t>(it->second)];
      const Vec3& x0 = mesh.nodes[static_cast<size_t>(tri[0])];
      const Vec3 n = (mesh.nodes[static_cast<size_t>(tri[1])] - x0).cross(mesh.nodes[static_cast<size_t>(tri[2])] - x0);
      const Vec3 opposite = mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(f)])];
      if (n.dot(x0 - opposite) < 0.0) {
        // Swap vertices 1 and 2: edges (0,1)<->(0,2); (1,2) stays.
        std::swap(tri[1], tri[2]);
        std::swap(tri[3], tri[5]);
      }
      oriented[static_cast<size_t>(it->second)] = 1;
    }
  }
  for (char o : oriented)
    if (!o) throw_numerical_error(fmt::format("{}: a boundary triangle has no tetrahedron", at));
}

namespace {
/// Whether the curved tetrahedron's Jacobian is non-positive at a quadrature point or a vertex.
bool folded(const TetMesh& m, const std::array<int, 10>& t) {
  double grads[10][3];
  auto det_at = [&](const std::array<double, 3>& xi) {
    element::tet_p2_grad(xi, grads);
    Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
    for (int k = 0; k < 10; ++k)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) j(a, b) += m.nodes[static_cast<size_t>(t[static_cast<size_t>(k)])][a] * grads[k][b];
    return j.determinant();
  };
  for (const element::QuadPoint& q : element::tet_quadrature())
    if (!(det_at(q.xi) > 0.0)) return true;
  for (const std::array<double, 3>& v : {std::array<double, 3>{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}})
    if (!(det_at(v) > 0.0)) return true;
  return false;
}
}  // namespace

int repair_edge_nodes(TetMesh& mesh) {
  // gmsh places the edge nodes on the reparametrized surface; where it cannot (a handful
  // on a patch seam, left at 1e21) the edge node goes to the chord midpoint.
  for (const auto& t : mesh.tets)
    for (size_t k = 0; k < kTetEdges.size(); ++k) {
      Vec3& x = mesh.nodes[static_cast<size_t>(t[4 + k])];
      const Vec3& a = mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(kTetEdges[k][0])])];
      const Vec3& b = mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(kTetEdges[k][1])])];
      if (!x.allFinite() || (x - 0.5 * (a + b)).norm() > 0.5 * (b - a).norm()) x = 0.5 * (a + b);
    }
  // A curved element that a rough surface folds (non-positive Jacobian at a quadrature point or
  // a vertex) gets straight edges; repeated while any is left.
  int total = 0;
  for (int pass = 0; pass < 8; ++pass) {
    int straightened = 0;
    for (const auto& t : mesh.tets) {
      if (!folded(mesh, t)) continue;
      for (size_t k = 0; k < kTetEdges.size(); ++k)
        mesh.nodes[static_cast<size_t>(t[4 + k])] =
            0.5 * (mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(kTetEdges[k][0])])] +
                   mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(kTetEdges[k][1])])]);
      ++straightened;
    }
    total += straightened;
    if (straightened == 0) break;
  }
  return total;
}

}  // namespace flowire::mesh
