// The command line's programs finding one another (programs.hpp).
#include "programs.hpp"

#include <sys/prctl.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "dispatch.hpp"

namespace flowire::cli {

std::filesystem::path sibling_program(const char* name) {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  const std::filesystem::path p = self.parent_path() / name;
  return access(p.c_str(), X_OK) == 0 ? p : std::filesystem::path();
}

int exec_program(const std::filesystem::path& program, char** argv) {
  std::fflush(stdout);
  std::fflush(stderr);
  execv(program.c_str(), argv);
  std::perror(("flowire: error: cannot start " + program.string()).c_str());
  return 3;
}

void follow_parent() {
  const char* parent = std::getenv(kParentVariable);
  if (!parent) return;
  const long pid = std::strtol(parent, nullptr, 10);
  ::prctl(PR_SET_PDEATHSIG, SIGTERM);
  if (static_cast<long>(::getppid()) != pid) std::raise(SIGTERM);  // it ended before prctl
}

}  // namespace flowire::cli
