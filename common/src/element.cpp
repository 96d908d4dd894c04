// Reference P2/P1 tetrahedron and P2 triangle: basis functions written out in barycentric
// coordinates, and symmetric quadrature rules (Walkington's 14-point degree-5 rule on the
// tetrahedron, the 4-point degree-2 rule, the 6-point degree-4 rule on the triangle).
#include "flowire/common/element.hpp"

#include <vector>

namespace flowire::element {
namespace {

std::vector<QuadPoint> make_tet_rule() {
  std::vector<QuadPoint> q;
  // Orbit of (a, a, a, 1-3a): 4 points.
  auto orbit4 = [&q](double a, double w) {
    const double b = 1.0 - 3.0 * a;
    q.push_back({{a, a, a}, w});
    q.push_back({{b, a, a}, w});
    q.push_back({{a, b, a}, w});
    q.push_back({{a, a, b}, w});
  };
  // Orbit of (a, a, b, b) with b = 1/2 - a: 6 points (barycentric; xi = L1, L2, L3).
  auto orbit6 = [&q](double a, double w) {
    const double b = 0.5 - a;
    const double l[6][4] = {{a, a, b, b}, {a, b, a, b}, {a, b, b, a}, {b, a, a, b}, {b, a, b, a}, {b, b, a, a}};
    for (const auto& p : l) q.push_back({{p[1], p[2], p[3]}, w});
  };
  orbit4(0.0927352503108912264, 0.01224884051939365826);
  orbit4(0.3108859192633006097, 0.01878132095300264180);
  orbit6(0.0455037041256496494, 0.007091003462846911495);
  return q;
}

std::vector<QuadPoint> make_tri_rule() {
  std::vector<QuadPoint> q;
  auto orbit3 = [&q](double a, double w) {
    const double b = 1.0 - 2.0 * a;
    q.push_back({{a, a, 0.0}, 0.5 * w});
    q.push_back({{b, a, 0.0}, 0.5 * w});
    q.push_back({{a, b, 0.0}, 0.5 * w});
  };
  orbit3(0.445948490915965, 0.223381589678011);
  orbit3(0.091576213509771, 0.109951743655322);
  return q;
}

}  // namespace

std::span<const QuadPoint> tet_quadrature() {
  static const std::vector<QuadPoint> rule = make_tet_rule();
  return rule;
}

std::span<const QuadPoint> tet_quadrature_degree2() {
  // Barycentric (a, a, a, b) and its permutations, a = (5 − √5)/20, b = (5 + 3√5)/20.
  static constexpr double a = 0.1381966011250105151795;
  static constexpr double b = 0.5854101966249684544614;
  static constexpr double w = 1.0 / 24.0;
  static const std::vector<QuadPoint> rule = {{{a, a, a}, w}, {{b, a, a}, w}, {{a, b, a}, w}, {{a, a, b}, w}};
  return rule;
}

std::span<const QuadPoint> tri_quadrature() {
  static const std::vector<QuadPoint> rule = make_tri_rule();
  return rule;
}

void tet_p2(const std::array<double, 3>& xi, double* v) {
  const double l[4] = {1.0 - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]};
  for (int i = 0; i < 4; ++i) v[i] = l[i] * (2.0 * l[i] - 1.0);
  for (int e = 0; e < 6; ++e) v[4 + e] = 4.0 * l[kTetEdges[e][0]] * l[kTetEdges[e][1]];
}

void tet_p2_grad(const std::array<double, 3>& xi, double (*g)[3]) {
  const double l[4] = {1.0 - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]};
  static constexpr double dl[4][3] = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int i = 0; i < 4; ++i)
    for (int d = 0; d < 3; ++d) g[i][d] = (4.0 * l[i] - 1.0) * dl[i][d];
  for (int e = 0; e < 6; ++e) {
    const int a = kTetEdges[e][0], b = kTetEdges[e][1];
    for (int d = 0; d < 3; ++d) g[4 + e][d] = 4.0 * (dl[a][d] * l[b] + l[a] * dl[b][d]);
  }
}

void tet_p2_hessian(double (*h)[3][3]) {
  // L_i(2L_i − 1) has second derivatives 4·∇L_i∇L_iᵀ; 4L_aL_b has 4(∇L_a∇L_bᵀ + ∇L_b∇L_aᵀ).
  static constexpr double dl[4][3] = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int i = 0; i < 4; ++i)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) h[i][a][b] = 4.0 * dl[i][a] * dl[i][b];
  for (int e = 0; e < 6; ++e) {
    const int p = kTetEdges[e][0], q = kTetEdges[e][1];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) h[4 + e][a][b] = 4.0 * (dl[p][a] * dl[q][b] + dl[q][a] * dl[p][b]);
  }
}

void tet_p1(const std::array<double, 3>& xi, double* v) {
  v[0] = 1.0 - xi[0] - xi[1] - xi[2];
  v[1] = xi[0];
  v[2] = xi[1];
  v[3] = xi[2];
}

void tri_p2(const std::array<double, 3>& xi, double* v) {
  const double l[3] = {1.0 - xi[0] - xi[1], xi[0], xi[1]};
  for (int i = 0; i < 3; ++i) v[i] = l[i] * (2.0 * l[i] - 1.0);
  for (int e = 0; e < 3; ++e) v[3 + e] = 4.0 * l[kTriEdges[e][0]] * l[kTriEdges[e][1]];
}

void tri_p2_grad(const std::array<double, 3>& xi, double (*g)[2]) {
  const double l[3] = {1.0 - xi[0] - xi[1], xi[0], xi[1]};
  static constexpr double dl[3][2] = {{-1, -1}, {1, 0}, {0, 1}};
  for (int i = 0; i < 3; ++i)
    for (int d = 0; d < 2; ++d) g[i][d] = (4.0 * l[i] - 1.0) * dl[i][d];
  for (int e = 0; e < 3; ++e) {
    const int a = kTriEdges[e][0], b = kTriEdges[e][1];
    for (int d = 0; d < 2; ++d) g[3 + e][d] = 4.0 * (dl[a][d] * l[b] + l[a] * dl[b][d]);
  }
}

}  // namespace flowire::element
