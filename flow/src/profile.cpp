#include "flowire/flow/profile.hpp"

#include <algorithm>
#include <cmath>

namespace flowire::flow {
namespace {
constexpr double kPi = 3.14159265358979323846;

// Power series of J_n(z), n = 0 or 1: sum_m (-1)^m (z/2)^(2m+n) / (m! (m+n)!).
std::complex<double> bessel_series(int n, std::complex<double> z) {
  const std::complex<double> h = 0.5 * z;
  const std::complex<double> h2 = -h * h;
  std::complex<double> term = n == 0 ? std::complex<double>(1.0) : h;
  std::complex<double> sum = term;
  for (int m = 1; m < 400; ++m) {
    term *= h2 / (static_cast<double>(m) * static_cast<double>(m + n));
    sum += term;
    // (|term| ≤ 10⁻¹⁷ |sum| and m > |z|, in squared moduli: no square root a term)
    if (std::norm(term) <= 1e-34 * std::norm(sum) && static_cast<double>(m) * m > std::norm(z)) break;
  }
  return sum;
}
}  // namespace

double laminar_velocity(double flow, double radius, double d) {
  const double rho2 = (d * d) / (radius * radius);
  if (rho2 >= 1.0) return 0.0;
  return 2.0 * flow / (kPi * radius * radius) * (1.0 - rho2);
}

std::complex<double> bessel_j0(std::complex<double> z) { return bessel_series(0, z); }
std::complex<double> bessel_j1(std::complex<double> z) { return bessel_series(1, z); }

double womersley_number(double radius, double omega, double density, double viscosity) {
  return radius * std::sqrt(omega * density / viscosity);
}

std::complex<double> womersley_flow_ratio(double alpha) {
  if (alpha < 1e-3) return {1.0, 0.0};
  const std::complex<double> lambda = alpha * std::polar(1.0, 0.75 * kPi);
  const std::complex<double> f = 1.0 - 2.0 * bessel_j1(lambda) / (lambda * bessel_j0(lambda));
  return std::complex<double>(0.0, -8.0 / (alpha * alpha)) * f;  // Q = πR²G/(iρω)·f
}

double womersley_velocity(std::complex<double> flow_amplitude, double radius, double alpha, double rho,
                          double omega_t) {
  if (rho >= 1.0) return 0.0;
  const std::complex<double> phase = std::polar(1.0, omega_t);
  const double area = kPi * radius * radius;
  if (alpha < 1e-3) return 2.0 * (flow_amplitude * phase).real() / area * (1.0 - rho * rho);
  const std::complex<double> lambda = alpha * std::polar(1.0, 0.75 * kPi);
  const std::complex<double> j0 = bessel_j0(lambda);
  const std::complex<double> shape =
      (1.0 - bessel_j0(lambda * rho) / j0) / (1.0 - 2.0 * bessel_j1(lambda) / (lambda * j0));
  return (flow_amplitude / area * shape * phase).real();
}

WomersleyShape::WomersleyShape(double alpha) : alpha_(alpha) {
  value_.resize(kIntervals + 1);
  slope_.resize(kIntervals + 1);
  // J0(λ) and the flow's denominator once (they were evaluated at every node: half the Bessel
  // series of the table, a twentieth of a pushed run's CPU in the settle against the flow).
  const std::complex<double> lambda = alpha * std::polar(1.0, 0.75 * kPi);
  const std::complex<double> j0 = alpha < 1e-3 ? 1.0 : bessel_j0(lambda);
  const std::complex<double> den = alpha < 1e-3 ? 1.0 : 1.0 - 2.0 * bessel_j1(lambda) / (lambda * j0);
  for (int k = 0; k <= kIntervals; ++k) {
    const double rho = static_cast<double>(k) / kIntervals;
    if (alpha < 1e-3) {  // the laminar limit, 2(1 − ρ²)
      value_[static_cast<size_t>(k)] = 2.0 * (1.0 - rho * rho);
      slope_[static_cast<size_t>(k)] = -4.0 * rho;
      continue;
    }
    value_[static_cast<size_t>(k)] = (1.0 - bessel_j0(lambda * rho) / j0) / den;
    slope_[static_cast<size_t>(k)] = lambda * bessel_j1(lambda * rho) / (j0 * den);
  }
}

std::complex<double> WomersleyShape::operator()(double rho) const {
  if (!(rho < 1.0)) return 0.0;
  const double x = std::max(rho, 0.0) * kIntervals;
  const int k = std::min(static_cast<int>(x), kIntervals - 1);
  const double t = x - k, h = 1.0 / kIntervals;
  const double t2 = t * t, t3 = t2 * t;
  const auto i = static_cast<size_t>(k);
  return (2 * t3 - 3 * t2 + 1) * value_[i] + (t3 - 2 * t2 + t) * h * slope_[i] + (-2 * t3 + 3 * t2) * value_[i + 1] +
         (t3 - t2) * h * slope_[i + 1];
}

}  // namespace flowire::flow
