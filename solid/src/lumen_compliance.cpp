// The wall's compliance between lumen points: nearest faces through a uniform grid, the
// face's P2 shape functions at the point, and per lumen node the sparse forward solve
// L⁻¹ P E_a of the tangent's factor, solved on first use and kept.
#include "flowire/solid/lumen_compliance.hpp"

#include <fmt/format.h>
#include <sched.h>

#include <Eigen/Sparse>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <limits>
#include <mutex>
#include <numbers>
#include <thread>
#include <unordered_map>

#include "flowire/common/element.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/kernel_clones.hpp"

// BLAS's symmetric rank-k update on the lower triangle of C: C ← α A Aᵀ + β C (trans "N", A n × k)
// or α Aᵀ A + β C ("T", A k × n); the Fortran interface.
extern "C" void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha,
                       const double* a, const int* lda, const double* beta, double* c, const int* ldc, size_t uplo_len,
                       size_t trans_len);

namespace flowire::solid {
namespace {

// Zᵀ(lo + q, slot_k) += u_q · v_k for a node's entries k (rows slot_k of Zᵀ's np-long columns, values
// v_k, three a row) and the weights u_q (u0, u1, u2: three contiguous runs of @p width) of the
// points lo .. lo + width − 1: the inner loop over the points is contiguous, in vector registers.
FLOWIRE_KERNEL_CLONES
void add_node_columns(const double* v, const int* slot, size_t count, const double* u, size_t width, double* zt,
                      Eigen::Index np) {
  const double* __restrict u0 = u;
  const double* __restrict u1 = u + width;
  const double* __restrict u2 = u + 2 * width;
  for (size_t k = 0; k < count; ++k) {
    double* __restrict z = zt + static_cast<size_t>(slot[k]) * static_cast<size_t>(np);
    const double v0 = v[3 * k], v1 = v[3 * k + 1], v2 = v[3 * k + 2];
    for (size_t q = 0; q < width; ++q) z[q] += u0[q] * v0 + u1[q] * v1 + u2[q] * v2;
  }
}

// G += Σ_k a_k b_kᵀ over @p count rows, a_k and b_k the three values of row k of two nodes' columns
// (three a row, contiguous; G column-major 3 × 3). Row k's b is loaded four wide (its three and the
// next row's first, whose products are dropped): three multiply-adds of four a row instead of nine,
// two rows at a time for independent sums.
FLOWIRE_KERNEL_CLONES
void add_row_products(const double* __restrict a, const double* __restrict b, size_t count, double* __restrict g) {
  using V4 = double __attribute__((vector_size(32)));
  V4 s0{}, s1{}, s2{}, t0{}, t1{}, t2{};
  size_t k = 0;
  for (; k + 2 < count; k += 2) {  // row k + 1's four-wide load reads row k + 2's first value
    V4 b0, b1;
    std::memcpy(&b0, b + 3 * k, sizeof b0);
    std::memcpy(&b1, b + 3 * k + 3, sizeof b1);
    s0 += a[3 * k] * b0, s1 += a[3 * k + 1] * b0, s2 += a[3 * k + 2] * b0;
    t0 += a[3 * k + 3] * b1, t1 += a[3 * k + 4] * b1, t2 += a[3 * k + 5] * b1;
  }
  s0 += t0, s1 += t1, s2 += t2;
  for (int c = 0; c < 3; ++c) g[3 * c] += s0[c], g[3 * c + 1] += s1[c], g[3 * c + 2] += s2[c];
  for (; k < count; ++k)
    for (size_t r = 0; r < 3; ++r)
      for (size_t c = 0; c < 3; ++c) g[3 * c + r] += a[3 * k + r] * b[3 * k + c];
}

// G_ab = Y_aᵀ Y_b over the rows both columns hold: both are ascending, and two lumen nodes' reaches
// share the path from where they meet in the elimination tree to its root, so after the jumps past
// each one's own rows the shared rows come in long equal runs, each a dense product.
Mat3 column_block(const HalfColumns& a, const HalfColumns& b) {
  Mat3 g = Mat3::Zero();
  const int* ia = a.index.data();
  const int* ib = b.index.data();
  const int* const ea = ia + a.size();
  const int* const eb = ib + b.size();
  while (ia < ea && ib < eb) {
    if (*ia < *ib) {
      ia = std::lower_bound(ia, ea, *ib);
    } else if (*ib < *ia) {
      ib = std::lower_bound(ib, eb, *ia);
    } else {
      const auto run = std::mismatch(ia, ea, ib, eb);
      const auto count = static_cast<size_t>(run.first - ia);
      add_row_products(a.value.data() + 3 * (ia - a.index.data()), b.value.data() + 3 * (ib - b.index.data()), count,
                       g.data());
      ia = run.first;
      ib = run.second;
    }
  }
  return g;
}

/// The cores this process may run on (its affinity; a process pinned to one core of many has one).
int usable_cores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) return CPU_COUNT(&set);
  return static_cast<int>(std::thread::hardware_concurrency());
}

/// The key of the ordered node pair (a, b).
std::uint64_t pair_key(int a, int b) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

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
  double edge = 0.0;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (m.face_group[f] != lumen) continue;
    faces_.push_back(static_cast<int>(f));
    for (int node : m.faces[f]) {
      lo = lo.cwiseMin(m.nodes[static_cast<size_t>(node)]);
      hi = hi.cwiseMax(m.nodes[static_cast<size_t>(node)]);
    }
    edge += (m.nodes[static_cast<size_t>(m.faces[f][1])] - m.nodes[static_cast<size_t>(m.faces[f][0])]).norm();
  }
  if (faces_.empty())
    throw_usage_error(fmt::format("wall: the lumen group '{}' has no face", m.groups[static_cast<size_t>(lumen)].name));
  budget_ = budget;
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
    Vec3 clo = m.nodes[static_cast<size_t>(face[0])], chi = clo;  // (the flat triangle closer() measures)
    for (int c = 1; c < 3; ++c) {
      clo = clo.cwiseMin(m.nodes[static_cast<size_t>(face[static_cast<size_t>(c)])]);
      chi = chi.cwiseMax(m.nodes[static_cast<size_t>(face[static_cast<size_t>(c)])]);
    }
    face_lo_.push_back(clo);
    face_hi_.push_back(chi);
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
                        static_cast<size_t>(i)])
      closer(x, k, best, best_d2);
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
    // Every face not yet visited lies outside the block of cells visited (its bounding box meets
    // none of them): farther from x than `ring` cells, and than x is from the block's sides.
    if (best.face < 0) continue;
    double inside = std::numeric_limits<double>::infinity();
    for (int d = 0; d < 3; ++d) {
      const double lo = grid_origin_[d] + (c[static_cast<size_t>(d)] - ring) * cell_;
      inside = std::min({inside, x[d] - lo, lo + (2 * ring + 1) * cell_ - x[d]});
    }
    if (std::sqrt(best_d2) <= std::max(ring * cell_, inside)) break;
  }
  if (best.face >= 0) set_normal(best), shape_weights(best);
  return best;
}

void LumenCompliance::closer(const Vec3& x, int k, LumenPoint& best, double& best_d2) const {
  // (no nearer than its corners' box)
  const Vec3 out = (face_lo_[static_cast<size_t>(k)] - x).cwiseMax(x - face_hi_[static_cast<size_t>(k)]).cwiseMax(0.0);
  if (out.squaredNorm() >= best_d2) return;
  const auto& m = solid_.mesh();
  const auto& face = m.faces[static_cast<size_t>(faces_[static_cast<size_t>(k)])];
  const Vec3& a = m.nodes[static_cast<size_t>(face[0])];
  const Vec3& b = m.nodes[static_cast<size_t>(face[1])];
  const Vec3& c = m.nodes[static_cast<size_t>(face[2])];
  std::array<double, 3> bary{};
  const Vec3 q = closest_on_triangle(x, a, b, c, bary);
  const double d2 = (q - x).squaredNorm();
  if (d2 < best_d2) {
    best_d2 = d2;
    best.face = faces_[static_cast<size_t>(k)];
    best.bary = bary;
    best.point = q;
  }
}

void LumenCompliance::set_normal(LumenPoint& p) const {
  const auto& m = solid_.mesh();
  const auto& face = m.faces[static_cast<size_t>(p.face)];
  const Vec3& a = m.nodes[static_cast<size_t>(face[0])];
  const Vec3& b = m.nodes[static_cast<size_t>(face[1])];
  const Vec3& c = m.nodes[static_cast<size_t>(face[2])];
  p.normal = (b - a).cross(c - a).normalized();
}

void LumenCompliance::shape_weights(LumenPoint& p) const {
  std::array<double, 6> w{};
  element::tri_p2({p.bary[1], p.bary[2], 0.0}, w.data());
  p.weights.clear();
  p.weights.reserve(6);
  for (int a = 0; a < 6; ++a)
    p.weights.emplace_back(solid_.mesh().faces[static_cast<size_t>(p.face)][static_cast<size_t>(a)],
                           w[static_cast<size_t>(a)]);
}

void LumenCompliance::faces_within(const Vec3& x, double r, std::vector<int>& near) const {
  near.clear();
  std::array<int, 3> c0{}, c1{};
  for (int d = 0; d < 3; ++d) {
    const auto dd = static_cast<size_t>(d);
    c0[dd] = std::clamp(static_cast<int>((x[d] - r - grid_origin_[d]) / cell_), 0, dims_[dd] - 1);
    c1[dd] = std::clamp(static_cast<int>((x[d] + r - grid_origin_[d]) / cell_), 0, dims_[dd] - 1);
  }
  for (int i = c0[0]; i <= c1[0]; ++i)
    for (int j = c0[1]; j <= c1[1]; ++j)
      for (int l = c0[2]; l <= c1[2]; ++l) {
        const auto& cell = cells_[(static_cast<size_t>(l) * static_cast<size_t>(dims_[1]) + static_cast<size_t>(j)) *
                                      static_cast<size_t>(dims_[0]) +
                                  static_cast<size_t>(i)];
        near.insert(near.end(), cell.begin(), cell.end());
      }
  std::sort(near.begin(), near.end());
  near.erase(std::unique(near.begin(), near.end()), near.end());
  std::erase_if(near, [&](int k) {
    LumenPoint probe;
    double d2 = r * r * (1.0 + 1e-12);
    closer(x, k, probe, d2);
    return probe.face < 0;
  });
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
  // A sample y lies within ρ of the centre c, so its nearest lumen point q does within 2ρ of c
  // (|q − y| ≤ |c − y| ≤ ρ): the faces within 2ρ of the centre are all a sample's search needs.
  std::vector<int> near;
  faces_within(centre.point, 2.0 * radius, near);
  std::vector<std::pair<int, double>> acc;  // (node, weight): a few dozen
  LumenPoint sample;
  if (near.empty()) return centre;  // (never: the centre's face is within)
  // The last sample's face, tried first: the next sample's is mostly the same, and its distance
  // prunes the others by their boxes. The first is the centre's.
  size_t hint = 0;
  for (size_t i = 0; i < near.size(); ++i)
    if (faces_[static_cast<size_t>(near[i])] == centre.face) hint = i;
  auto add = [&](const Vec3& y, double w) {
    double best_d2 = std::numeric_limits<double>::infinity();
    closer(y, near[hint], sample, best_d2);
    for (size_t i = 0; i < near.size(); ++i)
      if (i != hint) {
        const int before = sample.face;
        closer(y, near[i], sample, best_d2);
        if (sample.face != before) hint = i;
      }
    shape_weights(sample);
    for (const auto& [node, wn] : sample.weights) {
      auto it = std::find_if(acc.begin(), acc.end(), [node = node](const auto& e) { return e.first == node; });
      if (it == acc.end())
        acc.emplace_back(node, w * wn);
      else
        it->second += w * wn;
    }
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
  std::sort(acc.begin(), acc.end());
  centre.weights = std::move(acc);
  return centre;
}

struct LumenCompliance::Ahead {
  // Each lumen node's column: not kept (0), kept or being solved by the caller (1), being solved by
  // the second thread (2), solved by it and not yet taken (3). Under `m`, as everything below but
  // the thread's workspace and `solved`.
  enum State : char { free = 0, caller = 1, solving = 2, solved_ahead = 3 };
  std::mutex m;
  std::condition_variable wake, done;
  std::vector<Vec3> points;  ///< the last request: its points and reach, not yet taken
  double reach = 0.0;
  /// and the kept columns of the nodes the caller's compliance last used: the new nodes' blocks
  /// with them are formed too
  std::vector<std::pair<int, std::shared_ptr<const HalfColumns>>> partners;
  std::unordered_map<std::uint64_t, Mat3> blocks;  ///< formed, not yet taken
  bool pending = false, stop = false, failed = false, busy = false;
  std::uint64_t generation = 0;  ///< raised by clear(): the thread's older requests are void
  std::vector<char> state;
  std::vector<int> inflight;  ///< the nodes of the batch being solved
  std::unordered_map<int, std::shared_ptr<const HalfColumns>> ready;
  std::atomic<int> solved{0};
  std::atomic<std::int64_t> nanoseconds{0};  ///< spent solving and forming blocks
  HalfSolveWork work;
  std::thread thread;
};

LumenCompliance::~LumenCompliance() {
  if (!ahead_) return;
  {
    const std::lock_guard<std::mutex> lock(ahead_->m);
    ahead_->stop = true;
  }
  ahead_->wake.notify_all();
  ahead_->thread.join();
}

int LumenCompliance::anticipated_nodes() const { return ahead_ ? ahead_->solved.load() : 0; }

double LumenCompliance::anticipated_seconds() const {
  return ahead_ ? 1e-9 * static_cast<double>(ahead_->nanoseconds.load()) : 0.0;
}

std::vector<int> LumenCompliance::nodes_near(std::span<const Vec3> points, double reach) const {
  const auto& m = solid_.mesh();
  std::vector<char> seen(static_cast<size_t>(m.num_nodes()), 0);
  std::vector<int> nodes, near;
  for (const Vec3& p : points) {
    faces_within(p, reach, near);
    for (int k : near)
      for (int node : m.faces[static_cast<size_t>(faces_[static_cast<size_t>(k)])])
        if (!seen[static_cast<size_t>(node)]) seen[static_cast<size_t>(node)] = 1, nodes.push_back(node);
  }
  return nodes;
}

void LumenCompliance::anticipate(std::span<const Vec3> points, double reach) {
  static const int cores = usable_cores();
  if (cores < 2) return;
  solid_.prepare_half_solve();  // (the maps the thread's solves read, made here before it reads them)
  if (!ahead_) {
    ahead_ = std::make_unique<Ahead>();
    ahead_->state.assign(static_cast<size_t>(solid_.mesh().num_nodes()), Ahead::free);
    for (const auto& [node, y] : columns_) {
      (void)y;
      ahead_->state[static_cast<size_t>(node)] = Ahead::caller;
    }
    ahead_->thread = std::thread([this] {
      Ahead& a = *ahead_;
      std::vector<std::vector<std::pair<int, double>>> unit;
      std::vector<HalfColumns> solved;
      std::unique_lock<std::mutex> lock(a.m);
      for (;;) {
        a.busy = false;
        a.done.notify_all();
        a.wake.wait(lock, [&] { return a.stop || a.pending; });
        if (a.stop) return;
        a.busy = true;
        const std::vector<Vec3> at = std::move(a.points);
        auto partners = std::move(a.partners);
        const double reach_now = a.reach;
        const std::uint64_t generation = a.generation;
        a.pending = false;
        lock.unlock();
        const std::vector<int> nodes = nodes_near(at, reach_now);
        lock.lock();
        size_t next = 0;
        while (!a.stop && !a.pending && generation == a.generation) {
          a.inflight.clear();
          for (; next < nodes.size() && a.inflight.size() < ElasticSolid::kHalfSolveBatch; ++next)
            if (a.state[static_cast<size_t>(nodes[next])] == Ahead::free) {
              a.inflight.push_back(nodes[next]);
              a.state[static_cast<size_t>(nodes[next])] = Ahead::solving;
            }
          if (a.inflight.empty()) break;
          const std::vector<int> batch = a.inflight;
          lock.unlock();
          unit.assign(3 * batch.size(), {});
          for (size_t k = 0; k < batch.size(); ++k)
            for (int c = 0; c < 3; ++c) unit[3 * k + static_cast<size_t>(c)] = {{3 * batch[k] + c, 1.0}};
          solved.resize(batch.size());
          const auto t0 = std::chrono::steady_clock::now();
          bool ok = true;
          try {
            solid_.half_solve(unit, solved, a.work);
          } catch (...) {  // (the caller solves these itself, and meets the error there)
            ok = false;
          }
          // Each new column's blocks with the partners' and with the new columns before it.
          std::vector<std::pair<std::uint64_t, Mat3>> blocks;
          if (ok)
            for (size_t k = 0; k < batch.size(); ++k) {
              for (const auto& [node, y] : partners)
                blocks.emplace_back(pair_key(batch[k], node), column_block(solved[k], *y));
              for (size_t j = 0; j < k; ++j)
                blocks.emplace_back(pair_key(batch[k], batch[j]), column_block(solved[k], solved[j]));
            }
          a.nanoseconds +=
              std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count();
          lock.lock();
          for (auto& [key, g] : blocks) a.blocks[key] = g;
          for (size_t k = 0; k < batch.size(); ++k) {
            a.state[static_cast<size_t>(batch[k])] = ok ? Ahead::solved_ahead : Ahead::free;
            if (ok) {
              auto column = std::make_shared<const HalfColumns>(std::move(solved[k]));
              partners.emplace_back(batch[k], column);  // (a later batch's blocks with this one)
              a.ready[batch[k]] = std::move(column), ++a.solved;
            }
          }
          a.inflight.clear();
          a.done.notify_all();
          if (!ok) {
            a.failed = true;
            a.busy = false;
            a.done.notify_all();
            return;
          }
        }
      }
    });
  }
  {
    const std::lock_guard<std::mutex> lock(ahead_->m);
    if (ahead_->failed) return;
    ahead_->points.assign(points.begin(), points.end());
    ahead_->reach = reach;
    ahead_->partners.clear();
    for (const Blocks& b : blocks_)
      for (int node : b.nodes)
        if (auto it = columns_.find(node); it != columns_.end()) ahead_->partners.emplace_back(node, it->second);
    std::sort(ahead_->partners.begin(), ahead_->partners.end());
    ahead_->partners.erase(std::unique(ahead_->partners.begin(), ahead_->partners.end()), ahead_->partners.end());
    ahead_->pending = true;
  }
  ahead_->wake.notify_one();
}

void LumenCompliance::wait_anticipated() {
  if (!ahead_) return;
  Ahead& a = *ahead_;
  std::unique_lock<std::mutex> lock(a.m);
  a.done.wait(lock, [&] { return a.failed || (!a.pending && !a.busy); });
}

void LumenCompliance::keep(int node, std::shared_ptr<const HalfColumns> y) {
  auto& kept = columns_[node];
  if (kept) kept_bytes_ -= kept->size() * (sizeof(int) + 3 * sizeof(double));
  kept = std::move(y);
  kept_bytes_ += kept->size() * (sizeof(int) + 3 * sizeof(double));
  last_use_.try_emplace(node, tick_);
}

void LumenCompliance::take_ready() {
  Ahead& a = *ahead_;
  for (auto& [node, y] : a.ready) {
    keep(node, std::move(y));
    a.state[static_cast<size_t>(node)] = Ahead::caller;
  }
  a.ready.clear();
  if (pair_blocks_.size() > 100000) pair_blocks_.clear();  // (about 10 MB: mostly those of past steps)
  for (const auto& [key, g] : a.blocks) pair_blocks_[key] = g;
  a.blocks.clear();
}

Mat3 LumenCompliance::block_between(int a, int b) {
  if (auto it = pair_blocks_.find(pair_key(a, b)); it != pair_blocks_.end()) return it->second;
  if (auto it = pair_blocks_.find(pair_key(b, a)); it != pair_blocks_.end()) return it->second.transpose();
  ++block_products_;
  return column_block(column(a), column(b));
}

void LumenCompliance::prefetch(std::span<const LumenPoint> points) {
  ++tick_;
  std::vector<int> fresh;
  for (const auto& p : points)
    for (const auto& [node, w] : p.weights) {
      last_use_[node] = tick_;
      if (!columns_.count(node) && std::find(fresh.begin(), fresh.end(), node) == fresh.end()) fresh.push_back(node);
    }
  if (ahead_ && !fresh.empty()) {
    // Take what the second thread has solved; the nodes it is solving are waited for once the
    // caller has solved the others.
    std::unique_lock<std::mutex> lock(ahead_->m);
    Ahead& a = *ahead_;
    take_ready();
    std::vector<int> own, wait;
    for (int node : fresh) {
      char& st = a.state[static_cast<size_t>(node)];
      if (st == Ahead::solving) {
        wait.push_back(node);
      } else if (!columns_.count(node)) {
        st = Ahead::caller;
        own.push_back(node);
      }
    }
    fresh = std::move(own);
    lock.unlock();
    solve_columns(fresh);
    if (!wait.empty()) {
      lock.lock();
      a.done.wait(lock, [&] {
        return std::none_of(wait.begin(), wait.end(),
                            [&](int node) { return a.state[static_cast<size_t>(node)] == Ahead::solving; });
      });
      take_ready();
    }
  } else {
    solve_columns(fresh);
  }
  for (const auto& p : points)
    for (const auto& [node, w] : p.weights) last_use_[node] = tick_;
  // Over the budget: drop the columns asked for longest ago (never those of this call; at least
  // a few hundred nodes are kept, a step's contacts).
  if (static_cast<double>(kept_bytes_) <= budget_ || columns_.size() <= 256) return;
  std::vector<std::pair<std::uint64_t, int>> by_age;
  for (const auto& [node, column] : columns_) {
    (void)column;
    const std::uint64_t used = last_use_[node];
    if (used < tick_) by_age.emplace_back(used, node);
  }
  std::sort(by_age.begin(), by_age.end());
  std::unique_lock<std::mutex> lock;
  if (ahead_) lock = std::unique_lock<std::mutex>(ahead_->m);
  for (const auto& [used, node] : by_age) {
    if (static_cast<double>(kept_bytes_) <= budget_ || columns_.size() <= 256) break;
    kept_bytes_ -= columns_.at(node)->size() * (sizeof(int) + 3 * sizeof(double));
    columns_.erase(node);
    last_use_.erase(node);
    if (ahead_) ahead_->state[static_cast<size_t>(node)] = Ahead::free;
    ++dropped_;
  }
}

void LumenCompliance::solve_columns(const std::vector<int>& fresh) {
  // The new nodes solved together, a batch at a time: their reaches end in the same top
  // separators, read once a batch.
  constexpr size_t batch = ElasticSolid::kHalfSolveBatch;
  std::vector<std::vector<std::pair<int, double>>> unit;
  std::vector<HalfColumns> solved;
  for (size_t first = 0; first < fresh.size(); first += batch) {
    const size_t count = std::min(batch, fresh.size() - first);
    unit.assign(3 * count, {});
    for (size_t k = 0; k < count; ++k)
      for (int c = 0; c < 3; ++c) unit[3 * k + static_cast<size_t>(c)] = {{3 * fresh[first + k] + c, 1.0}};
    solved.resize(count);
    solid_.half_solve(unit, solved);
    for (size_t k = 0; k < count; ++k) {
      keep(fresh[first + k], std::make_shared<const HalfColumns>(std::move(solved[k])));
      ++solved_;
    }
  }
}

void LumenCompliance::clear() {
  if (ahead_) {  // (the thread reads the factor: it finishes its batch, and its requests are void)
    Ahead& a = *ahead_;
    std::unique_lock<std::mutex> lock(a.m);
    ++a.generation;
    a.pending = false;
    a.done.wait(lock, [&] { return a.inflight.empty(); });
    a.ready.clear();
    a.blocks.clear();
    std::fill(a.state.begin(), a.state.end(), Ahead::free);
  }
  columns_.clear();
  pair_blocks_.clear();
  last_use_.clear();
  kept_bytes_ = 0;
  blocks_.clear();
}

LumenCompliance::Blocks& LumenCompliance::cache_at(int cache) {
  if (cache < 0) throw_usage_error(fmt::format("wall: no compliance cache {}", cache));
  if (static_cast<int>(blocks_.size()) <= cache) blocks_.resize(static_cast<size_t>(cache) + 1);
  return blocks_[static_cast<size_t>(cache)];
}

LumenCompliance::Blocks& LumenCompliance::form_blocks(std::span<const LumenPoint> points, int cache) {
  Blocks& kept = cache_at(cache);
  const auto num_nodes = static_cast<size_t>(solid_.mesh().num_nodes());
  if (kept.slot.empty()) kept.slot.assign(num_nodes, -1);
  if (mark_.empty()) mark_.assign(num_nodes, 0);
  // The nodes kept from now on: this call's, then the last call's others (a body's contacts'
  // anchoring and their loads, or its anchorings a step apart, are at nearly the same nodes).
  std::vector<int> nodes;
  for (const auto& p : points)
    for (const auto& [node, w] : p.weights) {
      (void)w;
      if (!mark_[static_cast<size_t>(node)]) mark_[static_cast<size_t>(node)] = 1, nodes.push_back(node);
    }
  std::vector<int> call = nodes;
  for (int node : kept.last_call)
    if (!mark_[static_cast<size_t>(node)]) mark_[static_cast<size_t>(node)] = 1, nodes.push_back(node);
  for (int node : nodes) mark_[static_cast<size_t>(node)] = 0;
  const auto nn = static_cast<Eigen::Index>(nodes.size());
  Eigen::MatrixXd g(3 * nn, 3 * nn);
  std::vector<Eigen::Index> fresh;  // the nodes whose blocks were not kept
  for (Eigen::Index q = 0; q < nn; ++q) {
    const int bq = kept.slot[static_cast<size_t>(nodes[static_cast<size_t>(q)])];
    if (bq < 0) {
      fresh.push_back(q);
      continue;
    }
    for (Eigen::Index p = 0; p <= q; ++p) {
      const int bp = kept.slot[static_cast<size_t>(nodes[static_cast<size_t>(p)])];
      if (bp < 0) continue;
      g.block<3, 3>(3 * p, 3 * q) = kept.g.block<3, 3>(3 * bp, 3 * bq);
      g.block<3, 3>(3 * q, 3 * p) = kept.g.block<3, 3>(3 * bq, 3 * bp);
    }
  }
  // The new blocks, each node's column read once against the few fresh nodes' (which stay in cache).
  for (Eigen::Index q = 0; q < nn; ++q) {
    const bool q_fresh = kept.slot[static_cast<size_t>(nodes[static_cast<size_t>(q)])] < 0;
    for (Eigen::Index p : fresh) {
      if (q_fresh && p > q) break;  // (a pair of fresh nodes once)
      const Mat3 gpq = block_between(nodes[static_cast<size_t>(p)], nodes[static_cast<size_t>(q)]);
      g.block<3, 3>(3 * p, 3 * q) = gpq;
      g.block<3, 3>(3 * q, 3 * p) = gpq.transpose();
    }
  }
  for (int node : kept.nodes) kept.slot[static_cast<size_t>(node)] = -1;
  kept.nodes = std::move(nodes);
  for (size_t k = 0; k < kept.nodes.size(); ++k) kept.slot[static_cast<size_t>(kept.nodes[k])] = static_cast<int>(k);
  kept.g = std::move(g);
  kept.last_call = std::move(call);
  return kept;
}

Eigen::MatrixXd LumenCompliance::compliance(std::span<const LumenPoint> points, std::span<const Vec3> directions,
                                            int cache) {
  if (!by_blocks(points, cache)) return compliance_by_columns(points, directions);
  // C_ij = Σ_a Σ_b w_ia w_jb d_iᵀ G_ab d_j over the points' nodes: H = G W (column j: Σ_b w_jb G_·b d_j),
  // then C = Wᵀ H.
  const Blocks& b = form_blocks(points, cache);
  const auto np = static_cast<Eigen::Index>(points.size());
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(b.g.rows(), np);
  for (Eigen::Index j = 0; j < np; ++j)
    for (const auto& [node, w] : points[static_cast<size_t>(j)].weights)
      h.col(j).noalias() +=
          b.g.middleCols<3>(3 * b.slot[static_cast<size_t>(node)]) * (w * directions[static_cast<size_t>(j)]);
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(np, np);
  for (Eigen::Index i = 0; i < np; ++i)
    for (const auto& [node, w] : points[static_cast<size_t>(i)].weights)
      c.row(i).noalias() +=
          (w * directions[static_cast<size_t>(i)]).transpose() * h.middleRows<3>(3 * b.slot[static_cast<size_t>(node)]);
  // (symmetric to round-off: made exactly so)
  return 0.5 * (c + c.transpose());
}

std::vector<Vec3> LumenCompliance::displacements(std::span<const LumenPoint> points, std::span<const Vec3> forces,
                                                 int cache) {
  // The forces gathered on the nodes (F_b = Σ_j w_jb f_j), moved by G, read with each point's weights.
  prefetch(points);
  const Blocks& b = form_blocks(points, cache);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(b.g.rows());
  for (size_t j = 0; j < points.size(); ++j)
    for (const auto& [node, w] : points[j].weights)
      f.segment<3>(3 * b.slot[static_cast<size_t>(node)]) += w * forces[j];
  const Eigen::VectorXd u = b.g * f;
  std::vector<Vec3> out(points.size(), Vec3::Zero());
  for (size_t i = 0; i < points.size(); ++i)
    for (const auto& [node, w] : points[i].weights) out[i] += w * u.segment<3>(3 * b.slot[static_cast<size_t>(node)]);
  return out;
}

bool LumenCompliance::by_blocks(std::span<const LumenPoint> points, int cache) {
  // Two exact ways to the compliance: from the kept node blocks, whose cost is the blocks of the
  // nodes new to the call (each against every kept node: nine products a shared row), or as
  // C = Zᵀ Z from the points' forward-solved forces (three products a row for each use of a node,
  // then the rank update over the rows they reach). The blocks win where a body's points share few
  // nodes and slide onto a few new ones a step (a wire on a wall meshed coarser than its
  // footprint: the Feel++ arch, 2.3 new of 41 nodes for 45 points), the columns where a footprint
  // spans many nodes of a fine wall (the tortuous iliac's, 8.6 new of 171 for 27 points). The
  // nodes new to each call are averaged over the calls, and the way changes only where the other
  // is twice as cheap (switching to the blocks forms all of them once).
  prefetch(points);
  Blocks& kept = cache_at(cache);
  if (mark_.empty()) mark_.assign(static_cast<size_t>(solid_.mesh().num_nodes()), 0);
  for (int node : kept.last_call) mark_[static_cast<size_t>(node)] = 2;
  double nodes = 0.0, fresh = 0.0, uses = 0.0, rows = 0.0;
  std::vector<int> call;
  for (const auto& p : points)
    for (const auto& [node, w] : p.weights) {
      (void)w;
      uses += 1.0;
      char& m = mark_[static_cast<size_t>(node)];
      if (m == 1 || m == 3) continue;  // (seen in this call)
      if (m == 0) fresh += 1.0;
      m = static_cast<char>(m + 1);
      call.push_back(node);
      nodes += 1.0;
      rows += static_cast<double>(column(node).size());
    }
  for (int node : kept.last_call) mark_[static_cast<size_t>(node)] = 0;
  for (int node : call) mark_[static_cast<size_t>(node)] = 0;
  if (way_ != Way::automatic) kept.by_blocks = way_ == Way::blocks;
  if (nodes == 0.0 || way_ != Way::automatic) {
    if (!kept.by_blocks) kept.last_call = std::move(call);
    return kept.by_blocks;
  }
  const double mean_rows = rows / nodes, np = static_cast<double>(points.size());
  // (per shared row and product; the columns' scattered sums and rank update measured 2.5 times
  // slower a product than the blocks' dense kernel on the Feel++ arch: 0.73 ms for 4.4 M, 0.17 ms for
  // 2.5 M; a block's rows are taken as a whole column's, which overstates them where two nodes'
  // reaches meet high in the tree)
  const double by_columns = 2.5 * mean_rows * (3.0 * uses + 0.75 * np * np);
  if (kept.calls++ == 0) {
    kept.mean_fresh = -1.0;
    kept.by_blocks = 4.5 * mean_rows * nodes * nodes <= by_columns;  // (every block formed)
  } else {
    kept.mean_fresh = kept.mean_fresh < 0.0 ? fresh : 0.8 * kept.mean_fresh + 0.2 * fresh;
    const double f = kept.mean_fresh, steady = 9.0 * mean_rows * f * (2.0 * nodes - 0.5 * f);
    if (kept.by_blocks && steady > 2.0 * by_columns) kept.by_blocks = false;
    if (!kept.by_blocks && 2.0 * steady < by_columns) kept.by_blocks = true;
  }
  if (!kept.by_blocks) {  // (the blocks not kept; the call's nodes measure the next call's new ones)
    for (int node : kept.nodes) kept.slot[static_cast<size_t>(node)] = -1;
    kept.nodes.clear();
    kept.g.resize(0, 0);
    kept.last_call = std::move(call);
  }
  return kept.by_blocks;
}

Eigen::MatrixXd LumenCompliance::compliance_by_columns(std::span<const LumenPoint> points,
                                                       std::span<const Vec3> directions) {
  // C = Zᵀ Z with column i of Z the force d_i spread over point i's nodes and forward-solved:
  // z_i = Σ_b w_b Σ_c d_ic Y_bc, summed from each distinct node's columns (neighbouring points
  // share most of their nodes) onto the rows they reach, then C by a symmetric rank-k update.
  std::vector<int> rows, nodes;
  const auto num_nodes = static_cast<size_t>(solid_.mesh().num_nodes());
  if (node_slot_.size() != num_nodes) node_slot_.assign(num_nodes, -1);
  if (row_slot_.empty()) row_slot_.assign(static_cast<size_t>(solid_.num_dofs()), -1);
  uses_.clear();
  for (size_t i = 0; i < points.size(); ++i)
    for (const auto& [node, w] : points[i].weights) {
      int& at = node_slot_[static_cast<size_t>(node)];
      if (at < 0) {
        at = static_cast<int>(nodes.size());
        nodes.push_back(node);
        for (int row : column(node).index)
          if (row_slot_[static_cast<size_t>(row)] < 0) {
            row_slot_[static_cast<size_t>(row)] = static_cast<int>(rows.size());
            rows.push_back(row);
          }
      }
      uses_.push_back({at, static_cast<Eigen::Index>(i), w * directions[i]});
    }
  for (int node : nodes) node_slot_[static_cast<size_t>(node)] = -1;
  std::stable_sort(uses_.begin(), uses_.end(), [](const Use& x, const Use& y) { return x.node < y.node; });
  const auto nr = static_cast<Eigen::Index>(rows.size());
  const auto np = static_cast<Eigen::Index>(points.size());
  // Zᵀ (points × rows, column-major: a row's points together), each node's columns read once for
  // the points that use it: neighbours along the wire, so a node's points are taken as the range
  // between the first and the last of them (zero weights for those between that do not).
  zt_.assign(static_cast<size_t>(np * nr), 0.0);
  for (size_t first = 0; first < uses_.size();) {
    size_t last = first;
    while (last < uses_.size() && uses_[last].node == uses_[first].node) ++last;
    const NodeColumns& yb = column(nodes[static_cast<size_t>(uses_[first].node)]);
    Eigen::Index lo = np, hi = -1;
    for (size_t q = first; q < last; ++q) lo = std::min(lo, uses_[q].point), hi = std::max(hi, uses_[q].point);
    const auto width = static_cast<size_t>(hi - lo + 1);
    node_weights_.assign(3 * width, 0.0);
    for (size_t q = first; q < last; ++q)
      for (size_t c = 0; c < 3; ++c)
        node_weights_[c * width + static_cast<size_t>(uses_[q].point - lo)] +=
            uses_[q].weight[static_cast<Eigen::Index>(c)];
    node_rows_.resize(yb.size());
    for (size_t k = 0; k < yb.size(); ++k) node_rows_[k] = row_slot_[static_cast<size_t>(yb.index[k])];
    add_node_columns(yb.value.data(), node_rows_.data(), yb.size(), node_weights_.data(), width, zt_.data() + lo, np);
    first = last;
  }
  for (int row : rows) row_slot_[static_cast<size_t>(row)] = -1;
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(np, np);
  if (np > 0 && nr > 0) {  // (BLAS's rank update: Eigen's took 1.8 times as long here)
    const int n = static_cast<int>(np), k = static_cast<int>(nr);
    const double one = 1.0, zero = 0.0;
    dsyrk_("L", "N", &n, &k, &one, zt_.data(), &n, &zero, c.data(), &n, 1, 1);
  }
  return c.selfadjointView<Eigen::Lower>();
}

Eigen::VectorXd LumenCompliance::response(std::span<const LumenPoint> points, std::span<const Vec3> forces) {
  prefetch(points);
  Eigen::VectorXd r = Eigen::VectorXd::Zero(solid_.num_dofs());
  for (size_t j = 0; j < points.size(); ++j)
    for (const auto& [node, w] : points[j].weights) {
      const NodeColumns& y = column(node);
      const Vec3 f = w * forces[j];
      for (size_t k = 0; k < y.size(); ++k)
        r[y.index[k]] += f[0] * y.value[3 * k] + f[1] * y.value[3 * k + 1] + f[2] * y.value[3 * k + 2];
    }
  return r;
}

Vec3 LumenCompliance::displacement(const LumenPoint& at, const Eigen::VectorXd& response) {
  prefetch(std::span<const LumenPoint>(&at, 1));
  Vec3 u = Vec3::Zero();
  for (const auto& [node, w] : at.weights) {
    const NodeColumns& y = column(node);
    Vec3 dot = Vec3::Zero();
    for (size_t k = 0; k < y.size(); ++k)
      dot += response[y.index[k]] * Vec3(y.value[3 * k], y.value[3 * k + 1], y.value[3 * k + 2]);
    u += w * dot;
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
