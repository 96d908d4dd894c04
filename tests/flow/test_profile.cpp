// Velocity profiles in a rigid tube (flow/src/profile.cpp): the laminar parabola, the
// Bessel series against tabulated Kelvin functions and an arbitrary-precision evaluation,
// the Womersley flow ratio against the reference table, and the profile as the solver uses it.
#include "flowire/flow/profile.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include "flow_test_networks.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

using namespace flowire::flow::test;

double rel(std::complex<double> a, std::complex<double> b) { return std::abs(a - b) / std::abs(b); }

TEST(FlowProfile, LaminarParabolaCarriesItsFlowAndVanishesAtTheWall) {
  const double q = 3e-6, r = 2e-3;
  // Centre: twice the mean velocity Q/(πr²); the wall and beyond: 0.
  EXPECT_NEAR(laminar_velocity(q, r, 0.0), 2.0 * q / (M_PI * r * r), 1e-15);
  EXPECT_EQ(laminar_velocity(q, r, r), 0.0);
  EXPECT_EQ(laminar_velocity(q, r, 1.5 * r), 0.0);
  EXPECT_NEAR(laminar_velocity(q, r, 0.5 * r), 0.75 * laminar_velocity(q, r, 0.0), 1e-15);
  // ∫ u 2πd dd over the disk (midpoint rule, O(h²)).
  const int n = 20000;
  double flux = 0.0;
  for (int i = 0; i < n; ++i) {
    const double d = (i + 0.5) / n * r;
    flux += laminar_velocity(q, r, d) * 2.0 * M_PI * d * r / n;
  }
  EXPECT_NEAR(flux, q, 1e-8 * q);
}

TEST(FlowProfile, BesselSeriesEqualsTheKelvinFunctionsAndAnArbitraryPrecisionEvaluation) {
  // J0(x·i^{3/2}) = ber x + i bei x: Abramowitz & Stegun table 9.12 (x = 1, 2, 5; the x = 10
  // value and the others to 17 digits from mpmath 1.3 at 30 digits).
  const std::complex<double> i32 = std::polar(1.0, 0.75 * M_PI);
  const double kelvin[][3] = {{1, 0.98438178121308688, 0.24956604003665972},
                              {2, 0.75173418271380823, 0.97229162730666121},
                              {5, -6.2300824786663577, 0.11603438155020038},
                              {10, 138.84046594163265, 56.370458553906638}};
  for (const auto& k : kelvin) EXPECT_LT(rel(bessel_j0(k[0] * i32), {k[1], k[2]}), 1e-13) << "x = " << k[0];
  EXPECT_LT(rel(bessel_j1(10.0 * i32), {-59.477610426263329, 131.87863917568693}), 1e-13);
  EXPECT_LT(rel(bessel_j0({3.0, -2.0}), {-1.2492348796074222, 0.94798379205773478}), 1e-14);
  EXPECT_LT(rel(bessel_j1({3.0, -2.0}), {0.78014884857925378, 1.2609820602388484}), 1e-14);
  // J0' = −J1 (central differences along the real axis of the analytic function).
  for (const std::complex<double> z : {std::complex<double>(0.7, 0.2), 4.0 * i32, std::complex<double>(-2.0, 5.0)}) {
    const double h = 1e-5;
    const std::complex<double> d = (bessel_j0(z + h) - bessel_j0(z - h)) / (2.0 * h);
    EXPECT_LT(rel(d, -bessel_j1(z)), 1e-9) << z;
  }
}

TEST(FlowProfile, WomersleyNumberOfAnAorta) {
  // r = 1 cm, 75 beats/min (ω = 2π/0.8 s), ρ = 1060 kg/m³, η = 3.5 mPa·s: α = r√(ωρ/η).
  EXPECT_NEAR(womersley_number(0.01, 2 * M_PI / 0.8, 1060.0, 3.5e-3), 15.422822172734750, 1e-13);
}

TEST(FlowProfile, WomersleyFlowRatioEqualsAnArbitraryPrecisionEvaluation) {
  // −8i/α² (1 − 2J1(Λ)/(ΛJ0(Λ))), Λ = i^{3/2}α, by mpmath 1.3 at 40 digits; α = 25 and 40
  // are where the power series cancels most.
  const double ref[][3] = {{0.5, 0.99821297057668253, -0.041589499638108059},
                           {4, 0.14604477537699514, -0.32148051511584706},
                           {25, 0.00070345293614265699, -0.012075769290257558},
                           {40, 0.00017363789914099611, -0.0048232089923062417}};
  for (const auto& r : ref) EXPECT_LT(rel(womersley_flow_ratio(r[0]), {r[1], r[2]}), 1e-11) << "alpha " << r[0];
  // The quasi-steady limit, and the next term: the impedance Z/R = 1/ratio = 1 + iα²/6 + O(α⁴),
  // the inertance 4ρl/(3πr²) of Inertance::Womersley (ωL/R = α²/6).
  EXPECT_EQ(womersley_flow_ratio(0.0), std::complex<double>(1.0, 0.0));
  for (const double alpha : {0.05, 0.1, 0.2}) {
    const std::complex<double> z = 1.0 / womersley_flow_ratio(alpha);
    EXPECT_NEAR(z.imag() / (alpha * alpha / 6.0), 1.0, 0.1 * alpha * alpha) << alpha;
    EXPECT_NEAR(z.real(), 1.0, 0.01 * std::pow(alpha, 4)) << alpha;
  }
  // The profile shape S(ρ), same reference: u(Q̂ = 1, r = 1, ωt = 0) = Re S/π, at ωt = −π/2 Im S/π.
  const double shape[][4] = {{17, 0.5, 1.0788754291686747, -0.094787462842053579},
                             {17, 0.95, 0.61029852157822058, 0.29415528533915835},
                             {3, 0.3, 1.7447017927783347, -0.22359742365991579}};
  for (const auto& s : shape) {
    const std::complex<double> got(womersley_velocity({1.0, 0.0}, 1.0, s[0], s[1], 0.0),
                                   womersley_velocity({1.0, 0.0}, 1.0, s[0], s[1], -0.5 * M_PI));
    EXPECT_LT(rel(M_PI * got, {s[2], s[3]}), 1e-12) << "alpha " << s[0] << " rho " << s[1];
  }
}

TEST(FlowProfile, BesselAndWomersleyTableOfReference5) {
  // Reference 5: |Q/Q_Poiseuille| and phase for a sinusoidal pressure gradient.
  const double table[][3] = {{1, 0.986, -9.5}, {2, 0.825, -33}, {3, 0.548, -54}, {5, 0.242, -71}, {10, 0.069, -81}};
  for (const auto& row : table) {
    const auto ratio = womersley_flow_ratio(row[0]);
    EXPECT_NEAR(std::abs(ratio), row[1], 0.006) << "alpha " << row[0];
    EXPECT_NEAR(std::arg(ratio) * 180.0 / M_PI, row[2], 1.0) << "alpha " << row[0];
  }
  EXPECT_NEAR(bessel_j0(2.0).real(), 0.22389077914123567, 1e-14);
  EXPECT_NEAR(bessel_j1(2.0).real(), 0.57672480775687339, 1e-14);
  // The Womersley profile carries the flow it is given: integrate over the disk.
  for (double alpha : {0.5, 3.0, 12.0}) {
    const std::complex<double> qhat(2e-6, -1e-6);
    const double r = 1e-3;
    for (double wt : {0.0, 1.0, 2.5}) {
      double q = 0.0;
      const int n = 4000;
      for (int i = 0; i < n; ++i) {
        const double rho = (i + 0.5) / n;
        q += womersley_velocity(qhat, r, alpha, rho, wt) * 2.0 * M_PI * rho * r * r / n;
      }
      EXPECT_NEAR(q, (qhat * std::polar(1.0, wt)).real(), 2e-6 * std::abs(qhat)) << alpha;
    }
  }
}

TEST(FlowProfile, TabulatedWomersleyShapeEqualsTheBesselSeries) {
  // Between its nodes the table interpolates; it must agree with the series everywhere,
  // including inside the Stokes layer at the wall at aortic α.
  for (double alpha : {0.0, 0.5, 3.0, 10.0, 17.0, 25.0}) {
    const WomersleyShape shape(alpha);
    double worst = 0.0;
    for (int i = 0; i <= 5000; ++i) {
      const double rho = i / 5000.0 * (1.0 - 1e-12);
      const double direct = womersley_velocity({1.0, 0.0}, 1.0, alpha, rho, 0.0);
      const double direct_im = womersley_velocity({1.0, 0.0}, 1.0, alpha, rho, -0.5 * M_PI);
      const std::complex<double> table = shape(rho) / M_PI;
      worst = std::max({worst, std::abs(table.real() - direct), std::abs(table.imag() - direct_im)});
    }
    EXPECT_LT(worst, 1e-7 * 2.0 / M_PI) << alpha;  // of the laminar centre value 2/π
  }
}

TEST(FlowProfile, WomersleyProfileOfAMeasuredWaveformIsTheSumOfItsHarmonics) {
  // A table inlet (as a measured waveform arrives) with a first and a third harmonic:
  // p(t) = p0 + p1 sin ωt + p3 cos 3ωt. In a tube the quasi-steady flow is p(t)/R, so the
  // exact velocity is the parabola of the mean plus the Womersley solutions of α and α√3,
  // summed here with the Bessel series (womersley_velocity), not the solver's tables.
  const double r = 4e-3, len = 0.1, period = 0.8, p0 = 1000, p1 = 600, p3 = 250;
  const Network net = tube(len, r, 2);
  const double omega = 2 * M_PI / period;
  std::vector<double> times, values;
  for (int i = 0; i <= 2000; ++i) {
    const double t = period * i / 2000;
    times.push_back(t);
    values.push_back(p0 + p1 * std::sin(omega * t) + p3 * std::cos(3 * omega * t));
  }
  FlowSpec spec = pressure_spec(net, 0, Waveform::table(times, values), {{net.num_nodes() - 1, 0.0}});
  spec.profile = Profile::Womersley;
  auto s = make_solver(net, spec);
  const double R = 8 * spec.viscosity * len / (M_PI * std::pow(r, 4));
  const double alpha = womersley_number(r, omega, spec.density, spec.viscosity);
  const Vec3 a = net.node(0);
  double worst = 0.0, scale = 0.0;
  for (double t : {0.0, 0.13, 0.37, 0.61}) {
    s->advance(t);
    for (double rho : {0.0, 0.3, 0.7, 0.9, 0.97}) {
      // sin ωt = Re[−i e^{iωt}], cos 3ωt = Re[e^{3iωt}]
      const double exact = 2 * p0 / R / (M_PI * r * r) * (1 - rho * rho) +
                           womersley_velocity({0.0, -p1 / R}, r, alpha, rho, omega * t) +
                           womersley_velocity({p3 / R, 0.0}, r, alpha * std::sqrt(3.0), rho, 3 * omega * t);
      const double u = s->axial_velocity_at(0, a + Vec3(0, rho * r, 0));
      worst = std::max(worst, std::abs(u - exact));
      scale = std::max(scale, std::abs(exact));
    }
  }
  EXPECT_LT(worst, 1e-4 * scale) << "alpha " << alpha;
}

TEST(FlowProfile, WomersleyProfileOptionCarriesTheSegmentFlow) {
  const Network net = tube(0.1, 2e-3, 2);
  FlowSpec spec = pressure_spec(net, 0, Waveform::sine(1200.0, 800.0, 0.5), {{net.num_nodes() - 1, 0.0}});
  spec.profile = Profile::Womersley;
  auto s = make_solver(net, spec);
  const Vec3 a = net.node(0);
  for (double t : {0.0, 0.1, 0.33}) {
    s->advance(t);
    double q = 0.0;
    const int n = 2000;
    for (int i = 0; i < n; ++i) {
      const double d = (i + 0.5) / n * 2e-3;
      q += s->axial_velocity_at(0, a + Vec3(0, d, 0)) * 2.0 * M_PI * d * 2e-3 / n;
    }
    EXPECT_NEAR(q, s->segment_flow(0), 1e-5 * std::abs(s->segment_flow(0)));
  }
  EXPECT_GT(s->segment_state(0).womersley, 0.0);
}

}  // namespace
}  // namespace flowire::flow
