#pragma once
/// @file units.hpp
/// @brief Physical quantities written as "<number> <unit>" and converted to SI.
#include <optional>
#include <string>
#include <string_view>

namespace flowire::units {

/// @brief The physical dimension a scene key expects; a unit of another dimension is an error.
enum class Dimension {
  None,              ///< dimensionless (no unit allowed except none)
  Length,            ///< m, cm, mm, um
  Pressure,          ///< Pa, kPa, mmHg, cmH2O, dyn/cm^2, MPa, GPa
  Time,              ///< s, ms, us, min
  Viscosity,         ///< Pa*s, mPa*s, cP, P
  Density,           ///< kg/m^3, g/cm^3
  FlowRate,          ///< m^3/s, mL/s, mL/min, L/min
  Velocity,          ///< m/s, cm/s, mm/s
  Angle,             ///< rad, deg, turn
  AngularSpeed,      ///< rad/s, deg/s, turn/s, turns/s, rpm
  Frequency,         ///< Hz, bpm, 1/s
  Force,             ///< N, mN, uN
  Moment,            ///< N*m, N*mm
  Resistance,        ///< Pa*s/m^3, mmHg*s/mL, dyn*s/cm^5
  Compliance,        ///< m^3/Pa, mL/mmHg, cm^5/dyn
  Acceleration,      ///< m/s^2
  SupportStiffness,  ///< Pa/m, N/m^3, kPa/mm, MPa/m (an elastic support: traction per displacement)
};

/// @brief Name of a dimension, for messages ("length", "pressure", ...).
std::string_view dimension_name(Dimension d);
/// @brief The SI unit of a dimension, for docs ("m", "Pa", ...).
std::string_view si_unit(Dimension d);

/// @brief Factor converting one `unit` of dimension `d` to SI; nullopt if the unit is unknown
/// or belongs to another dimension.
std::optional<double> unit_factor(std::string_view unit, Dimension d);

/// @brief Parse "12", "12.5 mm", "120 mmHg", "3.5e-3 Pa*s" into SI for dimension `d`.
/// @throws flowire::Error (input) with `where` prefixed, naming the unit expected.
double parse_quantity(std::string_view text, Dimension d, std::string_view where);

/// @brief Length-unit names accepted by `--length-unit` / `length_unit` (m, cm, mm, um).
double length_unit_factor(std::string_view unit, std::string_view where);

/// @brief 1 mmHg in Pa (133.322387415).
inline constexpr double mmHg = 133.322387415;

}  // namespace flowire::units
