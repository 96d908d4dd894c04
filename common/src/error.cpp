#include "flowire/common/error.hpp"

#include <fmt/format.h>

namespace flowire {

void throw_input_error(std::string_view where, std::string_view what) {
  if (where.empty()) throw Error(ErrorKind::Input, std::string(what));
  throw Error(ErrorKind::Input, fmt::format("{}: {}", where, what));
}

void throw_usage_error(std::string_view what) { throw Error(ErrorKind::Usage, std::string(what)); }

void throw_numerical_error(std::string_view what) { throw Error(ErrorKind::Numerical, std::string(what)); }

}  // namespace flowire
