// The fluid force on no-slip boundaries of meshes built in code (ShapeDomain): a tube
// (wall force = Δp·A), and a wire along the axis of a tube, whose axial force has the
// closed form of annular Poiseuille flow; the variational (weak-form) force against the
// surface integral of the stress, with their observed orders under refinement.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "fem_test_cases.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/shape_domain.hpp"
#include "flowire/flow/fem/stokes.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kEta = 3.5e-3;

using Kind = BoundaryGroup::Kind;
using test::tube_with_wire;

/// Exact axial force per length on the inner cylinder of annular Poiseuille flow
/// (a ≤ r ≤ R, u(a) = u(R) = 0, pressure gradient −G):
/// u(r) = G/(4η)[R² − r² − (R² − a²) ln(R/r)/ln(R/a)], and 2πaη u'(a) =
/// (πG/2)[(R² − a²)/ln(R/a) − 2a²]; the outer wall takes (πG/2)[2R² − (R² − a²)/ln(R/a)].
double annulus_inner_force(double r_out, double a, double g) {
  return 0.5 * kPi * g * ((r_out * r_out - a * a) / std::log(r_out / a) - 2.0 * a * a);
}
double annulus_outer_force(double r_out, double a, double g) {
  return 0.5 * kPi * g * (2.0 * r_out * r_out - (r_out * r_out - a * a) / std::log(r_out / a));
}

TEST(FemForces, TubeWallTakesThePressureDropTimesTheArea) {
  const double r = 1e-3, l = 4e-3, dp = 10.0;
  const TetMesh mesh = build_mesh(tube_with_wire(r, l, 0.0, 0.35e-3, 0.0));
  ASSERT_EQ(mesh.groups.size(), 3u);
  EXPECT_EQ(mesh.group_named("inlet"), 1);
  EXPECT_NEAR(mesh.area(1) / (kPi * r * r), 1.0, 1e-4);  // curved boundary nodes
  const std::vector<double> p = {0.0, dp, 0.0};
  StokesOptions so;
  so.viscosity = kEta;
  const StokesSolution sol = solve_stokes(mesh, p, so);
  const double q = kPi * std::pow(r, 4) * dp / (8.0 * kEta * l);
  EXPECT_NEAR(sol.group_flow[2] / q, 1.0, 2e-3);
  const auto f = boundary_forces(mesh, sol, so);
  const auto fs = surface_forces(mesh, sol, kEta);
  const double exact = dp * kPi * r * r;
  std::printf("tube wall force: weak form %.8e, surface %.8e, exact %.8e N (rel %.2e, %.2e)\n", f[0].x(), fs[0].x(),
              exact, f[0].x() / exact - 1.0, fs[0].x() / exact - 1.0);
  // The weak-form force on all no-slip nodes balances the open-boundary loads exactly:
  // Δp times the discrete inlet area.
  EXPECT_NEAR(f[0].x() / (dp * mesh.area(1)), 1.0, 1e-9);
  EXPECT_NEAR(f[0].x() / exact, 1.0, 1e-4);
  EXPECT_LT(std::abs(f[0].y()) + std::abs(f[0].z()), 1e-9 * exact);
  EXPECT_NEAR(fs[0].x() / exact, 1.0, 2e-2);
  EXPECT_EQ(f[1], Vec3::Zero());  // open groups carry no force entry
}

struct AnnulusResult {
  double h, wire_error, wall_error, wire_surface_error;
  int tets;
};

AnnulusResult annulus(double h, double h_wire) {
  const double r = 1.5e-3, a = 0.178e-3, l = 1.5e-3, dp = 5.0;
  const TetMesh mesh = build_mesh(tube_with_wire(r, l, a, h, h_wire));
  const int wire = mesh.group_named("obstacle");
  EXPECT_EQ(wire, 3);
  std::vector<double> p(mesh.groups.size(), 0.0);
  p[static_cast<size_t>(mesh.group_named("inlet"))] = dp;
  StokesOptions so;
  so.viscosity = kEta;
  const StokesSolution sol = solve_stokes(mesh, p, so);
  const auto f = boundary_forces(mesh, sol, so);
  const auto fs = surface_forces(mesh, sol, kEta);
  const double g = dp / l;
  const double fw = annulus_inner_force(r, a, g) * l, fo = annulus_outer_force(r, a, g) * l;
  AnnulusResult res{h_wire, f[3].x() / fw - 1.0, f[0].x() / fo - 1.0, fs[3].x() / fw - 1.0, mesh.num_tets()};
  std::printf(
      "annulus h_wire %.3f mm, %d tets, %d unknowns: wire force %.6e N (exact %.6e), weak form %.2e, "
      "surface %.2e; wall %.2e; lateral force on the wire %.1e of the axial\n",
      h_wire * 1e3, mesh.num_tets(), sol.unknowns, f[3].x(), fw, res.wire_error, res.wire_surface_error, res.wall_error,
      std::hypot(f[3].y(), f[3].z()) / fw);
  // The two walls share the load Δp·π(R² − a²) (exactly, for the weak form).
  EXPECT_NEAR((f[0].x() + f[3].x()) / (fw + fo), 1.0, 1e-3);
  return res;
}

TEST(FemForces, CoaxialWireMatchesAnnularPoiseuille) {
  const AnnulusResult coarse = annulus(0.5e-3, 0.08e-3);
  const AnnulusResult fine = annulus(0.35e-3, 0.055e-3);
  EXPECT_LT(std::abs(fine.wire_error), 5e-4);
  EXPECT_LT(std::abs(fine.wall_error), 5e-4);
  const double ratio = coarse.h / fine.h;
  const double order = std::log(std::abs(coarse.wire_error / fine.wire_error)) / std::log(ratio);
  const double order_s = std::log(std::abs(coarse.wire_surface_error / fine.wire_surface_error)) / std::log(ratio);
  std::printf("observed order of the wire force: weak form %.2f, surface integral %.2f\n", order, order_s);
  // Measured: weak form 4.1e-4 -> 2.0e-4 (order 1.9), surface integral 3.4e-2 -> 1.9e-2
  // (order 1.6): the weak form is some 90 times closer on the same field.
  EXPECT_GT(order, 1.5);
  EXPECT_GT(order_s, 1.0);
  EXPECT_LT(10.0 * std::abs(fine.wire_error), std::abs(fine.wire_surface_error));
}

}  // namespace
}  // namespace flowire::flow::fem
