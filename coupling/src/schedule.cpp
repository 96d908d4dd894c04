#include "flowire/coupling/schedule.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <fstream>
#include <sstream>

#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"

namespace flowire::coupling {

namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) cells.push_back(trim(cell));
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

}  // namespace

DriveSchedule::DriveSchedule(std::vector<Row> rows) : rows_(std::move(rows)) {}

DriveSchedule DriveSchedule::read_csv(const std::string& path) {
  std::ifstream in = open_input(path, input_limit::kTable, "an insertion schedule (CSV)");
  std::string line;
  int lineno = 0;
  // Header: the three columns, any order, nothing else.
  std::array<int, 3> col = {-1, -1, -1};
  const std::array<const char*, 3> names = {"time", "speed", "rotation_speed"};
  size_t ncols = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (trim(line).empty()) continue;
    const auto cells = split(line);
    ncols = cells.size();
    for (size_t k = 0; k < cells.size(); ++k) {
      int which = -1;
      for (int n = 0; n < 3; ++n)
        if (cells[k] == names[static_cast<size_t>(n)]) which = n;
      const auto where = fmt::format("{}:{}", path, lineno);
      if (which < 0)
        throw_input_error(where,
                          fmt::format("unknown column '{}' (the columns are time,speed,rotation_speed)", cells[k]));
      if (col[static_cast<size_t>(which)] >= 0)
        throw_input_error(where, fmt::format("column '{}' appears twice", cells[k]));
      col[static_cast<size_t>(which)] = static_cast<int>(k);
    }
    for (int n = 0; n < 3; ++n)
      if (col[static_cast<size_t>(n)] < 0)
        throw_input_error(fmt::format("{}:{}", path, lineno),
                          fmt::format("missing column '{}' (the header must name time,speed,rotation_speed)",
                                      names[static_cast<size_t>(n)]));
    break;
  }
  if (ncols == 0)
    throw_input_error(path, "the insertion schedule is empty (expected a header time,speed,rotation_speed)");
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    ++lineno;
    if (trim(line).empty()) continue;
    const auto where = fmt::format("{}:{}", path, lineno);
    const auto cells = split(line);
    if (cells.size() != ncols)
      throw_input_error(where, fmt::format("expected {} values, found {}", ncols, cells.size()));
    double v[3];
    for (int n = 0; n < 3; ++n) {
      const std::string& cell = cells[static_cast<size_t>(col[static_cast<size_t>(n)])];
      size_t used = 0;
      try {
        v[n] = std::stod(cell, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (cell.empty() || used != cell.size())
        throw_input_error(where, fmt::format("{}: '{}' is not a number", names[static_cast<size_t>(n)], cell));
      if (!std::isfinite(v[n]))
        throw_input_error(where, fmt::format("{} is not finite", names[static_cast<size_t>(n)]));
    }
    if (v[0] < 0.0) throw_input_error(where, fmt::format("time {} s is negative", v[0]));
    if (!rows.empty() && !(v[0] > rows.back().time))
      throw_input_error(where, fmt::format("time {} s does not come after the previous row's {} s (rows must be in "
                                           "increasing time)",
                                           v[0], rows.back().time));
    rows.push_back({v[0], v[1], v[2]});
  }
  if (rows.empty()) throw_input_error(path, "the insertion schedule has a header but no row");
  return DriveSchedule(std::move(rows));
}

void DriveSchedule::integral_to(double t, double& length, double& angle) const {
  length = angle = 0.0;
  for (size_t k = 0; k < rows_.size() && rows_[k].time < t; ++k) {
    const double end = k + 1 < rows_.size() ? std::min(rows_[k + 1].time, t) : t;
    length += rows_[k].speed * (end - rows_[k].time);
    angle += rows_[k].rotation_speed * (end - rows_[k].time);
  }
}

void DriveSchedule::mean_over(double t0, double t1, double& speed, double& rotation_speed) const {
  double l0, a0, l1, a1;
  integral_to(t0, l0, a0);
  integral_to(t1, l1, a1);
  speed = (l1 - l0) / (t1 - t0);
  rotation_speed = (a1 - a0) / (t1 - t0);
}

}  // namespace flowire::coupling
