// Taylor–Hood P2/P1 Stokes / Navier–Stokes: element matrices computed here, a PETSc AIJ
// matrix with exact (CSR) preallocation, MUMPS or a fieldsplit Schur preconditioner.
#include "flowire/fem/stokes.hpp"

#include <fmt/format.h>
#include <mpi.h>
#include <petscksp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>

#include <Eigen/Dense>

#include "flowire/common/error.hpp"
#include "flowire/fem/element.hpp"

namespace flowire::fem {
namespace {

void check(PetscErrorCode code, const char* what) {
  if (code != 0) {
    const char* text = nullptr;
    PetscErrorMessage(code, &text, nullptr);
    throw_numerical_error(fmt::format("fem (petsc): {} failed: {}", what, text ? text : "unknown error"));
  }
}
#define FLOWIRE_PETSC(call) check((call), #call)

bool g_we_initialized = false;

void ensure_petsc() {
  PetscBool up = PETSC_FALSE;
  PetscInitialized(&up);
  if (up) return;
  int mpi_done = 0;
  MPI_Finalized(&mpi_done);
  if (mpi_done) throw_usage_error("fem: PETSc used after MPI_Finalize");
  FLOWIRE_PETSC(PetscInitializeNoArguments());
  if (!g_we_initialized) std::atexit([] { finalize_petsc(); });
  g_we_initialized = true;
}

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

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// Set an option in PETSc's database unless the user already set it.
void default_option(const char* name, const char* value) {
  PetscBool set = PETSC_FALSE;
  FLOWIRE_PETSC(PetscOptionsHasName(nullptr, nullptr, name, &set));
  if (!set) FLOWIRE_PETSC(PetscOptionsSetValue(nullptr, name, value));
}

/// Unknown numbering: wall nodes carry no velocity unknowns; rank r owns a contiguous
/// block [velocities of its free nodes (x,y,z interleaved), its pressures].
struct Numbering {
  std::vector<PetscInt> vdof;           // (num_nodes) global dof of the x velocity, -1 on the wall
  std::vector<PetscInt> pdof;           // (num_vertices) global dof of the pressure
  std::vector<PetscInt> pindex;         // (num_vertices) index in the pressure-only layout
  std::vector<int> vertex_node;         // (num_vertices) node of each vertex
  PetscInt total = 0, local = 0, begin = 0;    // all unknowns / mine / my first
  PetscInt p_local = 0, p_begin = 0;           // pressure-only layout
  PetscInt v_local = 0;                        // my velocity unknowns
  std::vector<int> my_nodes;            // free nodes whose velocity rows I own
  std::vector<int> my_vertices;         // vertices whose pressure rows I own
};

std::pair<long, long> split(long n, int parts, int r) {
  const long b = n / parts, extra = n % parts;
  const long lo = r * b + std::min<long>(r, extra);
  return {lo, lo + b + (r < extra ? 1 : 0)};
}

Numbering number(const TetMesh& mesh, int rank, int size) {
  Numbering num;
  const size_t nn = mesh.nodes.size();
  std::vector<char> wall(nn, 0);
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    if (mesh.groups[static_cast<size_t>(mesh.face_group[f])].kind == BoundaryGroup::Kind::Wall)
      for (int n : mesh.faces[f]) wall[static_cast<size_t>(n)] = 1;
  std::vector<int> free_nodes;
  for (size_t n = 0; n < nn; ++n)
    if (!wall[n]) free_nodes.push_back(static_cast<int>(n));
  const long nf = static_cast<long>(free_nodes.size()), nv = mesh.num_vertices;
  num.vertex_node.assign(static_cast<size_t>(nv), -1);
  for (size_t n = 0; n < nn; ++n)
    if (mesh.vertex_index[n] >= 0) num.vertex_node[static_cast<size_t>(mesh.vertex_index[n])] = static_cast<int>(n);
  num.vdof.assign(nn, -1);
  num.pdof.assign(static_cast<size_t>(nv), -1);
  num.pindex.assign(static_cast<size_t>(nv), -1);
  PetscInt offset = 0, poffset = 0;
  for (int r = 0; r < size; ++r) {
    const auto [fa, fb] = split(nf, size, r);
    const auto [va, vb] = split(nv, size, r);
    if (r == rank) {
      num.begin = offset;
      num.local = static_cast<PetscInt>(3 * (fb - fa) + (vb - va));
      num.v_local = static_cast<PetscInt>(3 * (fb - fa));
      num.p_begin = poffset;
      num.p_local = static_cast<PetscInt>(vb - va);
    }
    for (long f = fa; f < fb; ++f) {
      num.vdof[static_cast<size_t>(free_nodes[static_cast<size_t>(f)])] = offset + static_cast<PetscInt>(3 * (f - fa));
      if (r == rank) num.my_nodes.push_back(free_nodes[static_cast<size_t>(f)]);
    }
    for (long v = va; v < vb; ++v) {
      num.pdof[static_cast<size_t>(v)] = offset + static_cast<PetscInt>(3 * (fb - fa) + (v - va));
      num.pindex[static_cast<size_t>(v)] = poffset + static_cast<PetscInt>(v - va);
      if (r == rank) num.my_vertices.push_back(static_cast<int>(v));
    }
    offset += static_cast<PetscInt>(3 * (fb - fa) + (vb - va));
    poffset += static_cast<PetscInt>(vb - va);
  }
  num.total = offset;
  return num;
}

/// Tetrahedra around each node (CSR).
struct NodeTets {
  std::vector<int> offset, tets;
};
NodeTets node_tets(const TetMesh& mesh) {
  NodeTets nt;
  nt.offset.assign(mesh.nodes.size() + 1, 0);
  for (const auto& t : mesh.tets)
    for (int n : t) ++nt.offset[static_cast<size_t>(n) + 1];
  for (size_t i = 0; i < mesh.nodes.size(); ++i) nt.offset[i + 1] += nt.offset[i];
  nt.tets.resize(static_cast<size_t>(nt.offset.back()));
  std::vector<int> fill(nt.offset.begin(), nt.offset.end() - 1);
  for (size_t e = 0; e < mesh.tets.size(); ++e)
    for (int n : mesh.tets[e]) nt.tets[static_cast<size_t>(fill[static_cast<size_t>(n)]++)] = static_cast<int>(e);
  return nt;
}

/// Local rows of the system in CSR form (global column indices) for exact preallocation,
/// and the same for the pressure mass matrix in the pressure-only layout.
void sparsity(const TetMesh& mesh, const Numbering& num, const NodeTets& nt, std::vector<PetscInt>& ia,
              std::vector<PetscInt>& ja, std::vector<PetscInt>& pia, std::vector<PetscInt>& pja) {
  ia.assign(1, 0);
  ja.clear();
  std::vector<PetscInt> vel, pre;
  std::vector<int> mark(mesh.nodes.size(), -1);
  int stamp = 0;
  auto gather = [&](int node) {
    vel.clear();
    pre.clear();
    ++stamp;
    for (int k = nt.offset[static_cast<size_t>(node)]; k < nt.offset[static_cast<size_t>(node) + 1]; ++k)
      for (int m : mesh.tets[static_cast<size_t>(nt.tets[static_cast<size_t>(k)])]) {
        if (mark[static_cast<size_t>(m)] == stamp) continue;
        mark[static_cast<size_t>(m)] = stamp;
        if (num.vdof[static_cast<size_t>(m)] >= 0) vel.push_back(num.vdof[static_cast<size_t>(m)]);
        const int v = mesh.vertex_index[static_cast<size_t>(m)];
        if (v >= 0) pre.push_back(v);
      }
  };
  std::vector<PetscInt> row;
  for (int node : num.my_nodes) {
    gather(node);
    for (int c = 0; c < 3; ++c) {
      row.clear();
      for (PetscInt d : vel) row.push_back(d + c);
      for (int v : pre) row.push_back(num.pdof[static_cast<size_t>(v)]);
      std::sort(row.begin(), row.end());
      ja.insert(ja.end(), row.begin(), row.end());
      ia.push_back(static_cast<PetscInt>(ja.size()));
    }
  }
  pia.assign(1, 0);
  pja.clear();
  for (int v : num.my_vertices) {
    gather(num.vertex_node[static_cast<size_t>(v)]);
    row.clear();
    for (PetscInt d : vel)
      for (int c = 0; c < 3; ++c) row.push_back(d + c);
    row.push_back(num.pdof[static_cast<size_t>(v)]);
    std::sort(row.begin(), row.end());
    ja.insert(ja.end(), row.begin(), row.end());
    ia.push_back(static_cast<PetscInt>(ja.size()));
    row.clear();
    for (int w : pre) row.push_back(num.pindex[static_cast<size_t>(w)]);
    std::sort(row.begin(), row.end());
    pja.insert(pja.end(), row.begin(), row.end());
    pia.push_back(static_cast<PetscInt>(pja.size()));
  }
}

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
  double k[10][10];   // viscous (+ convection) block, the same for every component
  double bt[30][4];   // velocity (node i, component c -> row 3i+c) x pressure: -(q, div v)
  double mp[4][4];    // pressure mass / viscosity
};

bool element(const TetMesh& mesh, const Reference& ref, int e, double eta, double rho,
             const std::vector<Vec3>* wind, ElementMatrices& em) {
  const auto& t = mesh.tets[static_cast<size_t>(e)];
  Vec3 x[10], wn[10];
  for (int i = 0; i < 10; ++i) x[i] = mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(i)])];
  if (wind)
    for (int i = 0; i < 10; ++i) wn[i] = (*wind)[static_cast<size_t>(t[static_cast<size_t>(i)])];
  std::fill(&em.k[0][0], &em.k[0][0] + 100, 0.0);
  std::fill(&em.bt[0][0], &em.bt[0][0] + 120, 0.0);
  std::fill(&em.mp[0][0], &em.mp[0][0] + 16, 0.0);
  for (int q = 0; q < ref.nq; ++q) {
    Eigen::Matrix3d j = Eigen::Matrix3d::Zero();  // dx/dxi
    for (int i = 0; i < 10; ++i) j += x[i] * Eigen::RowVector3d(ref.dphi[q][i][0], ref.dphi[q][i][1], ref.dphi[q][i][2]);
    const double det = j.determinant();
    if (!(det > 0.0)) return false;
    const Eigen::Matrix3d jinv_t = j.inverse().transpose();
    double g[10][3];
    for (int i = 0; i < 10; ++i) {
      const Eigen::Vector3d gi = jinv_t * Eigen::Vector3d(ref.dphi[q][i][0], ref.dphi[q][i][1], ref.dphi[q][i][2]);
      g[i][0] = gi[0];
      g[i][1] = gi[1];
      g[i][2] = gi[2];
    }
    const double wd = ref.w[q] * det;
    for (int i = 0; i < 10; ++i)
      for (int jj = i; jj < 10; ++jj) {
        const double v = eta * wd * (g[i][0] * g[jj][0] + g[i][1] * g[jj][1] + g[i][2] * g[jj][2]);
        em.k[i][jj] += v;
        if (jj != i) em.k[jj][i] += v;
      }
    if (wind) {
      Vec3 b = Vec3::Zero();
      for (int i = 0; i < 10; ++i) b += ref.phi[q][i] * wn[i];
      for (int jj = 0; jj < 10; ++jj) {
        const double adv = rho * wd * (b[0] * g[jj][0] + b[1] * g[jj][1] + b[2] * g[jj][2]);
        for (int i = 0; i < 10; ++i) em.k[i][jj] += ref.phi[q][i] * adv;
      }
    }
    for (int i = 0; i < 10; ++i)
      for (int c = 0; c < 3; ++c)
        for (int l = 0; l < 4; ++l) em.bt[3 * i + c][l] -= wd * ref.psi[q][l] * g[i][c];
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) em.mp[a][b] += wd * ref.psi[q][a] * ref.psi[q][b] / eta;
  }
  return true;
}

struct Mpi {
  int rank = 0, size = 1;
  Mpi() {
    MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
    MPI_Comm_size(PETSC_COMM_WORLD, &size);
  }
};

/// Assemble the system matrix (and the pressure mass matrix when `mp` is given).
void assemble(const TetMesh& mesh, const Numbering& num, const Mpi& mpi, const StokesOptions& opt,
              const std::vector<Vec3>* wind, Mat a, Mat mp) {
  static const Reference ref;
  FLOWIRE_PETSC(MatZeroEntries(a));
  if (mp) FLOWIRE_PETSC(MatZeroEntries(mp));
  const auto [e0, e1] = split(mesh.num_tets(), mpi.size, mpi.rank);
  ElementMatrices em{};
  PetscInt rows_c[10], vrows[30], prows[4], pidx[4];
  double kbuf[100], btbuf[120], bbuf[120];
  int bad = -1;
  for (long e = e0; e < e1; ++e) {
    if (!element(mesh, ref, static_cast<int>(e), opt.viscosity, opt.density, wind, em)) {
      bad = static_cast<int>(e);
      break;
    }
    const auto& t = mesh.tets[static_cast<size_t>(e)];
    for (int i = 0; i < 10; ++i)
      for (int jj = 0; jj < 10; ++jj) kbuf[i * 10 + jj] = em.k[i][jj];
    for (int c = 0; c < 3; ++c) {
      for (int i = 0; i < 10; ++i) {
        const PetscInt d = num.vdof[static_cast<size_t>(t[static_cast<size_t>(i)])];
        rows_c[i] = d >= 0 ? d + c : -1;
      }
      FLOWIRE_PETSC(MatSetValues(a, 10, rows_c, 10, rows_c, kbuf, ADD_VALUES));
    }
    for (int i = 0; i < 10; ++i) {
      const PetscInt d = num.vdof[static_cast<size_t>(t[static_cast<size_t>(i)])];
      for (int c = 0; c < 3; ++c) vrows[3 * i + c] = d >= 0 ? d + c : -1;
    }
    for (int l = 0; l < 4; ++l) {
      const int v = mesh.vertex_index[static_cast<size_t>(t[static_cast<size_t>(l)])];
      prows[l] = num.pdof[static_cast<size_t>(v)];
      pidx[l] = num.pindex[static_cast<size_t>(v)];
    }
    for (int r = 0; r < 30; ++r)
      for (int l = 0; l < 4; ++l) {
        btbuf[r * 4 + l] = em.bt[r][l];
        bbuf[l * 30 + r] = em.bt[r][l];
      }
    FLOWIRE_PETSC(MatSetValues(a, 30, vrows, 4, prows, btbuf, ADD_VALUES));
    FLOWIRE_PETSC(MatSetValues(a, 4, prows, 30, vrows, bbuf, ADD_VALUES));
    if (mp) FLOWIRE_PETSC(MatSetValues(mp, 4, pidx, 4, pidx, &em.mp[0][0], ADD_VALUES));
  }
  FLOWIRE_PETSC(MatAssemblyBegin(a, MAT_FINAL_ASSEMBLY));
  FLOWIRE_PETSC(MatAssemblyEnd(a, MAT_FINAL_ASSEMBLY));
  if (mp) {
    FLOWIRE_PETSC(MatAssemblyBegin(mp, MAT_FINAL_ASSEMBLY));
    FLOWIRE_PETSC(MatAssemblyEnd(mp, MAT_FINAL_ASSEMBLY));
  }
  int any_bad = bad;
  MPI_Allreduce(&bad, &any_bad, 1, MPI_INT, MPI_MAX, PETSC_COMM_WORLD);
  if (any_bad >= 0)
    throw_numerical_error(fmt::format("fem: tetrahedron {} is inverted or degenerate (non-positive Jacobian of the "
                                      "curved element); use a smaller mesh size", any_bad));
}

/// Right-hand side: -p_k ∫ n·v over each inlet/outlet face.
void assemble_rhs(const TetMesh& mesh, const Numbering& num, const Mpi& mpi, std::span<const double> group_pressure,
                  Vec b) {
  FLOWIRE_PETSC(VecSet(b, 0.0));
  const auto [f0, f1] = split(static_cast<long>(mesh.faces.size()), mpi.size, mpi.rank);
  double phi[6], dphi[6][2];
  PetscInt rows[18];
  double vals[18];
  for (long f = f0; f < f1; ++f) {
    const int g = mesh.face_group[static_cast<size_t>(f)];
    if (mesh.groups[static_cast<size_t>(g)].kind == BoundaryGroup::Kind::Wall) continue;
    const double p = group_pressure[static_cast<size_t>(g)];
    if (p == 0.0) continue;
    const auto& tri = mesh.faces[static_cast<size_t>(f)];
    std::fill(vals, vals + 18, 0.0);
    for (const QuadPoint& q : tri_quadrature()) {
      tri_p2(q.xi, phi);
      tri_p2_grad(q.xi, dphi);
      Vec3 ts = Vec3::Zero(), tt = Vec3::Zero();
      for (int k = 0; k < 6; ++k) {
        ts += dphi[k][0] * mesh.nodes[static_cast<size_t>(tri[static_cast<size_t>(k)])];
        tt += dphi[k][1] * mesh.nodes[static_cast<size_t>(tri[static_cast<size_t>(k)])];
      }
      const Vec3 nds = ts.cross(tt);  // outward normal times the area element
      for (int k = 0; k < 6; ++k)
        for (int c = 0; c < 3; ++c) vals[3 * k + c] -= p * q.weight * phi[k] * nds[c];
    }
    // Vectors do not skip negative (wall) indices: pass only the free unknowns.
    PetscInt count = 0;
    for (int k = 0; k < 6; ++k) {
      const PetscInt d = num.vdof[static_cast<size_t>(tri[static_cast<size_t>(k)])];
      if (d < 0) continue;
      for (int c = 0; c < 3; ++c) {
        rows[count] = d + c;
        vals[count++] = vals[3 * k + c];
      }
    }
    if (count > 0) FLOWIRE_PETSC(VecSetValues(b, count, rows, vals, ADD_VALUES));
  }
  FLOWIRE_PETSC(VecAssemblyBegin(b));
  FLOWIRE_PETSC(VecAssemblyEnd(b));
}

void configure_solver(KSP ksp, Mat a, Mat mp, const Numbering& num, const StokesOptions& opt, bool symmetric, IsH& isu,
                      IsH& isp) {
  FLOWIRE_PETSC(KSPSetOptionsPrefix(ksp, "fem_"));
  FLOWIRE_PETSC(KSPSetOperators(ksp, a, a));
  PC pc = nullptr;
  FLOWIRE_PETSC(KSPGetPC(ksp, &pc));
  if (opt.solver == LinearSolver::Mumps) {
    FLOWIRE_PETSC(KSPSetType(ksp, KSPPREONLY));
    // Stokes is symmetric (indefinite): MUMPS LDLᵀ needs half the work of LU.
    FLOWIRE_PETSC(PCSetType(pc, symmetric ? PCCHOLESKY : PCLU));
    FLOWIRE_PETSC(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
  } else {
    if (opt.velocity_pc != "gamg" && opt.velocity_pc != "hypre")
      throw_usage_error(fmt::format("fem: velocity preconditioner '{}' is not one of: gamg, hypre", opt.velocity_pc));
    FLOWIRE_PETSC(KSPSetType(ksp, KSPFGMRES));
    FLOWIRE_PETSC(KSPGMRESSetRestart(ksp, 200));
    FLOWIRE_PETSC(KSPSetTolerances(ksp, opt.rtol, 1e-300, PETSC_DEFAULT, opt.max_iterations));
    FLOWIRE_PETSC(PCSetType(pc, PCFIELDSPLIT));
    FLOWIRE_PETSC(ISCreateStride(PETSC_COMM_WORLD, num.v_local, num.begin, 1, isu.out()));
    FLOWIRE_PETSC(ISSetBlockSize(isu, 3));
    FLOWIRE_PETSC(ISCreateStride(PETSC_COMM_WORLD, num.p_local, num.begin + num.v_local, 1, isp.out()));
    FLOWIRE_PETSC(PCFieldSplitSetIS(pc, "u", isu));
    FLOWIRE_PETSC(PCFieldSplitSetIS(pc, "p", isp));
    FLOWIRE_PETSC(PCFieldSplitSetType(pc, PC_COMPOSITE_SCHUR));
    FLOWIRE_PETSC(PCFieldSplitSetSchurFactType(pc, PC_FIELDSPLIT_SCHUR_FACT_UPPER));
    FLOWIRE_PETSC(PCFieldSplitSetSchurPre(pc, PC_FIELDSPLIT_SCHUR_PRE_USER, mp));
    default_option("-fem_fieldsplit_u_ksp_type", "preonly");
    default_option("-fem_fieldsplit_u_pc_type", opt.velocity_pc.c_str());
    default_option("-fem_fieldsplit_p_ksp_type", "preonly");
    default_option("-fem_fieldsplit_p_pc_type", "jacobi");
  }
  FLOWIRE_PETSC(KSPSetFromOptions(ksp));
}

}  // namespace

std::vector<double> group_fluxes(const TetMesh& mesh, const std::vector<Vec3>& velocity) {
  std::vector<double> flux(mesh.groups.size(), 0.0);
  double phi[6], dphi[6][2];
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& tri = mesh.faces[f];
    double sum = 0.0;
    for (const QuadPoint& q : tri_quadrature()) {
      tri_p2(q.xi, phi);
      tri_p2_grad(q.xi, dphi);
      Vec3 ts = Vec3::Zero(), tt = Vec3::Zero(), u = Vec3::Zero();
      for (int k = 0; k < 6; ++k) {
        const auto n = static_cast<size_t>(tri[static_cast<size_t>(k)]);
        ts += dphi[k][0] * mesh.nodes[n];
        tt += dphi[k][1] * mesh.nodes[n];
        u += phi[k] * velocity[n];
      }
      sum += q.weight * u.dot(ts.cross(tt));
    }
    flux[static_cast<size_t>(mesh.face_group[f])] += sum;
  }
  return flux;
}

namespace {

/// The linear system of one mesh: numbering, matrices, solver; assembled for a given
/// convection field, factorized once, then solved for any group pressures.
class System {
 public:
  System(const TetMesh& mesh, const StokesOptions& opt) : mesh_(mesh), opt_(opt), num_(number(mesh, mpi_.rank, mpi_.size)) {
    std::vector<PetscInt> ia, ja, pia, pja;
    {
      const NodeTets nt = node_tets(mesh);
      sparsity(mesh, num_, nt, ia, ja, pia, pja);
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
    // Every rank gets the whole solution.
    FLOWIRE_PETSC(VecScatterCreateToAll(x_, scatter_.out(), all_.out()));
  }

  [[nodiscard]] int unknowns() const { return static_cast<int>(num_.total); }

  /// Assemble (with the convection field `wind` for Navier–Stokes) and factorize.
  void prepare(const std::vector<Vec3>* wind) {
    auto t0 = std::chrono::steady_clock::now();
    assemble(mesh_, num_, mpi_, opt_, wind, a_, first_ ? Mat(mp_) : nullptr);
    first_ = false;
    assemble_seconds += seconds_since(t0);
    t0 = std::chrono::steady_clock::now();
    ksp_.reset();
    isu_.reset();
    isp_.reset();
    FLOWIRE_PETSC(KSPCreate(PETSC_COMM_WORLD, ksp_.out()));
    const bool symmetric = wind == nullptr;
    FLOWIRE_PETSC(MatSetOption(a_, MAT_SYMMETRIC, symmetric ? PETSC_TRUE : PETSC_FALSE));
    configure_solver(ksp_, a_, mp_, num_, opt_, symmetric, isu_, isp_);
    FLOWIRE_PETSC(KSPSetUp(ksp_));
    solve_seconds += seconds_since(t0);
    ++factorizations;
  }

  /// Solve for the given group pressures: velocity, pressure and group fluxes.
  StokesSolution solve(std::span<const double> group_pressure) {
    auto t0 = std::chrono::steady_clock::now();
    assemble_rhs(mesh_, num_, mpi_, group_pressure, b_);
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
    StokesSolution sol;
    sol.velocity.assign(mesh_.nodes.size(), Vec3::Zero());
    sol.pressure.assign(static_cast<size_t>(mesh_.num_vertices), 0.0);
    FLOWIRE_PETSC(VecScatterBegin(scatter_, x_, all_, INSERT_VALUES, SCATTER_FORWARD));
    FLOWIRE_PETSC(VecScatterEnd(scatter_, x_, all_, INSERT_VALUES, SCATTER_FORWARD));
    const PetscScalar* v = nullptr;
    FLOWIRE_PETSC(VecGetArrayRead(all_, &v));
    for (size_t n = 0; n < mesh_.nodes.size(); ++n) {
      const PetscInt d = num_.vdof[n];
      if (d >= 0) sol.velocity[n] = Vec3(v[d], v[d + 1], v[d + 2]);
    }
    for (size_t k = 0; k < sol.pressure.size(); ++k) sol.pressure[k] = v[num_.pdof[k]];
    FLOWIRE_PETSC(VecRestoreArrayRead(all_, &v));
    sol.group_flow = group_fluxes(mesh_, sol.velocity);
    sol.group_pressure.assign(group_pressure.begin(), group_pressure.end());
    return sol;
  }

  double assemble_seconds = 0.0, solve_seconds = 0.0;
  int krylov_iterations = 0, factorizations = 0;

 private:
  const TetMesh& mesh_;
  StokesOptions opt_;
  Mpi mpi_;
  Numbering num_;
  MatH a_, mp_;
  VecH b_, x_, all_;
  ScatterH scatter_;
  KspH ksp_;
  IsH isu_, isp_;
  bool first_ = true;
};

/// sol += c · other (fields, fluxes and group pressures).
void add_scaled(StokesSolution& sol, double c, const StokesSolution& other) {
  for (size_t n = 0; n < sol.velocity.size(); ++n) sol.velocity[n] += c * other.velocity[n];
  for (size_t k = 0; k < sol.pressure.size(); ++k) sol.pressure[k] += c * other.pressure[k];
  for (size_t g = 0; g < sol.group_flow.size(); ++g) sol.group_flow[g] += c * other.group_flow[g];
  for (size_t g = 0; g < sol.group_pressure.size(); ++g) sol.group_pressure[g] += c * other.group_pressure[g];
}

void check_conditions(const TetMesh& mesh, std::span<const GroupCondition> cond) {
  if (cond.size() != mesh.groups.size())
    throw_usage_error(fmt::format("fem: {} boundary conditions given for {} boundary groups", cond.size(),
                                  mesh.groups.size()));
  bool level = false;
  for (size_t g = 0; g < cond.size(); ++g) {
    if (mesh.groups[g].kind == BoundaryGroup::Kind::Wall) continue;
    const auto& c = cond[g];
    const double vals[3] = {c.pressure, c.flow, c.resistance};
    for (double v : vals)
      if (!std::isfinite(v)) throw_usage_error(fmt::format("fem: boundary value of {} is not finite", mesh.groups[g].name));
    if (c.type == GroupCondition::Type::Resistance && c.resistance < 0.0)
      throw_usage_error(fmt::format("fem: negative resistance {} on {}", c.resistance, mesh.groups[g].name));
    if (c.type != GroupCondition::Type::Flow) level = true;
  }
  if (!level)
    throw_usage_error("fem: every open boundary has a prescribed flow, which leaves the pressure level undetermined; "
                      "give at least one a pressure or a resistance");
}

}  // namespace

std::vector<double> boundary_pressures(const TetMesh& mesh, std::span<const GroupCondition> cond,
                                       const std::vector<int>& open, const std::vector<double>& base_flux,
                                       const std::vector<std::vector<double>>& unit_flux) {
  check_conditions(mesh, cond);
  std::vector<double> p(mesh.groups.size(), 0.0);
  for (size_t g = 0; g < cond.size(); ++g)
    if (mesh.groups[g].kind != BoundaryGroup::Kind::Wall && cond[g].type == GroupCondition::Type::Pressure)
      p[g] = cond[g].pressure;
  const auto n = static_cast<Eigen::Index>(open.size());
  if (n == 0) return p;
  // Row i: the condition of group open[i]; column j: the pressure of open[j].
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd rhs(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto gi = static_cast<size_t>(open[static_cast<size_t>(i)]);
    const auto& c = cond[gi];
    switch (c.type) {
      case GroupCondition::Type::Pressure:  // p_i = P
        a(i, i) = 1.0;
        rhs[i] = c.pressure;
        break;
      case GroupCondition::Type::Flow:  // Q_i = F0_i + Σ_j F_j,i p_j = Q
        for (Eigen::Index j = 0; j < n; ++j) a(i, j) = unit_flux[static_cast<size_t>(j)][gi];
        rhs[i] = c.flow - base_flux[gi];
        break;
      case GroupCondition::Type::Resistance:  // p_i − R (F0_i + Σ_j F_j,i p_j) = P_d
        for (Eigen::Index j = 0; j < n; ++j) a(i, j) = -c.resistance * unit_flux[static_cast<size_t>(j)][gi];
        a(i, i) += 1.0;
        rhs[i] = c.pressure + c.resistance * base_flux[gi];
        break;
    }
  }
  // Scale every row to a unit largest entry: flow rows (m³/s/Pa) and pressure rows differ
  // by many orders of magnitude.
  for (Eigen::Index i = 0; i < n; ++i) {
    const double s = a.row(i).cwiseAbs().maxCoeff();
    if (s > 0.0) {
      a.row(i) /= s;
      rhs[i] /= s;
    }
  }
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(a);
  if (lu.rank() < n || lu.rcond() < 1e-13)
    throw_usage_error("fem: the boundary conditions do not determine the boundary pressures");
  const Eigen::VectorXd x = lu.solve(rhs);
  for (Eigen::Index i = 0; i < n; ++i) p[static_cast<size_t>(open[static_cast<size_t>(i)])] = x[i];
  return p;
}

StokesSolution solve_stokes(const TetMesh& mesh, std::span<const double> group_pressure, const StokesOptions& opt) {
  if (group_pressure.size() != mesh.groups.size())
    throw_usage_error(fmt::format("fem: {} boundary pressures given for {} boundary groups", group_pressure.size(),
                                  mesh.groups.size()));
  std::vector<GroupCondition> cond(mesh.groups.size());
  for (size_t g = 0; g < cond.size(); ++g) cond[g] = GroupCondition::at_pressure(group_pressure[g]);
  return solve_stokes(mesh, std::span<const GroupCondition>(cond), opt);
}

StokesSolution solve_stokes(const TetMesh& mesh, std::span<const GroupCondition> cond, const StokesOptions& opt) {
  if (!(opt.viscosity > 0.0)) throw_usage_error("fem: viscosity must be > 0");
  if (mesh.tets.empty()) throw_usage_error("fem: empty mesh");
  check_conditions(mesh, cond);
  ensure_petsc();
  System sys(mesh, opt);
  // Groups whose pressure follows from a flow or resistance condition.
  std::vector<int> unknown;
  std::vector<double> known(mesh.groups.size(), 0.0);
  for (size_t g = 0; g < mesh.groups.size(); ++g) {
    if (mesh.groups[g].kind == BoundaryGroup::Kind::Wall) continue;
    if (cond[g].type == GroupCondition::Type::Pressure) known[g] = cond[g].pressure;
    else unknown.push_back(static_cast<int>(g));
  }
  const int max_steps = opt.equations == Equations::NavierStokes ? std::max(1, opt.picard_max_iterations) + 1 : 1;
  std::vector<Vec3> wind;
  StokesSolution sol;
  double change = 0.0;
  for (int step = 0; step < max_steps; ++step) {
    sys.prepare(step == 0 ? nullptr : &wind);
    sol = sys.solve(known);
    if (!unknown.empty()) {
      std::vector<StokesSolution> units;
      std::vector<std::vector<double>> flux;
      for (int g : unknown) {
        std::vector<double> e(mesh.groups.size(), 0.0);
        e[static_cast<size_t>(g)] = 1.0;
        units.push_back(sys.solve(e));
        flux.push_back(units.back().group_flow);
      }
      const std::vector<double> p = boundary_pressures(mesh, cond, unknown, sol.group_flow, flux);
      for (size_t k = 0; k < unknown.size(); ++k) add_scaled(sol, p[static_cast<size_t>(unknown[k])], units[k]);
    }
    if (opt.equations == Equations::Stokes) break;
    if (step > 0) {
      double du = 0.0, umax = 0.0;
      for (size_t n = 0; n < sol.velocity.size(); ++n) {
        du = std::max(du, (sol.velocity[n] - wind[n]).cwiseAbs().maxCoeff());
        umax = std::max(umax, sol.velocity[n].cwiseAbs().maxCoeff());
      }
      change = umax > 0.0 ? du / umax : 0.0;
      if (!std::isfinite(change)) throw_numerical_error("fem: Navier–Stokes Picard iterations produced NaN");
      if (change <= opt.picard_tolerance) break;
    }
    wind = sol.velocity;
    if (step + 1 == max_steps)
      throw_numerical_error(fmt::format("fem: Navier–Stokes Picard iterations did not converge in {} steps "
                                        "(last relative change {:.3g}); the Reynolds number may be too high",
                                        opt.picard_max_iterations, change));
  }
  for (const Vec3& u : sol.velocity)
    if (!u.allFinite()) throw_numerical_error("fem: the solution contains NaN");
  sol.unknowns = sys.unknowns();
  sol.krylov_iterations = sys.krylov_iterations;
  sol.picard_iterations = sys.factorizations;
  sol.assemble_seconds = sys.assemble_seconds;
  sol.solve_seconds = sys.solve_seconds;
  return sol;
}

StokesBasis::StokesBasis(const TetMesh& mesh, const StokesOptions& opt) : mesh_(mesh) {
  if (opt.equations != Equations::Stokes)
    throw_usage_error("fem: the boundary-value basis is for Stokes only (Navier–Stokes is not linear)");
  if (!(opt.viscosity > 0.0)) throw_usage_error("fem: viscosity must be > 0");
  if (mesh.tets.empty()) throw_usage_error("fem: empty mesh");
  ensure_petsc();
  System sys(mesh, opt);
  sys.prepare(nullptr);
  for (size_t g = 0; g < mesh.groups.size(); ++g) {
    if (mesh.groups[g].kind == BoundaryGroup::Kind::Wall) continue;
    open_.push_back(static_cast<int>(g));
    std::vector<double> e(mesh.groups.size(), 0.0);
    e[g] = 1.0;
    unit_.push_back(sys.solve(e));
    flux_.push_back(unit_.back().group_flow);
  }
  unknowns_ = sys.unknowns();
  assemble_seconds_ = sys.assemble_seconds;
  solve_seconds_ = sys.solve_seconds;
}

std::vector<double> StokesBasis::pressures(std::span<const GroupCondition> cond) const {
  // The basis spans every open group: the "base" field is zero and every group pressure
  // is an unknown of the small system (pressure groups get an identity row).
  const std::vector<double> zero(mesh_.groups.size(), 0.0);
  return boundary_pressures(mesh_, cond, open_, zero, flux_);
}

StokesSolution StokesBasis::solve(std::span<const GroupCondition> cond) const {
  const std::vector<double> p = pressures(cond);
  StokesSolution sol;
  sol.velocity.assign(mesh_.nodes.size(), Vec3::Zero());
  sol.pressure.assign(static_cast<size_t>(mesh_.num_vertices), 0.0);
  sol.group_flow.assign(mesh_.groups.size(), 0.0);
  sol.group_pressure.assign(mesh_.groups.size(), 0.0);
  for (size_t k = 0; k < open_.size(); ++k) add_scaled(sol, p[static_cast<size_t>(open_[k])], unit_[k]);
  sol.unknowns = unknowns_;
  sol.picard_iterations = 1;
  return sol;
}

void initialize() { ensure_petsc(); }

void finalize_petsc() {
  if (!g_we_initialized) return;
  PetscBool up = PETSC_FALSE, done = PETSC_FALSE;
  PetscInitialized(&up);
  PetscFinalized(&done);
  int mpi_done = 0;
  MPI_Finalized(&mpi_done);
  if (up && !done && !mpi_done) PetscFinalize();
}

}  // namespace flowire::fem
