#pragma once
/// @file output.hpp
/// @brief Output files are written to a temporary name and renamed into place, so a
/// failed run never leaves a half-written file behind.
#include <filesystem>
#include <functional>
#include <string>

namespace flowire {

/// @brief Call `writer(tmp)` with a temporary path next to `target`, then rename it to
/// `target`. If `writer` throws, the temporary file is removed and the exception passes on.
void write_atomically(const std::filesystem::path& target,
                      const std::function<void(const std::filesystem::path& tmp)>& writer);

/// @brief Write `text` to `target` atomically.
void write_text_atomically(const std::filesystem::path& target, const std::string& text);

}  // namespace flowire
