// The compressible neo-Hookean law: energy, first Piola–Kirchhoff stress and its tangent,
// written from the formulas in neo_hookean.hpp.
#include "flowire/solid/neo_hookean.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "flowire/common/error.hpp"

namespace flowire::solid {

NeoHookean NeoHookean::from_young_poisson(double young, double poisson, const char* where) {
  if (!(young > 0.0) || !std::isfinite(young))
    throw_usage_error(fmt::format("{}: Young's modulus must be a positive number of Pa, got {}", where, young));
  if (!(poisson > -1.0 && poisson < 0.5))
    throw_usage_error(
        fmt::format("{}: Poisson's ratio must lie in (-1, 0.5) for a compressible law, got {} (0.5 is incompressible)",
                    where, poisson));
  return {young / (2.0 * (1.0 + poisson)), young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson))};
}

namespace {

/// J − 1 of F = I + H from H's invariants: tr H + i₂ + i₃, i₂ = ½((tr H)² − tr H²), i₃ = det H.
double j_minus_one(const Mat3& h, double* i2_plus_i3 = nullptr) {
  const double tr = h.trace();
  const double rest = 0.5 * (tr * tr - (h * h).trace()) + h.determinant();
  if (i2_plus_i3) *i2_plus_i3 = rest;
  return tr + rest;
}

}  // namespace

double NeoHookean::energy(const Mat3& H) const {
  // W = μ/2 |H|² + μ tr H − μ ln J + λ/2 ln²J, and μ tr H − μ ln J = −μ(i₂ + i₃) + μ(j − ln(1 + j)):
  // every term second order in H, none cancels.
  double rest = 0.0;
  const double j = j_minus_one(H, &rest);
  if (!(j > -1.0)) return std::numeric_limits<double>::infinity();
  const double lnJ = std::log1p(j);
  double j_minus_log;  // j − ln(1 + j), by its series where the difference would cancel
  if (std::abs(j) < 1e-3) {
    j_minus_log = j * j * (0.5 - j * (1.0 / 3.0 - j * (0.25 - j * (0.2 - j / 6.0))));
  } else {
    j_minus_log = j - lnJ;
  }
  return 0.5 * mu * H.squaredNorm() - mu * rest + mu * j_minus_log + 0.5 * lambda * lnJ * lnJ;
}

Mat3 NeoHookean::stress(const Mat3& H) const {
  const Mat3 FinvT = (Mat3::Identity() + H).inverse().transpose();
  const double lnJ = std::log1p(j_minus_one(H));
  return mu * (H + H.transpose() * FinvT) + lambda * lnJ * FinvT;  // F − F⁻ᵀ = H + Hᵀ F⁻ᵀ
}

Tangent NeoHookean::tangent(const Mat3& H) const {
  const double lnJ = std::log1p(j_minus_one(H));
  const Mat3 Fi = (Mat3::Identity() + H).inverse();
  const double c = mu - lambda * lnJ;
  Tangent A;
  for (int D = 0; D < 3; ++D)
    for (int cc = 0; cc < 3; ++cc)
      for (int B = 0; B < 3; ++B)
        for (int a = 0; a < 3; ++a)
          A(a + 3 * B, cc + 3 * D) =
              (a == cc && B == D ? mu : 0.0) + c * Fi(B, cc) * Fi(D, a) + lambda * Fi(B, a) * Fi(D, cc);
  return A;
}

}  // namespace flowire::solid
