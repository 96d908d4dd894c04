#include "flowire/flow/losses.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "flowire/common/error.hpp"

namespace flowire::flow {
namespace {
constexpr double kDeanOnset = 11.6;  // White (1929): below this Dean number a bend adds no resistance
}  // namespace

double young_tsai_coefficient(double density, double reference_radius, double throat_radius,
                              double expansion_coefficient) {
  if (!(throat_radius > 0.0) || !(reference_radius > throat_radius)) return 0.0;
  const double a0 = std::numbers::pi * reference_radius * reference_radius;
  const double ratio = (reference_radius * reference_radius) / (throat_radius * throat_radius);
  return expansion_coefficient * density / (2.0 * a0 * a0) * (ratio - 1.0) * (ratio - 1.0);
}

namespace {

/// The radius at each node of branch @p b, in the branch's order, and the arc length there.
void branch_profile(const Network& net, int b, std::vector<double>& r, std::vector<double>& s) {
  const auto& br = net.branch(b);
  const size_t m = br.segments.size();
  r.assign(m + 1, 0.0);
  s.assign(m + 1, 0.0);
  for (size_t k = 0; k < m; ++k) {
    const auto& seg = net.segment(br.segments[k]);
    const bool forward = seg.node_from == br.nodes[k];
    r[k] = forward ? seg.radius_from : seg.radius_to;
    if (k + 1 == m) r[m] = forward ? seg.radius_to : seg.radius_from;
    s[k + 1] = s[k] + seg.length;
  }
}

}  // namespace

std::vector<Stenosis> find_stenoses(const Network& net, double density, double min_area_reduction,
                                    double expansion_coefficient) {
  if (!(min_area_reduction >= 0.0 && min_area_reduction < 1.0))
    throw_usage_error(fmt::format("stenosis losses: area reduction threshold {} is not in [0, 1)", min_area_reduction));
  std::vector<Stenosis> out;
  std::vector<double> r, s;
  for (int b = 0; b < net.num_branches(); ++b) {
    branch_profile(net, b, r, s);
    const size_t m = r.size() - 1;
    for (size_t k = 1; k < m; ++k) {
      if (!(r[k] < r[k - 1])) continue;
      size_t j = k;  // the throat may be a plateau k..j
      while (j < m && r[j + 1] == r[k]) ++j;
      if (j == m || !(r[j + 1] > r[k])) continue;
      // The shoulders: the largest radius on each side before the lumen is narrower than the throat.
      double left = r[k];
      for (size_t i = k; i-- > 0 && r[i] >= r[k];) left = std::max(left, r[i]);
      double right = r[k];
      for (size_t i = j + 1; i <= m && r[i] >= r[k]; ++i) right = std::max(right, r[i]);
      const double r0 = std::min(left, right);
      const double reduction = 1.0 - (r[k] * r[k]) / (r0 * r0);
      if (reduction < min_area_reduction || reduction <= 0.0) continue;
      Stenosis st;
      st.branch = b;
      st.throat_node = net.branch(b).nodes[j];
      st.s = s[j];
      st.throat_radius = r[k];
      st.reference_radius = r0;
      st.area_reduction = reduction;
      st.coefficient = young_tsai_coefficient(density, r0, r[k], expansion_coefficient);
      // From the throat to where the lumen has widened 90% of the way to the shoulder (a ripple on
      // the shoulder does not carry the loss on to its next crest).
      const double widened = r[k] + 0.9 * (r0 - r[k]);
      for (size_t i = j; i < m; ++i) {
        st.segments.push_back(net.branch(b).segments[i]);
        if (r[i + 1] >= widened) break;
      }
      out.push_back(std::move(st));
      k = j;
    }
  }
  return out;
}

namespace {

/// White's ratio φ and its slope dφ/dDe at @p de with two pow calls (the curved law's inner loop).
void dean_ratio_and_slope(double de, double& phi, double& slope) {
  if (!(de > kDeanOnset)) {
    phi = 1.0, slope = 0.0;
    return;
  }
  const double x = std::pow(kDeanOnset / de, 0.45), y = 1.0 - x;
  const double y02 = std::pow(y, 0.2), w = y * y * y02;  // (1 − x)^2.2
  phi = 1.0 / (1.0 - w);
  // dw/dDe = 2.2 (1 − x)^1.2 · 0.45 x / De;  φ = 1/(1 − w):  dφ/dDe = φ² dw/dDe
  slope = phi * phi * 2.2 * y * y02 * 0.45 * x / de;
}

}  // namespace

double dean_resistance_ratio(double de) {
  double phi = 1.0, slope = 0.0;
  dean_ratio_and_slope(de, phi, slope);
  return phi;
}

double dean_resistance_ratio_slope(double de) {
  double phi = 1.0, slope = 0.0;
  dean_ratio_and_slope(de, phi, slope);
  return slope;
}

namespace {
// Shah (J. Fluids Eng. 100:177–179, 1978): f_app Re = 3.44/√x⁺ + (1.25/(4x⁺) + 16 − 3.44/√x⁺)/(1 + a/x⁺²)
// with a = 0.00021; the drop over ½ρū² is 4 f_app Re x⁺, of which 64 x⁺ is Poiseuille's. The rest,
// K = 13.76√x⁺ − 64x⁺ + M/(1 + a/x⁺²) with M = 1.25 + 64x⁺ − 13.76√x⁺, is written
// K = 1.25 − M a/(x⁺² + a): no cancellation of large terms far downstream.
constexpr double kShahA = 0.00021;
constexpr double kShahInfinity = 1.25;
}  // namespace

double shah_incremental_drop(double x) {
  if (!(x > 0.0)) return 0.0;
  if (std::isinf(x)) return kShahInfinity;
  const double m = kShahInfinity + 64.0 * x - 13.76 * std::sqrt(x);
  return kShahInfinity - m * kShahA / (x * x + kShahA);
}

double shah_incremental_drop_slope(double x) {
  if (!(x > 0.0)) return std::numeric_limits<double>::infinity();  // K ~ 13.76 √x⁺ at the entrance
  if (std::isinf(x)) return 0.0;
  const double sx = std::sqrt(x), d = x * x + kShahA;
  const double m = kShahInfinity + 64.0 * x - 13.76 * sx, dm = 64.0 - 6.88 / sx;
  return -(dm * kShahA / d - m * kShahA * 2.0 * x / (d * d));
}

namespace {
/// E(Q) and dE/dQ of an entrance law (SegmentLaw) at q > 0 for the distances c, with ρ/(2A²) = k:
/// E = k q² [K(c₁/q) − K(c₀/q)],  dE/dq = 2kq [K(c₁/q) − K(c₀/q)] − k [c₁ K'(c₁/q) − c₀ K'(c₀/q)]
/// (c K'(c/q) → 0 as c → 0: the near end at the entrance itself adds nothing).
void entrance_terms(double k, const std::array<double, 2>& c, double q, double& e, double& de) {
  const double dk = shah_incremental_drop(c[1] / q) - shah_incremental_drop(c[0] / q);
  const double near = c[0] > 0.0 ? c[0] * shah_incremental_drop_slope(c[0] / q) : 0.0;
  e = k * q * q * dk;
  de = k * (2.0 * q * dk - (c[1] * shah_incremental_drop_slope(c[1] / q) - near));
}

/// The entrance law's E(Q) and dE/dQ for the direction of @p q (0 where none develops that way).
void signed_entrance_terms(const SegmentLaw& law, double q, double& e, double& de) {
  e = de = 0.0;
  const auto& c = q > 0.0 ? law.entry_forward : law.entry_backward;
  if (q == 0.0 || !(c[1] > 0.0)) return;
  entrance_terms(law.entry, c, std::abs(q), e, de);
  if (q < 0.0) e = -e;  // E is odd in Q, its slope even
}

}  // namespace

double SegmentLaw::entrance_drop(double q) const {
  double e = 0.0, de = 0.0;
  signed_entrance_terms(*this, q, e, de);
  return e;
}

double SegmentLaw::entrance_slope(double q) const {
  double e = 0.0, de = 0.0;
  signed_entrance_terms(*this, q, e, de);
  return de;
}

double SegmentLaw::bracketed_flow(double dp, double r, double straight, double guess) const {
  // g(Q) = Δp(Q) − |Δp| on [0, |straight|] in the direction of Δp (φ ≥ 1 and E(Q)Q ≥ 0 put the root
  // below the straight law's): Newton's method from the guess or the top, bisection where a step
  // leaves the bracket. Newton converges quadratically: a step below 1e-13 of the flow is the root
  // to round-off.
  const double target = std::abs(dp), sign = dp < 0.0 ? -1.0 : 1.0;
  double lo = 0.0, hi = std::abs(straight);
  const double start = sign * guess;
  double q = start > 0.0 && start < hi ? start : hi;
  const auto& c = sign > 0.0 ? entry_forward : entry_backward;
  const bool developing_here = developing() && c[1] > 0.0;
  for (int it = 0; it < 60; ++it) {
    // The drop along the flow and its slope together: one evaluation of White's ratio (two pow
    // calls) and of Shah's K at each end an iteration.
    double phi = 1.0, dphi = 0.0, e = 0.0, de = 0.0;
    if (dean > 0.0) dean_ratio_and_slope(dean * q, phi, dphi);
    if (developing_here && q > 0.0) entrance_terms(entry, c, q, e, de);
    const double g = r * q * phi + quadratic * q * q + e - target;
    if (g == 0.0) break;
    (g > 0.0 ? hi : lo) = q;
    double next = q - g / (r * (phi + dean * q * dphi) + 2.0 * quadratic * q + de);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool done = std::abs(next - q) <= 1e-13 * q;
    q = next;
    if (done) break;
  }
  return sign * q;
}

std::vector<double> segment_curvatures(const Network& net) {
  std::vector<double> kappa(static_cast<size_t>(net.num_segments()), 0.0);
  for (int b = 0; b < net.num_branches(); ++b) {
    const auto& br = net.branch(b);
    const size_t m = br.segments.size();
    if (m < 2) continue;
    // The turning angle at each interior node over the mean length of its two segments.
    std::vector<double> node(m + 1, 0.0);
    for (size_t k = 1; k < m; ++k) {
      const Vec3 d0 = net.node(br.nodes[k]) - net.node(br.nodes[k - 1]);
      const Vec3 d1 = net.node(br.nodes[k + 1]) - net.node(br.nodes[k]);
      const double angle = std::atan2(d0.cross(d1).norm(), d0.dot(d1));
      node[k] = angle / (0.5 * (d0.norm() + d1.norm()));
    }
    node[0] = node[1];  // a branch's ends turn into its neighbours: their own curvature is the next node's
    node[m] = node[m - 1];
    for (size_t k = 0; k < m; ++k) kappa[static_cast<size_t>(br.segments[k])] = 0.5 * (node[k] + node[k + 1]);
  }
  return kappa;
}

int add_curvature_losses(const Network& net, double density, double viscosity, std::vector<SegmentLaw>& laws) {
  const std::vector<double> kappa = segment_curvatures(net);
  int curved = 0;
  for (int s = 0; s < net.num_segments(); ++s) {
    const double k = kappa[static_cast<size_t>(s)];
    if (!(k > 0.0)) continue;
    if (laws.empty()) laws.assign(static_cast<size_t>(net.num_segments()), SegmentLaw{});
    const double a = net.segment(s).radius;
    // De = Re √(a/R), Re = ρ (Q/πa²)(2a)/μ
    laws[static_cast<size_t>(s)].dean = 2.0 * density / (std::numbers::pi * a * viscosity) * std::sqrt(a * k);
    ++curved;
  }
  return curved;
}

void add_stenosis_losses(const Network& net, const std::vector<Stenosis>& stenoses, std::vector<SegmentLaw>& laws) {
  if (stenoses.empty()) return;
  if (laws.empty()) laws.assign(static_cast<size_t>(net.num_segments()), SegmentLaw{});
  for (const Stenosis& st : stenoses) {
    double length = 0.0;
    for (int seg : st.segments) length += net.segment(seg).length;
    for (int seg : st.segments)
      laws[static_cast<size_t>(seg)].quadratic += st.coefficient * net.segment(seg).length / length;
  }
}

int add_entrance_losses(const Network& net, double density, double viscosity, const std::vector<char>& entrance,
                        std::vector<SegmentLaw>& laws) {
  int entrances = 0;
  const double per_length = viscosity * std::numbers::pi / (4.0 * density);  // c = x μπ/(4ρ): x⁺ = c/|Q|
  std::vector<double> r, s;
  for (int b = 0; b < net.num_branches(); ++b) {
    const auto& br = net.branch(b);
    const size_t m = br.segments.size();
    const bool at_start = entrance[static_cast<size_t>(br.nodes.front())] != 0;
    const bool at_end = entrance[static_cast<size_t>(br.nodes.back())] != 0;
    if (!at_start && !at_end) continue;
    if (laws.empty()) laws.assign(static_cast<size_t>(net.num_segments()), SegmentLaw{});
    branch_profile(net, b, r, s);
    const double length = s[m];
    for (size_t k = 0; k < m; ++k) {
      const auto& seg = net.segment(br.segments[k]);
      SegmentLaw& law = laws[static_cast<size_t>(br.segments[k])];
      const double area = std::numbers::pi * seg.radius * seg.radius;
      law.entry = density / (2.0 * area * area);
      // The segment runs along the branch (from node k to k + 1) or against it.
      const bool along = seg.node_from == br.nodes[k];
      if (at_start) (along ? law.entry_forward : law.entry_backward) = {s[k] * per_length, s[k + 1] * per_length};
      if (at_end)
        (along ? law.entry_backward : law.entry_forward) = {(length - s[k + 1]) * per_length,
                                                            (length - s[k]) * per_length};
    }
    entrances += static_cast<int>(at_start) + static_cast<int>(at_end);
  }
  return entrances;
}

}  // namespace flowire::flow
