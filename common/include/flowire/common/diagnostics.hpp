#pragma once
/// @file diagnostics.hpp
/// @brief Warnings reported by the libraries (numerical trouble, clamped input, choices
/// made on the user's behalf). They are collected for `summary.json` and can be routed
/// to a handler (the test base fails any test during which a warning is reported).
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace flowire {

using WarningHandler = std::function<void(std::string_view)>;

/// @brief Report a warning: it goes to the installed handler (default: collected).
void warn(std::string_view message);
/// @brief Install a handler; returns the previous one. An empty handler restores the default.
WarningHandler set_warning_handler(WarningHandler handler);
/// @brief Warnings collected by the default handler since the last `take_warnings()`.
std::vector<std::string> take_warnings();

}  // namespace flowire
