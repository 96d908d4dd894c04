// The dispatcher of independent tasks over threads and MPI ranks (dispatch.hpp), and the child
// processes that run them.
#include "dispatch.hpp"
#include "programs.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sched.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <deque>
#include <list>
#include <mutex>
#include <set>
#include <string_view>
#include <thread>

#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"

#ifdef FLOWIRE_WITH_MPI
#include <mpi.h>
#endif

extern char** environ;

namespace flowire::cli {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

/// Variables of MPI launchers: a child that kept them would try to join the launcher's job.
bool launcher_variable(std::string_view entry) {
  for (const std::string_view prefix : {"OMPI_", "PMIX_", "PMI_"})
    if (entry.substr(0, prefix.size()) == prefix) return true;
  return entry.substr(0, std::strlen(kParentVariable) + 1) == std::string(kParentVariable) + "=";
}

/// This process's environment for a child: without the launcher's variables, with this pid.
const std::vector<std::string>& child_environment() {
  static const std::vector<std::string> env = [] {
    std::vector<std::string> e;
    for (char** p = environ; p && *p; ++p)
      if (!launcher_variable(*p)) e.emplace_back(*p);
    e.push_back(fmt::format("{}={}", kParentVariable, static_cast<long>(::getpid())));
    return e;
  }();
  return env;
}

std::mutex g_children_mutex;
std::set<pid_t> g_children;  // children being waited for
bool g_refuse_children = false;

double thread_cpu_seconds() {
  timespec ts{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// Stop starting children and end the running ones.
void end_children(int signal) {
  std::lock_guard<std::mutex> lock(g_children_mutex);
  g_refuse_children = true;
  for (const pid_t pid : g_children) ::kill(pid, signal);
}

}  // namespace

int run_child(const std::vector<std::string>& args, const fs::path& log) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 34))
  posix_spawn_file_actions_addclosefrom_np(&fa, 3);  // no MPI socket or lock held by a child
#endif
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  std::vector<char*> envp;
  for (const auto& e : child_environment()) envp.push_back(const_cast<char*>(e.c_str()));
  envp.push_back(nullptr);
  pid_t pid = 0;
  {
    // Spawned and registered at once: end_children() either sees the child or stops it starting.
    std::lock_guard<std::mutex> lock(g_children_mutex);
    if (g_refuse_children) {
      posix_spawn_file_actions_destroy(&fa);
      return -1;
    }
    // A `run` starts in the scene runner, which hands what it cannot run to this program.
    static const fs::path runner = sibling_program("flowire-run");
    const bool run = args.size() > 1 && args[1] == "run" && !runner.empty();
    const int rc = posix_spawn(&pid, run ? runner.c_str() : "/proc/self/exe", &fa, nullptr, argv.data(), envp.data());
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0) return -1;
    g_children.insert(pid);
  }
  int status = 0;
  int rc = 0;
  while ((rc = ::waitpid(pid, &status, 0)) < 0 && errno == EINTR) {
  }
  {
    std::lock_guard<std::mutex> lock(g_children_mutex);
    g_children.erase(pid);
  }
  if (rc < 0) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

void signal_children(int signal) {
  std::lock_guard<std::mutex> lock(g_children_mutex);
  for (const pid_t pid : g_children) ::kill(pid, signal);
}

bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE", "MV2_COMM_WORLD_SIZE"})
    if (std::getenv(v)) return true;
  return false;
}

// ---------------------------------------------------------------- the threads of one rank

/// `threads` threads, each running one task at a time. Tasks are submitted and completions
/// taken by one thread (the dispatching one), which alone counts the busy slots.
class Dispatcher::Pool {
 public:
  struct Done {
    long index = 0;
    Outcome outcome;
  };

  Pool(int threads, Work work, int rank) : threads_(threads), work_(std::move(work)), rank_(rank) {
    for (int t = 0; t < threads; ++t) workers_.emplace_back([this] { loop(); });
  }
  ~Pool() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
      tasks_.clear();
    }
    task_ready_.notify_all();
    for (auto& t : workers_) t.join();
  }
  Pool(const Pool&) = delete;
  Pool& operator=(const Pool&) = delete;

  [[nodiscard]] bool free_slot() const { return busy_ < threads_; }
  [[nodiscard]] int busy() const { return busy_; }

  void submit(long index, std::string payload) {
    ++busy_;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      tasks_.emplace_back(index, std::move(payload));
    }
    task_ready_.notify_one();
  }

  /// The tasks finished so far; if none, waits up to @p timeout for one.
  std::vector<Done> take(std::chrono::microseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (done_.empty() && timeout.count() > 0) done_ready_.wait_for(lock, timeout, [this] { return !done_.empty(); });
    std::vector<Done> out(std::make_move_iterator(done_.begin()), std::make_move_iterator(done_.end()));
    done_.clear();
    busy_ -= static_cast<int>(out.size());
    return out;
  }

 private:
  void loop() {
    for (;;) {
      std::pair<long, std::string> task;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        task_ready_.wait(lock, [this] { return stopping_ || !tasks_.empty(); });
        if (stopping_) return;
        task = std::move(tasks_.front());
        tasks_.pop_front();
      }
      Done d;
      d.index = task.first;
      d.outcome.rank = rank_;
      try {
        d.outcome.text = work_(task.second);
        d.outcome.ok = true;
      } catch (const std::exception& e) {
        d.outcome.text = e.what();
      }
      {
        std::lock_guard<std::mutex> lock(mutex_);
        done_.push_back(std::move(d));
      }
      done_ready_.notify_one();
    }
  }

  const int threads_;
  Work work_;
  const int rank_;
  int busy_ = 0;  // the dispatching thread's count
  std::mutex mutex_;
  std::condition_variable task_ready_, done_ready_;
  std::deque<std::pair<long, std::string>> tasks_;
  std::deque<Done> done_;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
};

// ---------------------------------------------------------------- messages between ranks

/// One message between rank 0 and another rank. Every message of a rank to rank 0 is a
/// request for a task for one of its free slots, carrying the result of the task that slot
/// ran last (if any); rank 0 answers a request with a task, or keeps it until it has one, or
/// stops the rank.
struct Message {
  enum Kind : std::int32_t { Request = 1, Task = 2, Stop = 3 };
  std::int32_t kind = Request;
  std::int32_t source = 0;
  std::int64_t index = -1;  // Task: the task; Request: the task whose result it carries (-1: none)
  std::int32_t flag = 0;    // Request: the result is ok; Stop: abort (end the running children)
  std::int32_t status = 0;  // Stop: the exit status
  std::string text;         // Task: payload; Request: result
};

#ifdef FLOWIRE_WITH_MPI

class Dispatcher::Link {
 public:
  static constexpr int kTag = 7301;

  Link() {
    int up = 0;
    MPI_Initialized(&up);
    if (!up) {
      int provided = 0;
      // Only the dispatching thread calls MPI; the task threads never do.
      if (MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS)
        throw_usage_error("MPI_Init_thread failed");
      started_ = true;
    }
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  ~Link() {
    // Sends still pending belong to an aborted job: let them go.
    for (auto& p : sends_) MPI_Request_free(&p.request);
    sends_.clear();
    int done = 0;
    MPI_Finalized(&done);
    if (started_ && !done) MPI_Finalize();
  }
  Link(const Link&) = delete;
  Link& operator=(const Link&) = delete;

  [[nodiscard]] int rank() const { return rank_; }
  [[nodiscard]] int size() const { return size_; }

  void send(int to, const Message& m) {
    std::string buf(sizeof(std::int32_t) * 4 + sizeof(std::int64_t), '\0');
    char* p = buf.data();
    auto put = [&p](const auto& v) {
      std::memcpy(p, &v, sizeof(v));
      p += sizeof(v);
    };
    put(m.kind), put(m.index), put(m.flag), put(m.status), put(std::int32_t{0});
    buf += m.text;
    sends_.push_back({MPI_REQUEST_NULL, std::move(buf)});
    auto& s = sends_.back();
    MPI_Isend(s.buffer.data(), static_cast<int>(s.buffer.size()), MPI_CHAR, to, kTag, MPI_COMM_WORLD, &s.request);
    progress();
  }

  /// The next message from @p from (MPI_ANY_SOURCE: any rank), if one has arrived.
  bool receive(int from, Message& m) {
    int arrived = 0;
    MPI_Status st;
    MPI_Iprobe(from, kTag, MPI_COMM_WORLD, &arrived, &st);
    if (!arrived) return false;
    int count = 0;
    MPI_Get_count(&st, MPI_CHAR, &count);
    std::string buf(static_cast<size_t>(count), '\0');
    MPI_Recv(buf.data(), count, MPI_CHAR, st.MPI_SOURCE, kTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    const char* p = buf.data();
    auto get = [&p](auto& v) {
      std::memcpy(&v, p, sizeof(v));
      p += sizeof(v);
    };
    std::int32_t reserved = 0;
    get(m.kind), get(m.index), get(m.flag), get(m.status), get(reserved);
    m.text.assign(p, static_cast<size_t>(buf.data() + buf.size() - p));
    m.source = st.MPI_SOURCE;
    return true;
  }

  /// Free the buffers of the sends that have completed.
  void progress() {
    for (auto it = sends_.begin(); it != sends_.end();) {
      int done = 0;
      MPI_Test(&it->request, &done, MPI_STATUS_IGNORE);
      it = done ? sends_.erase(it) : std::next(it);
    }
  }

  /// Wait (polling) until every send has completed, at most @p max_seconds.
  void flush(double max_seconds) {
    const auto t0 = Clock::now();
    while (!sends_.empty() && seconds_since(t0) < max_seconds) {
      progress();
      if (!sends_.empty()) std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  }

 private:
  struct Pending {
    MPI_Request request;
    std::string buffer;
  };
  bool started_ = false;
  int rank_ = 0, size_ = 1;
  std::list<Pending> sends_;  // a list: the buffers must not move while MPI holds them
};

#else

class Dispatcher::Link {
 public:
  Link() { throw_usage_error("this flowire was built without MPI: run it without mpirun, with --jobs"); }
  [[nodiscard]] int rank() const { return 0; }
  [[nodiscard]] int size() const { return 1; }
  void send(int, const Message&) {}
  bool receive(int, Message&) { return false; }
  void progress() {}
  void flush(double) {}
};

#endif

// ---------------------------------------------------------------- the dispatcher

namespace {
/// How long the dispatching loop sleeps when nothing happened. Under MPI it polls the other
/// ranks: 100 µs after a message, doubling while nothing comes, up to 2 ms (a probe costs some
/// 20 µs of CPU: about 1 % of a core when idle, and a request waits at most 2 ms, against runs
/// of 0.2 s and more). Alone, a finished task wakes it at once; it wakes only to see signals.
constexpr std::chrono::microseconds kPollMpiMin{100};
constexpr std::chrono::microseconds kPollMpi{2000};
constexpr std::chrono::microseconds kPollAlone{50000};

/// The next sleep of a polling loop: short after activity, doubling up to @p longest.
std::chrono::microseconds next_poll(std::chrono::microseconds last, bool active, std::chrono::microseconds longest) {
  if (active) return kPollMpiMin;
  return std::min(longest, last * 2);
}

int any_source() {
#ifdef FLOWIRE_WITH_MPI
  return MPI_ANY_SOURCE;
#else
  return -1;
#endif
}
}  // namespace

Dispatcher::Dispatcher(int jobs, Work work) {
  if (launched_by_mpi()) {
    link_ = std::make_unique<Link>();
    rank_ = link_->rank();
    ranks_ = link_->size();
  }
  jobs_ = jobs > 0 ? jobs : link_ ? 1 : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  pool_ = std::make_unique<Pool>(jobs_, std::move(work), rank_);
  // The children run on the cores this process may use: a launcher that binds each rank to
  // one core would put all of a rank's jobs on it.
  cpu_set_t cpus;
  CPU_ZERO(&cpus);
  if (link_ && root() && jobs_ > 1 && ::sched_getaffinity(0, sizeof cpus, &cpus) == 0 && CPU_COUNT(&cpus) < jobs_)
    std::fprintf(stderr,
                 "flowire: warning: rank 0 may use %d core(s) for --jobs %d: the launcher binds the ranks (Open "
                 "MPI: mpirun --bind-to none), or run one rank per core with --jobs 1\n",
                 CPU_COUNT(&cpus), jobs_);
}

Dispatcher::~Dispatcher() {
  if (root() && !stopped_) abort_all(3);
  pool_.reset();  // joins the threads (their children have ended)
  link_.reset();  // finalizes MPI if it was started here
}

void Dispatcher::abort_all(int status) {
  end_children(SIGTERM);
  if (root() && link_ && !stopped_) {
    Message m;
    m.kind = Message::Stop;
    m.flag = 1;
    m.status = status;
    for (int r = 1; r < ranks_; ++r) link_->send(r, m);
    link_->flush(5.0);
  }
  stopped_ = true;
}

void Dispatcher::stop(int status) {
  if (!root() || stopped_) return;
  stopped_ = true;
  if (!link_) return;
  // Every slot of the other ranks asks once more after its last task: receive those requests,
  // so that no message is left unreceived when MPI ends.
  const size_t slots_elsewhere = static_cast<size_t>(ranks_ - 1) * static_cast<size_t>(jobs_);
  const auto t0 = Clock::now();
  Message m;
  while (idle_.size() < slots_elsewhere && seconds_since(t0) < 30.0) {
    if (link_->receive(any_source(), m)) {
      idle_.push_back(m.source);
    } else {
      std::this_thread::sleep_for(kPollMpi);
    }
  }
  m = Message{};
  m.kind = Message::Stop;
  m.status = status;
  for (int r = 1; r < ranks_; ++r) link_->send(r, m);
  link_->flush(30.0);
}

std::vector<Dispatcher::Outcome> Dispatcher::run(const std::vector<std::string>& payloads, const OnDone& on_done) {
  if (!root()) throw_usage_error("Dispatcher::run is rank 0's; the other ranks serve()");
  const auto t_start = Clock::now();
  const double cpu_start = thread_cpu_seconds();
  const size_t n = payloads.size();
  std::vector<Outcome> outcomes(n);
  size_t next = 0, remaining = n;
  auto record = [&](size_t i, Outcome o) {
    outcomes[i] = std::move(o);
    --remaining;
    ++stats_.tasks;
    if (on_done) on_done(i, outcomes[i]);
  };
  auto hand_out = [&](int to) {
    Message m;
    m.kind = Message::Task;
    m.index = static_cast<std::int64_t>(next);
    m.text = payloads[next++];
    link_->send(to, m);
    ++stats_.handed_out;
  };
  std::chrono::microseconds poll = kPollMpiMin;
  try {
    while (remaining > 0) {
      const auto t0 = Clock::now();
      bool active = false;
      while (next < n && pool_->free_slot()) {
        pool_->submit(static_cast<long>(next), payloads[next]);
        ++next;
        active = true;
      }
      if (link_) {
        while (next < n && !idle_.empty()) {
          hand_out(idle_.back());
          idle_.pop_back();
          active = true;
        }
        Message m;
        while (link_->receive(any_source(), m)) {
          active = true;
          if (m.index >= 0) record(static_cast<size_t>(m.index), Outcome{m.flag != 0, std::move(m.text), m.source});
          if (next < n) {
            hand_out(m.source);
          } else {
            idle_.push_back(m.source);
          }
        }
        link_->progress();
      }
      if (active) stats_.handling_seconds += seconds_since(t0);
      poll = next_poll(poll, active, link_ ? kPollMpi : kPollAlone);
      for (auto& d : pool_->take(active ? std::chrono::microseconds(0) : poll))
        record(static_cast<size_t>(d.index), std::move(d.outcome));
      ++stats_.wakeups;
      if (const int sig = interrupt_signal(); sig != 0) {
        abort_all(128 + sig);
        throw_if_interrupted("a batch of runs");
      }
    }
  } catch (const Error& e) {
    abort_all(exit_status(e));
    throw;
  } catch (...) {
    abort_all(3);
    throw;
  }
  stats_.cpu_seconds += thread_cpu_seconds() - cpu_start;
  stats_.wall_seconds += seconds_since(t_start);
  return outcomes;
}

int Dispatcher::serve() {
  if (root()) throw_usage_error("Dispatcher::serve is for the ranks other than 0");
  if (!link_) return 0;
  Message m;
  for (int j = 0; j < jobs_; ++j) link_->send(0, m);  // a request per slot, with no result
  int status = 0;
  std::chrono::microseconds poll = kPollMpiMin;
  for (bool stop = false; !stop;) {
    bool active = false;
    while (!stop && link_->receive(0, m)) {
      active = true;
      if (m.kind == Message::Task) {
        pool_->submit(static_cast<long>(m.index), std::move(m.text));
      } else {
        status = m.status;
        if (m.flag) end_children(SIGTERM);
        stop = true;
      }
    }
    poll = next_poll(poll, active, kPollMpi);
    for (auto& d : pool_->take(active || stop ? std::chrono::microseconds(0) : poll)) {
      Message r;
      r.index = d.index;
      r.flag = d.outcome.ok ? 1 : 0;
      r.text = std::move(d.outcome.text);
      link_->send(0, r);
    }
    link_->progress();
    if (const int sig = interrupt_signal(); sig != 0) {
      end_children(SIGTERM);
      throw_if_interrupted("a rank's batch of runs");
    }
  }
  link_->flush(5.0);
  return status;
}

}  // namespace flowire::cli
