// The wall as an elastic solid (solid/src/elastic_solid.cpp, tube_wall.cpp): the assembled
// gradient and tangent against central differences of the energy, Lamé's thick-walled tube
// under internal pressure at the quadratic element's order, rest without loads, the balance
// of the applied loads and the held nodes' reactions, and refusals of bad input.
#include "flowire/solid/elastic_solid.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "flowire/common/element.hpp"
#include "flowire/common/error.hpp"
#include "flowire/solid/tube_wall.hpp"
#include "flowire_test.hpp"

namespace flowire::solid {
namespace {

constexpr double kA = 2e-3, kB = 3e-3;  // lumen and outer radius (m)

ElasticSolid quarter_tube(double h, double length = 1e-3, double nu = 0.45) {
  return {mesh_tube_wall({kA, kB, length, h, true}), NeoHookean::from_young_poisson(1e6, nu)};
}

/// Plane strain, u_z = 0 at both ends and symmetry planes: the quarter tube of any length is
/// Lamé's problem.
void hold_plane_strain_quarter(ElasticSolid& s) {
  const auto& m = s.mesh();
  s.hold(m.group_named("end_0"), {false, false, true});
  s.hold(m.group_named("end_1"), {false, false, true});
  s.hold(m.group_named("symmetry_x"), {true, false, false});
  s.hold(m.group_named("symmetry_y"), {false, true, false});
}

TEST(ElasticSolid, GradientAndTangentAreTheEnergysDerivatives) {
  ElasticSolid s = quarter_tube(1e-3);
  s.support(s.mesh().group_named("outer"), 1e9);
  s.set_pressure(s.mesh().group_named("lumen"), 1.3e4);
  s.nodal_forces()[5] = 0.2;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> d(-1.0, 1.0);
  Eigen::VectorXd u(s.num_dofs()), dir(s.num_dofs());
  for (int i = 0; i < s.num_dofs(); ++i) {
    u[i] = 4e-5 * d(rng);  // strains of a few percent on a 1 mm mesh
    dir[i] = d(rng);
  }
  const Eigen::VectorXd g = s.gradient(u);
  const Eigen::SparseMatrix<double> h = s.hessian(u);
  const double eps = 1e-9;
  const double fd_energy = (s.energy(u + eps * dir) - s.energy(u - eps * dir)) / (2 * eps);
  EXPECT_NEAR(g.dot(dir), fd_energy, 1e-6 * std::abs(fd_energy));
  const Eigen::VectorXd fd_grad = (s.gradient(u + eps * dir) - s.gradient(u - eps * dir)) / (2 * eps);
  const Eigen::VectorXd hd = h * dir;
  EXPECT_LT((hd - fd_grad).norm(), 1e-6 * hd.norm());
  EXPECT_LT((Eigen::MatrixXd(h) - Eigen::MatrixXd(h.transpose())).norm(), 1e-12 * h.norm());
}

TEST(ElasticSolid, NothingMovesWhenNothingPushes) {
  ElasticSolid s{mesh_tube_wall({kA, kB, 4e-3, 1e-3, false}), NeoHookean::from_young_poisson(1e6, 0.45)};
  s.hold(s.mesh().group_named("end_0"));
  s.hold(s.mesh().group_named("end_1"));
  s.support(s.mesh().group_named("outer"), 1e8);
  const SolveReport r = s.solve();
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_EQ(s.displacement().cwiseAbs().maxCoeff(), 0.0);
}

TEST(ElasticSolid, NodalStressOfAHomogeneousStrainIsHookes) {
  // u = ε x, ε small and symmetric: every node's Cauchy stress is λ tr(ε) I + 2μ ε to O(|ε|²),
  // on curved quadratic elements too (the displacement is in their space exactly).
  const ElasticSolid s = quarter_tube(1e-3, 2e-3);
  Mat3 eps;
  eps << 2e-6, 1e-6, -0.5e-6, 1e-6, -3e-6, 0.7e-6, -0.5e-6, 0.7e-6, 1.5e-6;
  Eigen::VectorXd u(s.num_dofs());
  for (int n = 0; n < s.mesh().num_nodes(); ++n) u.segment<3>(3 * n) = eps * s.mesh().nodes[static_cast<size_t>(n)];
  const NeoHookean law = NeoHookean::from_young_poisson(1e6, 0.45);
  const Mat3 hooke = law.lambda * eps.trace() * Mat3::Identity() + 2.0 * law.mu * eps;
  double worst = 0.0;
  for (const Mat3& sigma : s.nodal_stress(u)) worst = std::max(worst, (sigma - hooke).cwiseAbs().maxCoeff());
  EXPECT_LT(worst, 1e-4 * hooke.cwiseAbs().maxCoeff());
  EXPECT_GT(hooke.cwiseAbs().maxCoeff(), 1.0) << "a stress that is not trivially zero";
}

TEST(ElasticSolid, APressureBasisGivesTheLoadOfTheSameField) {
  // p(X) = (1 − s) p₀ + s p₁ along the tube (s = z / length): the basis's product with (p₀, p₁)
  // is the load set_pressure builds from the field itself, face point by face point.
  ElasticSolid s = quarter_tube(1e-3, 3e-3);
  const int lumen = s.mesh().group_named("lumen");
  const double length = 3e-3, p0 = 1300.0, p1 = -450.0;
  const auto b = s.pressure_basis(lumen, 2, [&](const Vec3& x, std::vector<std::pair<int, double>>& w) {
    w.emplace_back(0, 1.0 - x.z() / length);
    w.emplace_back(1, x.z() / length);
  });
  s.set_pressure(lumen, [&](const Vec3& x) { return (1.0 - x.z() / length) * p0 + x.z() / length * p1; });
  const Eigen::VectorXd direct = s.loads();
  const Eigen::VectorXd product = b * Eigen::Vector2d(p0, p1);
  EXPECT_GT(direct.norm(), 0.0);
  EXPECT_LT((product - direct).norm(), 1e-12 * direct.norm());
}

double lame_radial(double r, double p, double E, double nu) {
  const double c = p * kA * kA / (E * (kB * kB - kA * kA));
  return (1 + nu) * c * ((1 - 2 * nu) * r + kB * kB / r);
}

/// L² error of the displacement against Lamé's, relative to the L² norm of Lamé's, by the
/// 14-point rule on the curved elements.
double lame_error(double h, int* newton_iterations = nullptr) {
  const double E = 1e6, nu = 0.45;
  ElasticSolid s = quarter_tube(h, 1e-3, nu);
  hold_plane_strain_quarter(s);
  const double p = 1e-2;  // Pa: p/E = 1e-8, the nonlinear terms 1e-8 of the linear ones
  s.set_pressure(s.mesh().group_named("lumen"), p);
  const SolveReport r = s.solve();
  EXPECT_TRUE(r.converged);
  if (newton_iterations) *newton_iterations = r.iterations;
  double error = 0.0, norm = 0.0;
  for (const auto& tet : s.mesh().tets)
    for (const auto& q : element::tet_quadrature()) {
      double n[10], dn[10][3];
      element::tet_p2(q.xi, n);
      element::tet_p2_grad(q.xi, dn);
      Vec3 x = Vec3::Zero(), u = Vec3::Zero();
      Eigen::Matrix3d jac = Eigen::Matrix3d::Zero();
      for (int k = 0; k < 10; ++k) {
        const Vec3& xk = s.mesh().nodes[static_cast<size_t>(tet[static_cast<size_t>(k)])];
        x += n[k] * xk;
        u += n[k] * s.displacement(tet[static_cast<size_t>(k)]);
        for (int b = 0; b < 3; ++b) jac.col(b) += xk * dn[k][b];
      }
      const double radius = std::hypot(x.x(), x.y());
      const Vec3 exact = lame_radial(radius, p, E, nu) * Vec3(x.x() / radius, x.y() / radius, 0.0);
      const double w = q.weight * jac.determinant();
      error += w * (u - exact).squaredNorm();
      norm += w * exact.squaredNorm();
    }
  return std::sqrt(error / norm);
}

TEST(ElasticSolid, LamesThickTubeConvergesAtTheQuadraticElementsOrder) {
  // ν = 0.45 (arterial tissue is nearly incompressible).
  std::vector<double> hs = {0.5e-3, 0.35e-3, 0.25e-3, 0.18e-3}, errors;
  int iterations = 0;
  for (double h : hs) {
    errors.push_back(lame_error(h, &iterations));
    EXPECT_LE(iterations, 2) << "a load 1e-8 of E is linear: Newton lands in one step";
    std::printf("h = %.3g mm: L2 error %.3e of Lamé's displacement, %d Newton iterations\n", h * 1e3, errors.back(),
                iterations);
  }
  const double slope = testing::loglog_slope(hs, errors);
  std::printf("L2 error against h: slope %.2f\n", slope);
  EXPECT_GT(slope, 2.6);  // P2 with curved (isoparametric) boundaries: O(h³) in L²
  EXPECT_LT(errors.back(), 1e-4);
}

/// Timoshenko's long thin cylindrical shell under a ring load P (N per m of circumference):
/// w(x) = Pβ/2k · e^{−β|x|} (cos β|x| + sin β|x|), k = Et/R², β⁴ = 3(1 − ν²)/R²t²
/// (Timoshenko & Woinowsky-Krieger, Theory of Plates and Shells, §278).
double ring_load_shell(double x, double P, double E, double nu, double R, double t) {
  const double beta = std::pow(3 * (1 - nu * nu) / (R * R * t * t), 0.25);
  const double k = E * t / (R * R);
  const double bx = beta * std::abs(x);
  return P * beta / (2 * k) * std::exp(-bx) * (std::cos(bx) + std::sin(bx));
}

TEST(ElasticSolid, AThinTubeUnderARingLoadBendsAsTimoshenkosShell) {
  // R/t = 50; the load a Gaussian band of pressure on the lumen (σ = t), the ring at z = 0 a
  // symmetry plane. Thin-shell theory leaves out O(t/R) and the transverse shear, O((βt)²):
  // together about 3% here.
  const double R = 5e-3, t = 0.1e-3, E = 1e6, nu = 0.45, P = 1e-4, sigma = t;
  const double beta = std::pow(3 * (1 - nu * nu) / (R * R * t * t), 0.25);
  ElasticSolid s{mesh_tube_wall({R - t / 2, R + t / 2, 6.0 / beta, 0.2e-3, true}),
                 NeoHookean::from_young_poisson(E, nu)};
  const auto& m = s.mesh();
  s.hold(m.group_named("end_0"), {false, false, true});
  s.hold(m.group_named("symmetry_x"), {true, false, false});
  s.hold(m.group_named("symmetry_y"), {false, true, false});
  const double a = R - t / 2;
  auto band = [&](double z) { return std::exp(-z * z / (2 * sigma * sigma)) / (sigma * std::sqrt(2 * M_PI)); };
  s.set_pressure(m.group_named("lumen"), [&](const Vec3& x) { return P * band(x.z()); });
  ASSERT_TRUE(s.solve().converged);
  // The shell's deflection under the band: the ring solution convolved with it (Simpson),
  // the load per unit length of the mid-surface's circumference P·a/R.
  auto shell = [&](double z) {
    const int n = 2000;
    const double lo = -6 * sigma, h = 12 * sigma / n;
    double sum = 0.0;
    for (int i = 0; i <= n; ++i) {
      const double zs = lo + i * h;
      const double w = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
      sum += w * band(zs) * ring_load_shell(z - zs, P * a / R, E, nu, R, t);
    }
    return sum * h / 3;
  };
  const double w0 = shell(0.0);
  double worst = 0.0, fe_max = 0.0;
  for (int n = 0; n < m.num_nodes(); ++n) {
    const Vec3& x = m.nodes[static_cast<size_t>(n)];
    const double r = std::hypot(x.x(), x.y());
    const double ur = s.displacement(n).dot(Vec3(x.x() / r, x.y() / r, 0.0));
    fe_max = std::max(fe_max, ur);
    worst = std::max(worst, std::abs(ur - shell(x.z())));
  }
  std::printf("ring load: shell w(0) %.4e m, 3D largest u_r %.4e m, largest difference %.2f%% of w(0)\n", w0, fe_max,
              100 * worst / w0);
  EXPECT_LT(worst, 0.03 * w0);
}

TEST(ElasticSolid, TheHeldNodesReactionsBalanceTheLoads) {
  ElasticSolid s{mesh_tube_wall({kA, kB, 6e-3, 1e-3, false}), NeoHookean::from_young_poisson(1e6, 0.45)};
  s.hold(s.mesh().group_named("end_0"));
  s.hold(s.mesh().group_named("end_1"));
  // A wire's tip pressing 50 mN outwards on one lumen node midway: a point load, large strains.
  int node = -1;
  for (int n = 0; n < s.mesh().num_nodes(); ++n) {
    const Vec3& x = s.mesh().nodes[static_cast<size_t>(n)];
    if (std::abs(std::hypot(x.x(), x.y()) - kA) < 1e-9 && std::abs(x.z() - 3e-3) < 0.5e-3 &&
        (node < 0 || x.x() > s.mesh().nodes[static_cast<size_t>(node)].x()))
      node = n;
  }
  ASSERT_GE(node, 0);
  s.nodal_forces().segment<3>(3 * node) = Vec3(0.05, 0.0, 0.0);
  const SolveReport r = s.solve();
  ASSERT_TRUE(r.converged);
  EXPECT_GT(s.displacement(node).x(), 0.0);
  // Reactions: the internal forces at the held components (the elastic forces sum to zero
  // over the whole body); with the load they sum to zero.
  const Eigen::VectorXd internal = s.gradient(s.displacement()) + s.loads();
  Vec3 reaction = Vec3::Zero();
  for (int n = 0; n < s.mesh().num_nodes(); ++n)
    for (int c = 0; c < 3; ++c)
      if (s.held(3 * n + c)) reaction[c] += internal[3 * n + c];
  EXPECT_LT((reaction + Vec3(0.05, 0.0, 0.0)).norm(), 1e-8 * 0.05) << reaction.transpose();
}

TEST(ElasticSolid, HalfSolvesGiveTheTangentsInverseBetweenAnyTwoLoads) {
  // bᵀ K⁻¹ c = (L⁻¹ P b)ᵀ (L⁻¹ P c): two sparse loads (one with a repeated and a held component)
  // against a full back-substitution, about a loaded state and again after a new factorization.
  ElasticSolid s{mesh_tube_wall({kA, kB, 4e-3, 1e-3, false}), NeoHookean::from_young_poisson(1e6, 0.45)};
  s.hold(s.mesh().group_named("end_0"));
  s.support(s.mesh().group_named("outer"), 1e8);
  s.set_pressure(s.mesh().group_named("lumen"), 2e4);
  int held = -1;
  for (int i = 0; i < s.num_dofs() && held < 0; ++i)
    if (s.held(i)) held = i;
  ASSERT_GE(held, 0);
  const int n = s.num_dofs();
  const std::vector<std::pair<int, double>> b = {{n / 2, 1.0}, {n / 2 + 1, -0.5}, {n / 2, 0.25}, {held, 3.0}};
  const std::vector<std::pair<int, double>> c = {{n / 3 + 2, 0.7}, {n - 1, 1.1}};
  auto dense = [&](const std::vector<std::pair<int, double>>& v) {
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(n, 1);
    for (const auto& [i, value] : v) x(i, 0) += value;
    return x;
  };
  // Column a of y against column b of z.
  auto sparse_dot = [&](const HalfColumns& y, int ya, const HalfColumns& z, int zb) {
    Eigen::VectorXd w = Eigen::VectorXd::Zero(n);
    for (size_t k = 0; k < z.size(); ++k) w[z.index[k]] = z.value[3 * k + static_cast<size_t>(zb)];
    double sum = 0.0;
    for (size_t k = 0; k < y.size(); ++k) sum += y.value[3 * k + static_cast<size_t>(ya)] * w[y.index[k]];
    return sum;
  };
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) {
      ASSERT_TRUE(s.solve({.keep_tangent = true}).converged);  // a new tangent
    }
    s.linearize();
    // b and c solved together, and c alone (in the first column of its own call).
    HalfColumns both, alone;
    const std::vector<std::vector<std::pair<int, double>>> bc = {b, c}, conly = {c};
    s.half_solve(bc, both);
    s.half_solve(conly, alone);
    EXPECT_LT(both.size(), static_cast<size_t>(n) / 2) << "a forward solve from a few rows reaches most of L";
    const Eigen::MatrixXd bb = dense(b), cc = dense(c);
    Eigen::MatrixXd kc = cc;
    s.tangent_solve(kc);
    Eigen::MatrixXd bb_free = bb;
    bb_free(held, 0) = 0.0;
    const double expected = (bb_free.transpose() * kc)(0, 0);
    EXPECT_NEAR(sparse_dot(both, 0, both, 1), expected, 1e-10 * std::abs(expected)) << "pass " << pass;
    EXPECT_NEAR(sparse_dot(both, 0, alone, 0), expected, 1e-10 * std::abs(expected)) << "pass " << pass;
    Eigen::MatrixXd kb = bb;
    s.tangent_solve(kb);
    const double bkb = (bb_free.transpose() * kb)(0, 0);
    EXPECT_NEAR(sparse_dot(both, 0, both, 0), bkb, 1e-10 * bkb);
  }
}

TEST(ElasticSolid, NodesSolvedTogetherGetTheColumnsEachGetsAlone) {
  // A batch of nodes' unit loads (their reaches share the top separators) against each node
  // solved alone: the same rows and values, and through them the same bᵀ K⁻¹ c against a full
  // back-substitution; nodes spread over the tube and one of them held.
  ElasticSolid s{mesh_tube_wall({kA, kB, 4e-3, 1e-3, false}), NeoHookean::from_young_poisson(1e6, 0.45)};
  s.hold(s.mesh().group_named("end_0"));
  s.support(s.mesh().group_named("outer"), 1e8);
  s.linearize();
  const int nodes = s.mesh().num_nodes();
  std::vector<int> picked;
  for (int k = 0; k < static_cast<int>(ElasticSolid::kHalfSolveBatch); ++k) picked.push_back((k * 7919 + 13) % nodes);
  int held = -1;
  for (int i = 0; i < s.num_dofs() && held < 0; ++i)
    if (s.held(i)) held = i / 3;
  ASSERT_GE(held, 0);
  picked.back() = held;
  std::vector<std::vector<std::pair<int, double>>> loads;
  for (int node : picked)
    for (int c = 0; c < 3; ++c) loads.push_back({{3 * node + c, 1.0}});
  std::vector<HalfColumns> together(picked.size());
  s.half_solve(loads, together);
  auto as_map = [](const HalfColumns& y) {
    std::map<int, std::array<double, 3>> m;
    for (size_t k = 0; k < y.size(); ++k) m[y.index[k]] = {y.value[3 * k], y.value[3 * k + 1], y.value[3 * k + 2]};
    return m;
  };
  for (size_t k = 0; k < picked.size(); ++k) {
    HalfColumns alone;
    const std::vector<std::vector<std::pair<int, double>>> three(loads.begin() + static_cast<long>(3 * k),
                                                                 loads.begin() + static_cast<long>(3 * k + 3));
    s.half_solve(three, alone);
    const auto a = as_map(alone), t = as_map(together[k]);
    ASSERT_EQ(a.size(), t.size()) << "node " << picked[k];
    if (static_cast<int>(k) + 1 == static_cast<int>(picked.size())) {
      EXPECT_EQ(t.size(), 0u) << "a held node has no column";
      continue;
    }
    EXPECT_GT(t.size(), 0u);
    for (const auto& [row, v] : a)
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(t.at(row)[static_cast<size_t>(c)], v[static_cast<size_t>(c)],
                    1e-12 * std::abs(v[static_cast<size_t>(c)]) + 1e-300);
  }
  // Between the first two nodes, against a full solve: (L⁻¹ P b)ᵀ (L⁻¹ P c) = bᵀ K⁻¹ c.
  const auto y0 = as_map(together[0]), y1 = as_map(together[1]);
  double dot = 0.0;
  for (const auto& [row, v] : y0)
    if (auto it = y1.find(row); it != y1.end()) dot += v[0] * it->second[2];
  Eigen::MatrixXd kc = Eigen::MatrixXd::Zero(s.num_dofs(), 1);
  kc(3 * picked[1] + 2, 0) = 1.0;
  s.tangent_solve(kc);
  const double expected = kc(3 * picked[0], 0);
  EXPECT_NEAR(dot, expected, 1e-10 * std::abs(expected));
  EXPECT_NE(expected, 0.0);
  // More than a batch, or loads not three a result: refused.
  std::vector<HalfColumns> too_many(ElasticSolid::kHalfSolveBatch + 1);
  std::vector<std::vector<std::pair<int, double>>> many(3 * too_many.size());
  EXPECT_THROW(s.half_solve(many, too_many), Error);
  std::vector<HalfColumns> two(2);
  EXPECT_THROW(s.half_solve(std::span(loads).first(5), two), Error);
}

TEST(ElasticSolid, RefusesBadGeometryAndLoads) {
  EXPECT_THROW((void)mesh_tube_wall({kA, kA, 1e-3, 1e-3, false}), Error);
  EXPECT_THROW((void)mesh_tube_wall({0.0, kB, 1e-3, 1e-3, false}), Error);
  EXPECT_THROW((void)mesh_tube_wall({kA, kB, 1e-3, 0.0, false}), Error);
  ElasticSolid s = quarter_tube(1e-3);
  EXPECT_THROW(s.support(0, -1.0), Error);
  EXPECT_THROW(s.set_pressure(99, 1.0), Error);
  EXPECT_THROW(s.set_pressure(0, std::nan("")), Error);
  // Nothing held, no support: the tangent is singular (rigid motions), a numerical failure.
  s.set_pressure(s.mesh().group_named("lumen"), 1e3);
  try {
    (void)s.solve();
    ADD_FAILURE() << "a free body solved";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Numerical) << e.what();
  }
}

}  // namespace
}  // namespace flowire::solid
