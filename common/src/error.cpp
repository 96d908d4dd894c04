#include "flowire/common/error.hpp"

#include <fmt/format.h>

#include <csignal>

#include "flowire/common/output.hpp"

namespace flowire {

void throw_input_error(std::string_view where, std::string_view what) {
  if (where.empty()) throw Error(ErrorKind::Input, std::string(what));
  throw Error(ErrorKind::Input, fmt::format("{}: {}", where, what));
}

void throw_usage_error(std::string_view what) { throw Error(ErrorKind::Usage, std::string(what)); }

void throw_numerical_error(std::string_view what) { throw Error(ErrorKind::Numerical, std::string(what)); }

int exit_status(const Error& e) {
  switch (e.kind()) {
    case ErrorKind::Numerical:
      return 3;
    case ErrorKind::Interrupted:
      return 128 + (interrupt_signal() != 0 ? interrupt_signal() : SIGINT);
    case ErrorKind::Input:
    case ErrorKind::Usage:
      break;
  }
  return 2;
}

}  // namespace flowire
