#pragma once
/// @file output.hpp
/// @brief The one way flowire writes a file, and the output folder of a run.
///
/// Every output goes through write_atomically: it is written under a temporary name unique
/// to the process (`.<name>.<pid>.<random>.partial`, hidden, next to the target), closed
/// with the close checked, flushed to the disk (fsync) and only then renamed into place. A
/// failed write (a full disk, a removed folder) is an error naming the file, and leaves the
/// target as it was: never a 0-byte or cut-off file. A run's folder is held by an
/// OutputFolder (a lock: two runs never write one folder), and SIGINT/SIGTERM remove the
/// temporaries being written (install_interrupt_handlers).
#include <filesystem>
#include <functional>
#include <ostream>
#include <string>

namespace flowire {

/// @brief Call `writer(tmp)` with a temporary path next to `target`, then check, flush and
/// rename it to `target`. If `writer` throws, or the file it leaves is missing or empty, or
/// it cannot be flushed or moved into place, the temporary file is removed and an input
/// error naming `target` is thrown (the writer's own exception passes on unchanged).
void write_atomically(const std::filesystem::path& target,
                      const std::function<void(const std::filesystem::path& tmp)>& writer);

/// @brief write_atomically for text written to a stream: `body(out)` writes, then the stream
/// is closed and the close checked (a full disk is often seen only there).
void write_stream_atomically(const std::filesystem::path& target, const std::function<void(std::ostream& out)>& body);

/// @brief Write `text` to `target` atomically.
void write_text_atomically(const std::filesystem::path& target, const std::string& text);

/// @brief Whether this process writes the outputs: true unless told otherwise. In a run
/// under MPI every rank computes the same results and only rank 0 writes them (PETSc's
/// start-up sets this, flow/petsc_runtime.cpp); on the other ranks write_atomically and
/// write_text_atomically do nothing.
[[nodiscard]] bool writes_outputs();
void set_writes_outputs(bool writes);

/// @brief A run's output folder, held for the run's lifetime: created if absent, locked
/// (`.flowire-run.lock`, an flock released by the kernel however the process ends), and
/// cleared of the temporaries that runs killed earlier left behind. A second run on a held
/// folder is an input error naming the holder's pid. Does nothing where writes_outputs() is
/// false.
class OutputFolder {
 public:
  explicit OutputFolder(std::filesystem::path dir);
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const { return dir_; }

 private:
  std::filesystem::path dir_;
  int lock_fd_ = -1;
};

/// @brief Catch SIGINT, SIGTERM and SIGHUP: the temporaries being written are removed, and
/// then the process ends by the signal, unless an InterruptibleSection is open: there the
/// first signal is only recorded, for the section to end cleanly at its next
/// throw_if_interrupted() (a second signal ends the process at once). Call once, from main.
void install_interrupt_handlers();

/// @brief A stretch of work (a run's time steps) that checks throw_if_interrupted() often
/// enough to stop within a moment of a signal. Sections do not nest.
class InterruptibleSection {
 public:
  InterruptibleSection();
  ~InterruptibleSection();
  InterruptibleSection(const InterruptibleSection&) = delete;
  InterruptibleSection& operator=(const InterruptibleSection&) = delete;
};

/// @brief The signal recorded inside an InterruptibleSection (0 if none).
[[nodiscard]] int interrupt_signal();
/// @brief Throw Error(ErrorKind::Interrupted) if a signal was recorded; `where` says what was
/// interrupted ("the run at t = 0.25 s").
void throw_if_interrupted(std::string_view where);

}  // namespace flowire
