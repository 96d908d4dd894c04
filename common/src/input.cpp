#include "flowire/common/input.hpp"

#include <fmt/format.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <sstream>

#include "flowire/common/error.hpp"

namespace flowire {

namespace {
std::string megabytes(std::uintmax_t bytes) { return fmt::format("{:.0f} MB", static_cast<double>(bytes) / 1048576.0); }
}  // namespace

void check_input_file(const std::string& path, std::uintmax_t max_bytes, std::string_view what) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) throw_input_error(path, fmt::format("no such file ({})", what));
    throw_input_error(path, fmt::format("cannot read {}: {}", what, std::strerror(errno)));
  }
  if (S_ISDIR(st.st_mode)) throw_input_error(path, fmt::format("is a folder, not {}", what));
  if (!S_ISREG(st.st_mode))
    throw_input_error(path, fmt::format("is not a regular file (a device, a pipe or a socket), not {}", what));
  if (static_cast<std::uintmax_t>(st.st_size) > max_bytes)
    throw_input_error(
        path, fmt::format("is {}; {} may be at most {}", megabytes(static_cast<std::uintmax_t>(st.st_size)), what,
                          megabytes(max_bytes)));
}

std::ifstream open_input(const std::string& path, std::uintmax_t max_bytes, std::string_view what) {
  check_input_file(path, max_bytes, what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw_input_error(path, fmt::format("cannot open {}: {}", what, std::strerror(errno)));
  return in;
}

std::string read_input(const std::string& path, std::uintmax_t max_bytes, std::string_view what) {
  std::ifstream in = open_input(path, max_bytes, what);
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw_input_error(path, fmt::format("reading {} failed", what));
  return ss.str();
}

}  // namespace flowire
