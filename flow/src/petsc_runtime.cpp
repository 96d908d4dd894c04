#include "flowire/flow/petsc_runtime.hpp"

#include <fmt/format.h>
#include <mpi.h>

#include <cstdlib>

#include "flowire/common/error.hpp"
#include "flowire/common/output.hpp"
#include "flowire/flow/solver.hpp"

namespace flowire::flow {

namespace {
bool g_we_initialized = false;  // PETSc was started here (and is ours to finalize)

bool mpi_running() {
  int up = 0, done = 0;
  MPI_Initialized(&up);
  MPI_Finalized(&done);
  return up && !done;
}
}  // namespace

void check_petsc(PetscErrorCode code, const char* what, std::string_view who) {
  if (code != 0) {
    const char* text = nullptr;
    PetscErrorMessage(code, &text, nullptr);
    throw_numerical_error(fmt::format("{} (petsc): {} failed: {}", who, what, text ? text : "unknown error"));
  }
}

void ensure_petsc(std::string_view who) {
  PetscBool up = PETSC_FALSE;
  PetscInitialized(&up);
  if (up) return;
  int mpi_done = 0;
  MPI_Finalized(&mpi_done);
  if (mpi_done) throw_usage_error(fmt::format("{}: PETSc used after MPI_Finalize", who));
  check_petsc(PetscInitializeNoArguments(), "PetscInitializeNoArguments()", who);
  set_writes_outputs(mpi_rank() == 0);  // one rank writes a run's files
  if (!g_we_initialized) std::atexit([] { finalize_petsc(); });
  g_we_initialized = true;
}

void finalize_petsc() {
  if (!g_we_initialized) return;
  PetscBool up = PETSC_FALSE, done = PETSC_FALSE;
  PetscInitialized(&up);
  PetscFinalized(&done);
  int mpi_done = 0;
  MPI_Finalized(&mpi_done);
  if (up && !done && !mpi_done) PetscFinalize();
}

int mpi_rank() {
  int rank = 0;
  if (mpi_running()) MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank;
}

int mpi_size() {
  int size = 1;
  if (mpi_running()) MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}

}  // namespace flowire::flow
