#pragma once
// The exact periodic solution of the linearized 1D model on a network of straight branches,
// one harmonic at a time: the oracle the compliant network model (flow.model: rlc) converges
// to as its segments shrink.
//
// Along a branch, with r(x) linear from its end a to its end b, the linearized 1D equations
// at angular frequency ω are a transmission line,
//   dP̂/dx = −Z'(x) Q̂,   dQ̂/dx = −Y'(x) P̂,
//   Z' = R' + iωL',  R' = 8μ/(πr⁴),  L' = ρ/(πr²) (× 4/3 for Inertance::Womersley),
//   Y' = iωC',       C' = 3πr³/(2Eh)  (thin incompressible wall; h = thickness_ratio·r or
//                                       a branch wall's absolute thickness),
// the per-length laws whose integrals over a segment are the rlc model's R, L and C. Its
// transfer matrix [P̂; Q̂](x₁) = M [P̂; Q̂](x₀) is, for a uniform branch, with γ = √(Z'Y'),
//   M = [[cosh γx, −Z'x sinhc γx], [−Y'x sinhc γx, cosh γx]],  sinhc z = sinh z / z,
// (Z_c sinh γx = Z'x sinhc γx: no division by zero at ω = 0, the resistor limit), and for a
// tapered one the same ODE integrated by RK4 on a fine grid. Reciprocity (det M = 1) makes
// the branch a two-port with the nodal admittance
//   [I_a; I_b] = (1/m₁₂) [[−m₁₁, 1], [1, −m₂₂]] [P̂_a; P̂_b]   (I: flow into the branch),
// for a uniform branch (1/Z_c)[[coth γl, −csch γl], [−csch γl, coth γl]]. These stamped into
// the nodal admittance matrix of the branch graph (trees and loops alike), each outlet's
// impedance to ground (its distal pressure a source of the mean only), pressure conditions
// as known potentials and flow conditions as injected currents, give every junction's P̂;
// from a branch's two end pressures its P̂(x) and Q̂(x) everywhere.
//
// Harmonics follow f(t) = ĉ₀ + Σ_{k>0} 2 Re(ĉ_k e^{ikωt}), ĉ_k = (1/T)∫ f e^{−ikωt} dt.
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "flowire/flow/spec.hpp"
#include "flowire/vessels/network.hpp"

namespace flowire::flow::test {

using cd = std::complex<double>;

/// A straight branch from a to b whose radius runs linearly from r_a to r_b (r_b ≤ 0: r_a, a cylinder).
struct ExactBranch {
  std::string name;
  Vec3 a, b;
  double r_a = 0.0, r_b = 0.0;
  [[nodiscard]] double length() const { return (b - a).norm(); }
  [[nodiscard]] double radius_b() const { return r_b > 0.0 ? r_b : r_a; }
  [[nodiscard]] bool uniform() const { return radius_b() == r_a; }
  [[nodiscard]] double radius(double x) const { return r_a + (radius_b() - r_a) * x / length(); }
};

/// The branches as centerlines (one two-point polyline each) for Network::build.
inline vessels::Centerlines centerlines_of(const std::vector<ExactBranch>& branches) {
  vessels::Centerlines c;
  for (const auto& br : branches) c.branches.push_back({br.name, {br.a, br.b}, {br.r_a, br.radius_b()}});
  return c;
}

/// ĉ_k of samples taken at m T/n, m = 0..n−1 (one period, its end left out).
inline cd sampled_harmonic(std::span<const double> v, int k) {
  cd sum = 0.0;
  const auto n = static_cast<double>(v.size());
  for (size_t m = 0; m < v.size(); ++m)
    sum += v[m] * std::polar(1.0, -2.0 * std::numbers::pi * k * static_cast<double>(m) / n);
  return sum / n;
}

/// ĉ_k of a waveform of period @p period, from @p n samples (exact for a sine; a table's kinks
/// leave a quadrature error of O(n⁻²)).
inline cd waveform_harmonic(const Waveform& w, double period, int k, int n = 16384) {
  std::vector<double> v(static_cast<size_t>(n));
  for (int m = 0; m < n; ++m) v[static_cast<size_t>(m)] = w(period * m / n);
  return sampled_harmonic(v, k);
}

/// The exact harmonic k (period T) of the linearized 1D model on @p branches with the
/// boundary conditions, walls and blood of @p spec; @p net (built from the same branches,
/// Network::build of centerlines_of) names the nodes the conditions sit on and the walls.
class ExactNetwork {
 public:
  using Transfer = std::array<cd, 4>;  // m11, m12, m21, m22

  ExactNetwork(std::vector<ExactBranch> branches, const FlowSpec& spec, const Network& net, double period, int k)
      : branches_(std::move(branches)), spec_(spec), net_(net), omega_(2.0 * std::numbers::pi * k / period) {
    for (const auto& br : branches_) {
      walls_.push_back({spec.wall_youngs_modulus, 0.0, spec.wall_thickness_ratio});
      for (const auto& w : spec.branch_walls)
        if (net.branches()[static_cast<size_t>(w.branch)].name == br.name)
          walls_.back() = {w.youngs_modulus, w.thickness, w.thickness_ratio};
      ends_.push_back({junction_at(br.a), junction_at(br.b)});
    }
    solve(period, k);
  }

  /// P̂ at distance x from the branch's end a.
  [[nodiscard]] cd pressure_at(int branch, double x) const { return state_at(branch, x)[0]; }
  /// Q̂ at distance x from the branch's end a, positive from a towards b.
  [[nodiscard]] cd flow_at(int branch, double x) const { return state_at(branch, x)[1]; }
  [[nodiscard]] const std::vector<ExactBranch>& branches() const { return branches_; }
  /// The branch named @p name, or −1.
  [[nodiscard]] int branch_named(const std::string& name) const {
    for (size_t i = 0; i < branches_.size(); ++i)
      if (branches_[i].name == name) return static_cast<int>(i);
    return -1;
  }

  /// P̂ at node @p i of the network, from its position on its branch.
  [[nodiscard]] cd node_pressure(int i) const {
    const int s = *net_.node_segments(i).first;
    const int b = branch_named(net_.branches()[static_cast<size_t>(net_.segment(s).branch)].name);
    return pressure_at(b, along(b, net_.node(i)));
  }
  /// Q̂ at the midpoint of segment @p s, positive from its node_from to its node_to: what
  /// the staggered segment flow of the lumped model stands for (half of the segment's
  /// compliance sits at each end node, so the flow between them is the line's at mid-segment).
  [[nodiscard]] cd segment_flow(int s) const {
    const auto& seg = net_.segment(s);
    const int b = branch_named(net_.branches()[static_cast<size_t>(seg.branch)].name);
    const double x0 = along(b, net_.node(seg.node_from)), x1 = along(b, net_.node(seg.node_to));
    const cd q = flow_at(b, 0.5 * (x0 + x1));
    return x1 > x0 ? q : -q;
  }

  /// Q̂ at node @p i, one of segment @p s's ends, positive from its node_from to its node_to.
  [[nodiscard]] cd segment_flow_at_node(int s, int i) const {
    const auto& seg = net_.segment(s);
    const int b = branch_named(net_.branches()[static_cast<size_t>(seg.branch)].name);
    const double x0 = along(b, net_.node(seg.node_from)), x1 = along(b, net_.node(seg.node_to));
    const cd q = flow_at(b, along(b, net_.node(i)));
    return x1 > x0 ? q : -q;
  }

  /// The transfer matrix of branch @p b from x0 to x1 (x from its end a).
  [[nodiscard]] Transfer transfer(int b, double x0, double x1) const {
    const auto& br = branches_[static_cast<size_t>(b)];
    if (br.uniform()) {
      const double d = x1 - x0;
      const auto [z, y] = per_length(b, x0);
      const cd g = std::sqrt(z * y) * d;
      const cd sc = std::abs(g) < 1e-8 ? 1.0 + g * g / 6.0 : std::sinh(g) / g;
      return {std::cosh(g), -z * d * sc, -y * d * sc, std::cosh(g)};
    }
    // RK4 on M' = A(x) M, A = [[0, −Z'], [−Y', 0]], 8192 steps over the branch's length.
    const int n = std::max(1, static_cast<int>(std::ceil(std::abs(x1 - x0) / br.length() * 8192.0)));
    const double h = (x1 - x0) / n;
    Transfer m = {1.0, 0.0, 0.0, 1.0};
    auto rhs = [&](double x, const Transfer& a) {
      const auto [z, y] = per_length(b, x);
      return Transfer{-z * a[2], -z * a[3], -y * a[0], -y * a[1]};
    };
    for (int i = 0; i < n; ++i) {
      const double x = x0 + h * i;
      const Transfer k1 = rhs(x, m), k2 = rhs(x + 0.5 * h, add(m, k1, 0.5 * h)),
                     k3 = rhs(x + 0.5 * h, add(m, k2, 0.5 * h)), k4 = rhs(x + h, add(m, k3, h));
      for (size_t j = 0; j < 4; ++j) m[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
    }
    return m;
  }

  /// Z'(x) and Y'(x) of branch @p b at ω.
  [[nodiscard]] std::pair<cd, cd> per_length(int b, double x) const {
    const auto& br = branches_[static_cast<size_t>(b)];
    const auto& w = walls_[static_cast<size_t>(b)];
    const double r = br.radius(x), pi = std::numbers::pi;
    const double inertance = (spec_.inertance == Inertance::Womersley ? 4.0 / 3.0 : 1.0) * spec_.density / (pi * r * r);
    const double h = w.thickness > 0.0 ? w.thickness : w.thickness_ratio * r;
    const double compliance = w.youngs_modulus > 0.0 ? 3.0 * pi * r * r * r / (2.0 * w.youngs_modulus * h) : 0.0;
    return {cd(8.0 * spec_.viscosity / (pi * r * r * r * r), omega_ * inertance), cd(0.0, omega_ * compliance)};
  }

 private:
  struct Wall {
    double youngs_modulus, thickness, thickness_ratio;
  };

  /// The junction at point x (branch ends closer than 1e-9 m are one junction), made on first sight.
  int junction_at(const Vec3& x) {
    for (size_t j = 0; j < junctions_.size(); ++j)
      if ((junctions_[j] - x).norm() < 1e-9) return static_cast<int>(j);
    junctions_.push_back(x);
    return static_cast<int>(junctions_.size()) - 1;
  }

  static Transfer add(const Transfer& m, const Transfer& k, double h) {
    return {m[0] + h * k[0], m[1] + h * k[1], m[2] + h * k[2], m[3] + h * k[3]};
  }

  /// Distance of point @p p from branch @p b's end a, along it.
  [[nodiscard]] double along(int b, const Vec3& p) const {
    const auto& br = branches_[static_cast<size_t>(b)];
    return std::clamp((p - br.a).dot(br.b - br.a) / br.length(), 0.0, br.length());
  }

  /// [P̂; Q̂] at x on branch b, carried from its end a.
  [[nodiscard]] std::array<cd, 2> state_at(int b, double x) const {
    const auto& e = end_state_[static_cast<size_t>(b)];
    const Transfer m = transfer(b, 0.0, x);
    return {m[0] * e[0] + m[1] * e[1], m[2] * e[0] + m[3] * e[1]};
  }

  /// The network node at junction j (the same point).
  [[nodiscard]] int network_node(int j) const {
    for (int i = 0; i < net_.num_nodes(); ++i)
      if ((net_.node(i) - junctions_[static_cast<size_t>(j)]).norm() < 1e-9) return i;
    return -1;
  }

  void solve(double period, int k) {
    const auto n = static_cast<Eigen::Index>(junctions_.size());
    Eigen::MatrixXcd Y = Eigen::MatrixXcd::Zero(n, n);
    Eigen::VectorXcd J = Eigen::VectorXcd::Zero(n), P = Eigen::VectorXcd::Zero(n);
    std::vector<Transfer> m(branches_.size());
    for (size_t b = 0; b < branches_.size(); ++b) {
      m[b] = transfer(static_cast<int>(b), 0.0, branches_[b].length());
      const auto [i, j] = ends_[b];
      const cd inv = 1.0 / m[b][1];
      Y(i, i) -= m[b][0] * inv, Y(i, j) += inv, Y(j, i) += inv, Y(j, j) -= m[b][3] * inv;
    }
    std::vector<bool> known(static_cast<size_t>(n), false);
    for (Eigen::Index j = 0; j < n; ++j) {
      const int node = network_node(static_cast<int>(j));
      for (const auto& in : spec_.inlets) {
        if (in.node != node) continue;
        const cd v = waveform_harmonic(in.waveform, period, k);
        if (in.type == InletBC::Type::Pressure) {
          known[static_cast<size_t>(j)] = true;
          P(j) = v;
        } else {
          J(j) += v;
        }
      }
      for (const auto& o : spec_.outlets) {
        if (o.node != node) continue;
        if (o.type == OutletBC::Type::Pressure) {
          known[static_cast<size_t>(j)] = true;
          P(j) = waveform_harmonic(o.pressure, period, k);
        } else if (o.type == OutletBC::Type::Flow) {
          J(j) -= waveform_harmonic(o.flow, period, k);
        } else {
          Y(j, j) += 1.0 / o.impedance(omega_);
          if (k == 0) J(j) += o.steady_pressure() / o.steady_resistance();
        }
      }
    }
    // Known pressures move to the right-hand side; the rest is one dense complex LU.
    std::vector<Eigen::Index> unknown;
    for (Eigen::Index j = 0; j < n; ++j)
      if (!known[static_cast<size_t>(j)]) unknown.push_back(j);
    const auto nu = static_cast<Eigen::Index>(unknown.size());
    Eigen::MatrixXcd A(nu, nu);
    Eigen::VectorXcd rhs(nu);
    for (Eigen::Index r = 0; r < nu; ++r) {
      rhs(r) = J(unknown[static_cast<size_t>(r)]);
      for (Eigen::Index c = 0; c < n; ++c)
        if (known[static_cast<size_t>(c)]) rhs(r) -= Y(unknown[static_cast<size_t>(r)], c) * P(c);
      for (Eigen::Index c = 0; c < nu; ++c)
        A(r, c) = Y(unknown[static_cast<size_t>(r)], unknown[static_cast<size_t>(c)]);
    }
    const Eigen::VectorXcd x = A.partialPivLu().solve(rhs);
    for (Eigen::Index r = 0; r < nu; ++r) P(unknown[static_cast<size_t>(r)]) = x(r);
    // Each branch's flow at its end a from its two end pressures: Q̂_a = (P̂_b − m₁₁P̂_a)/m₁₂.
    for (size_t b = 0; b < branches_.size(); ++b) {
      const cd pa = P(ends_[b][0]), pb = P(ends_[b][1]);
      end_state_.push_back({pa, (pb - m[b][0] * pa) / m[b][1]});
    }
  }

  std::vector<ExactBranch> branches_;
  FlowSpec spec_;
  const Network& net_;
  double omega_;
  std::vector<Wall> walls_;
  std::vector<std::array<int, 2>> ends_;  // junctions at a and b, per branch
  std::vector<Vec3> junctions_;
  std::vector<std::array<cd, 2>> end_state_;  // per branch: P̂, Q̂ at its end a
};

}  // namespace flowire::flow::test
