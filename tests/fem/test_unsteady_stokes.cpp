// Time-dependent Stokes (flow/fem/src/unsteady_stokes.cpp) against Womersley's exact
// solution: a straight tube driven by a sinusoidal pressure drop. Fully developed
// oscillating flow satisfies the traction conditions exactly (∂_n u = 0, uniform pressure on
// the end faces), so the outlet flow must follow Womersley's amplitude and phase; BDF2 must
// converge at order 2 in Δt.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>
#include <vector>

#include "fem_test_cases.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/network_mesh.hpp"
#include "flowire/flow/fem/stokes.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

using cd = std::complex<double>;
constexpr double kPi = std::numbers::pi;
constexpr double kR = 2e-3, kL = 10e-3, kEta = 3.5e-3, kRho = 1060.0, kAmp = 10.0;

/// Womersley's flow for the pressure gradient Ĝ e^{iωt}, over Poiseuille's πR⁴Ĝ/(8η):
/// Q̂/Q_P = (8/(iα²)) (1 − 2J₁(Λ)/(Λ J₀(Λ))), Λ = √(−i) α.
cd womersley_ratio(double alpha) {
  const cd lam = std::sqrt(cd(0.0, -1.0)) * alpha;
  return 8.0 / (cd(0.0, 1.0) * alpha * alpha) * (1.0 - 2.0 * test::bessel_j(1, lam) / (lam * test::bessel_j(0, lam)));
}

TEST(FemUnsteady, WomersleyRatioMatchesThePublishedTable) {
  // ../shared/reference (Womersley, rigid tube): α = 2: 0.825, −33°; 3: 0.548, −54°;
  // 5: 0.242, −71°. Checks the Bessel series the next test relies on.
  const double alpha[3] = {2, 3, 5}, mag[3] = {0.825, 0.548, 0.242}, deg[3] = {-33, -54, -71};
  for (int k = 0; k < 3; ++k) {
    const cd r = womersley_ratio(alpha[k]);
    EXPECT_NEAR(std::abs(r), mag[k], 2e-3);
    EXPECT_NEAR(std::arg(r) * 180 / kPi, deg[k], 1.0);
  }
}

/// Complex amplitude of the outlet flow over the last of `periods` periods, with N steps
/// per period of the inlet pressure kAmp·sin(ωt).
cd fem_flow_amplitude(const TetMesh& mesh, double omega, int n, int periods) {
  StokesOptions so;
  so.viscosity = kEta;
  so.density = kRho;
  const double period = 2 * kPi / omega, dt = period / n;
  UnsteadyStokes solver(mesh, so, dt);
  std::vector<GroupCondition> cond(mesh.groups.size(), GroupCondition::at_pressure(0.0));
  cd amp = 0.0;
  for (int s = 1; s <= periods * n; ++s) {
    const double t = s * dt;
    cond[1] = GroupCondition::at_pressure(kAmp * std::sin(omega * t));
    const StokesSolution& sol = solver.step(cond);
    EXPECT_NEAR(solver.time(), t, 1e-12);
    // Discrete Fourier coefficient of Q(t) = Im(Q̂ e^{iωt}) = (Q̂ e^{iωt} − conj)/(2i).
    if (s > (periods - 1) * n)
      amp += sol.group_flow[2] * 2.0 * cd(0.0, 1.0) * std::exp(cd(0.0, -omega * t)) / double(n);
  }
  return amp;
}

TEST(FemUnsteady, StraightTubeFollowsWomersleyAtOrderTwoInTime) {
  const auto net = test::tube(kR, kL);
  MeshOptions mo;
  mo.size_factor = 0.3;
  const TetMesh mesh = build_mesh(net, mo);
  const double alpha = 3.0;  // a proximal coronary artery at 60–70 beats per minute
  const double omega = alpha * alpha * kEta / (kRho * kR * kR);
  const cd exact = womersley_ratio(alpha) * (kPi * std::pow(kR, 4) * (kAmp / kL) / (8 * kEta));
  // Time order against a run with 4× smaller steps on the same mesh (the mesh's own
  // error cancels), and the finest run against Womersley.
  const int steps[4] = {20, 40, 80, 320};
  cd q[4];
  for (int k = 0; k < 4; ++k) {
    q[k] = fem_flow_amplitude(mesh, omega, steps[k], 3);
    const cd ratio = q[k] / exact * womersley_ratio(alpha);
    std::printf("α = 3, %d tets, %d steps per period: |Q/Q_P| %.5f (Womersley %.5f), phase %.3f° (%.3f°), error %.3e\n",
                mesh.num_tets(), steps[k], std::abs(ratio), std::abs(womersley_ratio(alpha)),
                std::arg(ratio) * 180 / kPi, std::arg(womersley_ratio(alpha)) * 180 / kPi,
                std::abs(q[k] / exact - 1.0));
  }
  const double e0 = std::abs(q[0] / q[3] - 1.0), e2 = std::abs(q[2] / q[3] - 1.0);
  const double order = std::log(e0 / e2) / std::log(4.0);
  std::printf("BDF2 error against 320 steps: %.3e (20 steps), %.3e (80 steps): observed order %.2f\n", e0, e2, order);
  EXPECT_GT(order, 1.8);
  EXPECT_LT(std::abs(q[3] / exact - 1.0), testing::tol(2e-3));
}

TEST(FemUnsteady, NavierStokesAndBadStepsAreUsageErrors) {
  const auto net = test::tube(kR, kL);
  MeshOptions mo;
  mo.size_factor = 0.8;
  const TetMesh mesh = build_mesh(net, mo);
  StokesOptions so;
  EXPECT_THROW(UnsteadyStokes(mesh, so, 0.0), Error);
  so.equations = Equations::NavierStokes;
  EXPECT_THROW(UnsteadyStokes(mesh, so, 1e-3), Error);
}

}  // namespace
}  // namespace flowire::flow::fem
