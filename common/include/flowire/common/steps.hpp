#pragma once
/// @file steps.hpp
/// @brief Numbers of time steps planned from input (a duration over a step, an output interval
/// over a step, a period over a step): computed in floating point and checked before they
/// become integers, so that a wrong unit or an absurd value is an input error, never an
/// overflow into a negative or meaningless count.
#include <fmt/format.h>

#include <cmath>
#include <string_view>

#include "flowire/common/error.hpp"

namespace flowire {

/// @brief The most time steps a run may plan. More is a mistake of a unit or of a key (a
/// duration in s meant in ms, a step of 1e-300 s), not a computation anyone could wait for.
inline constexpr double kMaxSteps = 1e9;

/// @brief round(@p span / @p step) as a count of steps, checked: @p span finite and >= 0,
/// @p step finite and > 0, and the count at most kMaxSteps.
/// @param where the input at fault, for the message ("scene.yaml:8: solve.duration")
/// @param ratio the quotient in the input's words ("solve.duration / solve.dt")
/// @throws flowire::Error (input) at @p where naming @p ratio and the limit otherwise.
[[nodiscard]] inline long step_count(double span, double step, std::string_view where, std::string_view ratio) {
  if (!(std::isfinite(span) && span >= 0.0 && std::isfinite(step) && step > 0.0))
    throw_input_error(where,
                      fmt::format("{} = {} / {}: needs a finite time >= 0 over a finite step > 0", ratio, span, step));
  const double n = std::round(span / step);
  if (!(n <= kMaxSteps))
    throw_input_error(
        where, fmt::format("{} = {:.3g} steps, more than the {:.0e} a run may plan", ratio, span / step, kMaxSteps));
  return static_cast<long>(n);
}

}  // namespace flowire
