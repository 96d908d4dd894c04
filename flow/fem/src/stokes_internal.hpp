#pragma once
// The Taylor–Hood P2/P1 Stokes / Navier–Stokes solver's parts shared by its source files
// (the public interface is flowire/flow/fem/stokes.hpp):
//   stokes_dofs.cpp      unknown numbering, sparsity pattern, linear-solver configuration
//   stokes_kernels.cpp   element matrices (Stokes) and residual/Jacobian (Navier–Stokes),
//                        their assembly into PETSc matrices and vectors
//   stokes.cpp           the linear system of a mesh; steady Stokes, boundary conditions by
//                        superposition of unit fields, boundary forces and fluxes
//   navier_stokes.cpp    Newton with density continuation for Navier–Stokes
//   unsteady_stokes.cpp  time-dependent Stokes (BDF2)
#include <fmt/format.h>
#include <petscksp.h>

#include <chrono>
#include <functional>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "flowire/common/error.hpp"
#include "flowire/flow/fem/element.hpp"
#include "flowire/flow/fem/stokes.hpp"
#include "flowire/flow/petsc_runtime.hpp"

#define FLOWIRE_PETSC(call) ::flowire::flow::check_petsc((call), #call, "fem")

namespace flowire::flow::fem::internal {

inline void ensure_petsc() { flow::ensure_petsc("fem"); }

/// Owns one PETSc object and destroys it at scope exit.
template <class T, PetscErrorCode (*Destroy)(T*)>
class Handle {
 public:
  Handle() = default;
  ~Handle() {
    if (h_) Destroy(&h_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  T* out() { return &h_; }
  void reset() {
    if (h_) Destroy(&h_);
    h_ = nullptr;
  }
  operator T() const { return h_; }  // NOLINT(google-explicit-constructor)

 private:
  T h_ = nullptr;
};
using MatH = Handle<Mat, MatDestroy>;
using VecH = Handle<Vec, VecDestroy>;
using KspH = Handle<KSP, KSPDestroy>;
using IsH = Handle<IS, ISDestroy>;
using ScatterH = Handle<VecScatter, VecScatterDestroy>;

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// ---- Unknowns and pattern (stokes_dofs.cpp) ----

/// Rank r's share [lo, hi) of n items split in `parts` contiguous blocks.
inline std::pair<long, long> split(long n, int parts, int r) {
  const long b = n / parts, extra = n % parts;
  const long lo = r * b + std::min<long>(r, extra);
  return {lo, lo + b + (r < extra ? 1 : 0)};
}

/// Set an option in PETSc's database unless the user already set it.
void default_option(const char* name, const char* value);

/// Unknown numbering: wall nodes carry no velocity unknowns; rank r owns a contiguous
/// block [velocities of its free nodes (x,y,z interleaved), its pressures].
struct Numbering {
  std::vector<PetscInt> vdof;                // (num_nodes) global dof of the x velocity, -1 on the wall
  std::vector<PetscInt> pdof;                // (num_vertices) global dof of the pressure
  std::vector<PetscInt> pindex;              // (num_vertices) index in the pressure-only layout
  std::vector<int> vertex_node;              // (num_vertices) node of each vertex
  PetscInt total = 0, local = 0, begin = 0;  // all unknowns / mine / my first
  PetscInt p_local = 0, p_begin = 0;         // pressure-only layout
  PetscInt v_local = 0;                      // my velocity unknowns
  std::vector<int> my_nodes;                 // free nodes whose velocity rows I own
  std::vector<int> my_vertices;              // vertices whose pressure rows I own
};

/// `fixed_group` >= 0: the nodes of that group carry a prescribed velocity too.
Numbering number(const TetMesh& mesh, int rank, int size, int fixed_group = -1);

/// Tetrahedra around each node (CSR).
struct NodeTets {
  std::vector<int> offset, tets;
};
NodeTets node_tets(const TetMesh& mesh);

/// Local rows of the system in CSR form (global column indices) for exact preallocation,
/// and the same for the pressure mass matrix in the pressure-only layout.
/// `coupled`: every velocity component couples to every other (the Navier–Stokes Jacobian).
void sparsity(const TetMesh& mesh, const Numbering& num, const NodeTets& nt, bool coupled, std::vector<PetscInt>& ia,
              std::vector<PetscInt>& ja, std::vector<PetscInt>& pia, std::vector<PetscInt>& pja);

// ---- Elements and assembly (stokes_kernels.cpp) ----

/// Reference basis at the quadrature points, computed once.
struct Reference {
  static constexpr int kMaxQ = 14;
  int nq = 0;
  double w[kMaxQ];
  double phi[kMaxQ][10];
  double dphi[kMaxQ][10][3];
  double psi[kMaxQ][4];
  Reference() {
    const auto rule = tet_quadrature();
    nq = static_cast<int>(rule.size());
    for (int q = 0; q < nq; ++q) {
      w[q] = rule[static_cast<size_t>(q)].weight;
      tet_p2(rule[static_cast<size_t>(q)].xi, phi[q]);
      tet_p2_grad(rule[static_cast<size_t>(q)].xi, dphi[q]);
      tet_p1(rule[static_cast<size_t>(q)].xi, psi[q]);
    }
  }
};

/// Element matrices of one tetrahedron.
struct ElementMatrices {
  double k[10][10];  // viscous block, the same for every component
  double m[10][10];  // velocity mass block (per component)
  double bt[30][4];  // velocity (node i, component c -> row 3i+c) x pressure: -(q, div v)
  double mp[4][4];   // pressure mass / viscosity
};

bool element(const TetMesh& mesh, const Reference& ref, int e, double eta, ElementMatrices& em);

struct Mpi {
  int rank = 0, size = 1;
  Mpi() {
    MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
    MPI_Comm_size(PETSC_COMM_WORLD, &size);
  }
};

/// Assemble the system matrix (and the pressure mass matrix when `mp` is given).
/// With `mass_coef` c > 0 the velocity block is K + c·M (time-dependent Stokes), and with
/// `mass` the velocity mass matrix M is assembled there too.
void assemble(const TetMesh& mesh, const Numbering& num, const Mpi& mpi, const StokesOptions& opt, Mat a, Mat mp,
              double mass_coef = 0.0, Mat mass = nullptr);

/// Add `vals` (count entries) at `rows` of a vector, skipping wall (negative) rows: PETSc
/// vectors do not skip negative indices.
void add_to_vector(Vec b, int count, const PetscInt* rows, const double* vals);

/// Reference data of the Navier–Stokes element: the P2 second derivatives and the P1
/// gradients (both constant on the reference tetrahedron).
struct ReferenceNs : Reference {
  double hess[10][3][3];
  static constexpr double dpsi[4][3] = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  ReferenceNs() { tet_p2_hessian(hess); }
};

/// The current iterate seen by the element loops: velocity per node, pressure per
/// vertex, pressure per group.
struct State {
  const std::vector<Vec3>* velocity = nullptr;
  const std::vector<double>* pressure = nullptr;  // by vertex index
  const std::vector<double>* group_pressure = nullptr;
};

/// Parameters of the Navier–Stokes residual.
struct NsParams {
  double eta = 0.0, rho = 0.0, backflow = 0.0;
  bool stabilize = false;
  const std::function<Vec3(const Vec3&)>* body_force = nullptr;
  const std::function<Vec3(const Vec3&, const Vec3&, int)>* traction = nullptr;
};

NsParams ns_params(const StokesOptions& opt);

/// Residual (34: velocity rows 3i+c, then 4 pressure rows) and Jacobian (34 × 34, row
/// major) of one tetrahedron for the Navier–Stokes weak form with SUPG + LSIC (see
/// stokes.hpp). Returns false for a non-positive Jacobian determinant.
bool ns_element(const TetMesh& mesh, const ReferenceNs& ref, int e, const NsParams& prm, const State& st, double* res,
                double* jac);

/// Residual and Jacobian of one open-boundary triangle: the pressure and traction
/// terms, and the backflow term on outlets (18 velocity rows 3k+c).
void ns_face(const TetMesh& mesh, size_t f, const NsParams& prm, const State& st, double* res, double* jac,
             bool& any_jac);

/// Assemble the Navier–Stokes Jacobian into `a` and the residual into `r` at the state.
/// With `shape` (a velocity per node, nonzero only on prescribed-velocity nodes), also
/// the lifting −J_{free,fixed}·shape into `lift`: the right-hand side of the field that
/// a unit amplitude of the prescribed velocity adds.
void assemble_ns(const TetMesh& mesh, const Numbering& num, const Mpi& mpi, const NsParams& prm, const State& st,
                 const std::vector<Vec3>* shape, Mat a, Vec r, Vec lift);

/// Right-hand side: -p_k ∫ n·v over each inlet/outlet face; with `data`, also its body
/// force ∫ f·v and its traction ∫ g·v.
void assemble_rhs(const TetMesh& mesh, const Numbering& num, const Mpi& mpi, std::span<const double> group_pressure,
                  const StokesOptions* data, Vec b);

void configure_solver(KSP ksp, Mat a, Mat mp, const Numbering& num, const StokesOptions& opt, bool symmetric, IsH& isu,
                      IsH& isp);

// ---- The linear system of one mesh and boundary conditions (stokes.cpp) ----

/// The linear system of one mesh: numbering, matrices, solver. Stokes: assembled and
/// factorized once, then solved for any group pressures. Navier–Stokes: the Jacobian and
/// residual at a state, factorized per Newton step (the symbolic factorization is kept).
class System {
 public:
  /// `fixed_group` >= 0: that group's velocity is prescribed (Navier–Stokes inlet profile).
  System(const TetMesh& mesh, const StokesOptions& opt, bool navier_stokes, int fixed_group = -1)
      : mesh_(mesh), opt_(opt), ns_(navier_stokes), num_(number(mesh, mpi_.rank, mpi_.size, fixed_group)) {
    std::vector<PetscInt> ia, ja, pia, pja;
    {
      const NodeTets nt = node_tets(mesh);
      sparsity(mesh, num_, nt, ns_, ia, ja, pia, pja);
    }
    FLOWIRE_PETSC(MatCreate(PETSC_COMM_WORLD, a_.out()));
    FLOWIRE_PETSC(MatSetSizes(a_, num_.local, num_.local, num_.total, num_.total));
    FLOWIRE_PETSC(MatSetType(a_, MATAIJ));
    FLOWIRE_PETSC(MatSeqAIJSetPreallocationCSR(a_, ia.data(), ja.data(), nullptr));
    FLOWIRE_PETSC(MatMPIAIJSetPreallocationCSR(a_, ia.data(), ja.data(), nullptr));
    FLOWIRE_PETSC(MatSetOption(a_, MAT_NEW_NONZERO_LOCATION_ERR, PETSC_TRUE));
    if (opt.solver == LinearSolver::Fieldsplit) {
      FLOWIRE_PETSC(MatCreate(PETSC_COMM_WORLD, mp_.out()));
      FLOWIRE_PETSC(MatSetSizes(mp_, num_.p_local, num_.p_local, mesh.num_vertices, mesh.num_vertices));
      FLOWIRE_PETSC(MatSetType(mp_, MATAIJ));
      FLOWIRE_PETSC(MatSeqAIJSetPreallocationCSR(mp_, pia.data(), pja.data(), nullptr));
      FLOWIRE_PETSC(MatMPIAIJSetPreallocationCSR(mp_, pia.data(), pja.data(), nullptr));
    }
    FLOWIRE_PETSC(MatCreateVecs(a_, x_.out(), b_.out()));
    FLOWIRE_PETSC(VecDuplicate(b_, lift_.out()));
    // Every rank gets the whole solution.
    FLOWIRE_PETSC(VecScatterCreateToAll(x_, scatter_.out(), all_.out()));
  }

  [[nodiscard]] int unknowns() const { return static_cast<int>(num_.total); }

  /// Stokes: assemble and factorize.
  void prepare_stokes() {
    auto t0 = std::chrono::steady_clock::now();
    assemble(mesh_, num_, mpi_, opt_, a_, Mat(mp_));
    assemble_seconds += seconds_since(t0);
    FLOWIRE_PETSC(MatSetOption(a_, MAT_SYMMETRIC, PETSC_TRUE));
    factorize(true);
  }

  /// Navier–Stokes: assemble the Jacobian and the residual (into the right-hand side, with
  /// its sign flipped: the Newton update solves J δx = −r) at the state, and factorize.
  void prepare_newton(const NsParams& prm, const State& st, const std::vector<Vec3>* shape) {
    auto t0 = std::chrono::steady_clock::now();
    assemble_ns(mesh_, num_, mpi_, prm, st, shape, a_, b_, lift_);
    FLOWIRE_PETSC(VecScale(b_, -1.0));
    FLOWIRE_PETSC(MatSetOption(a_, MAT_SYMMETRIC, PETSC_FALSE));
    if (mp_ && !mass_done_) {
      // The Schur preconditioner's pressure mass matrix: assembled once, with a Stokes
      // matrix that is then overwritten.
      assemble(mesh_, num_, mpi_, opt_, scratch(), Mat(mp_));
      mass_done_ = true;
    }
    assemble_seconds += seconds_since(t0);
    factorize(false);
  }

  /// Solve for the given group pressures (and, with `with_data`, the body force and the
  /// traction of the options): velocity, pressure and group fluxes.
  StokesSolution solve(std::span<const double> group_pressure, bool with_data) {
    assemble_rhs(mesh_, num_, mpi_, group_pressure, with_data ? &opt_ : nullptr, b_);
    StokesSolution sol = solve_rhs();
    sol.group_pressure.assign(group_pressure.begin(), group_pressure.end());
    return sol;
  }

  /// Solve with prepare_newton's lifting as the right-hand side: the free part of the
  /// field of a unit prescribed-velocity amplitude.
  StokesSolution solve_lift() {
    FLOWIRE_PETSC(VecCopy(lift_, b_));
    return solve_rhs();
  }

  /// Solve with the right-hand side already in place (prepare_newton's −r). Group
  /// pressures of the result are 0.
  StokesSolution solve_rhs() {
    auto t0 = std::chrono::steady_clock::now();
    FLOWIRE_PETSC(KSPSolve(ksp_, b_, x_));
    KSPConvergedReason reason;
    FLOWIRE_PETSC(KSPGetConvergedReason(ksp_, &reason));
    PetscInt its = 0;
    FLOWIRE_PETSC(KSPGetIterationNumber(ksp_, &its));
    solve_seconds += seconds_since(t0);
    if (reason < 0)
      throw_numerical_error(fmt::format("fem: the linear solve failed ({}) after {} iterations",
                                        KSPConvergedReasons[reason], static_cast<long>(its)));
    if (opt_.solver == LinearSolver::Fieldsplit) krylov_iterations += static_cast<int>(its);
    return gather(x_);
  }

  /// A distributed solution vector as a field on every rank, with its group fluxes.
  StokesSolution gather(Vec x) {
    StokesSolution sol;
    sol.velocity.assign(mesh_.nodes.size(), Vec3::Zero());
    sol.pressure.assign(static_cast<size_t>(mesh_.num_vertices), 0.0);
    FLOWIRE_PETSC(VecScatterBegin(scatter_, x, all_, INSERT_VALUES, SCATTER_FORWARD));
    FLOWIRE_PETSC(VecScatterEnd(scatter_, x, all_, INSERT_VALUES, SCATTER_FORWARD));
    const PetscScalar* v = nullptr;
    FLOWIRE_PETSC(VecGetArrayRead(all_, &v));
    for (size_t n = 0; n < mesh_.nodes.size(); ++n) {
      const PetscInt d = num_.vdof[n];
      if (d >= 0) sol.velocity[n] = Vec3(v[d], v[d + 1], v[d + 2]);
    }
    for (size_t k = 0; k < sol.pressure.size(); ++k) sol.pressure[k] = v[num_.pdof[k]];
    FLOWIRE_PETSC(VecRestoreArrayRead(all_, &v));
    sol.group_flow = group_fluxes(mesh_, sol.velocity);
    sol.group_pressure.assign(mesh_.groups.size(), 0.0);
    return sol;
  }

  /// Time-dependent Stokes: assemble K + c·M (and M), factorize.
  void prepare_unsteady(double c) {
    auto t0 = std::chrono::steady_clock::now();
    if (!mass_) FLOWIRE_PETSC(MatDuplicate(a_, MAT_DO_NOT_COPY_VALUES, mass_.out()));
    assemble(mesh_, num_, mpi_, opt_, a_, Mat(mp_), c, mass_);
    assemble_seconds += seconds_since(t0);
    FLOWIRE_PETSC(MatSetOption(a_, MAT_SYMMETRIC, PETSC_TRUE));
    factorize(true);
  }

  /// Solve with the group pressures' right-hand side plus M·h (h: a solution-layout
  /// vector); the solution stays in x().
  StokesSolution solve_with_history(std::span<const double> group_pressure, Vec h) {
    assemble_rhs(mesh_, num_, mpi_, group_pressure, nullptr, b_);
    FLOWIRE_PETSC(MatMultAdd(mass_, h, b_, b_));
    return solve_rhs();
  }

  [[nodiscard]] Vec x() const { return x_; }
  [[nodiscard]] Vec new_vector() const {
    Vec v = nullptr;
    FLOWIRE_PETSC(VecDuplicate(x_, &v));
    FLOWIRE_PETSC(VecSet(v, 0.0));
    return v;
  }

  double assemble_seconds = 0.0, solve_seconds = 0.0;
  int krylov_iterations = 0, factorizations = 0;

 private:
  void factorize(bool symmetric) {
    const auto t0 = std::chrono::steady_clock::now();
    if (!ksp_) {
      FLOWIRE_PETSC(KSPCreate(PETSC_COMM_WORLD, ksp_.out()));
      configure_solver(ksp_, a_, mp_, num_, opt_, symmetric, isu_, isp_);
    } else {
      // Same nonzero pattern: PETSc keeps the symbolic factorization.
      FLOWIRE_PETSC(KSPSetOperators(ksp_, a_, a_));
    }
    FLOWIRE_PETSC(KSPSetUp(ksp_));
    solve_seconds += seconds_since(t0);
    ++factorizations;
  }

  Mat scratch() {
    if (!scratch_) {
      FLOWIRE_PETSC(MatDuplicate(a_, MAT_DO_NOT_COPY_VALUES, scratch_.out()));
    }
    return scratch_;
  }

  const TetMesh& mesh_;
  StokesOptions opt_;
  bool ns_ = false;
  Mpi mpi_;
  Numbering num_;
  MatH a_, mp_, scratch_, mass_;
  VecH b_, x_, all_, lift_;
  ScatterH scatter_;
  KspH ksp_;
  IsH isu_, isp_;
  bool mass_done_ = false;
};

/// sol += c · other (fields, fluxes and group pressures).
void add_scaled(StokesSolution& sol, double c, const StokesSolution& other);

void check_conditions(const TetMesh& mesh, std::span<const GroupCondition> cond);

/// Groups whose pressure follows from a flow or resistance condition, and the known
/// pressures (0 on those groups).
void split_conditions(const TetMesh& mesh, std::span<const GroupCondition> cond, std::vector<int>& unknown,
                      std::vector<double>& known);

/// The unit fields of the factorized matrix (pressure 1 on one unknown group, 0
/// elsewhere; no body force or traction) and their fluxes.
void unit_fields(System& sys, const TetMesh& mesh, const std::vector<int>& unknown, std::vector<StokesSolution>& units,
                 std::vector<std::vector<double>>& flux);

double max_abs(const std::vector<Vec3>& v);

StokesSolution solve_linear_stokes(const TetMesh& mesh, std::span<const GroupCondition> cond, const StokesOptions& opt);

/// Mean of the (P1) pressure over boundary group g.
double mean_pressure(const TetMesh& mesh, const std::vector<double>& pressure, int g);

// ---- Navier–Stokes (navier_stokes.cpp) ----

/// Steady Navier–Stokes by Newton with density continuation (see stokes.hpp).
StokesSolution solve_navier_stokes(const TetMesh& mesh, std::span<const GroupCondition> cond, const StokesOptions& opt);

}  // namespace flowire::flow::fem::internal
