#include "flowire/coupling/drag.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "flowire/common/error.hpp"

namespace flowire::coupling {

namespace {

constexpr double kPi = std::numbers::pi;
// Blend between Kaplun's creeping-flow expansion and the Sucker–Brauer correlation.
constexpr double kBlendLow = 0.4, kBlendHigh = 1.0;

/// g(Re) = Re·C_D/2 and dg/dRe for Kaplun (1957): Re·C_D = 8π(ε − 0.87ε³), ε = 1/ln(7.406/Re).
std::pair<double, double> kaplun_g(double re) {
  const double eps = 1.0 / std::log(7.406 / re);
  const double deps = eps * eps / re;  // dε/dRe
  return {4.0 * kPi * (eps - 0.87 * eps * eps * eps), 4.0 * kPi * (1.0 - 2.61 * eps * eps) * deps};
}

/// g(Re) = Re·C_D/2 and dg/dRe for Sucker & Brauer (1975).
std::pair<double, double> sucker_brauer_g(double re) {
  constexpr double b = 3.64e-7;
  const double q = 1.0 + b * re * re;
  const double g = 0.59 * re + 3.4 * std::pow(re, 0.11) + 0.98 * std::sqrt(re) - 2e-4 * re * re / q;
  const double dg = 0.59 + 0.374 * std::pow(re, -0.89) + 0.49 / std::sqrt(re) - 4e-4 * re / (q * q);
  return {g, dg};
}

/// g(Re) = Re·C_D(Re)/2 with its derivative, on the blended curve.
std::pair<double, double> curve_g(double re) {
  if (re <= kBlendLow) return kaplun_g(re);
  if (re >= kBlendHigh) return sucker_brauer_g(re);
  const double span = std::log(kBlendHigh / kBlendLow);
  const double xi = std::log(re / kBlendLow) / span;
  const double s = xi * xi * (3.0 - 2.0 * xi);
  const double ds = 6.0 * xi * (1.0 - xi) / (re * span);  // ds/dRe
  const auto [gk, dgk] = kaplun_g(re);
  const auto [gs, dgs] = sucker_brauer_g(re);
  return {(1.0 - s) * gk + s * gs, (1.0 - s) * dgk + s * dgs + (gs - gk) * ds};
}

}  // namespace

DragCurvePoint cylinder_drag_curve(double re) {
  if (!(re > 0.0) || !std::isfinite(re))
    throw_usage_error(fmt::format("cylinder drag curve: Reynolds number must be positive and finite (got {})", re));
  const auto [g, dg] = curve_g(re);
  // C_D = 2g/Re, dC_D/dRe = 2(g' Re − g)/Re².
  return {2.0 * g / re, 2.0 * (dg * re - g) / (re * re)};
}

double cylinder_drag_coefficient(double re) { return cylinder_drag_curve(re).cd; }

AnnulusShear annulus_shear(double eta, double a, double vessel_radius) {
  const double R = std::max(vessel_radius, 2.0 * a);
  const double L = std::log(R / a);
  const double x2 = (a / R) * (a / R);
  return {1.0 - x2 * (1.0 + 2.0 * L), 2.0 * kPi * eta / L};
}

double slender_body_normal_coefficient(double eta, double L, double r) {
  if (!(L > r) || !(r > 0.0))
    throw_usage_error(fmt::format("slender-body drag needs length > radius > 0 (L = {}, r = {})", L, r));
  return 4.0 * kPi * eta / std::log(L / r);
}

DragForce slender_body_drag(const Vec3& u, const Vec3& v, const Vec3& t, double eta, double L, double r, double ell) {
  const double cn = slender_body_normal_coefficient(eta, L, r);
  const double ct = 0.5 * cn;
  const Mat3 tt = t * t.transpose();
  const Mat3 C = ell * (cn * (Mat3::Identity() - tt) + ct * tt);
  DragForce d;
  d.force = C * (u - v);
  d.dfdv = -C;
  return d;
}

namespace {

DragForce cylinder_drag(const DragModel& m, const DragInput& in) {
  DragForce d;
  const double a = m.wire_radius, eta = m.viscosity, rho = m.density;
  const double R = std::max(in.vessel_radius, 2.0 * a);
  const Vec3& t = in.t;
  const Mat3 tt = t * t.transpose();
  const Mat3 P = Mat3::Identity() - tt;
  const double w = m.scale * in.ell;

  // Along the wire: annular Poiseuille shear.
  const auto sh = annulus_shear(eta, a, R);
  const double ft = sh.coefficient * (sh.kappa * t.dot(in.u) - t.dot(in.v));
  d.force = w * ft * t;
  d.dfdv = -w * sh.coefficient * tt;

  // Across the wire: f_n = η g(Re_n) w_n, g ≥ g_conf.
  const Vec3 wn = P * (in.u - in.v);
  const double speed = wn.norm();
  const double g_conf = 4.0 * kPi / (std::log(R / a) - (R * R - a * a) / (R * R + a * a));
  double g = g_conf, dg = 0.0;
  if (speed > 0.0) {
    const double re = rho * speed * 2.0 * a / eta;
    d.reynolds_normal = re;
    const auto [gf, dgf] = curve_g(re);
    if (gf > g_conf) g = gf, dg = dgf;
  }
  d.force += w * eta * g * wn;
  // ∂f_n/∂w = η g P + η g'(Re) (∂Re/∂|w_n|) w_n ŵ_nᵀ = η g P + ρ d g' w_n w_nᵀ/|w_n|; ∂w/∂v = −I.
  Mat3 J = eta * g * P;
  if (dg != 0.0) J += rho * 2.0 * a * dg * (wn * wn.transpose()) / speed;
  d.dfdv -= w * J;
  return d;
}

}  // namespace

DragForce blood_drag(const DragModel& m, const DragInput& in) {
  switch (m.law) {
    case DragLaw::None:
      return {};
    case DragLaw::Cylinder:
      return cylinder_drag(m, in);
    case DragLaw::SlenderBody: {
      auto d = slender_body_drag(in.u, in.v, in.t, m.viscosity, m.wire_length, m.wire_radius, m.scale * in.ell);
      return d;
    }
    case DragLaw::VelocityOffset: {
      // The published form (eq. 10): the blood velocity is added to the velocity update,
      // Δv += u, i.e. an impulse m·u per step, which as a force is m·u/Δt.
      DragForce d;
      if (in.dt > 0.0) d.force = m.scale * m.mass_per_length * in.ell * in.u / in.dt;
      return d;
    }
  }
  return {};
}

}  // namespace flowire::coupling
