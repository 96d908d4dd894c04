#pragma once
// Independent tasks (runs of a study, evaluations of a fit's generation) shared out over the
// processes of a job, behind one interface for one machine and for MPI.
//
// Every rank runs up to `jobs` tasks at a time, each in a thread of its own that typically
// starts a `flowire run` child process (run_child) and waits for it. Without an MPI launcher
// there is one rank. Under `mpirun -n N` (or srun) rank 0 runs the caller's logic and hands the
// tasks out one at a time to whichever slot asks first (dynamic load balancing: runs that differ
// tenfold in length keep every slot busy), from its main thread, while its own `jobs` threads
// run tasks too; ranks 1..N-1 only serve. Tasks and results are text (JSON): a task's payload
// must say everything needed to run it, so that a result never depends on which rank ran it.
//
// MPI is only waited on by polling with short sleeps: a blocking receive would spin a core that
// the child processes need.
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace flowire::cli {

/// @brief The variable that tells a child which process started it (follow_parent, programs.hpp).
inline constexpr const char* kParentVariable = "FLOWIRE_PARENT_PID";

/// @brief Run this program with @p args (argv[0] first) as a child process, stdin from
/// /dev/null, stdout and stderr to @p log; wait for it and return its exit status (128 + the
/// signal if one ended it, -1 if it could not be started). The child gets this process's
/// environment without the MPI launcher's variables (OMPI_*, PMIX_*, PMI_*), so that a child
/// that uses MPI (PETSc) starts as a singleton of its own, and it ends (SIGTERM) when this
/// process ends (follow_parent, programs.hpp). No file descriptor other than 0, 1 and 2 is passed on.
int run_child(const std::vector<std::string>& args, const std::filesystem::path& log);

/// @brief Send @p signal to every child process that run_child is waiting for.
void signal_children(int signal);

/// @brief True if an MPI launcher (mpirun/mpiexec of Open MPI or MPICH, srun) started this
/// process: its environment carries the launcher's rank variables.
[[nodiscard]] bool launched_by_mpi();

/// @brief Shares tasks out over this process's threads and, under an MPI launcher, over the
/// job's ranks (see the file comment). One per process: it starts MPI when launched by an MPI
/// launcher and finalizes it when destroyed.
class Dispatcher {
 public:
  /// What every rank does with a task: its payload in, its result out. An exception is the
  /// task's failure (its message is the outcome's text).
  using Work = std::function<std::string(const std::string& payload)>;

  struct Outcome {
    bool ok = false;   ///< false: the work threw; `text` is its message
    std::string text;  ///< the work's result
    int rank = 0;      ///< the rank that ran it
  };

  /// Called on rank 0's main thread as each task finishes, with its index in the batch.
  using OnDone = std::function<void(size_t index, const Outcome& outcome)>;

  /// What rank 0's dispatching cost (measured over run()).
  struct Stats {
    long tasks = 0;                 ///< tasks finished
    long handed_out = 0;            ///< of which sent to another rank
    double cpu_seconds = 0.0;       ///< CPU time of rank 0's dispatching thread (polling included)
    double handling_seconds = 0.0;  ///< wall time it spent receiving, sending and handing out
    double wall_seconds = 0.0;      ///< wall time of run()
    long wakeups = 0;               ///< times the dispatching loop woke up
  };

  /// @param jobs tasks at a time on each rank; 0: the hardware threads without MPI, 1 per rank
  /// under MPI (one rank per core).
  /// @param work what a task is, on every rank.
  Dispatcher(int jobs, Work work);
  ~Dispatcher();
  Dispatcher(const Dispatcher&) = delete;
  Dispatcher& operator=(const Dispatcher&) = delete;

  [[nodiscard]] bool root() const { return rank_ == 0; }
  [[nodiscard]] int rank() const { return rank_; }
  [[nodiscard]] int ranks() const { return ranks_; }
  [[nodiscard]] int jobs() const { return jobs_; }
  /// Tasks that run at once over the whole job: ranks × jobs.
  [[nodiscard]] int slots() const { return ranks_ * jobs_; }

  /// @brief Rank 0: run every task (handed out in the order given) and return the outcomes in
  /// that order. SIGINT/SIGTERM (inside an InterruptibleSection) stop it: the running children
  /// are ended, the other ranks told to stop, and flowire::Error (interrupted) is thrown.
  std::vector<Outcome> run(const std::vector<std::string>& payloads, const OnDone& on_done = {});

  /// @brief Ranks 1..N-1: run the tasks rank 0 hands out until it calls stop(); returns the
  /// exit status rank 0 gave.
  int serve();

  /// @brief Rank 0: tell the other ranks to stop with exit status @p status (once; later
  /// calls do nothing). The destructor stops them with status 3 if nobody did.
  void stop(int status);

  [[nodiscard]] const Stats& stats() const { return stats_; }

 private:
  class Pool;
  class Link;
  void abort_all(int status);
  int rank_ = 0;
  int ranks_ = 1;
  int jobs_ = 1;
  bool stopped_ = false;        // rank 0 told the others to stop
  std::vector<int> idle_;       // rank 0: free slots of other ranks (their requests) given no task yet
  std::unique_ptr<Link> link_;  // the messages between ranks; null without an MPI launcher
  std::unique_ptr<Pool> pool_;
  Stats stats_;
};

}  // namespace flowire::cli
