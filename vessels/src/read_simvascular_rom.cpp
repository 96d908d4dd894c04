// SimVascular ROM centerlines (the centerlines SimVascular's reduced-order model builder
// writes): points carry BranchId (>= 0 on a branch, -1 inside a bifurcation region),
// BifurcationId (which region, -1 on branches) and optionally Path (arc length along the
// branch); line cells, often two-point ones, share point ids. Each BranchId becomes one branch
// named branch_<BranchId>, ordered along Path where present; each bifurcation region (a
// connected set of points with BranchId -1 and one BifurcationId) collapses into one junction,
// its branching point (the point with most neighbours) or else its centroid; each branch end is
// extended to what it touches: a region's junction, or the next point of another branch. The
// points of one BranchId must form one chain. File units throughout.
#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <vector>

#include "flowire/common/error.hpp"
#include "polydata_internal.hpp"

namespace flowire::vessels::detail {

std::vector<Polyline> simvascular_rom(const PolyData& pd, const std::vector<double>& radii) {
  const auto* branch_arr = find_array(pd.point_data, "BranchId");
  require_tuples(pd, *branch_arr, pd.points.size(), "point");
  const auto* bif_arr = find_array(pd.point_data, "BifurcationId");
  if (bif_arr) require_tuples(pd, *bif_arr, pd.points.size(), "point");
  const auto* path_arr = find_array(pd.point_data, "Path");
  if (path_arr && path_arr->tuples() != pd.points.size()) path_arr = nullptr;

  std::vector<long long> canon(pd.points.size());
  for (size_t i = 0; i < canon.size(); ++i) canon[i] = static_cast<long long>(i);
  const auto adj = adjacency(pd, canon, false);
  const size_t np = pd.points.size();
  std::vector<char> used(np, 0);
  for (const auto& ids : pd.lines)
    for (const long long id : ids) used[static_cast<size_t>(id)] = 1;

  auto branch_of = [&](size_t i) { return int_at(*branch_arr, i); };

  // Bifurcation regions: connected sets of points with BranchId < 0 (split by BifurcationId).
  std::vector<long long> region(np, -1);
  std::vector<Vec3> junction;
  for (size_t i = 0; i < np; ++i) {
    if (!used[i] || branch_of(i) >= 0 || region[i] >= 0) continue;
    const long long id = static_cast<long long>(junction.size());
    std::vector<size_t> stack{i}, members;
    region[i] = id;
    while (!stack.empty()) {
      const size_t v = stack.back();
      stack.pop_back();
      members.push_back(v);
      for (const long long w : adj[v]) {
        const auto u = static_cast<size_t>(w);
        if (region[u] >= 0 || branch_of(u) >= 0) continue;
        if (bif_arr && int_at(*bif_arr, u) != int_at(*bif_arr, i)) continue;
        region[u] = id;
        stack.push_back(u);
      }
    }
    // The junction is the region's branching point (most neighbours), else its centroid.
    size_t hub = i;
    for (const size_t v : members)
      if (adj[v].size() > adj[hub].size()) hub = v;
    Vec3 x = pd.points[hub];
    if (adj[hub].size() < 3) {
      x.setZero();
      for (const size_t v : members) x += pd.points[v];
      x /= static_cast<double>(members.size());
    }
    junction.push_back(x);
  }

  std::map<long long, std::vector<size_t>> members;
  for (size_t i = 0; i < np; ++i)
    if (used[i] && branch_of(i) >= 0) members[branch_of(i)].push_back(i);
  if (members.empty()) throw_input_error(pd.source, "no point has BranchId >= 0: no branch to read");

  std::vector<Polyline> out;
  for (const auto& entry : members) {
    const long long b = entry.first;
    const std::vector<size_t>& pts = entry.second;
    auto in_branch = [&](long long w) { return branch_of(static_cast<size_t>(w)) == b; };
    size_t start = pts.front();
    for (const size_t v : pts) {
      const auto n = std::count_if(adj[v].begin(), adj[v].end(), in_branch);
      if (n <= 1) {
        start = v;
        break;
      }
    }
    std::vector<long long> chain{static_cast<long long>(start)};
    std::vector<char> seen(np, 0);
    seen[start] = 1;
    for (bool more = true; more;) {
      more = false;
      for (const long long w : adj[static_cast<size_t>(chain.back())])
        if (in_branch(w) && !seen[static_cast<size_t>(w)]) {
          seen[static_cast<size_t>(w)] = 1;
          chain.push_back(w);
          more = true;
          break;
        }
    }
    if (chain.size() != pts.size())
      throw_input_error(
          pd.source,
          fmt::format("BranchId {}: its {} points do not form one chain (point {} is "
                      "reached from neither end)",
                      b, pts.size(), *std::find_if(pts.begin(), pts.end(), [&](size_t v) { return !seen[v]; })));
    if (path_arr && chain.size() > 1 &&
        path_arr->values[static_cast<size_t>(chain.back()) * static_cast<size_t>(path_arr->components)] <
            path_arr->values[static_cast<size_t>(chain.front()) * static_cast<size_t>(path_arr->components)])
      std::reverse(chain.begin(), chain.end());

    Polyline p = make_polyline(pd, radii, chain, fmt::format("branch_{}", b));
    // Extend each end to the junction of the bifurcation region (or the branch) it touches.
    auto attach = [&](size_t end, bool front) {
      for (const long long w : adj[end]) {
        const auto u = static_cast<size_t>(w);
        if (branch_of(u) == b) continue;
        const Vec3 x = region[u] >= 0 ? junction[static_cast<size_t>(region[u])] : pd.points[u];
        const double r = front ? p.radii.front() : p.radii.back();
        if (x == (front ? p.points.front() : p.points.back())) return;
        if (front) {
          p.points.insert(p.points.begin(), x);
          p.radii.insert(p.radii.begin(), r);
        } else {
          p.points.push_back(x);
          p.radii.push_back(r);
        }
        return;
      }
    };
    attach(static_cast<size_t>(chain.front()), true);
    attach(static_cast<size_t>(chain.back()), false);
    if (p.points.size() < 2)
      throw_input_error(pd.source, fmt::format("BranchId {} has a single point and touches no junction", b));
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace flowire::vessels::detail
