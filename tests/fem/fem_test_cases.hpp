#pragma once
// Networks shared by the fem tests: a straight tube and small Y bifurcations.
#include <cmath>
#include <complex>

#include "flowire/vessels/generators.hpp"
#include "flowire/vessels/network.hpp"

namespace flowire::fem::test {

/// Bessel function J_n of a complex argument by its power series (|z| ≤ 10 here), for
/// Womersley's exact solution.
inline std::complex<double> bessel_j(int n, std::complex<double> z) {
  std::complex<double> term = std::pow(z / 2.0, n);
  for (int k = 1; k <= n; ++k) term /= static_cast<double>(k);
  std::complex<double> sum = term;
  for (int k = 1; k < 200; ++k) {
    term *= -(z / 2.0) * (z / 2.0) / (static_cast<double>(k) * static_cast<double>(k + n));
    sum += term;
    if (std::abs(term) < 1e-17 * std::abs(sum)) break;
  }
  return sum;
}

/// Straight tube along x, radius r, length l, one segment per 5 mm.
inline vessels::Network tube(double r = 2e-3, double l = 30e-3) {
  vessels::StraightTubeParams p;
  p.radius = r;
  p.length = l;
  return vessels::Network::build(vessels::straight_tube(p));
}

/// Y bifurcation at a small scale (parent radius 1 mm) for low Reynolds numbers.
inline vessels::Network y_small(double asymmetry = 0.0) {
  vessels::YBifurcationParams p;
  p.parent_radius = 1e-3;
  p.parent_length = 10e-3;
  p.child_length = 10e-3;
  p.asymmetry = asymmetry;
  return vessels::Network::build(vessels::y_bifurcation(p));
}

}  // namespace flowire::fem::test
