#include "flowire/coupling/trace_compare.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"

namespace flowire::coupling {

std::vector<TracePoint> read_tip_trace(const std::string& path) {
  std::ifstream in = open_input(path, input_limit::kTable, "a tip trace (CSV)");
  std::string line;
  if (!std::getline(in, line)) throw_input_error(path, "empty file (expected a header time,inserted_length,x,y,z)");
  if (line.rfind("time,inserted_length,x,y,z", 0) != 0)
    throw_input_error(fmt::format("{}:1", path), "header must start with time,inserted_length,x,y,z");
  std::vector<TracePoint> out;
  int lineno = 1;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty()) continue;
    std::stringstream ss(line);
    std::string cell;
    double v[5];
    for (int k = 0; k < 5; ++k) {
      if (!std::getline(ss, cell, ',')) throw_input_error(fmt::format("{}:{}", path, lineno), "expected 5 columns");
      try {
        size_t used = 0;
        v[k] = std::stod(cell, &used);
      } catch (const std::exception&) {
        throw_input_error(fmt::format("{}:{}", path, lineno), fmt::format("'{}' is not a number", cell));
      }
      if (!std::isfinite(v[k])) throw_input_error(fmt::format("{}:{}", path, lineno), "value is not finite");
    }
    out.push_back({v[0], v[1], Eigen::Vector3d(v[2], v[3], v[4])});
  }
  if (out.size() < 2) throw_input_error(path, "a tip trace needs at least 2 rows");
  return out;
}

namespace {
/// Position at inserted length L, interpolating along a trace sorted by inserted length.
Eigen::Vector3d at_length(const std::vector<TracePoint>& t, double L) {
  auto it =
      std::lower_bound(t.begin(), t.end(), L, [](const TracePoint& p, double v) { return p.inserted_length < v; });
  if (it == t.begin()) return it->x;
  if (it == t.end()) return t.back().x;
  const auto& b = *it;
  const auto& a = *(it - 1);
  const double den = b.inserted_length - a.inserted_length;
  const double w = den > 0 ? (L - a.inserted_length) / den : 1.0;
  return (1 - w) * a.x + w * b.x;
}

std::vector<TracePoint> monotone(std::vector<TracePoint> t) {
  // Keep the first time each inserted length is reached (pull-backs are not compared).
  std::vector<TracePoint> out;
  for (const auto& p : t)
    if (out.empty() || p.inserted_length > out.back().inserted_length) out.push_back(p);
  return out;
}
}  // namespace

CompareResult compare_traces(const std::vector<TracePoint>& a_in, const std::vector<TracePoint>& b_in, double spacing,
                             double row_spacing) {
  if (!(spacing > 0) || !(row_spacing >= spacing))
    throw_usage_error("compare: spacing must be positive and <= row spacing");
  const auto a = monotone(a_in), b = monotone(b_in);
  const double lo = std::max(a.front().inserted_length, b.front().inserted_length);
  const double hi = std::min(a.back().inserted_length, b.back().inserted_length);
  CompareResult r;
  if (!(hi > lo)) return r;
  CompareRow row;
  double sum_row = 0, sum_all = 0;
  double next_row = lo + row_spacing;
  for (double L = lo; L <= hi + 1e-12; L += spacing) {
    const double d2 = (at_length(a, L) - at_length(b, L)).squaredNorm();
    sum_row += d2;
    sum_all += d2;
    ++row.samples;
    ++r.samples;
    row.max_distance = std::max(row.max_distance, std::sqrt(d2));
    const bool last = L + spacing > hi + 1e-12;
    if (L >= next_row - 1e-12 || last) {
      row.inserted_length = L;
      row.rms_published = std::sqrt(0.5 * sum_row);
      row.rms = std::sqrt(sum_row / row.samples);
      r.rows.push_back(row);
      row = {};
      sum_row = 0;
      next_row += row_spacing;
    }
  }
  r.rms_published_total = std::sqrt(0.5 * sum_all);
  r.rms_total = std::sqrt(sum_all / std::max(1, r.samples));
  return r;
}

std::string compare_csv(const CompareResult& r) {
  std::string out = "inserted_length,samples,rms_published,rms,max_distance\n";
  for (const auto& row : r.rows)
    out += fmt::format("{:.6g},{},{:.6g},{:.6g},{:.6g}\n", row.inserted_length, row.samples, row.rms_published, row.rms,
                       row.max_distance);
  return out;
}

}  // namespace flowire::coupling
