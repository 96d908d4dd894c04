// Navier–Stokes at arterial Reynolds numbers: the element Jacobian against finite
// differences of the residual, a manufactured exact solution with swirl (convection,
// centripetal pressure and an x-dependent swirl all active) with the observed order of
// convergence, Poiseuille at Re = 1000 (an exact Navier–Stokes solution), and a Y
// bifurcation at the inlet Reynolds number of a carotid bifurcation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "fem_test_cases.hpp"
#include "flowire/flow/fem/element.hpp"
#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/network_mesh.hpp"
#include "flowire/flow/fem/stokes.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kEta = 3.5e-3, kRho = 1060.0;

#ifndef FLOWIRE_FEM_SLOW  // the slow binary holds only the mesh study (test names must be unique)
/// Manufactured solution in the tube of radius R along x (length L):
///   u = (U s, −Ω z s q(x), Ω y s q(x)),  s = 1 − (y² + z²)/R²,  q = 1 + ½ sin(2πx/L),
///   p = P₀ (1 − x/L).
/// Divergence-free for any q (∂_y(−z s) + ∂_z(y s) = 0), zero on the wall (s = 0); the
/// swirl changes along x, so (u·∇)u ≠ 0 everywhere. The body force is
/// f = ρ(u·∇)u − ηΔu + ∇p and the open faces carry the traction g = η(∇u)n − p n, both
/// from the closed forms below (Δs = −4/R², Δ(z s) = −8z/R² in the cross-section). The
/// inlet takes u itself as its profile.
struct Manufactured {
  double r, l, u0, omega, p0;

  [[nodiscard]] double q(double x) const { return 1.0 + 0.5 * std::sin(2 * kPi * x / l); }
  [[nodiscard]] double dq(double x) const { return 0.5 * (2 * kPi / l) * std::cos(2 * kPi * x / l); }
  [[nodiscard]] double ddq(double x) const { return -0.5 * std::pow(2 * kPi / l, 2) * std::sin(2 * kPi * x / l); }
  [[nodiscard]] double s(const Vec3& x) const { return 1.0 - (x.y() * x.y() + x.z() * x.z()) / (r * r); }

  [[nodiscard]] Vec3 velocity(const Vec3& x) const {
    const double ss = s(x), qq = q(x.x());
    return {u0 * ss, -omega * x.z() * ss * qq, omega * x.y() * ss * qq};
  }
  [[nodiscard]] double pressure(const Vec3& x) const { return p0 * (1.0 - x.x() / l); }
  /// grad(a, b) = ∂u_a/∂x_b.
  [[nodiscard]] Eigen::Matrix3d gradient(const Vec3& x) const {
    const double y = x.y(), z = x.z(), ss = s(x), qq = q(x.x()), dqq = dq(x.x()), r2 = r * r;
    const double sy = -2 * y / r2, sz = -2 * z / r2;
    Eigen::Matrix3d g;
    g << 0.0, u0 * sy, u0 * sz,                                                    //
        -omega * z * ss * dqq, -omega * z * sy * qq, -omega * (ss + z * sz) * qq,  //
        omega * y * ss * dqq, omega * (ss + y * sy) * qq, omega * y * sz * qq;
    return g;
  }
  [[nodiscard]] Vec3 laplacian(const Vec3& x) const {
    const double y = x.y(), z = x.z(), ss = s(x), qq = q(x.x()), d2 = ddq(x.x()), r2 = r * r;
    return {-4.0 * u0 / r2, -omega * (z * ss * d2 - 8.0 * z * qq / r2), omega * (y * ss * d2 - 8.0 * y * qq / r2)};
  }
  [[nodiscard]] Vec3 body_force(const Vec3& x) const {
    const Vec3 u = velocity(x);
    return kRho * (gradient(x) * u) - kEta * laplacian(x) + Vec3(-p0 / l, 0.0, 0.0);
  }
  [[nodiscard]] Vec3 traction(const Vec3& x, const Vec3& n) const { return kEta * (gradient(x) * n) - pressure(x) * n; }
};

StokesOptions ns_options(const Manufactured& m, Stabilization stab) {
  StokesOptions so;
  so.viscosity = kEta;
  so.density = kRho;
  so.equations = Equations::NavierStokes;
  so.stabilization = stab;
  so.body_force = [m](const Vec3& x) { return m.body_force(x); };
  so.traction = [m](const Vec3& x, const Vec3& n, int) { return m.traction(x, n); };
  so.inlet_velocity = [m](const Vec3& x) { return m.velocity(x); };
  return so;
}

/// Relative L2 errors of velocity and pressure against the manufactured solution.
std::pair<double, double> l2_errors(const TetMesh& mesh, const StokesSolution& sol, const Manufactured& m) {
  double eu = 0.0, nu = 0.0, ep = 0.0, np = 0.0, phi[10], g[10][3], psi[4];
  for (const auto& t : mesh.tets)
    for (const QuadPoint& q : tet_quadrature()) {
      tet_p2(q.xi, phi);
      tet_p2_grad(q.xi, g);
      tet_p1(q.xi, psi);
      Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
      Vec3 x = Vec3::Zero(), u = Vec3::Zero();
      double p = 0.0;
      for (int i = 0; i < 10; ++i) {
        const auto n = static_cast<size_t>(t[static_cast<size_t>(i)]);
        j += mesh.nodes[n] * Eigen::RowVector3d(g[i][0], g[i][1], g[i][2]);
        x += phi[i] * mesh.nodes[n];
        u += phi[i] * sol.velocity[n];
      }
      for (int l = 0; l < 4; ++l)
        p += psi[l] *
             sol.pressure[static_cast<size_t>(mesh.vertex_index[static_cast<size_t>(t[static_cast<size_t>(l)])])];
      const double w = q.weight * j.determinant();
      eu += w * (u - m.velocity(x)).squaredNorm();
      nu += w * m.velocity(x).squaredNorm();
      ep += w * std::pow(p - m.pressure(x), 2);
      np += w * std::pow(m.pressure(x), 2);
    }
  return {std::sqrt(eu / nu), std::sqrt(ep / np)};
}

/// The manufactured solution at the mesh's nodes plus a perturbation of relative size
/// `noise` (so no symmetry hides a wrong derivative).
void manufactured_state(const TetMesh& mesh, const Manufactured& m, std::vector<Vec3>& u, std::vector<double>& p,
                        double noise = 0.1) {
  u.resize(mesh.nodes.size());
  for (size_t n = 0; n < u.size(); ++n) {
    const Vec3& x = mesh.nodes[n];
    u[n] = m.velocity(x) + noise * m.u0 * Vec3(std::sin(3e3 * x.y()), std::cos(2e3 * x.z()), std::sin(1e3 * x.x()));
  }
  p.assign(static_cast<size_t>(mesh.num_vertices), 0.0);
  for (size_t n = 0; n < mesh.nodes.size(); ++n)
    if (mesh.vertex_index[n] >= 0) p[static_cast<size_t>(mesh.vertex_index[n])] = m.pressure(mesh.nodes[n]);
}

/// Largest column error of the element Jacobian against central differences of the
/// residual, relative to the largest Jacobian entry.
double element_jacobian_error(const TetMesh& mesh, int tet, const StokesOptions& so, std::vector<Vec3> u,
                              std::vector<double> p) {
  double res[34], jac[34 * 34], rp[34], rm[34], scratch[34 * 34];
  EXPECT_TRUE(detail::navier_stokes_element(mesh, tet, so, u, p, res, jac));
  double scale = 0.0;
  for (double v : jac) scale = std::max(scale, std::abs(v));
  const auto& t = mesh.tets[static_cast<size_t>(tet)];
  double worst = 0.0;
  for (int col = 0; col < 34; ++col) {
    double* value = nullptr;
    if (col < 30)
      value = &u[static_cast<size_t>(t[static_cast<size_t>(col / 3)])][col % 3];
    else
      value = &p[static_cast<size_t>(mesh.vertex_index[static_cast<size_t>(t[static_cast<size_t>(col - 30)])])];
    const double v0 = *value, h = 1e-6 * std::max(1.0, std::abs(v0));
    *value = v0 + h;
    detail::navier_stokes_element(mesh, tet, so, u, p, rp, scratch);
    *value = v0 - h;
    detail::navier_stokes_element(mesh, tet, so, u, p, rm, scratch);
    *value = v0;
    for (int row = 0; row < 34; ++row) {
      const double fd = (rp[row] - rm[row]) / (2 * h);
      worst = std::max(worst, std::abs(fd - jac[row * 34 + col]) / scale);
    }
  }
  return worst;
}

TEST(FemNavierStokes, ElementJacobianMatchesFiniteDifferences) {
  const auto net = test::tube(2e-3, 10e-3);
  MeshOptions mo;
  mo.size_factor = 0.8;
  const TetMesh mesh = build_mesh(net, mo);
  // Fast flow (element Reynolds number far above 3: τ_C = ρ|u|h/2) and slow flow (below
  // 3: τ_C ∝ |u|²), each with SUPG and without.
  for (double u0 : {1.0, 2e-3}) {
    const Manufactured m{2e-3, 10e-3, u0, u0 / 2e-3, 50.0 * u0};
    std::vector<Vec3> u;
    std::vector<double> p;
    manufactured_state(mesh, m, u, p);
    for (Stabilization stab : {Stabilization::Supg, Stabilization::None}) {
      const StokesOptions so = ns_options(m, stab);
      double worst = 0.0;
      for (int tet = 0; tet < mesh.num_tets(); tet += std::max(1, mesh.num_tets() / 25))
        worst = std::max(worst, element_jacobian_error(mesh, tet, so, u, p));
      std::printf("U = %g m/s, %s: largest Jacobian error %.2e of the largest entry\n", u0,
                  stab == Stabilization::Supg ? "SUPG" : "Galerkin", worst);
      EXPECT_LT(worst, 1e-6);
    }
  }
}

TEST(FemNavierStokes, OutletFaceJacobianMatchesFiniteDifferences) {
  // Flow entering through the outlet (u·n < 0 over most of it) switches the backflow
  // term on; a cross-flow keeps u·n away from 0 at the quadrature points.
  const auto net = test::tube(2e-3, 10e-3);
  MeshOptions mo;
  mo.size_factor = 0.8;
  const TetMesh mesh = build_mesh(net, mo);
  StokesOptions so;
  so.viscosity = kEta;
  so.density = kRho;
  so.equations = Equations::NavierStokes;
  std::vector<Vec3> u(mesh.nodes.size());
  for (size_t n = 0; n < u.size(); ++n)
    u[n] = Vec3(-0.5 + 0.2 * std::sin(2e3 * mesh.nodes[n].y()), 0.3, 0.1 * std::cos(1e3 * mesh.nodes[n].z()));
  const std::vector<double> gp = {0.0, 30.0, 10.0};
  int faces = 0;
  double worst = 0.0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.groups[static_cast<size_t>(mesh.face_group[f])].kind != BoundaryGroup::Kind::Outlet) continue;
    ++faces;
    double res[18], jac[18 * 18], rp[18], rm[18], scratch[18 * 18];
    detail::navier_stokes_face(mesh, static_cast<int>(f), so, u, gp, res, jac);
    double scale = 0.0;
    for (double v : jac) scale = std::max(scale, std::abs(v));
    ASSERT_GT(scale, 0.0);
    for (int col = 0; col < 18; ++col) {
      auto& value = u[static_cast<size_t>(mesh.faces[f][static_cast<size_t>(col / 3)])][col % 3];
      const double v0 = value, h = 1e-7;
      value = v0 + h;
      detail::navier_stokes_face(mesh, static_cast<int>(f), so, u, gp, rp, scratch);
      value = v0 - h;
      detail::navier_stokes_face(mesh, static_cast<int>(f), so, u, gp, rm, scratch);
      value = v0;
      for (int row = 0; row < 18; ++row)
        worst = std::max(worst, std::abs((rp[row] - rm[row]) / (2 * h) - jac[row * 18 + col]) / scale);
    }
  }
  std::printf("%d outlet faces: largest backflow Jacobian error %.2e of the largest entry\n", faces, worst);
  EXPECT_GT(faces, 0);
  EXPECT_LT(worst, 1e-6);
}

struct MmsRun {
  double h, eu, ep;
};

MmsRun mms_run(const Manufactured& m, double factor, Stabilization stab) {
  const auto net = test::tube(m.r, m.l);
  MeshOptions mo;
  mo.size_factor = factor;
  const TetMesh mesh = build_mesh(net, mo);
  // Inlet: the exact velocity as the profile, its amplitude from the exact mean inlet
  // pressure P₀; outlet: the exact traction (group pressure 0). Newton starts from the
  // interpolant of the exact solution: this is about the discretization (the
  // continuation from Stokes is exercised by the tests below).
  std::vector<GroupCondition> cond(mesh.groups.size(), GroupCondition::at_pressure(0.0));
  cond[1] = GroupCondition::at_pressure(m.p0);
  StokesSolution guess;
  manufactured_state(mesh, m, guess.velocity, guess.pressure, 0.0);
  guess.group_pressure.assign(mesh.groups.size(), 0.0);
  StokesOptions so = ns_options(m, stab);
  so.initial_guess = &guess;
  const StokesSolution sol = solve_stokes(mesh, std::span<const GroupCondition>(cond), so);
  MmsRun r{factor * m.r, 0.0, 0.0};
  std::tie(r.eu, r.ep) = l2_errors(mesh, sol, m);
  std::printf("%s h = %.2f mm: %d tets, Re %.0f, %d Newton steps, velocity L2 %.3e, pressure L2 %.3e\n",
              stab == Stabilization::Supg ? "SUPG" : "Galerkin", r.h * 1e3, mesh.num_tets(), sol.reynolds,
              sol.newton_iterations, r.eu, r.ep);
  return r;
}

TEST(FemNavierStokes, ManufacturedSwirlConvergesAtOrderThree) {
  // R = 2 mm, U = 0.5 m/s on the axis: inlet Reynolds number ρ·(U/2)·2R/η = 303 (606 on
  // the peak velocity), swirl up to 0.38 U. The element Reynolds numbers ρ|u|h/η run
  // from about 30 to 100: convection dominates in every element.
  const Manufactured m{2e-3, 10e-3, 0.5, 0.5 / 2e-3, 40.0};
  const double factors[3] = {0.7, 0.5, 0.36};
  MmsRun supg[3];
  for (int k = 0; k < 3; ++k) supg[k] = mms_run(m, factors[k], Stabilization::Supg);
  const double order_u = std::log(supg[0].eu / supg[2].eu) / std::log(supg[0].h / supg[2].h);
  const double order_p = std::log(supg[0].ep / supg[2].ep) / std::log(supg[0].h / supg[2].h);
  std::printf("SUPG observed order: velocity %.2f, pressure %.2f\n", order_u, order_p);
  // Taylor–Hood on a quadratic geometry: velocity h³, pressure h² (at least); SUPG,
  // LSIC and the backflow term are consistent, so they keep these orders.
  EXPECT_GT(order_u, 2.5);
  EXPECT_GT(order_p, 1.7);
  EXPECT_LT(supg[2].eu, 2e-2);
  // Plain Galerkin on the finest mesh: it converges there, less accurately (on the
  // coarsest mesh it has no solution near the exact one at all).
  const MmsRun galerkin = mms_run(m, factors[2], Stabilization::None);
  EXPECT_LT(supg[2].eu, galerkin.eu);
}

TEST(FemNavierStokes, PoiseuilleAtReynoldsThousand) {
  // Fully developed flow solves Navier–Stokes exactly with the pressure conditions
  // (∂_n u = 0 on the end faces): the flow must stay Hagen–Poiseuille's at Re = 1000.
  const double r = 2e-3, l = 30e-3;
  const double vbar = 1000.0 * kEta / (kRho * 2 * r);
  const double dp = 8 * kEta * l * vbar / (r * r);
  const auto net = test::tube(r, l);
  MeshOptions mo;
  mo.size_factor = 0.5;
  const TetMesh mesh = build_mesh(net, mo);
  std::vector<double> p(mesh.groups.size(), 0.0);
  p[1] = dp;
  StokesOptions so;
  so.viscosity = kEta;
  so.density = kRho;
  so.equations = Equations::NavierStokes;
  const StokesSolution sol = solve_stokes(mesh, p, so);
  const double q = kPi * std::pow(r, 4) * dp / (8 * kEta * l);
  std::printf("tube at Re %.1f: flow error %.3e, %d Newton steps, %d density steps\n", sol.reynolds,
              sol.group_flow[2] / q - 1.0, sol.newton_iterations, sol.continuation_steps);
  EXPECT_LT(std::abs(sol.group_flow[2] / q - 1.0), testing::tol(5e-3));
  EXPECT_NEAR(sol.reynolds, 1000.0, 10.0);
}

#endif

/// The symmetric small Y with an inlet flow for Reynolds number `re` (on the inlet's
/// mean velocity and diameter) and both outlets at 0 Pa, by Navier–Stokes (density ρ).
StokesSolution y_at_reynolds(double size_factor, double re, double rho, int* tets = nullptr, double asymmetry = 0.0) {
  const auto net = test::y_small(asymmetry);
  MeshOptions mo;
  mo.size_factor = size_factor;
  const TetMesh mesh = build_mesh(net, mo);
  if (tets) *tets = mesh.num_tets();
  const double area = mesh.area(1);
  const double d = 2 * std::sqrt(area / kPi);
  const double q_in = re * kEta / (kRho * d) * area;
  std::vector<GroupCondition> cond(mesh.groups.size(), GroupCondition::at_pressure(0.0));
  cond[1] = GroupCondition::with_flow(-q_in);
  StokesOptions so;
  so.viscosity = kEta;
  so.density = rho;
  so.equations = Equations::NavierStokes;
  return solve_stokes(mesh, std::span<const GroupCondition>(cond), so);
}

#ifndef FLOWIRE_FEM_SLOW
TEST(FemNavierStokes, YBifurcationAtCarotidReynoldsNumber) {
  // Inlet flow for Re = 600 (the common carotid's peak is a few hundred to about 1000),
  // outlets at a common pressure. Newton reaches it from the Stokes solution; mass is
  // conserved by the discrete divergence constraint; the symmetric Y splits evenly; and
  // the inertia shows in the inlet pressure, against the same problem without it
  // (density 10⁻⁹ of blood's: Stokes with the same inlet profile).
  const StokesSolution ns = y_at_reynolds(0.5, 600.0, kRho);
  const StokesSolution st = y_at_reynolds(0.5, 600.0, kRho * 1e-9);
  const double out = ns.group_flow[2] + ns.group_flow[3];
  std::printf(
      "Y at Re %.0f: inlet pressure %.2f Pa (without inertia %.2f Pa), split %.5f / %.5f, %d Newton steps "
      "in %d density steps, mass balance %.2e\n",
      ns.reynolds, ns.group_pressure[1], st.group_pressure[1], ns.group_flow[2] / out, ns.group_flow[3] / out,
      ns.newton_iterations, ns.continuation_steps, (out + ns.group_flow[1]) / out);
  EXPECT_NEAR(ns.reynolds, 600.0, 1.0);
  EXPECT_LT(std::abs(out + ns.group_flow[1]), 1e-9 * out);
  EXPECT_NEAR(ns.group_flow[2] / out, 0.5, 5e-3);
  EXPECT_GT(std::abs(ns.group_pressure[1] / st.group_pressure[1] - 1.0), 0.05);
}

#endif

#ifdef FLOWIRE_FEM_SLOW
TEST(FemNavierStokesSlow, YBifurcationAtRe600MeshConvergence) {
  // The asymmetric Y (asymmetry 0.3) at Re = 600 on three meshes (ratio 1/√2, the finest
  // about 20k tets): the outlet flow split and the inlet pressure. On these meshes the
  // changes alternate in sign (measured: split 0.6458, 0.6486, 0.6450; inlet pressure
  // 604, 573, 596 Pa), so no order is claimed; asserted: the three meshes agree on the
  // split within 0.5% of the flow and on the inlet pressure within 8%.
  const double factors[3] = {0.6, 0.6 / std::sqrt(2.0), 0.3};
  double p[3], split[3];
  for (int k = 0; k < 3; ++k) {
    int tets = 0;
    const StokesSolution ns = y_at_reynolds(factors[k], 600.0, kRho, &tets, 0.3);
    p[k] = ns.group_pressure[1];
    split[k] = ns.group_flow[2] / (ns.group_flow[2] + ns.group_flow[3]);
    std::printf(
        "size factor %.3f: %d tets, inlet pressure %.4f Pa, split %.5f, %d Newton steps in %d density "
        "steps, %.1f s\n",
        factors[k], tets, p[k], split[k], ns.newton_iterations, ns.continuation_steps,
        ns.assemble_seconds + ns.solve_seconds);
  }
  for (const auto* v : {p, split}) {
    const double d01 = v[0] - v[1], d12 = v[1] - v[2];
    std::printf("changes %.4g then %.4g%s, order %.2f\n", d01, d12, d01 * d12 > 0 ? "" : " (sign changes)",
                std::log(std::abs(d01 / d12)) / std::log(std::sqrt(2.0)));
  }
  EXPECT_LT(*std::max_element(split, split + 3) - *std::min_element(split, split + 3), 5e-3);
  EXPECT_LT((*std::max_element(p, p + 3) - *std::min_element(p, p + 3)) / p[2], 0.08);
}
#endif

}  // namespace
}  // namespace flowire::flow::fem
