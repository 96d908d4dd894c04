#include "flowire/coupling/drag.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>

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

// The Oseen point force midway in a channel |z| < h, stream U along x (2κ = U/ν), walls
// moving with the stream (no-slip for the disturbance): with ψ̂(ξ, z) the stream function's
// Fourier transform along x, (D² − ξ² − 2iκξ)(D² − ξ²)ψ̂ = δ′(z) per unit force/η; the free
// solution plus A sinh(|ξ|z) + B sinh(βz), β² = ξ² + 2iκξ, with ψ̂ = ψ̂′ = 0 at z = h, gives
// the images' velocity at the force, (1/π) Re ∫₀^∞ (A|ξ| + Bβ) dξ. In the denominator of the
// drag this enters as C(s) = ln(2/s) − γ + ½ − W(s), s = κh, which the table holds at
// ln s = −8, −7.75, …, 9 (mpmath, 30 digits; docs/blood-drag.md). C(0) = −0.9156893 is
// Faxén's constant; for large s, W s → π/2.
constexpr double kTableX0 = -8.0, kTableDx = 0.25;
constexpr double kWallConstant[] = {
    -0.9156892771, -0.9156892796, -0.9156892838, -0.9156892907, -0.9156893020, -0.9156893206, -0.9156893514,
    -0.9156894021, -0.9156894857, -0.9156896236, -0.9156898509, -0.9156902256, -0.9156908434, -0.9156918621,
    -0.9156935415, -0.9156963104, -0.9157008755, -0.9157084020, -0.9157208109, -0.9157412688, -0.9157749961,
    -0.9158305974, -0.9159222530, -0.9160733255, -0.9163222877, -0.9167324474, -0.9174078458, -0.9185191126,
    -0.9203451256, -0.9233391253, -0.9282309594, -0.9361782705, -0.9489726337, -0.9692785976, -1.0008143759,
    -1.0482689386, -1.1166751659, -1.2101529333, -1.3305330711, -1.4768220216, -1.6458948383, -1.8337337099,
    -2.0363870161, -2.2504396436, -2.4731454435, -2.7023853338, -2.9365578960, -3.1744621809, -3.4151979045,
    -3.6580883016, -3.9026227759, -4.1484147224, -4.3951704722, -4.6426663118, -4.8907313872, -5.1392349217,
    -5.3880766160, -5.6371794100, -5.8864840063, -6.1359447124, -6.3855262763, -6.6352014711, -6.8849492482,
    -7.1347533212, -7.3846010790, -7.6344827500, -7.8843907582, -8.1343192266, -8.3842635945};
constexpr int kTableSize = static_cast<int>(sizeof(kWallConstant) / sizeof(kWallConstant[0]));
constexpr double kEuler = 0.57721566490153286;
// Beyond the table: W s = π/2 + b/√s, b matching its last entry.
constexpr double kWakeBlockageTail = 0.917932;
// Faxén's series is used up to k = 0.4 (its last term is then 1.3% of the whole).
constexpr double kMaxGapRatio = 0.4;

/// C(x) at x = ln s and dC/dx: cubic Hermite on the table, slopes by central differences.
std::pair<double, double> wall_constant(double x) {
  const double* c = kWallConstant;
  const auto slope = [c](int i) {
    if (i == 0) return (-3.0 * c[0] + 4.0 * c[1] - c[2]) / (2.0 * kTableDx);
    if (i == kTableSize - 1) return (3.0 * c[i] - 4.0 * c[i - 1] + c[i - 2]) / (2.0 * kTableDx);
    return (c[i + 1] - c[i - 1]) / (2.0 * kTableDx);
  };
  const double u = (x - kTableX0) / kTableDx;
  const int i = std::clamp(static_cast<int>(std::floor(u)), 0, kTableSize - 2);
  const double t = u - i;
  const double h00 = (1 + 2 * t) * (1 - t) * (1 - t), h10 = t * (1 - t) * (1 - t), h01 = t * t * (3 - 2 * t),
               h11 = t * t * (t - 1);
  const double d00 = 6 * t * (t - 1), d10 = (1 - t) * (1 - 3 * t), d01 = 6 * t * (1 - t), d11 = t * (3 * t - 2);
  const double m0 = slope(i) * kTableDx, m1 = slope(i + 1) * kTableDx;
  return {h00 * c[i] + h10 * m0 + h01 * c[i + 1] + h11 * m1,
          (d00 * c[i] + d10 * m0 + d01 * c[i + 1] + d11 * m1) / kTableDx};
}

/// Glauert's blockage branch of the channel law, g = (1 + ε) g(Re(1 + ε)), and dg/dRe.
std::pair<double, double> blockage_g(double re, double k) {
  const auto [g0, dg0] = curve_g(re);
  const double s = re / (4.0 * k);
  const auto wall = channel_oseen_wall(s);
  const double eps = kPi * kPi / 12.0 * k * k + g0 * wall.w / (4.0 * kPi);
  const double deps = (dg0 * wall.w + g0 * wall.dw / (4.0 * k)) / (4.0 * kPi);
  const double q = 1.0 + eps;
  const auto [g1, dg1] = curve_g(re * q);
  return {q * g1, deps * g1 + q * dg1 * (q + re * deps)};
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

double faxen_channel_coefficient(double k) {
  if (!(k > 0.0) || !(k <= 0.5))
    throw_usage_error(fmt::format("Faxén's channel drag needs 0 < a/h <= 0.5 (got {})", k));
  const double k2 = k * k;
  return 4.0 * kPi / (std::log(1.0 / k) - 0.9157 + k2 * (1.7244 + k2 * (-1.7302 + k2 * (2.4056 - 4.5913 * k2))));
}

ChannelOseenWall channel_oseen_wall(double s) {
  if (!(s > 0.0) || !std::isfinite(s))
    throw_usage_error(fmt::format("channel Oseen wall term: s must be positive and finite (got {})", s));
  const double x = std::log(s);
  const double x_end = kTableX0 + kTableDx * (kTableSize - 1);
  if (x > x_end) {
    const double r = std::sqrt(s);
    return {(kPi / 2.0 + kWakeBlockageTail / r) / s, -(kPi / 2.0 + 1.5 * kWakeBlockageTail / r) / (s * s)};
  }
  const auto [c, dc] = x < kTableX0 ? std::pair{kWallConstant[0], 0.0} : wall_constant(x);
  // W = ln(2/s) − γ + ½ − C(ln s).
  return {std::log(2.0 / s) - kEuler + 0.5 - c, (-1.0 - dc) / s};
}

ChannelDrag channel_drag_coefficient(double re, double k) {
  if (!(re > 0.0) || !std::isfinite(re) || !(k > 0.0))
    throw_usage_error(fmt::format("channel drag needs Re > 0 and a/h > 0 (got {}, {})", re, k));
  k = std::min(k, kMaxGapRatio);
  const double gf = faxen_channel_coefficient(k);
  const auto [gb, dgb] = blockage_g(re, k);
  if (gf >= gb) return {gf, 0.0, true};
  return {gb, dgb, false};
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
  const double a = in.wire_radius > 0.0 ? in.wire_radius : m.wire_radius, eta = m.viscosity, rho = m.density;
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

  // Across the wire: f_n = η g(Re_n) w_n, g = c² g_∘ + (1 − c²) g_= (see the header).
  const Vec3 wn = P * (in.u - in.v);
  const double speed = wn.norm();
  const double re = rho * speed * 2.0 * a / eta;
  d.reynolds_normal = speed > 0.0 ? re : 0.0;
  // The vessel's axis across the wire: c² = (t·A)², n = t × A / |t × A|.
  double c2 = 1.0, k = kMaxGapRatio;
  if (in.axis.squaredNorm() > 0.0) {
    const Vec3 A = in.axis.normalized();
    const Vec3 n = t.cross(A);
    const double sin2 = n.squaredNorm();
    c2 = 1.0 - sin2;
    if (sin2 > 0.0) {
      // Half-chord of the vessel through the vertex along n (n ⊥ A, offset ⊥ A).
      const Vec3 o = in.axis_offset - in.axis_offset.dot(A) * A;
      const double on = o.dot(n) / std::sqrt(sin2);
      const double h2 = R * R - o.squaredNorm() + on * on;
      if (h2 > (a / kMaxGapRatio) * (a / kMaxGapRatio)) k = a / std::sqrt(h2);
    }
  }
  double g = 0.0, dg = 0.0;
  if (c2 > 0.0) {
    // Along: the coaxial-tube floor or the curve.
    const double g_conf = 4.0 * kPi / (std::log(R / a) - (R * R - a * a) / (R * R + a * a));
    double gc = g_conf, dgc = 0.0;
    if (speed > 0.0) {
      const auto [gf, dgf] = curve_g(re);
      if (gf > g_conf) gc = gf, dgc = dgf;
    }
    g += c2 * gc, dg += c2 * dgc;
  }
  if (c2 < 1.0) {
    // Across: the channel of half-width a/k.
    ChannelDrag ch{faxen_channel_coefficient(k), 0.0, true};
    if (speed > 0.0) ch = channel_drag_coefficient(re, k);
    g += (1.0 - c2) * ch.g, dg += (1.0 - c2) * ch.dg;
  }
  d.force += w * eta * g * wn;
  // ∂f_n/∂w = η g P + η g'(Re) (∂Re/∂|w_n|) w_n ŵ_nᵀ = η g P + ρ d g' w_n w_nᵀ/|w_n|; ∂w/∂v = −I.
  Mat3 J = eta * g * P;
  if (dg != 0.0 && speed > 0.0) J += rho * 2.0 * a * dg * (wn * wn.transpose()) / speed;
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
      auto d = slender_body_drag(in.u, in.v, in.t, m.viscosity, m.wire_length,
                                 in.wire_radius > 0.0 ? in.wire_radius : m.wire_radius, m.scale * in.ell);
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
