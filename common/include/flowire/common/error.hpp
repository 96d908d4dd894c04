#pragma once
/// @file error.hpp
/// @brief flowire's exception types and the helpers that throw them.
///
/// Three tiers (see docs/design.md): `assert` inside hot kernels, `flowire::Error` at the
/// API and input boundary, and numerical trouble counted as warnings (diagnostics.hpp)
/// unless it makes the result meaningless, in which case `NumericalError` is thrown.
#include <stdexcept>
#include <string>
#include <string_view>

namespace flowire {

/// @brief What kind of failure; selects the CLI exit status (usage/input: 2, numerical: 3,
/// interrupted: 128 + the signal, as a shell reports a process the signal ended).
enum class ErrorKind { Input, Usage, Numerical, Interrupted };

/// @brief The one exception type thrown by flowire libraries.
class Error : public std::runtime_error {
 public:
  Error(ErrorKind kind, std::string message) : std::runtime_error(std::move(message)), kind_(kind) {}
  [[nodiscard]] ErrorKind kind() const noexcept { return kind_; }

 private:
  ErrorKind kind_;
};

/// @brief Bad input data: a file, a key, a value. `where` names the file and place
/// ("aorta.vtp: point 17", "scene.yaml:12: flow.solver"), `what` says what is wrong.
[[noreturn]] void throw_input_error(std::string_view where, std::string_view what);
/// @brief Bad input without a file (API misuse, invalid argument).
[[noreturn]] void throw_usage_error(std::string_view what);
/// @brief Numerical failure: singular system, divergence, NaN.
[[noreturn]] void throw_numerical_error(std::string_view what);

/// @brief The CLI exit status of an error: 2 for input and usage, 3 for a numerical failure,
/// 128 + the signal for an interrupted run (130 after SIGINT, 143 after SIGTERM).
[[nodiscard]] int exit_status(const Error& e);

}  // namespace flowire
