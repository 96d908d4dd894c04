// What every centerline convention of poly data needs, whatever wrote the file: arrays found by
// name (any case), the radius at every point (`radius`, `radii`, `MaximumInscribedSphereRadius`,
// `misr`, else sqrt(CenterlineSectionArea / pi), in file units), the checks on line cells and
// points (ids in range, finite coordinates, finite positive radii, no duplicate points or
// self-loops unless the writer is known to repeat points), and cells turned into polylines or
// into a point adjacency. Every error names the file and the cell or point at fault.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>

#include "flowire/common/error.hpp"
#include "polydata_internal.hpp"

namespace flowire::vessels::detail {
namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  for (auto& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string array_names(const std::vector<NumericArray>& arrays) {
  if (arrays.empty()) return "none";
  std::string out;
  for (const auto& a : arrays) out += (out.empty() ? "" : ", ") + a.name;
  return out;
}

}  // namespace

const NumericArray* find_array(const std::vector<NumericArray>& arrays, std::string_view name) {
  const auto key = lower(name);
  for (const auto& a : arrays)
    if (lower(a.name) == key) return &a;
  return nullptr;
}

const StringArray* find_strings(const std::vector<StringArray>& arrays, std::string_view name) {
  const auto key = lower(name);
  for (const auto& a : arrays)
    if (lower(a.name) == key) return &a;
  return nullptr;
}

/// Integer value of tuple i, first component (arrays stored as double).
long long int_at(const NumericArray& a, size_t i) {
  const double v = a.values[i * static_cast<size_t>(a.components)];
  if (!std::isfinite(v) || std::abs(v) > 1e15) return std::numeric_limits<long long>::min();
  return std::llround(v);
}

void require_tuples(const PolyData& pd, const NumericArray& a, size_t n, const char* what) {
  if (a.components < 1 || a.tuples() != n || a.values.size() != n * static_cast<size_t>(a.components))
    throw_input_error(pd.source, fmt::format("{} array '{}' has {} values for {} {}", what, a.name, a.values.size(), n,
                                             what[0] == 'p' ? "points" : "cells"));
}

/// Radius at every point, from the first radius-like point array found.
std::vector<double> point_radii(const PolyData& pd) {
  for (const char* name : {"radius", "radii", "MaximumInscribedSphereRadius", "misr"}) {
    if (const auto* a = find_array(pd.point_data, name)) {
      require_tuples(pd, *a, pd.points.size(), "point");
      std::vector<double> r(pd.points.size());
      for (size_t i = 0; i < r.size(); ++i) r[i] = a->values[i * static_cast<size_t>(a->components)];
      return r;
    }
  }
  if (const auto* a = find_array(pd.point_data, "CenterlineSectionArea")) {
    require_tuples(pd, *a, pd.points.size(), "point");
    std::vector<double> r(pd.points.size());
    for (size_t i = 0; i < r.size(); ++i) {
      const double area = a->values[i * static_cast<size_t>(a->components)];
      r[i] = area >= 0.0 ? std::sqrt(area / std::numbers::pi) : area;
    }
    return r;
  }
  throw_input_error(pd.source, fmt::format("no radius array: expected a point array 'radius', 'radii' or "
                                           "'MaximumInscribedSphereRadius' (point arrays in the file: {})",
                                           array_names(pd.point_data)));
}

void require_lines(const PolyData& pd) {
  if (!pd.lines.empty()) return;
  if (pd.points.empty()) throw_input_error(pd.source, "no points and no line cells: the file is empty");
  throw_input_error(pd.source,
                    fmt::format("no line cells (centerline polylines) among {} points{}", pd.points.size(),
                                pd.other_cells > 0 ? fmt::format(" and {} other cells (a surface?)", pd.other_cells)
                                                   : std::string{}));
}

/// Checks every line cell (ids in range, at least two points) and every point the cells use
/// (finite coordinates, finite positive radius).
void validate(const PolyData& pd, const std::vector<double>& radii) {
  require_lines(pd);
  const auto np = static_cast<long long>(pd.points.size());
  std::vector<char> checked(pd.points.size(), 0);
  for (size_t c = 0; c < pd.lines.size(); ++c) {
    const auto& ids = pd.lines[c];
    if (ids.size() < 2)
      throw_input_error(pd.source, fmt::format("line cell {} has {} point(s); a line needs at least 2", c, ids.size()));
    for (const long long id : ids) {
      if (id < 0 || id >= np)
        throw_input_error(pd.source,
                          fmt::format("line cell {}: point id {} is out of range (the file has {} points)", c, id, np));
      const auto i = static_cast<size_t>(id);
      if (checked[i]) continue;
      checked[i] = 1;
      if (!pd.points[i].allFinite())
        throw_input_error(pd.source, fmt::format("point {} (line cell {}): coordinate is not finite", id, c));
      if (!std::isfinite(radii[i]))
        throw_input_error(pd.source, fmt::format("point {} (line cell {}): radius is not finite", id, c));
      if (radii[i] <= 0.0)
        throw_input_error(pd.source,
                          fmt::format("point {} (line cell {}): radius {} is not positive", id, c, radii[i]));
    }
  }
}

/// Point ids of a cell with consecutive coincident points removed (VMTK writes a few) or,
/// when `allow_duplicates` is false, reported.
std::vector<long long> cell_ids(const PolyData& pd, size_t c, bool allow_duplicates) {
  const auto& ids = pd.lines[c];
  std::vector<long long> out;
  out.reserve(ids.size());
  for (size_t k = 0; k < ids.size(); ++k) {
    const long long id = ids[k];
    if (!out.empty()) {
      const long long prev = out.back();
      const bool same = prev == id || pd.points[static_cast<size_t>(prev)] == pd.points[static_cast<size_t>(id)];
      if (same) {
        if (allow_duplicates) continue;
        if (ids.size() == 2 && prev == id)
          throw_input_error(pd.source, fmt::format("line cell {} joins point {} to itself (self-loop)", c, id));
        throw_input_error(pd.source, fmt::format("line cell {}: points {} and {} (ids {} and {}) coincide "
                                                 "(duplicate point)",
                                                 c, k - 1, k, ids[k - 1], id));
      }
    }
    out.push_back(id);
  }
  if (out.size() < 2)
    throw_input_error(pd.source, fmt::format("line cell {}: all its points coincide (duplicate point)", c));
  return out;
}

Polyline make_polyline(const PolyData& pd, const std::vector<double>& radii, const std::vector<long long>& ids,
                       std::string name) {
  Polyline p;
  p.name = std::move(name);
  p.points.reserve(ids.size());
  p.radii.reserve(ids.size());
  for (const long long id : ids) {
    p.points.push_back(pd.points[static_cast<size_t>(id)]);
    p.radii.push_back(radii[static_cast<size_t>(id)]);
  }
  return p;
}

/// Appends q to p, skipping points of q that coincide with the last point of p.
void append_points(Polyline& p, const Polyline& q, size_t from) {
  for (size_t i = from; i < q.points.size(); ++i) {
    if (!p.points.empty() && p.points.back() == q.points[i]) continue;
    p.points.push_back(q.points[i]);
    p.radii.push_back(q.radii[i]);
  }
}

/// Point adjacency from line cells (each consecutive pair of ids is an edge; duplicates merged).
std::vector<std::vector<long long>> adjacency(const PolyData& pd, const std::vector<long long>& canon,
                                              bool allow_duplicates, EdgeOrigins* origins) {
  std::vector<std::vector<long long>> adj(pd.points.size());
  std::set<std::pair<long long, long long>> seen;
  for (size_t c = 0; c < pd.lines.size(); ++c) {
    const auto ids = cell_ids(pd, c, allow_duplicates);
    for (size_t k = 0; k + 1 < ids.size(); ++k) {
      long long a = canon[static_cast<size_t>(ids[k])];
      long long b = canon[static_cast<size_t>(ids[k + 1])];
      if (a == b) continue;
      if (!seen.emplace(std::min(a, b), std::max(a, b)).second) continue;
      if (origins)
        (*origins)[{std::min(a, b), std::max(a, b)}] =
            a < b ? EdgeOrigin{ids[k], ids[k + 1]} : EdgeOrigin{ids[k + 1], ids[k]};
      adj[static_cast<size_t>(a)].push_back(b);
      adj[static_cast<size_t>(b)].push_back(a);
    }
  }
  return adj;
}

}  // namespace flowire::vessels::detail
