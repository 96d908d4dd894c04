#pragma once
/// @file input.hpp
/// @brief Every input file is opened through here: it must be a regular file (not a folder,
/// a device such as /dev/zero, or a pipe that never ends) no larger than its kind allows, so
/// that a wrong path is one clear error instead of a hang, a crash or gigabytes of memory.
#include <cstdint>
#include <fstream>
#include <string>
#include <string_view>

namespace flowire {

/// @brief Size limits by kind of file, in bytes (each far above any real file of its kind).
namespace input_limit {
inline constexpr std::uintmax_t kScene = 8ULL << 20;     ///< a YAML scene (yaml-cpp reads ~1 MB/s)
inline constexpr std::uintmax_t kTable = 512ULL << 20;   ///< CSV tables, JSON models
inline constexpr std::uintmax_t kGeometry = 4ULL << 30;  ///< centerlines, networks, lumen surfaces
}  // namespace input_limit

/// @brief Check that @p path names a readable regular file of at most @p max_bytes;
/// @p what names the kind of file in the message ("the scene", "the svZeroDSolver model").
/// @throws flowire::Error (input) naming the file otherwise.
void check_input_file(const std::string& path, std::uintmax_t max_bytes, std::string_view what);

/// @brief check_input_file, then open it (binary).
[[nodiscard]] std::ifstream open_input(const std::string& path, std::uintmax_t max_bytes, std::string_view what);

/// @brief check_input_file, then the whole file.
[[nodiscard]] std::string read_input(const std::string& path, std::uintmax_t max_bytes, std::string_view what);

}  // namespace flowire
