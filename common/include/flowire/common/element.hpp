#pragma once
/// @file element.hpp
/// @brief Reference P2 / P1 tetrahedron and P2 triangle: basis functions and quadrature,
/// shared by the finite-element parts (the 3D flow check in flow/fem, the vessel wall in solid/).
///
/// Reference tetrahedron: vertices (0,0,0), (1,0,0), (0,1,0), (0,0,1), barycentric
/// coordinates \f$ L_0 = 1-\xi-\eta-\zeta,\ L_1=\xi,\ L_2=\eta,\ L_3=\zeta \f$.
/// P2 basis: vertex i: \f$ L_i(2L_i-1) \f$; edge (a,b): \f$ 4L_aL_b \f$, edges in the order
/// (0,1), (1,2), (0,2), (0,3), (1,3), (2,3). P1 basis: \f$ L_i \f$.
/// Reference triangle: (0,0), (1,0), (0,1); P2 edges (0,1), (1,2), (0,2).
#include <array>
#include <span>

namespace flowire::element {

/// Edge e of the tetrahedron joins vertices kTetEdges[e][0] and kTetEdges[e][1].
inline constexpr std::array<std::array<int, 2>, 6> kTetEdges{{{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}}};
/// Edge e of the triangle joins vertices kTriEdges[e][0] and kTriEdges[e][1].
inline constexpr std::array<std::array<int, 2>, 3> kTriEdges{{{0, 1}, {1, 2}, {0, 2}}};

/// @brief A quadrature point on a reference element (weights sum to the reference measure).
struct QuadPoint {
  std::array<double, 3> xi;  ///< reference coordinates (the third is 0 on a triangle)
  double weight;
};

/// @brief 14-point rule on the reference tetrahedron, exact for polynomials of degree 5
/// (weights sum to 1/6).
std::span<const QuadPoint> tet_quadrature();
/// @brief 4-point rule on the reference tetrahedron, exact for polynomials of degree 2
/// (weights 1/24): the stiffness of a straight 10-node tetrahedron exactly, the usual rule
/// of solid mechanics with quadratic tetrahedra.
std::span<const QuadPoint> tet_quadrature_degree2();
/// @brief 6-point rule on the reference triangle, exact for degree 4 (weights sum to 1/2):
/// Dunavant's degree-4 rule (Dunavant 1985, Int. J. Numer. Methods Eng. 21, 1129–1148).
std::span<const QuadPoint> tri_quadrature();

/// @brief P2 basis values (10) at reference point xi.
void tet_p2(const std::array<double, 3>& xi, double* values);
/// @brief P2 basis gradients (10 × 3, row per function) with respect to xi.
void tet_p2_grad(const std::array<double, 3>& xi, double (*grads)[3]);
/// @brief P2 basis second derivatives (10 × 3 × 3) with respect to xi (constant on the
/// reference tetrahedron).
void tet_p2_hessian(double (*hess)[3][3]);
/// @brief P1 basis values (4).
void tet_p1(const std::array<double, 3>& xi, double* values);
/// @brief P2 triangle basis values (6) at (s, t) = (xi[0], xi[1]).
void tri_p2(const std::array<double, 3>& xi, double* values);
/// @brief P2 triangle gradients (6 × 2) with respect to (s, t).
void tri_p2_grad(const std::array<double, 3>& xi, double (*grads)[2]);

}  // namespace flowire::element
