// The wall's compliance between lumen points: nearest faces through a uniform grid, the
// face's P2 shape functions at the point, and columns of the tangent's inverse solved per
// lumen node on first use and kept.
#include "flowire/solid/lumen_compliance.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <unordered_map>

#include "flowire/common/element.hpp"
#include "flowire/common/error.hpp"

namespace flowire::solid {
namespace {

/// Closest point of triangle (a, b, c) to p, with its barycentric coordinates (Ericson,
/// Real-Time Collision Detection, §5.1.5).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, std::array<double, 3>& bary) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) {
    bary = {1, 0, 0};
    return a;
  }
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) {
    bary = {0, 1, 0};
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    bary = {1 - v, v, 0};
    return a + v * ab;
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) {
    bary = {0, 0, 1};
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    bary = {1 - w, 0, w};
    return a + w * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    bary = {0, 1 - w, w};
    return b + w * (c - b);
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  bary = {1 - v - w, v, w};
  return a + ab * v + ac * w;
}

}  // namespace

LumenCompliance::LumenCompliance(const ElasticSolid& solid, int lumen, double budget) : solid_(solid) {
  const auto& m = solid.mesh();
  if (lumen < 0 || lumen >= static_cast<int>(m.groups.size()))
    throw_usage_error(fmt::format("wall: no lumen group {}", lumen));
  lumen_index_.assign(static_cast<size_t>(m.num_nodes()), -1);
  double edge = 0.0;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (m.face_group[f] != lumen) continue;
    faces_.push_back(static_cast<int>(f));
    for (int node : m.faces[f]) {
      if (lumen_index_[static_cast<size_t>(node)] < 0) {
        lumen_index_[static_cast<size_t>(node)] = static_cast<int>(lumen_nodes_.size());
        lumen_nodes_.push_back(node);
      }
      lo = lo.cwiseMin(m.nodes[static_cast<size_t>(node)]);
      hi = hi.cwiseMax(m.nodes[static_cast<size_t>(node)]);
    }
    edge += (m.nodes[static_cast<size_t>(m.faces[f][1])] - m.nodes[static_cast<size_t>(m.faces[f][0])]).norm();
  }
  if (faces_.empty())
    throw_usage_error(fmt::format("wall: the lumen group '{}' has no face", m.groups[static_cast<size_t>(lumen)].name));
  // A column: 3 × 3 numbers for each lumen node; at least a few hundred are kept (a step's contacts).
  max_columns_ = std::max<size_t>(
      256, static_cast<size_t>(budget / (9.0 * sizeof(double) * static_cast<double>(lumen_nodes_.size()))));
  cell_ = 2.0 * edge / static_cast<double>(faces_.size());
  const Vec3 extent = hi - lo;
  // No more than about 2 million cells.
  while ((extent / cell_).prod() > 2e6) cell_ *= 2.0;
  grid_origin_ = lo;
  for (int d = 0; d < 3; ++d) dims_[static_cast<size_t>(d)] = static_cast<int>(extent[d] / cell_) + 1;
  cells_.assign(static_cast<size_t>(dims_[0]) * static_cast<size_t>(dims_[1]) * static_cast<size_t>(dims_[2]), {});
  for (size_t k = 0; k < faces_.size(); ++k) {
    const auto& face = m.faces[static_cast<size_t>(faces_[k])];
    Vec3 flo = m.nodes[static_cast<size_t>(face[0])], fhi = flo;
    for (int node : face) {
      flo = flo.cwiseMin(m.nodes[static_cast<size_t>(node)]);
      fhi = fhi.cwiseMax(m.nodes[static_cast<size_t>(node)]);
    }
    std::array<int, 3> c0{}, c1{};
    for (int d = 0; d < 3; ++d) {
      c0[static_cast<size_t>(d)] =
          std::clamp(static_cast<int>((flo[d] - lo[d]) / cell_), 0, dims_[static_cast<size_t>(d)] - 1);
      c1[static_cast<size_t>(d)] =
          std::clamp(static_cast<int>((fhi[d] - lo[d]) / cell_), 0, dims_[static_cast<size_t>(d)] - 1);
    }
    for (int i = c0[0]; i <= c1[0]; ++i)
      for (int j = c0[1]; j <= c1[1]; ++j)
        for (int l = c0[2]; l <= c1[2]; ++l)
          cells_[(static_cast<size_t>(l) * static_cast<size_t>(dims_[1]) + static_cast<size_t>(j)) *
                     static_cast<size_t>(dims_[0]) +
                 static_cast<size_t>(i)]
              .push_back(static_cast<int>(k));
  }
}

LumenPoint LumenCompliance::locate(const Vec3& x) const {
  const auto& m = solid_.mesh();
  LumenPoint best;
  double best_d2 = std::numeric_limits<double>::infinity();
  std::array<int, 3> c{};
  for (int d = 0; d < 3; ++d)
    c[static_cast<size_t>(d)] =
        std::clamp(static_cast<int>((x[d] - grid_origin_[d]) / cell_), 0, dims_[static_cast<size_t>(d)] - 1);
  const int max_ring = std::max({dims_[0], dims_[1], dims_[2]});
  auto visit = [&](int i, int j, int l) {
    for (int k : cells_[(static_cast<size_t>(l) * static_cast<size_t>(dims_[1]) + static_cast<size_t>(j)) *
                            static_cast<size_t>(dims_[0]) +
                        static_cast<size_t>(i)]) {
      const auto& face = m.faces[static_cast<size_t>(faces_[static_cast<size_t>(k)])];
      const Vec3& a = m.nodes[static_cast<size_t>(face[0])];
      const Vec3& b = m.nodes[static_cast<size_t>(face[1])];
      const Vec3& cc = m.nodes[static_cast<size_t>(face[2])];
      std::array<double, 3> bary{};
      const Vec3 q = closest_on_triangle(x, a, b, cc, bary);
      const double d2 = (q - x).squaredNorm();
      if (d2 < best_d2) {
        best_d2 = d2;
        best.face = faces_[static_cast<size_t>(k)];
        best.bary = bary;
        best.point = q;
        best.normal = (b - a).cross(cc - a).normalized();
      }
    }
  };
  for (int ring = 0; ring <= max_ring; ++ring) {
    // The shell of cells at Chebyshev distance `ring` from x's cell.
    for (int i = c[0] - ring; i <= c[0] + ring; ++i)
      for (int j = c[1] - ring; j <= c[1] + ring; ++j)
        for (int l = c[2] - ring; l <= c[2] + ring; ++l) {
          if (std::max({std::abs(i - c[0]), std::abs(j - c[1]), std::abs(l - c[2])}) != ring) continue;
          if (i < 0 || j < 0 || l < 0 || i >= dims_[0] || j >= dims_[1] || l >= dims_[2]) continue;
          visit(i, j, l);
        }
    // Every face not yet visited lies farther than `ring` cells from x.
    if (best.face >= 0 && std::sqrt(best_d2) <= ring * cell_) break;
  }
  if (best.face >= 0) {
    std::array<double, 6> w{};
    element::tri_p2({best.bary[1], best.bary[2], 0.0}, w.data());
    best.weights.reserve(6);
    for (int a = 0; a < 6; ++a)
      best.weights.emplace_back(m.faces[static_cast<size_t>(best.face)][static_cast<size_t>(a)],
                                w[static_cast<size_t>(a)]);
  }
  return best;
}

LumenPoint LumenCompliance::locate_patch(const Vec3& x, double radius) const {
  LumenPoint centre = locate(x);
  if (!(radius > 0.0) || centre.face < 0) return centre;
  const auto& m = solid_.mesh();
  // Rings of samples as fine as the faces at the centre (their longest edge), at least three:
  // ring k (k = 1..K) covers radii [(k−1)ρ/K, kρ/K] with 6(k−1) samples at its centroid radius
  // (the first, a disc, one at the centre), each weighted by its share of the disc's area.
  const auto& f = m.faces[static_cast<size_t>(centre.face)];
  double edge = 0.0;
  for (int i = 0; i < 3; ++i)
    edge = std::max(edge, (m.nodes[static_cast<size_t>(f[static_cast<size_t>(i)])] -
                           m.nodes[static_cast<size_t>(f[static_cast<size_t>((i + 1) % 3)])])
                              .norm());
  const int rings = std::clamp(static_cast<int>(std::ceil(2.0 * radius / std::max(edge, 1e-300))), 3, 24);
  const Vec3 n = centre.normal;
  const Vec3 e1 = (std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(n).normalized();
  const Vec3 e2 = n.cross(e1);
  std::unordered_map<int, double> acc;
  auto add = [&](const Vec3& y, double w) {
    for (const auto& [node, wn] : locate(y).weights) acc[node] += w * wn;
  };
  const double dr = 1.0 / rings;
  add(centre.point, dr * dr);
  for (int k = 2; k <= rings; ++k) {
    const double ri = (k - 1) * dr, ro = k * dr;
    const double rc = radius * (2.0 / 3.0) * (ro * ro * ro - ri * ri * ri) / (ro * ro - ri * ri);
    const int count = 6 * (k - 1);
    const double w = (ro * ro - ri * ri) / count;
    for (int j = 0; j < count; ++j) {
      const double phi = (2.0 * std::numbers::pi * (j + 0.5 * (k % 2))) / count;
      add(centre.point + rc * (std::cos(phi) * e1 + std::sin(phi) * e2), w);
    }
  }
  centre.weights.assign(acc.begin(), acc.end());
  std::sort(centre.weights.begin(), centre.weights.end());
  return centre;
}

const Eigen::MatrixXd& LumenCompliance::column(int node) const { return columns_.at(node); }

void LumenCompliance::prefetch(std::span<const LumenPoint> points) {
  ++tick_;
  std::vector<int> missing;
  for (const auto& p : points)
    for (const auto& [node, w] : p.weights) {
      last_use_[node] = tick_;
      if (!columns_.count(node) && std::find(missing.begin(), missing.end(), node) == missing.end())
        missing.push_back(node);
    }
  // Many right-hand sides per back-substitution: the supernodal solve then works on blocks.
  constexpr size_t kBatch = 64;
  for (size_t first = 0; first < missing.size(); first += kBatch) {
    const size_t count = std::min(kBatch, missing.size() - first);
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(solid_.num_dofs(), 3 * static_cast<Eigen::Index>(count));
    for (size_t q = 0; q < count; ++q)
      for (int c = 0; c < 3; ++c) x(3 * missing[first + q] + c, 3 * static_cast<Eigen::Index>(q) + c) = 1.0;
    solid_.tangent_solve(x);
    for (size_t q = 0; q < count; ++q) {
      Eigen::MatrixXd kept(3 * static_cast<Eigen::Index>(lumen_nodes_.size()), 3);
      for (size_t a = 0; a < lumen_nodes_.size(); ++a)
        kept.middleRows<3>(3 * static_cast<Eigen::Index>(a)) =
            x.block<3, 3>(3 * lumen_nodes_[a], 3 * static_cast<Eigen::Index>(q));
      columns_.emplace(missing[first + q], std::move(kept));
    }
  }
  solved_ += static_cast<int>(missing.size());
  if (columns_.size() <= max_columns_) return;
  // Over the budget: drop the columns asked for longest ago (never those of this call).
  std::vector<std::pair<std::uint64_t, int>> by_age;
  for (const auto& [node, column] : columns_) {
    (void)column;
    const std::uint64_t used = last_use_[node];
    if (used < tick_) by_age.emplace_back(used, node);
  }
  std::sort(by_age.begin(), by_age.end());
  for (const auto& [used, node] : by_age) {
    if (columns_.size() <= max_columns_) break;
    columns_.erase(node);
    last_use_.erase(node);
    ++dropped_;
  }
}

Eigen::MatrixXd LumenCompliance::compliance(std::span<const LumenPoint> points, std::span<const Vec3> directions) {
  prefetch(points);
  const auto n = static_cast<Eigen::Index>(points.size());
  Eigen::MatrixXd c(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const auto& pj = points[static_cast<size_t>(j)];
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto& pi = points[static_cast<size_t>(i)];
      const Vec3& di = directions[static_cast<size_t>(i)];
      double sum = 0.0;
      for (const auto& [node_b, wb] : pj.weights) {
        const Eigen::MatrixXd& col = column(node_b);
        const Vec3 load = wb * directions[static_cast<size_t>(j)];
        for (const auto& [node_a, wa] : pi.weights)
          sum += wa * di.dot(col.middleRows<3>(3 * lumen_index_[static_cast<size_t>(node_a)]) * load);
      }
      c(i, j) = sum;  // (each entry from its own column: the symmetry is Maxwell–Betti's, not imposed)
    }
  }
  return c;
}

Vec3 LumenCompliance::displacement(const LumenPoint& at, std::span<const LumenPoint> points,
                                   std::span<const Vec3> forces) {
  prefetch(points);
  Vec3 u = Vec3::Zero();
  for (size_t j = 0; j < points.size(); ++j)
    for (const auto& [node_b, wb] : points[j].weights) {
      const Eigen::MatrixXd& col = column(node_b);
      const Vec3 load = wb * forces[j];
      for (const auto& [node_a, wa] : at.weights)
        u += wa * (col.middleRows<3>(3 * lumen_index_[static_cast<size_t>(node_a)]) * load);
    }
  return u;
}

Vec3 LumenCompliance::interpolate(const LumenPoint& at, const Eigen::VectorXd& field) const {
  Vec3 v = Vec3::Zero();
  for (const auto& [node, w] : at.weights) v += w * field.segment<3>(3 * node);
  return v;
}

Eigen::VectorXd LumenCompliance::nodal_forces(std::span<const LumenPoint> points, std::span<const Vec3> forces) const {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(solid_.num_dofs());
  for (size_t j = 0; j < points.size(); ++j)
    for (const auto& [node, w] : points[j].weights) f.segment<3>(3 * node) += w * forces[j];
  return f;
}

}  // namespace flowire::solid
