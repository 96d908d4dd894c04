#include "flowire/common/units.hpp"

#include <fmt/format.h>

#include <array>
#include <charconv>
#include <cmath>
#include <numbers>

#include "flowire/common/error.hpp"

namespace flowire::units {
namespace {

struct UnitEntry {
  std::string_view name;
  Dimension dim;
  double factor;
};

constexpr double kPi = std::numbers::pi;

constexpr std::array kUnits = {
    UnitEntry{"m", Dimension::Length, 1.0},
    UnitEntry{"cm", Dimension::Length, 1e-2},
    UnitEntry{"mm", Dimension::Length, 1e-3},
    UnitEntry{"um", Dimension::Length, 1e-6},
    UnitEntry{"Pa", Dimension::Pressure, 1.0},
    UnitEntry{"kPa", Dimension::Pressure, 1e3},
    UnitEntry{"MPa", Dimension::Pressure, 1e6},
    UnitEntry{"GPa", Dimension::Pressure, 1e9},
    UnitEntry{"mmHg", Dimension::Pressure, mmHg},
    UnitEntry{"cmH2O", Dimension::Pressure, 98.0665},
    UnitEntry{"dyn/cm^2", Dimension::Pressure, 0.1},
    UnitEntry{"s", Dimension::Time, 1.0},
    UnitEntry{"ms", Dimension::Time, 1e-3},
    UnitEntry{"us", Dimension::Time, 1e-6},
    UnitEntry{"min", Dimension::Time, 60.0},
    UnitEntry{"Pa*s", Dimension::Viscosity, 1.0},
    UnitEntry{"mPa*s", Dimension::Viscosity, 1e-3},
    UnitEntry{"cP", Dimension::Viscosity, 1e-3},
    UnitEntry{"P", Dimension::Viscosity, 0.1},
    UnitEntry{"kg/m^3", Dimension::Density, 1.0},
    UnitEntry{"g/cm^3", Dimension::Density, 1e3},
    UnitEntry{"m^3/s", Dimension::FlowRate, 1.0},
    UnitEntry{"mL/s", Dimension::FlowRate, 1e-6},
    UnitEntry{"mL/min", Dimension::FlowRate, 1e-6 / 60.0},
    UnitEntry{"L/min", Dimension::FlowRate, 1e-3 / 60.0},
    UnitEntry{"m/s", Dimension::Velocity, 1.0},
    UnitEntry{"cm/s", Dimension::Velocity, 1e-2},
    UnitEntry{"mm/s", Dimension::Velocity, 1e-3},
    UnitEntry{"rad", Dimension::Angle, 1.0},
    UnitEntry{"deg", Dimension::Angle, kPi / 180.0},
    UnitEntry{"turn", Dimension::Angle, 2.0 * kPi},
    UnitEntry{"turns", Dimension::Angle, 2.0 * kPi},
    UnitEntry{"rad/s", Dimension::AngularSpeed, 1.0},
    UnitEntry{"deg/s", Dimension::AngularSpeed, kPi / 180.0},
    UnitEntry{"turn/s", Dimension::AngularSpeed, 2.0 * kPi},
    UnitEntry{"turns/s", Dimension::AngularSpeed, 2.0 * kPi},
    UnitEntry{"rpm", Dimension::AngularSpeed, 2.0 * kPi / 60.0},
    UnitEntry{"Hz", Dimension::Frequency, 1.0},
    UnitEntry{"1/s", Dimension::Frequency, 1.0},
    UnitEntry{"bpm", Dimension::Frequency, 1.0 / 60.0},
    UnitEntry{"N", Dimension::Force, 1.0},
    UnitEntry{"mN", Dimension::Force, 1e-3},
    UnitEntry{"uN", Dimension::Force, 1e-6},
    UnitEntry{"N*m", Dimension::Moment, 1.0},
    UnitEntry{"N*mm", Dimension::Moment, 1e-3},
    UnitEntry{"Pa*s/m^3", Dimension::Resistance, 1.0},
    UnitEntry{"mmHg*s/mL", Dimension::Resistance, mmHg * 1e6},
    UnitEntry{"dyn*s/cm^5", Dimension::Resistance, 1e5},
    UnitEntry{"m^3/Pa", Dimension::Compliance, 1.0},
    UnitEntry{"mL/mmHg", Dimension::Compliance, 1e-6 / mmHg},
    UnitEntry{"cm^5/dyn", Dimension::Compliance, 1e-5},
    UnitEntry{"m/s^2", Dimension::Acceleration, 1.0},
    UnitEntry{"Pa/m", Dimension::SupportStiffness, 1.0},
    UnitEntry{"N/m^3", Dimension::SupportStiffness, 1.0},
    UnitEntry{"kPa/mm", Dimension::SupportStiffness, 1e6},
    UnitEntry{"MPa/m", Dimension::SupportStiffness, 1e6},
};

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

std::string units_of(Dimension d) {
  std::string out;
  for (const auto& u : kUnits) {
    if (u.dim != d) continue;
    if (!out.empty()) out += ", ";
    out += u.name;
  }
  return out;
}

}  // namespace

std::string_view dimension_name(Dimension d) {
  switch (d) {
    case Dimension::None:
      return "dimensionless";
    case Dimension::Length:
      return "length";
    case Dimension::Pressure:
      return "pressure";
    case Dimension::Time:
      return "time";
    case Dimension::Viscosity:
      return "viscosity";
    case Dimension::Density:
      return "density";
    case Dimension::FlowRate:
      return "flow rate";
    case Dimension::Velocity:
      return "velocity";
    case Dimension::Angle:
      return "angle";
    case Dimension::AngularSpeed:
      return "angular speed";
    case Dimension::Frequency:
      return "frequency";
    case Dimension::Force:
      return "force";
    case Dimension::Moment:
      return "moment";
    case Dimension::Resistance:
      return "resistance";
    case Dimension::Compliance:
      return "compliance";
    case Dimension::Acceleration:
      return "acceleration";
    case Dimension::SupportStiffness:
      return "support stiffness";
  }
  return "?";
}

std::string_view si_unit(Dimension d) {
  for (const auto& u : kUnits)
    if (u.dim == d && u.factor == 1.0) return u.name;
  return "";
}

std::optional<double> unit_factor(std::string_view unit, Dimension d) {
  for (const auto& u : kUnits)
    if (u.dim == d && u.name == unit) return u.factor;
  return std::nullopt;
}

double parse_quantity(std::string_view text, Dimension d, std::string_view where) {
  const std::string_view t = trim(text);
  double value = 0.0;
  const auto* begin = t.data();
  const auto* end = t.data() + t.size();
  auto [ptr, ec] = std::from_chars(begin, end, value);
  if (ec != std::errc() || ptr == begin)
    throw_input_error(where, fmt::format("'{}' is not a number (expected \"<number> <unit>\")", text));
  if (!std::isfinite(value)) throw_input_error(where, fmt::format("'{}' is not finite", text));
  const std::string_view unit = trim(std::string_view(ptr, static_cast<size_t>(end - ptr)));
  if (unit.empty()) return value;
  if (d == Dimension::None)
    throw_input_error(where, fmt::format("'{}': this value is dimensionless, remove the unit '{}'", text, unit));
  const auto f = unit_factor(unit, d);
  if (!f) {
    for (const auto& u : kUnits)
      if (u.name == unit)
        throw_input_error(where, fmt::format("unit '{}' is a {} but a {} is expected (use one of: {})", unit,
                                             dimension_name(u.dim), dimension_name(d), units_of(d)));
    throw_input_error(where,
                      fmt::format("unknown unit '{}' for a {} (use one of: {})", unit, dimension_name(d), units_of(d)));
  }
  return value * *f;
}

double length_unit_factor(std::string_view unit, std::string_view where) {
  const auto f = unit_factor(trim(unit), Dimension::Length);
  if (!f)
    throw_input_error(where,
                      fmt::format("unknown length unit '{}' (use one of: {})", unit, units_of(Dimension::Length)));
  return *f;
}

}  // namespace flowire::units
