// Mesh convergence on the straight tube: three mesh sizes (the finest 3.7k tets, about a second), the L2 error of the
// velocity against the exact Poiseuille profile and the flow error, with the observed
// orders. Taylor–Hood P2 on a quadratic geometry: the velocity L2 error falls like h³
// (observed 3.0); the asserted slope is 2.5.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "fem_test_cases.hpp"
#include "flowire/flow/fem/element.hpp"
#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/network_mesh.hpp"
#include "flowire/flow/fem/stokes.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

constexpr double kR = 2e-3, kL = 30e-3, kEta = 3.5e-3, kDp = 20.0;

/// Relative L2 error of the FEM velocity against u = umax (1 − ρ²/R²) e_x.
double velocity_l2_error(const TetMesh& mesh, const StokesSolution& sol) {
  const double umax = kDp * kR * kR / (4.0 * kEta * kL);
  double err = 0.0, norm = 0.0, phi[10], g[10][3];
  for (const auto& t : mesh.tets)
    for (const QuadPoint& q : tet_quadrature()) {
      tet_p2(q.xi, phi);
      tet_p2_grad(q.xi, g);
      Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
      Vec3 x = Vec3::Zero(), u = Vec3::Zero();
      for (int i = 0; i < 10; ++i) {
        const auto n = static_cast<size_t>(t[static_cast<size_t>(i)]);
        j += mesh.nodes[n] * Eigen::RowVector3d(g[i][0], g[i][1], g[i][2]);
        x += phi[i] * mesh.nodes[n];
        u += phi[i] * sol.velocity[n];
      }
      const double w = q.weight * j.determinant();
      const double rho2 = x.y() * x.y() + x.z() * x.z();
      const Vec3 exact(umax * (1.0 - rho2 / (kR * kR)), 0.0, 0.0);
      err += w * (u - exact).squaredNorm();
      norm += w * exact.squaredNorm();
    }
  return std::sqrt(err / norm);
}

TEST(FemConvergence, StraightTubeObservedOrder) {
  const auto net = test::tube(kR, kL);
  const double factors[3] = {0.8, 0.56, 0.4};
  double h[3], e_u[3], e_q[3];
  const double q_exact = std::numbers::pi * std::pow(kR, 4) * kDp / (8.0 * kEta * kL);
  for (int k = 0; k < 3; ++k) {
    MeshOptions mo;
    mo.size_factor = factors[k];
    const TetMesh mesh = build_mesh(net, mo);
    std::vector<double> p(mesh.groups.size(), 0.0);
    p[1] = kDp;
    StokesOptions so;
    so.viscosity = kEta;
    const StokesSolution sol = solve_stokes(mesh, p, so);
    h[k] = factors[k] * kR;
    e_u[k] = velocity_l2_error(mesh, sol);
    e_q[k] = std::abs(sol.group_flow[2] / q_exact - 1.0);
    std::printf("h = %.3f mm: %d tets, velocity L2 error %.3e, flow error %.3e\n", h[k] * 1e3, mesh.num_tets(), e_u[k],
                e_q[k]);
  }
  const double order_u = std::log(e_u[0] / e_u[2]) / std::log(h[0] / h[2]);
  const double order_q = std::log(e_q[0] / e_q[2]) / std::log(h[0] / h[2]);
  std::printf("observed order: velocity L2 %.2f, flow %.2f\n", order_u, order_q);
  EXPECT_GT(order_u, 2.5);
  EXPECT_LT(e_u[2], e_u[1]);
  EXPECT_LT(e_u[1], e_u[0]);
}

}  // namespace
}  // namespace flowire::flow::fem
