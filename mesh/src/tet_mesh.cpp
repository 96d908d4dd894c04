// The quadratic tetrahedral mesh's own queries: its groups by name and by network end node,
// and its volume and boundary areas integrated over the curved (quadratic) elements.
#include "flowire/mesh/tet_mesh.hpp"

#include <Eigen/Dense>

#include "flowire/common/element.hpp"

namespace flowire::mesh {

using element::QuadPoint;
using element::tet_p2_grad;
using element::tet_quadrature;
using element::tri_p2_grad;
using element::tri_quadrature;

int TetMesh::group_named(const std::string& name) const {
  for (size_t g = 0; g < groups.size(); ++g)
    if (groups[g].name == name) return static_cast<int>(g);
  return -1;
}

int TetMesh::group_of_node(int network_node) const {
  for (size_t g = 0; g < groups.size(); ++g)
    if (groups[g].kind != BoundaryGroup::Kind::Wall && groups[g].node == network_node) return static_cast<int>(g);
  return -1;
}

double TetMesh::volume() const {
  double v = 0.0;
  double grads[10][3];
  for (const auto& t : tets)
    for (const QuadPoint& q : tet_quadrature()) {
      tet_p2_grad(q.xi, grads);
      Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
      for (int k = 0; k < 10; ++k)
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) j(a, b) += nodes[static_cast<size_t>(t[static_cast<size_t>(k)])][a] * grads[k][b];
      v += q.weight * j.determinant();
    }
  return v;
}

double TetMesh::area(int group) const {
  double a = 0.0;
  double grads[6][2];
  for (size_t f = 0; f < faces.size(); ++f) {
    if (face_group[f] != group) continue;
    for (const QuadPoint& q : tri_quadrature()) {
      tri_p2_grad(q.xi, grads);
      Vec3 ts = Vec3::Zero(), tt = Vec3::Zero();
      for (int k = 0; k < 6; ++k) {
        ts += grads[k][0] * nodes[static_cast<size_t>(faces[f][static_cast<size_t>(k)])];
        tt += grads[k][1] * nodes[static_cast<size_t>(faces[f][static_cast<size_t>(k)])];
      }
      a += q.weight * ts.cross(tt).norm();
    }
  }
  return a;
}

}  // namespace flowire::mesh
