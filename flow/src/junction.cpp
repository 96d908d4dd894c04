// Mynard & Valen-Sendstad's unified junction loss model (junction.hpp), in the branches' own
// directions in space, with its exact derivatives by forward automatic differentiation.
#include "flowire/flow/junction.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <type_traits>
#include <unsupported/Eigen/AutoDiff>

namespace flowire::flow {
namespace {

using Dual = Eigen::AutoDiffScalar<Eigen::VectorXd>;

double value_of(double x) { return x; }
double value_of(const Dual& x) { return x.value(); }

template <class T>
struct Vec {
  T x, y, z;
};
// Constants are made from `zero` (a Dual of zero value and derivatives of the right size): a
// Dual constant without derivatives would not combine with the others inside an expression.
template <class T>
Vec<T> constant(const Vec3& v, const T& zero) {
  return {zero + v.x(), zero + v.y(), zero + v.z()};
}
template <class T>
T dot(const Vec<T>& a, const Vec<T>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class T>
Vec<T> cross(const Vec<T>& a, const Vec<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
/// The angle between two unit vectors, in [0, π]: atan2(|a × b|, a·b), accurate near 0 and π,
/// where its derivative is singular and taken as zero (parallel directions).
template <class T>
T angle(const Vec<T>& a, const Vec<T>& b, const T& zero) {
  const Vec<T> c = cross(a, b);
  const T s2 = dot(c, c);
  const T d = dot(a, b);
  if (value_of(s2) < 1e-24) return zero + (value_of(d) > 0.0 ? 0.0 : std::numbers::pi);
  using std::atan2;
  using std::sqrt;
  return atan2(sqrt(s2), d);
}

/// C of every branch (junction.hpp) at the outward flows @p o.
template <class T>
void coefficients(const Junction& j, const T* o, T* c) {
  using std::cos;
  using std::exp;
  using std::sqrt;
  constexpr double pi = std::numbers::pi;
  const size_t n = j.branches.size();
  if (n == 0) return;
  const T zero = o[0] * 0.0;
  for (size_t i = 0; i < n; ++i) c[i] = zero;
  // The suppliers (flow into the junction, outward ≤ 0) merged: their total flow, their flow-
  // weighted direction and Σ U_s Q_s.
  T qtot = zero, energy = zero;
  Vec<T> sup{zero, zero, zero};
  Vec3 collectors = Vec3::Zero();
  int num_collectors = 0;
  size_t largest = 0;
  double largest_q = -1.0;
  for (size_t i = 0; i < n; ++i) {
    const auto& b = j.branches[i];
    if (value_of(o[i]) > 0.0) {
      collectors += b.direction;
      ++num_collectors;
      continue;
    }
    const T q = -o[i];
    qtot += q;
    energy += q * q / b.area;
    sup.x += q * b.direction.x();
    sup.y += q * b.direction.y();
    sup.z += q * b.direction.z();
    if (value_of(q) > largest_q) {
      largest_q = value_of(q);
      largest = i;
    }
  }
  if (num_collectors == 0 || !(value_of(qtot) > 0.0)) return;
  Vec<T> ps;
  const T sup_norm2 = dot(sup, sup);
  if (value_of(sup_norm2) > 1e-30 * value_of(qtot) * value_of(qtot)) {
    const T len = sqrt(sup_norm2);
    ps = {sup.x / len, sup.y / len, sup.z / len};
  } else {  // suppliers meeting head on: the largest one's direction
    ps = constant<T>(j.branches[largest].direction, zero);
  }
  // The merged collector, turned so that the pseudo-supplier lies at least π/2 from it.
  Vec3 pc = collectors.norm() > 1e-12 ? Vec3(collectors.normalized())
                                      : Vec3(-value_of(ps.x), -value_of(ps.y), -value_of(ps.z));
  T cos_theta = dot(ps, constant<T>(pc, zero));
  if (value_of(cos_theta) > 0.0) {
    pc = -pc;
    cos_theta = -cos_theta;
  }
  const Vec<T> pcv = constant<T>(pc, zero);
  const T theta = angle(ps, pcv, zero);
  // The pseudo-supplier's side of the pseudo-collector's axis.
  const Vec<T> side{ps.x - cos_theta * pcv.x, ps.y - cos_theta * pcv.y, ps.z - cos_theta * pcv.z};
  for (size_t i = 0; i < n; ++i) {
    if (!(value_of(o[i]) > 0.0)) continue;
    const auto& b = j.branches[i];
    const Vec<T> e = constant<T>(b.direction, zero);
    const double s = value_of(dot(e, side));
    const double sigma = s > 1e-12 ? 1.0 : (s < -1e-12 ? -1.0 : 0.0);
    const T lambda = o[i] / qtot;
    const T eta = (0.8 * (pi - theta) * sigma - 0.2) * (1.0 - lambda);
    const T area_ratio = qtot * qtot / ((1.0 - eta) * energy) / b.area;
    const T psi = angle(ps, e, zero);
    c[i] = (1.0 - exp(-lambda / 0.02)) * (1.0 - cos(0.75 * (pi - psi)) / (area_ratio * lambda));
  }
}

/// The length-weighted median of a branch's segment radii: its section away from a flared junction
/// (where a section normal to one branch's centerline also cuts the others).
double median_radius(const Network& net, const vessels::Branch& br) {
  std::vector<std::pair<double, double>> rl;
  double total = 0.0;
  for (int s : br.segments) {
    rl.emplace_back(net.segment(s).radius, net.segment(s).length);
    total += net.segment(s).length;
  }
  std::sort(rl.begin(), rl.end());
  double acc = 0.0;
  for (const auto& [r, l] : rl) {
    acc += l;
    if (acc >= 0.5 * total) return r;
  }
  return rl.empty() ? 0.0 : rl.back().first;
}

}  // namespace

std::vector<Junction> find_junctions(const Network& net) {
  std::vector<Junction> out;
  for (int node = 0; node < net.num_nodes(); ++node) {
    if (net.degree(node) < 3) continue;
    Junction j;
    j.node = node;
    const auto [first, last] = net.node_segments(node);
    for (const int* it = first; it != last; ++it) {
      const int s = *it;
      const auto& seg = net.segment(s);
      JunctionBranch b;
      b.segment = s;
      b.outward = seg.node_from == node ? 1.0 : -1.0;
      const int far = seg.node_from == node ? seg.node_to : seg.node_from;
      const auto& br = net.branch(seg.branch);
      const double r = median_radius(net, br);
      b.area = std::numbers::pi * r * r;
      // Along the branch from the junction until two radii from it (or the branch's end).
      const auto pos = std::find(br.segments.begin(), br.segments.end(), s);
      const int k0 = static_cast<int>(pos - br.segments.begin());
      const int step = pos != br.segments.end() && br.nodes[static_cast<size_t>(k0)] == node ? 1 : -1;
      Vec3 tip = net.node(far);
      for (int k = k0; pos != br.segments.end() && k >= 0 && k < static_cast<int>(br.segments.size()); k += step) {
        const int end = step > 0 ? br.nodes[static_cast<size_t>(k) + 1] : br.nodes[static_cast<size_t>(k)];
        tip = net.node(end);
        if ((tip - net.node(node)).norm() >= 2.0 * r || net.degree(end) != 2) break;
      }
      const Vec3 d = tip - net.node(node);
      b.direction = d.norm() > 0.0 ? Vec3(d.normalized()) : Vec3(1.0, 0.0, 0.0);
      j.branches.push_back(b);
    }
    out.push_back(std::move(j));
  }
  return out;
}

std::vector<double> unified_junction_coefficients(const Junction& j, const double* outward) {
  std::vector<double> c(j.branches.size());
  coefficients<double>(j, outward, c.data());
  return c;
}

void unified_junction_drops(const Junction& j, double density, const double* outward, double* drop, double* jacobian) {
  const size_t n = j.branches.size();
  // (Returns its own type: an automatic-differentiation expression would outlive its operands.)
  auto velocity2 = [&](size_t i, const auto& q) -> std::decay_t<decltype(q)> {
    return q * q / (j.branches[i].area * j.branches[i].area);
  };
  if (jacobian == nullptr) {
    coefficients<double>(j, outward, drop);  // C, then C ρ U² in place
    for (size_t i = 0; i < n; ++i) drop[i] = drop[i] * density * velocity2(i, outward[i]);
    return;
  }
  std::vector<Dual> o(n), c(n);
  for (size_t i = 0; i < n; ++i) o[i] = Dual(outward[i], static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(i));
  coefficients<Dual>(j, o.data(), c.data());
  for (size_t i = 0; i < n; ++i) {
    const Dual d = c[i] * density * velocity2(i, o[i]);
    drop[i] = d.value();
    for (size_t k = 0; k < n; ++k)
      jacobian[i * n + k] = d.derivatives().size() > 0 ? d.derivatives()[static_cast<Eigen::Index>(k)] : 0.0;
  }
}

void segment_end_drops(const Network& net, const std::vector<Junction>& junctions, double density, const double* q,
                       std::vector<std::array<double, 2>>& drops, std::vector<std::vector<double>>* jacobians) {
  drops.assign(static_cast<size_t>(net.num_segments()), {0.0, 0.0});
  if (jacobians) jacobians->resize(junctions.size());
  thread_local std::vector<double> outward, drop;  // (a junction's branches) reused from call to call
  for (size_t i = 0; i < junctions.size(); ++i) {
    const auto& j = junctions[i];
    const size_t n = j.branches.size();
    outward.resize(n);
    drop.resize(n);
    for (size_t b = 0; b < n; ++b) outward[b] = j.branches[b].outward * q[j.branches[b].segment];
    double* jac = nullptr;
    if (jacobians) {
      (*jacobians)[i].resize(n * n);
      jac = (*jacobians)[i].data();
    }
    unified_junction_drops(j, density, outward.data(), drop.data(), jac);
    for (size_t b = 0; b < n; ++b) {
      const int s = j.branches[b].segment;
      drops[static_cast<size_t>(s)][net.segment(s).node_from == j.node ? 0 : 1] = drop[b];
    }
  }
}

}  // namespace flowire::flow
