// VMTK vmtkbranchextractor output (also what SimVascular writes as its branch-split centerlines):
// the paths of vmtkcenterlines cut into tracts, with the cell arrays GroupIds (the vessel piece
// a tract belongs to), CenterlineIds (the path it was cut from), TractIds (its place along that
// path) and, optionally, Blanking (1 for the tracts inside a bifurcation region). Each group
// becomes one branch named group_<GroupId>, read from its first non-blanked tract. A group that
// is not the first on its path starts at the end of the group before it there (its parent) and
// runs through the blanked tract between them, if any: every bifurcation region becomes one
// junction, the parent's end, whose radius on each daughter is the daughter's own. File units.
#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "flowire/common/error.hpp"
#include "polydata_internal.hpp"

namespace flowire::vessels::detail {

std::vector<Polyline> branch_split_vmtk(const PolyData& pd, const std::vector<double>& radii) {
  const auto* group = find_array(pd.cell_data, "GroupIds");
  const auto* line = find_array(pd.cell_data, "CenterlineIds");
  const auto* tract = find_array(pd.cell_data, "TractIds");
  const auto* blank = find_array(pd.cell_data, "Blanking");
  const size_t nc = pd.lines.size();
  for (const auto* a : {group, line, tract, blank})
    if (a) require_tuples(pd, *a, nc, "cell");

  struct Tract {
    size_t cell;
    long long group, tract;
    bool blanked;
  };
  std::map<long long, std::vector<Tract>> by_line;
  for (size_t c = 0; c < nc; ++c)
    by_line[int_at(*line, c)].push_back({c, int_at(*group, c), int_at(*tract, c), blank && int_at(*blank, c) != 0});
  for (auto& [id, ts] : by_line) {
    std::stable_sort(ts.begin(), ts.end(), [](const Tract& a, const Tract& b) { return a.tract < b.tract; });
    for (size_t k = 1; k < ts.size(); ++k)
      if (ts[k].tract == ts[k - 1].tract)
        throw_input_error(pd.source, fmt::format("line cells {} and {}: centerline {} has tract {} twice",
                                                 ts[k - 1].cell, ts[k].cell, id, ts[k].tract));
  }

  // Representative tract of each group: the first non-blanked cell with that group id,
  // with the blanked tract before it and the group before that (its parent) on its centerline.
  struct Rep {
    size_t cell;
    std::optional<size_t> blank_cell;
    std::optional<long long> parent;
  };
  std::map<long long, Rep> reps;
  std::vector<long long> order;
  for (size_t c = 0; c < nc; ++c) {
    if (blank && int_at(*blank, c) != 0) continue;
    const long long g = int_at(*group, c);
    if (reps.count(g)) continue;
    const auto& ts = by_line[int_at(*line, c)];
    const auto it = std::find_if(ts.begin(), ts.end(), [&](const Tract& t) { return t.cell == c; });
    Rep rep{c, std::nullopt, std::nullopt};
    auto k = static_cast<size_t>(it - ts.begin());
    if (k > 0 && ts[k - 1].blanked) {
      rep.blank_cell = ts[k - 1].cell;
      --k;
    }
    if (k > 0 && !ts[k - 1].blanked) rep.parent = ts[k - 1].group;
    reps.emplace(g, rep);
    order.push_back(g);
  }
  if (reps.empty()) throw_input_error(pd.source, "every line cell is blanked (Blanking = 1): no branch left");

  // Own points of each group first, then join each group to the end of its parent.
  std::map<long long, Polyline> own;
  for (const long long g : order)
    own.emplace(g, make_polyline(pd, radii, cell_ids(pd, reps.at(g).cell, true), fmt::format("group_{}", g)));

  std::vector<Polyline> out;
  for (const long long g : order) {
    const Rep& rep = reps.at(g);
    Polyline p;
    p.name = own.at(g).name;
    if (rep.parent && own.count(*rep.parent) && *rep.parent != g) {
      const Polyline& parent = own.at(*rep.parent);
      p.points.push_back(parent.points.back());
      p.radii.push_back(parent.radii.back());
      if (rep.blank_cell) append_points(p, make_polyline(pd, radii, cell_ids(pd, *rep.blank_cell, true), {}), 1);
      append_points(p, own.at(g), p.points.size() == 1 && !rep.blank_cell ? 1 : 0);
      // The junction point is the parent's; its radius on this branch is this branch's own.
      if (p.radii.size() > 1) p.radii.front() = p.radii[1];
    } else {
      if (rep.blank_cell) append_points(p, make_polyline(pd, radii, cell_ids(pd, *rep.blank_cell, true), {}));
      append_points(p, own.at(g));
    }
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace flowire::vessels::detail
