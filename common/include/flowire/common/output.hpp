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

/// @brief Whether this process writes the outputs: true unless told otherwise. In a run
/// under MPI every rank computes the same results and only rank 0 writes them (PETSc's
/// start-up sets this, flow/petsc_runtime.cpp); on the other ranks write_atomically and
/// write_text_atomically do nothing.
[[nodiscard]] bool writes_outputs();
void set_writes_outputs(bool writes);

}  // namespace flowire
