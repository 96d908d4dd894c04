#pragma once
/// @file petsc_runtime.hpp
/// @brief The program's one owner of PETSc and MPI. Every PETSc user (the network's `petsc`
/// solver, the FEM) starts PETSc through ensure_petsc(), reports PETSc errors through
/// check_petsc() and asks for its rank here; finalize_petsc() (flow/solver.hpp) ends what
/// ensure_petsc() started, once, also at exit. Built only with PETSc (FLOWIRE_WITH_PETSC).
#include <petscsys.h>

#include <string_view>

namespace flowire::flow {

/// @brief Start PETSc (and MPI, unless the program did) if it is not running.
/// @param who the caller, for the message ("flow.solver", "fem").
/// @throws flowire::Error (usage) after MPI_Finalize.
void ensure_petsc(std::string_view who);

/// @brief A nonzero PETSc error code becomes flowire::Error (numerical):
/// "WHO (petsc): WHAT failed: PETSc's message".
void check_petsc(PetscErrorCode code, const char* what, std::string_view who);

/// @brief This process's rank in MPI_COMM_WORLD and the number of ranks: 0 and 1 when MPI is
/// not running (not started, or already finalized).
int mpi_rank();
int mpi_size();

}  // namespace flowire::flow
