#include "flowire/coupling/interaction.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "flowire/common/error.hpp"

namespace flowire::coupling {

PenaltyResult wall_penalty(double d, const Vec3& n, const Mat3& hess_d, double a, double k) {
  PenaltyResult r;
  const double delta = d + a;
  if (delta <= 0.0) return r;
  r.penetration = delta;
  r.energy = 0.5 * k * delta * delta;
  r.gradient = k * delta * n;
  r.hessian = k * (n * n.transpose() + delta * hess_d);
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
