// Point location in a curved quadratic tetrahedral mesh and field evaluation.
#include "flowire/flow/fem/sample.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <tuple>

#include "flowire/flow/fem/element.hpp"

namespace flowire::flow::fem {

FieldSampler::FieldSampler(const TetMesh& mesh, const StokesSolution& solution) : mesh_(mesh), sol_(solution) {
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (const Vec3& x : mesh.nodes) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  const Vec3 ext = (hi - lo).cwiseMax(Vec3::Constant(1e-12));
  // About two tetrahedra per bucket on average.
  const double vol = ext.prod();
  const double target = std::cbrt(vol / std::max(1.0, 0.5 * mesh.num_tets()));
  for (int d = 0; d < 3; ++d)
    dims_[static_cast<size_t>(d)] = std::clamp(static_cast<int>(std::ceil(ext[d] / target)), 1, 512);
  lo_ = lo;
  cell_ = Vec3(ext[0] / dims_[0], ext[1] / dims_[1], ext[2] / dims_[2]);
  const size_t nb = static_cast<size_t>(dims_[0]) * static_cast<size_t>(dims_[1]) * static_cast<size_t>(dims_[2]);
  auto range = [&](const std::array<int, 10>& t, std::array<int, 3>& a, std::array<int, 3>& b) {
    Vec3 tl = Vec3::Constant(1e300), th = Vec3::Constant(-1e300);
    for (int n : t) {
      tl = tl.cwiseMin(mesh.nodes[static_cast<size_t>(n)]);
      th = th.cwiseMax(mesh.nodes[static_cast<size_t>(n)]);
    }
    for (int d = 0; d < 3; ++d) {
      a[static_cast<size_t>(d)] =
          std::clamp(static_cast<int>(std::floor((tl[d] - lo_[d]) / cell_[d])), 0, dims_[static_cast<size_t>(d)] - 1);
      b[static_cast<size_t>(d)] =
          std::clamp(static_cast<int>(std::floor((th[d] - lo_[d]) / cell_[d])), 0, dims_[static_cast<size_t>(d)] - 1);
    }
  };
  offset_.assign(nb + 1, 0);
  std::array<int, 3> a{}, b{};
  for (const auto& t : mesh.tets) {
    range(t, a, b);
    for (int i = a[0]; i <= b[0]; ++i)
      for (int j = a[1]; j <= b[1]; ++j)
        for (int k = a[2]; k <= b[2]; ++k) ++offset_[static_cast<size_t>((i * dims_[1] + j) * dims_[2] + k) + 1];
  }
  for (size_t i = 0; i < nb; ++i) offset_[i + 1] += offset_[i];
  items_.resize(static_cast<size_t>(offset_.back()));
  std::vector<int> fill(offset_.begin(), offset_.end() - 1);
  for (size_t e = 0; e < mesh.tets.size(); ++e) {
    range(mesh.tets[e], a, b);
    for (int i = a[0]; i <= b[0]; ++i)
      for (int j = a[1]; j <= b[1]; ++j)
        for (int k = a[2]; k <= b[2]; ++k)
          items_[static_cast<size_t>(fill[static_cast<size_t>((i * dims_[1] + j) * dims_[2] + k)]++)] =
              static_cast<int>(e);
  }
}

int FieldSampler::locate(const Vec3& x, double tolerance, std::array<double, 3>& xi) const {
  int idx[3];
  for (int d = 0; d < 3; ++d) {
    const double c = (x[d] - lo_[d]) / cell_[d];
    if (c < -1e-9 * dims_[static_cast<size_t>(d)] || c > dims_[static_cast<size_t>(d)] * (1.0 + 1e-9)) return -1;
    idx[d] = std::clamp(static_cast<int>(std::floor(c)), 0, dims_[static_cast<size_t>(d)] - 1);
  }
  const size_t bucket = static_cast<size_t>((idx[0] * dims_[1] + idx[1]) * dims_[2] + idx[2]);
  int best = -1;
  double best_min = -1e300;
  std::array<double, 3> best_xi{};
  double grads[10][3], phi[10];
  for (int k = offset_[bucket]; k < offset_[bucket + 1]; ++k) {
    const int e = items_[static_cast<size_t>(k)];
    const auto& t = mesh_.tets[static_cast<size_t>(e)];
    const Vec3& x0 = mesh_.nodes[static_cast<size_t>(t[0])];
    Eigen::Matrix3d m;
    for (int c = 0; c < 3; ++c) m.col(c) = mesh_.nodes[static_cast<size_t>(t[static_cast<size_t>(c + 1)])] - x0;
    Eigen::Vector3d r = m.partialPivLu().solve(x - x0);
    if (std::min({r[0], r[1], r[2], 1.0 - r.sum()}) < -0.2) continue;
    // Newton on the quadratic map.
    std::array<double, 3> s{r[0], r[1], r[2]};
    for (int it = 0; it < 20; ++it) {
      tet_p2(s, phi);
      tet_p2_grad(s, grads);
      Vec3 f = -x;
      Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
      for (int i = 0; i < 10; ++i) {
        const Vec3& xn = mesh_.nodes[static_cast<size_t>(t[static_cast<size_t>(i)])];
        f += phi[i] * xn;
        j += xn * Eigen::RowVector3d(grads[i][0], grads[i][1], grads[i][2]);
      }
      const Eigen::Vector3d ds = j.partialPivLu().solve(f);
      for (int d = 0; d < 3; ++d) s[static_cast<size_t>(d)] -= ds[d];
      if (ds.cwiseAbs().maxCoeff() < 1e-13) break;
    }
    const double mn = std::min({s[0], s[1], s[2], 1.0 - s[0] - s[1] - s[2]});
    if (mn > best_min) {
      best_min = mn;
      best = e;
      best_xi = s;
    }
    if (mn >= 0.0) break;
  }
  if (best < 0 || best_min < -tolerance) return -1;
  xi = best_xi;
  return best;
}

std::optional<PointValue> FieldSampler::at(const Vec3& x, double tolerance) const {
  std::array<double, 3> xi{};
  const int e = locate(x, tolerance, xi);
  if (e < 0) return std::nullopt;
  PointValue v;
  v.tet = e;
  double phi[10], psi[4];
  tet_p2(xi, phi);
  tet_p1(xi, psi);
  const auto& t = mesh_.tets[static_cast<size_t>(e)];
  for (int i = 0; i < 10; ++i) v.velocity += phi[i] * sol_.velocity[static_cast<size_t>(t[static_cast<size_t>(i)])];
  for (int l = 0; l < 4; ++l)
    v.pressure +=
        psi[l] * sol_.pressure[static_cast<size_t>(mesh_.vertex_index[static_cast<size_t>(t[static_cast<size_t>(l)])])];
  return v;
}

std::tuple<double, double, bool> section_pressure(const FieldSampler& fs, const Vec3& c, const Vec3& axis, double r) {
  const Vec3 t = axis.normalized();
  const Vec3 a = (std::abs(t.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(t).normalized();
  const Vec3 b = t.cross(a);
  // Equal-area rings (midpoints in ρ²) times 12 angles, plus the centre.
  constexpr int kRings = 4, kAngles = 12;
  const double rmax = 0.95 * r;
  double sum = 0.0, weight = 0.0, centre = std::numeric_limits<double>::quiet_NaN();
  const double tol = 1e-6;
  if (auto v = fs.at(c, tol)) centre = v->pressure;
  for (int i = 0; i < kRings; ++i) {
    const double rho = rmax * std::sqrt((i + 0.5) / kRings);
    for (int k = 0; k < kAngles; ++k) {
      const double phi = 2.0 * std::numbers::pi * (k + 0.5 * (i % 2)) / kAngles;
      const Vec3 x = c + rho * (std::cos(phi) * a + std::sin(phi) * b);
      if (auto v = fs.at(x, tol)) {
        sum += v->pressure;
        weight += 1.0;
      }
    }
  }
  if (weight == 0.0 && std::isnan(centre)) return {0.0, 0.0, false};
  const double mean = weight > 0.0 ? sum / weight : centre;
  return {mean, std::isnan(centre) ? mean : centre, true};
}

std::optional<double> section_total_pressure(const FieldSampler& fs, const Vec3& c, const Vec3& axis, double r,
                                             double density) {
  const Vec3 t = axis.normalized();
  const Vec3 a = (std::abs(t.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(t).normalized();
  const Vec3 b = t.cross(a);
  constexpr int kRings = 8, kAngles = 24;  // equal-area rings: every point weighs the same
  double energy = 0.0, flux = 0.0;
  for (int i = 0; i < kRings; ++i) {
    const double rho = r * std::sqrt((i + 0.5) / kRings);
    for (int k = 0; k < kAngles; ++k) {
      const double phi = 2.0 * std::numbers::pi * (k + 0.5 * (i % 2)) / kAngles;
      const auto v = fs.at(c + rho * (std::cos(phi) * a + std::sin(phi) * b), 1e-6);
      if (!v) continue;
      const double un = v->velocity.dot(t);
      energy += (v->pressure + 0.5 * density * v->velocity.squaredNorm()) * un;
      flux += un;
    }
  }
  if (!(std::abs(flux) > 0.0)) return std::nullopt;
  return energy / flux;
}

}  // namespace flowire::flow::fem
