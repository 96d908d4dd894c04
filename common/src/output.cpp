#include "flowire/common/output.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <fstream>
#include <random>
#include <regex>
#include <system_error>

#include "flowire/common/error.hpp"

namespace flowire {

namespace {
namespace fs = std::filesystem;

bool g_writes_outputs = true;

// ---------------------------------------------------------------- temporaries in flight
// A fixed table the signal handler can read without allocating: each slot holds the path of
// a temporary being written. A slot is claimed (state 1), filled, published (state 2), and
// released (0) once the file is renamed or removed.
struct TempSlot {
  std::atomic<int> state{0};
  std::array<char, 4096> path{};
};
std::array<TempSlot, 32> g_temps;

class TempRegistration {
 public:
  explicit TempRegistration(const fs::path& p) {
    const std::string s = p.string();
    if (s.size() >= g_temps[0].path.size()) return;  // not tracked: removed on errors, not on signals
    for (auto& slot : g_temps) {
      int expected = 0;
      if (!slot.state.compare_exchange_strong(expected, 1)) continue;
      std::memcpy(slot.path.data(), s.c_str(), s.size() + 1);
      slot.state.store(2);
      slot_ = &slot;
      return;
    }
  }
  ~TempRegistration() {
    if (slot_) slot_->state.store(0);
  }
  TempRegistration(const TempRegistration&) = delete;
  TempRegistration& operator=(const TempRegistration&) = delete;

 private:
  TempSlot* slot_ = nullptr;
};

void remove_temporaries_in_flight() {  // async-signal-safe: unlink only
  for (auto& slot : g_temps)
    if (slot.state.load() == 2) ::unlink(slot.path.data());
}

/// `.<name>.<pid>.<random>.partial`: unique to this process and this call, hidden from the
/// globs users write (wire_*.vtp), and recognisable as a temporary of a given pid.
fs::path temporary_for(const fs::path& target) {
  static std::atomic<unsigned long long> counter{0};
  static const unsigned long long seed = [] {
    std::random_device rd;
    return (static_cast<unsigned long long>(rd()) << 32) ^ rd();
  }();
  const unsigned long long n = seed + 0x9E3779B97F4A7C15ULL * (counter.fetch_add(1) + 1);
  return target.parent_path() /
         fmt::format(".{}.{}.{:016x}.partial", target.filename().string(), static_cast<long>(::getpid()), n);
}

/// Flush a written temporary to the disk; false (errno set) if the disk refuses.
bool sync_file(const fs::path& p) {
  const int fd = ::open(p.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool synced = ::fsync(fd) == 0 || errno == EINVAL || errno == EROFS;  // EINVAL: no sync (pipes, some fs)
  const int saved = errno;
  const bool closed = ::close(fd) == 0;
  errno = synced ? errno : saved;
  return synced && closed;
}

// ---------------------------------------------------------------- signals
std::atomic<int> g_interrupt{0};
std::atomic<bool> g_section_open{false};

extern "C" void on_terminating_signal(int sig) {
  if (g_section_open.load() && g_interrupt.load() == 0) {
    g_interrupt.store(sig);
    return;
  }
  remove_temporaries_in_flight();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}
}  // namespace

bool writes_outputs() { return g_writes_outputs; }
void set_writes_outputs(bool writes) { g_writes_outputs = writes; }

void write_atomically(const fs::path& target, const std::function<void(const fs::path& tmp)>& writer) {
  if (!g_writes_outputs) return;
  const std::string name = target.string();
  // A folder that cannot be made or a file that cannot be moved into place is bad input
  // (an output path under a regular file, a read-only folder): one error naming the file.
  std::error_code ec;
  if (!target.parent_path().empty()) {
    fs::create_directories(target.parent_path(), ec);
    if (ec)
      throw_input_error(name,
                        fmt::format("cannot create the folder {}: {}", target.parent_path().string(), ec.message()));
  }
  if (fs::is_directory(target, ec)) throw_input_error(name, "is a folder; cannot write a file there");
  const fs::path tmp = temporary_for(target);
  const TempRegistration registration(tmp);
  try {
    writer(tmp);
    const auto size = fs::file_size(tmp, ec);
    if (ec) throw_input_error(name, "the file could not be written");
    if (size == 0) throw_input_error(name, "the file could not be written (it came out empty; disk full?)");
    if (!sync_file(tmp)) throw_input_error(name, fmt::format("the file could not be saved: {}", std::strerror(errno)));
    fs::rename(tmp, target, ec);
    if (ec) throw_input_error(name, fmt::format("the file could not be put in place: {}", ec.message()));
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
}

void write_stream_atomically(const fs::path& target, const std::function<void(std::ostream& out)>& body) {
  write_atomically(target, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw_input_error(target.string(), fmt::format("cannot open for writing: {}", std::strerror(errno)));
    body(out);
    out.close();  // the buffered tail is written here: a full disk shows at the close
    if (out.fail()) throw_input_error(target.string(), "write failed (disk full?)");
  });
}

void write_text_atomically(const fs::path& target, const std::string& text) {
  write_stream_atomically(target, [&](std::ostream& out) { out << text; });
}

// ---------------------------------------------------------------- OutputFolder

OutputFolder::OutputFolder(fs::path dir) : dir_(std::move(dir)) {
  if (!g_writes_outputs) return;
  if (dir_.empty()) dir_ = ".";
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) throw_input_error(dir_.string(), fmt::format("cannot create the output folder: {}", ec.message()));
  if (!fs::is_directory(dir_)) throw_input_error(dir_.string(), "the output folder is not a folder");
  const fs::path lock = dir_ / ".flowire-run.lock";
  lock_fd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd_ < 0)
    throw_input_error(dir_.string(), fmt::format("cannot write to the output folder: {}", std::strerror(errno)));
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    std::array<char, 32> buf{};
    const ssize_t n = ::pread(lock_fd_, buf.data(), buf.size() - 1, 0);
    ::close(lock_fd_);
    lock_fd_ = -1;
    const std::string holder = n > 0 ? std::string(buf.data(), static_cast<size_t>(n)) : std::string("unknown");
    throw_input_error(dir_.string(),
                      fmt::format("another flowire run (pid {}) is writing to this output folder; wait for it to "
                                  "end or choose another --out",
                                  holder.substr(0, holder.find_first_of("\n "))));
  }
  const std::string pid = fmt::format("{}\n", static_cast<long>(::getpid()));
  if (::ftruncate(lock_fd_, 0) != 0 ||
      ::pwrite(lock_fd_, pid.data(), pid.size(), 0) != static_cast<ssize_t>(pid.size()))
    throw_input_error(dir_.string(), fmt::format("cannot write to the output folder: {}", std::strerror(errno)));

  // Temporaries of processes that no longer exist (a run killed by SIGKILL or a power cut).
  static const std::regex temp_name(R"(^\..+\.([0-9]+)\.[0-9a-f]+\.partial$)");
  auto clear_stale = [&](const fs::path& folder) {
    for (const auto& e : fs::directory_iterator(folder, ec)) {
      std::smatch m;
      const std::string n = e.path().filename().string();
      if (!e.is_regular_file(ec) || !std::regex_match(n, m, temp_name)) continue;
      const long pid_of = std::stol(m[1].str());
      if (pid_of != static_cast<long>(::getpid()) && ::kill(static_cast<pid_t>(pid_of), 0) != 0 && errno == ESRCH)
        fs::remove(e.path(), ec);
    }
  };
  clear_stale(dir_);
  for (const auto& e : fs::directory_iterator(dir_, ec))
    if (e.is_directory(ec) && !e.is_symlink(ec)) clear_stale(e.path());
}

OutputFolder::~OutputFolder() {
  if (lock_fd_ >= 0) ::close(lock_fd_);  // closing releases the flock
}

// ---------------------------------------------------------------- signals

void install_interrupt_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_terminating_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(sig, &sa, nullptr);
}

InterruptibleSection::InterruptibleSection() {
  g_interrupt.store(0);
  g_section_open.store(true);
}

InterruptibleSection::~InterruptibleSection() { g_section_open.store(false); }

int interrupt_signal() { return g_interrupt.load(); }

void throw_if_interrupted(std::string_view where) {
  const int sig = g_interrupt.load();
  if (sig == 0) return;
  throw Error(ErrorKind::Interrupted, fmt::format("{} was interrupted by {}", where,
                                                  sig == SIGINT    ? "SIGINT"
                                                  : sig == SIGTERM ? "SIGTERM"
                                                                   : "SIGHUP"));
}

}  // namespace flowire
