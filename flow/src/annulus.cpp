#include "flowire/flow/annulus.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "flowire/common/error.hpp"

namespace flowire::flow {

double annulus_flow_fraction(double radius_ratio, double eccentricity) {
  const double k = radius_ratio;
  if (!std::isfinite(k) || !std::isfinite(eccentricity) || k < 0.0 || k >= 1.0)
    throw_usage_error(
        fmt::format("annulus: radius ratio a/R = {} must be in [0, 1), eccentricity {} finite", k, eccentricity));
  if (k == 0.0) return 1.0;
  // Lengths in units of R: tube radius 1, wire radius k, offset c. Q in units of πGR⁴/(8η).
  const double k2 = k * k;
  const double concentric = 1.0 - k2 * k2 - (1.0 - k2) * (1.0 - k2) / std::log(1.0 / k);
  const double e = std::clamp(eccentricity, 0.0, kMaxAnnulusEccentricity);
  const double c = e * (1.0 - k);
  if (c < 1e-9) return concentric;             // the series agrees with it to rounding there
  const double cf = 0.5 * (1.0 - k2 + c * c);  // c·F
  const double c2m2 = cf * cf - c * c;         // c²M² = c²F² − c²R² ≥ 0
  const double f_plus_m = (cf + std::sqrt(c2m2)) / c;
  const double alpha = std::log(f_plus_m);
  const double diff = std::log(1.0 / k) + std::log1p(-c / f_plus_m);  // β − α > 0
  const double sum_ab = 2.0 * alpha + diff;                           // β + α
  // Σ n e^{−n(β+α)}/sinh(n(β−α)) by recurrence; the terms fall like e^{−2nβ}.
  const double q_ab = std::exp(-sum_ab), q_d = std::exp(-diff);
  double pow_ab = 1.0, pow_d = 1.0, series = 0.0;
  for (int n = 1; n < 100000; ++n) {
    pow_ab *= q_ab;
    pow_d *= q_d;
    const double term = n * pow_ab * 2.0 * pow_d / (1.0 - pow_d * pow_d);  // 1/sinh(x) = 2e^{−x}/(1 − e^{−2x})
    series += term;
    if (term <= 1e-17 * series) break;
  }
  const double q = 1.0 - k2 * k2 - 4.0 * c2m2 / diff - 8.0 * c2m2 * series;
  if (!(q > 0.0) || !std::isfinite(q))
    throw_numerical_error(fmt::format("annulus: the eccentric flow at a/R = {}, e = {} is {}", k, e, q));
  return q;
}

}  // namespace flowire::flow
