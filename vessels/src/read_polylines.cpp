// Polylines of any other writer (VTK writers, BlueFern's coronary trees, hand-made files): line
// cells with a radius point array, with no convention of their own. Cells that share a point id,
// or points closer than 1e-6 of their radius (the last bits two writers round differently), are
// joined; a branch is a chain between junctions and ends (a closed ring is cut in two). A point
// written once per cell (a junction repeated at the start of every daughter) keeps in each
// branch the radius that branch's cell gives it, and a chain is also cut where two cells meet
// with different radii. Branches are named branch_0, branch_1, ... File units throughout.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <unordered_map>
#include <utility>
#include <vector>

#include "polydata_internal.hpp"

namespace flowire::vessels::detail {
namespace {

/// Points closer than kSamePoint × their radius are one point (sharing the smallest id): the
/// end points two writers compute for the same junction differ in the last bits.
constexpr double kSamePoint = 1e-6;

std::vector<long long> canonical_ids(const PolyData& pd, const std::vector<double>& radii) {
  const size_t n = pd.points.size();
  double rmax = 0.0;
  for (size_t i = 0; i < n; ++i)
    if (std::isfinite(radii[i])) rmax = std::max(rmax, radii[i]);
  const double cell = kSamePoint * rmax;
  std::vector<long long> canon(n);
  for (size_t i = 0; i < n; ++i) canon[i] = static_cast<long long>(i);
  if (!(cell > 0.0)) return canon;
  // Hash grid of cell size ≥ every tolerance: near points are in neighbouring cells.
  using Cell = Eigen::Matrix<int64_t, 3, 1>;
  auto key = [](const Cell& k) {
    return (static_cast<uint64_t>(k.x() & 0x1FFFFF) << 42) ^ (static_cast<uint64_t>(k.y() & 0x1FFFFF) << 21) ^
           static_cast<uint64_t>(k.z() & 0x1FFFFF);
  };
  auto cell_of = [&](const Vec3& x) {
    const Eigen::Array3d f = (x / cell).array().floor().max(-4e18).min(4e18);
    return Cell(static_cast<int64_t>(f.x()), static_cast<int64_t>(f.y()), static_cast<int64_t>(f.z()));
  };
  std::unordered_multimap<uint64_t, long long> grid;
  grid.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec3& x = pd.points[i];
    if (!x.allFinite()) continue;  // validated (and reported) before the chains are built
    const Cell k = cell_of(x);
    for (int dx = -1; dx <= 1 && canon[i] == static_cast<long long>(i); ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto range = grid.equal_range(key(k + Cell(dx, dy, dz)));
          for (auto it = range.first; it != range.second; ++it) {
            const auto j = static_cast<size_t>(it->second);
            if ((pd.points[j] - x).norm() <= kSamePoint * std::max(radii[i], radii[j]))
              canon[i] = std::min(canon[i], canon[j]);
          }
        }
    if (canon[i] == static_cast<long long>(i)) grid.emplace(key(k), static_cast<long long>(i));
  }
  return canon;
}

}  // namespace

/// Chains between points of degree != 2 (ends, junctions); closed rings are cut in two.
/// Each point of a chain takes the radius its own line cell gives it; a chain is also cut
/// where two cells meet with different radii at their shared point.
std::vector<Polyline> graph_chains(const PolyData& pd, const std::vector<double>& radii, bool allow_duplicates) {
  const auto canon = canonical_ids(pd, radii);
  EdgeOrigins origins;
  const auto adj = adjacency(pd, canon, allow_duplicates, &origins);
  std::vector<long long> order;  // vertices in order of first use
  {
    std::vector<char> seen(pd.points.size(), 0);
    for (const auto& ids : pd.lines)
      for (const long long id : ids) {
        const auto v = static_cast<size_t>(canon[static_cast<size_t>(id)]);
        if (!seen[v]) seen[v] = 1, order.push_back(static_cast<long long>(v));
      }
  }
  std::set<std::pair<long long, long long>> used;
  auto edge = [](long long a, long long b) { return std::make_pair(std::min(a, b), std::max(a, b)); };
  auto deg = [&](long long v) { return adj[static_cast<size_t>(v)].size(); };
  std::vector<std::vector<long long>> chains;
  auto walk = [&](long long start, long long next) {
    std::vector<long long> chain{start, next};
    used.insert(edge(start, next));
    long long prev = start, cur = next;
    while (deg(cur) == 2 && cur != start) {
      const auto& nb = adj[static_cast<size_t>(cur)];
      const long long nxt = nb[0] == prev ? nb[1] : nb[0];
      if (used.count(edge(cur, nxt))) break;
      used.insert(edge(cur, nxt));
      chain.push_back(nxt);
      prev = cur;
      cur = nxt;
    }
    chains.push_back(std::move(chain));
  };
  for (const long long v : order)
    if (deg(v) != 2)
      for (const long long w : adj[static_cast<size_t>(v)])
        if (!used.count(edge(v, w))) walk(v, w);
  for (const long long v : order)  // what is left are closed rings
    for (const long long w : adj[static_cast<size_t>(v)])
      if (!used.count(edge(v, w))) walk(v, w);

  // The file point that stands for chain vertex `v` on the edge {v, w}.
  auto origin = [&](long long v, long long w) {
    const auto& o = origins.at(edge(v, w));
    return static_cast<size_t>(v < w ? o.at_a : o.at_b);
  };
  std::vector<Polyline> out;
  auto emit = [&](const std::vector<long long>& chain, size_t lo, size_t hi) {
    Polyline p;
    p.name = fmt::format("branch_{}", out.size());
    for (size_t k = lo; k <= hi; ++k) {
      p.points.push_back(pd.points[static_cast<size_t>(chain[k])]);
      p.radii.push_back(radii[k < hi ? origin(chain[k], chain[k + 1]) : origin(chain[k], chain[k - 1])]);
    }
    out.push_back(std::move(p));
  };
  for (auto& chain : chains) {
    std::vector<size_t> cuts{0};
    for (size_t k = 1; k + 1 < chain.size(); ++k)
      if (radii[origin(chain[k], chain[k - 1])] != radii[origin(chain[k], chain[k + 1])]) cuts.push_back(k);
    if (cuts.size() == 1 && chain.size() >= 4 && chain.front() == chain.back())
      cuts.push_back(chain.size() / 2);  // ring
    cuts.push_back(chain.size() - 1);
    for (size_t i = 0; i + 1 < cuts.size(); ++i) emit(chain, cuts[i], cuts[i + 1]);
  }
  return out;
}

}  // namespace flowire::vessels::detail
