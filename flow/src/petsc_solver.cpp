// The nodal conductance system distributed with PETSc: rows split over the MPI ranks,
// KSPCG preconditioned by GAMG (or hypre BoomerAMG), one solve per boundary source;
// the solutions are gathered on every rank so frames are evaluated locally.
#include <fmt/format.h>
#include <petscksp.h>

#include <cstdlib>

#include "flowire/common/error.hpp"
#include "flowire/flow/petsc_runtime.hpp"
#include "solvers.hpp"

namespace flowire::flow::detail {
namespace {

#define FLOWIRE_PETSC(call) ::flowire::flow::check_petsc((call), #call, "flow")

class PetscSolver final : public ResponseSolver {
 public:
  PetscSolver(const Network& net, FlowSpec spec) : ResponseSolver(net, std::move(spec)) {
    ensure_petsc("flow.solver");
    Stopwatch sw;
    const Eigen::SparseMatrix<double, Eigen::RowMajor> g = nodal_matrix(net_, a_);
    const Eigen::MatrixXd b = source_rhs();
    const auto n = static_cast<PetscInt>(g.rows());
    timings_.assemble += sw.seconds();
    Stopwatch sf;
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(b.rows(), b.cols());
    if (n > 0) solve(g, b, x);
    set_responses(x);
    timings_.factor = sf.seconds();
  }
  [[nodiscard]] std::string_view name() const override { return "petsc"; }
  [[nodiscard]] int iterations() const { return iterations_; }

 private:
  void solve(const Eigen::SparseMatrix<double, Eigen::RowMajor>& g, const Eigen::MatrixXd& b, Eigen::MatrixXd& x) {
    const auto n = static_cast<PetscInt>(g.rows());
    Mat a = nullptr;
    Vec rhs = nullptr, sol = nullptr, all = nullptr;
    KSP ksp = nullptr;
    VecScatter scatter = nullptr;
    auto cleanup = [&] {
      if (scatter) VecScatterDestroy(&scatter);
      if (all) VecDestroy(&all);
      if (ksp) KSPDestroy(&ksp);
      if (rhs) VecDestroy(&rhs);
      if (sol) VecDestroy(&sol);
      if (a) MatDestroy(&a);
    };
    try {
      FLOWIRE_PETSC(MatCreate(PETSC_COMM_WORLD, &a));
      FLOWIRE_PETSC(MatSetSizes(a, PETSC_DECIDE, PETSC_DECIDE, n, n));
      FLOWIRE_PETSC(MatSetType(a, MATAIJ));
      // Ownership of rows: PETSc's default split.
      PetscInt lo = 0, hi = 0;
      {
        PetscLayout layout = nullptr;
        FLOWIRE_PETSC(PetscLayoutCreate(PETSC_COMM_WORLD, &layout));
        FLOWIRE_PETSC(PetscLayoutSetSize(layout, n));
        FLOWIRE_PETSC(PetscLayoutSetUp(layout));
        FLOWIRE_PETSC(PetscLayoutGetRange(layout, &lo, &hi));
        FLOWIRE_PETSC(PetscLayoutDestroy(&layout));
      }
      std::vector<PetscInt> dnz(static_cast<size_t>(hi - lo), 0), onz(static_cast<size_t>(hi - lo), 0);
      for (PetscInt r = lo; r < hi; ++r)
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(g, r); it; ++it)
          ++((it.col() >= lo && it.col() < hi) ? dnz : onz)[static_cast<size_t>(r - lo)];
      FLOWIRE_PETSC(MatSeqAIJSetPreallocation(a, 0, dnz.data()));
      FLOWIRE_PETSC(MatMPIAIJSetPreallocation(a, 0, dnz.data(), 0, onz.data()));
      for (PetscInt r = lo; r < hi; ++r) {
        const auto start = g.outerIndexPtr()[r];
        const auto count = static_cast<PetscInt>(g.outerIndexPtr()[r + 1] - start);
        std::vector<PetscInt> cols(g.innerIndexPtr() + start, g.innerIndexPtr() + start + count);
        FLOWIRE_PETSC(MatSetValues(a, 1, &r, count, cols.data(), g.valuePtr() + start, INSERT_VALUES));
      }
      FLOWIRE_PETSC(MatAssemblyBegin(a, MAT_FINAL_ASSEMBLY));
      FLOWIRE_PETSC(MatAssemblyEnd(a, MAT_FINAL_ASSEMBLY));
      FLOWIRE_PETSC(MatSetOption(a, MAT_SPD, PETSC_TRUE));

      FLOWIRE_PETSC(MatCreateVecs(a, &sol, &rhs));
      FLOWIRE_PETSC(KSPCreate(PETSC_COMM_WORLD, &ksp));
      FLOWIRE_PETSC(KSPSetOperators(ksp, a, a));
      FLOWIRE_PETSC(KSPSetType(ksp, KSPCG));
      PC pc = nullptr;
      FLOWIRE_PETSC(KSPGetPC(ksp, &pc));
      if (spec_.petsc_pc == "hypre") {
        FLOWIRE_PETSC(PCSetType(pc, PCHYPRE));
      } else if (spec_.petsc_pc == "gamg") {
        FLOWIRE_PETSC(PCSetType(pc, PCGAMG));
      } else {
        throw_input_error("flow.petsc_pc", fmt::format("'{}' is not one of: gamg, hypre", spec_.petsc_pc));
      }
      FLOWIRE_PETSC(KSPSetTolerances(ksp, spec_.petsc_rtol, 1e-300, PETSC_DEFAULT, 20000));
      FLOWIRE_PETSC(KSPSetFromOptions(ksp));
      FLOWIRE_PETSC(VecScatterCreateToAll(sol, &scatter, &all));

      std::vector<PetscInt> idx(static_cast<size_t>(hi - lo));
      for (PetscInt r = lo; r < hi; ++r) idx[static_cast<size_t>(r - lo)] = r;
      for (Eigen::Index k = 0; k < b.cols(); ++k) {
        std::vector<double> vals(static_cast<size_t>(hi - lo));
        for (PetscInt r = lo; r < hi; ++r) vals[static_cast<size_t>(r - lo)] = b(r, k);
        FLOWIRE_PETSC(VecSetValues(rhs, hi - lo, idx.data(), vals.data(), INSERT_VALUES));
        FLOWIRE_PETSC(VecAssemblyBegin(rhs));
        FLOWIRE_PETSC(VecAssemblyEnd(rhs));
        if (b.col(k).lpNorm<Eigen::Infinity>() == 0.0) continue;
        FLOWIRE_PETSC(KSPSolve(ksp, rhs, sol));
        KSPConvergedReason reason;
        FLOWIRE_PETSC(KSPGetConvergedReason(ksp, &reason));
        PetscInt its = 0;
        FLOWIRE_PETSC(KSPGetIterationNumber(ksp, &its));
        iterations_ += static_cast<int>(its);
        if (reason < 0)
          throw_numerical_error(
              fmt::format("flow (petsc): CG did not converge (reason {}, {} iterations); "
                          "try petsc_pc hypre or the superposition solver",
                          static_cast<int>(reason), its));
        FLOWIRE_PETSC(VecScatterBegin(scatter, sol, all, INSERT_VALUES, SCATTER_FORWARD));
        FLOWIRE_PETSC(VecScatterEnd(scatter, sol, all, INSERT_VALUES, SCATTER_FORWARD));
        const PetscScalar* arr = nullptr;
        FLOWIRE_PETSC(VecGetArrayRead(all, &arr));
        for (PetscInt r = 0; r < n; ++r) x(r, k) = arr[r];
        FLOWIRE_PETSC(VecRestoreArrayRead(all, &arr));
      }
    } catch (...) {
      cleanup();
      throw;
    }
    cleanup();
  }

  int iterations_ = 0;
};

}  // namespace

std::unique_ptr<FlowSolver> make_petsc_solver(const Network& net, FlowSpec spec) {
  return std::make_unique<PetscSolver>(net, std::move(spec));
}

}  // namespace flowire::flow::detail
