#pragma once
// One status line on stderr, redrawn in place: only when stderr is a terminal, never into a
// pipe or a log file (the run's progress, a study's runs done).
#include <unistd.h>

#include <cstdio>
#include <string>

namespace flowire::cli {

class TerminalLine {
 public:
  TerminalLine() : enabled_(isatty(fileno(stderr)) == 1) {}
  ~TerminalLine() { clear(); }
  TerminalLine(const TerminalLine&) = delete;
  TerminalLine& operator=(const TerminalLine&) = delete;
  [[nodiscard]] bool enabled() const { return enabled_; }
  /// Replace the line by @p text (nothing when stderr is no terminal).
  void draw(const std::string& text) {
    if (!enabled_) return;
    std::fprintf(stderr, "\r\033[K%s", text.c_str());
    std::fflush(stderr);
    drawn_ = true;
  }
  /// Erase the line, if one was drawn.
  void clear() {
    if (!drawn_) return;
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
    drawn_ = false;
  }

 private:
  bool enabled_;
  bool drawn_ = false;
};

}  // namespace flowire::cli
