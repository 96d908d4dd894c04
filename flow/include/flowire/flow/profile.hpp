#pragma once
/// @file profile.hpp
/// @brief Velocity profiles in a rigid circular tube: laminar (Poiseuille) and Womersley.
///
/// Sources: the laminar profile is eq. 8 of the published method (the Hagen–Poiseuille
/// parabola); the oscillatory one is Womersley's solution for a sinusoidal pressure gradient
/// in a rigid tube (J. R. Womersley 1955, J. Physiol. 127, 553–563); the Bessel functions
/// are summed from their ascending series (Abramowitz & Stegun, Handbook of Mathematical
/// Functions, eq. 9.1.10).
#include <complex>
#include <vector>

namespace flowire::flow {

/// @brief Laminar axial velocity at distance d from the axis of a tube of radius r
/// carrying flow Q: \f$ u(d) = \frac{2Q}{\pi r^2}\left(1 - \frac{d^2}{r^2}\right) \f$, 0 for d ≥ r.
[[nodiscard]] double laminar_velocity(double flow, double radius, double d);

/// @brief Bessel functions of the first kind J0, J1 of a complex argument (the power series
/// of Abramowitz & Stegun eq. 9.1.10; accurate to ~1e-12 relative for |z| ≤ 60, which covers
/// α ≤ 60). On the ray arg z = 3π/4 they are the Kelvin functions, J0(x i^{3/2}) = ber x + i bei x
/// (A&S 9.9.1).
[[nodiscard]] std::complex<double> bessel_j0(std::complex<double> z);
[[nodiscard]] std::complex<double> bessel_j1(std::complex<double> z);

/// @brief Womersley number \f$ \alpha = r\sqrt{\omega\rho/\eta} \f$.
[[nodiscard]] double womersley_number(double radius, double omega, double density, double viscosity);

/// @brief Flow of the Womersley solution relative to the quasi-steady Poiseuille flow for
/// the same sinusoidal pressure gradient: \f$ \frac{-8i}{\alpha^2}\left(1 - \frac{2J_1(\Lambda)}{\Lambda
/// J_0(\Lambda)}\right) \f$, \f$ \Lambda = i^{3/2}\alpha \f$. |ratio| and arg(ratio) are the amplitude and phase of the
/// reference table (e.g. α = 2: 0.825, −33°).
[[nodiscard]] std::complex<double> womersley_flow_ratio(double alpha);

/// @brief Womersley velocity at relative radius ρ = d/r of the oscillating flow
/// Q(t) = Re[Q̂ e^{iωt}] in a tube of radius r at Womersley number α:
/// \f$ u = \mathrm{Re}\left[\frac{\hat Q}{\pi r^2}
/// \frac{1 - J_0(\Lambda\rho)/J_0(\Lambda)}{1 - 2J_1(\Lambda)/(\Lambda J_0(\Lambda))} e^{i\omega t}\right] \f$.
/// Tends to the laminar profile as α → 0. Allocation-free.
[[nodiscard]] double womersley_velocity(std::complex<double> flow_amplitude, double radius, double alpha, double rho,
                                        double omega_t);

/// @brief The Womersley profile shape of one α as a function of ρ = d/r, tabulated once:
/// \f$ S(\rho) = \frac{1 - J_0(\Lambda\rho)/J_0(\Lambda)}{1 - 2J_1(\Lambda)/(\Lambda J_0(\Lambda))} \f$,
/// so that u = Re[Q̂/(πr²) S(ρ) e^{iωt}] (womersley_velocity). Values and exact derivatives
/// \f$ S'(\rho) = \Lambda J_1(\Lambda\rho)/(J_0(\Lambda)\,(1 - 2J_1(\Lambda)/(\Lambda J_0(\Lambda)))) \f$
/// at 513 points, cubic Hermite interpolation between them: within 1e-7 of the series for
/// α ≤ 25 (tests), at the cost of a table lookup instead of three Bessel series.
class WomersleyShape {
 public:
  explicit WomersleyShape(double alpha);
  /// @brief S(ρ) for 0 ≤ ρ ≤ 1 (0 beyond the wall).
  [[nodiscard]] std::complex<double> operator()(double rho) const;
  [[nodiscard]] double alpha() const { return alpha_; }

 private:
  static constexpr int kIntervals = 512;
  double alpha_;
  std::vector<std::complex<double>> value_, slope_;  ///< (kIntervals + 1) S and dS/dρ at the nodes
};

}  // namespace flowire::flow
