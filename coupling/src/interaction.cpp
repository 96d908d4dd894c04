#include "flowire/coupling/interaction.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "flowire/common/error.hpp"

namespace flowire::coupling {

double onset_quadratic(double g, double delta, double* d1, double* d2) {
  // ½ g₊² with its kink at g = 0 replaced by the cubic u³/(6δ), u = g + δ/2, over
  // |g| < δ/2: the second derivative ramps linearly from 0 to 1 there, so φ ∈ C².
  if (!(g > -0.5 * delta)) {
    if (d1) *d1 = 0.0;
    if (d2) *d2 = 0.0;
    return 0.0;
  }
  if (g < 0.5 * delta) {
    const double u = g + 0.5 * delta;
    if (d1) *d1 = 0.5 * u * u / delta;
    if (d2) *d2 = u / delta;
    return u * u * u / (6.0 * delta);
  }
  if (d1) *d1 = g;
  if (d2) *d2 = 1.0;
  return 0.5 * g * g + delta * delta / 24.0;
}

PenaltyResult wall_penalty(double d, const Vec3& n, const Mat3& hess_d, double a, double k, double onset) {
  PenaltyResult r;
  const double delta = d + a;
  double d1 = 0.0, d2 = 0.0;
  const double phi = onset_quadratic(delta, onset, &d1, &d2);
  if (!(phi > 0.0)) return r;
  r.penetration = std::max(delta, 0.0);
  r.normal_force = k * d1;
  r.energy = k * phi;
  r.gradient = k * d1 * n;
  r.hessian = k * (d2 * n * n.transpose() + d1 * hess_d);
  return r;
}

double capsule_distance(const Vec3& x, const Vec3& a, const Vec3& b, double r, Vec3* grad, Mat3* hess) {
  const Vec3 ab = b - a;
  const double L2 = ab.squaredNorm();
  const double t_raw = L2 > 0.0 ? (x - a).dot(ab) / L2 : 0.0;
  const double t = std::clamp(t_raw, 0.0, 1.0);
  const Vec3 q = a + t * ab;
  Vec3 e = x - q;
  const double rho = e.norm();
  const Vec3 tan = L2 > 0.0 ? Vec3(ab / std::sqrt(L2)) : Vec3::UnitX();
  Vec3 n = rho > 0.0 ? Vec3(e / rho) : tan.unitOrthogonal();
  if (grad) *grad = n;
  if (hess) {
    if (rho <= 0.0) {
      hess->setZero();
    } else if (t_raw > 0.0 && t_raw < 1.0) {
      *hess = (Mat3::Identity() - tan * tan.transpose() - n * n.transpose()) / rho;
    } else {
      *hess = (Mat3::Identity() - n * n.transpose()) / rho;
    }
  }
  return rho - r;
}

FrictionResult coulomb_friction(const Vec3& v, const Vec3& n, double normal_force, double mu, double eps) {
  FrictionResult r;
  if (normal_force <= 0.0 || mu <= 0.0) return r;
  const Mat3 P = Mat3::Identity() - n * n.transpose();
  const Vec3 vt = P * v;
  const double s = std::sqrt(vt.squaredNorm() + eps * eps);
  const double c = mu * normal_force;
  r.dissipation = c * (s - eps);
  r.force = -c * vt / s;
  // ∇²D = c (P/s − P v vᵀ P / s³) (P is a projector, so P v = v_t).
  r.dfdv = -c * (P / s - vt * vt.transpose() / (s * s * s));
  return r;
}

}  // namespace flowire::coupling
