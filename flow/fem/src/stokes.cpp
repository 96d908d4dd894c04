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

StokesSolution solve_stokes(const TetMesh& mesh, std::span<const double> group_pressure, const StokesOptions& opt) {
  if (group_pressure.size() != mesh.groups.size())
    throw_usage_error(fmt::format("fem: {} boundary pressures given for {} boundary groups", group_pressure.size(),
                                  mesh.groups.size()));
  if (!(opt.viscosity > 0.0)) throw_usage_error("fem: viscosity must be > 0");
  if (mesh.tets.empty()) throw_usage_error("fem: empty mesh");
  ensure_petsc();
  const Mpi mpi;
  StokesSolution sol;
  auto t0 = std::chrono::steady_clock::now();
  const Numbering num = number(mesh, mpi.rank, mpi.size);
  sol.unknowns = static_cast<int>(num.total);
  std::vector<PetscInt> ia, ja, pia, pja;
  {
    const NodeTets nt = node_tets(mesh);
    sparsity(mesh, num, nt, ia, ja, pia, pja);
  }
  MatH a, mp;
  FLOWIRE_PETSC(MatCreate(PETSC_COMM_WORLD, a.out()));
  FLOWIRE_PETSC(MatSetSizes(a, num.local, num.local, num.total, num.total));
  FLOWIRE_PETSC(MatSetType(a, MATAIJ));
  FLOWIRE_PETSC(MatSeqAIJSetPreallocationCSR(a, ia.data(), ja.data(), nullptr));
  FLOWIRE_PETSC(MatMPIAIJSetPreallocationCSR(a, ia.data(), ja.data(), nullptr));
  FLOWIRE_PETSC(MatSetOption(a, MAT_NEW_NONZERO_LOCATION_ERR, PETSC_TRUE));
  const bool fieldsplit = opt.solver == LinearSolver::Fieldsplit;
  if (fieldsplit) {
    FLOWIRE_PETSC(MatCreate(PETSC_COMM_WORLD, mp.out()));
    FLOWIRE_PETSC(MatSetSizes(mp, num.p_local, num.p_local, mesh.num_vertices, mesh.num_vertices));
    FLOWIRE_PETSC(MatSetType(mp, MATAIJ));
    FLOWIRE_PETSC(MatSeqAIJSetPreallocationCSR(mp, pia.data(), pja.data(), nullptr));
    FLOWIRE_PETSC(MatMPIAIJSetPreallocationCSR(mp, pia.data(), pja.data(), nullptr));
  }
  VecH b, x;
  FLOWIRE_PETSC(MatCreateVecs(a, x.out(), b.out()));
  assemble_rhs(mesh, num, mpi, group_pressure, b);

  // Every rank gets the whole solution.
  ScatterH scatter;
  VecH all;
  FLOWIRE_PETSC(VecScatterCreateToAll(x, scatter.out(), all.out()));
  std::vector<Vec3> velocity(mesh.nodes.size(), Vec3::Zero());
  std::vector<double> pressure(static_cast<size_t>(mesh.num_vertices), 0.0);
  auto unpack = [&] {
    FLOWIRE_PETSC(VecScatterBegin(scatter, x, all, INSERT_VALUES, SCATTER_FORWARD));
    FLOWIRE_PETSC(VecScatterEnd(scatter, x, all, INSERT_VALUES, SCATTER_FORWARD));
    const PetscScalar* v = nullptr;
    FLOWIRE_PETSC(VecGetArrayRead(all, &v));
    for (size_t n = 0; n < mesh.nodes.size(); ++n) {
      const PetscInt d = num.vdof[n];
      velocity[n] = d >= 0 ? Vec3(v[d], v[d + 1], v[d + 2]) : Vec3::Zero();
    }
    for (size_t k = 0; k < pressure.size(); ++k) pressure[k] = v[num.pdof[k]];
    FLOWIRE_PETSC(VecRestoreArrayRead(all, &v));
  };

  const int max_steps = opt.equations == Equations::NavierStokes ? std::max(1, opt.picard_max_iterations) + 1 : 1;
  std::vector<Vec3> wind;
  double change = 0.0;
  for (int step = 0; step < max_steps; ++step) {
    t0 = std::chrono::steady_clock::now();
    assemble(mesh, num, mpi, opt, step == 0 ? nullptr : &wind, a, step == 0 ? Mat(mp) : nullptr);
    sol.assemble_seconds += seconds_since(t0);
    t0 = std::chrono::steady_clock::now();
    KspH ksp;
    IsH isu, isp;
    FLOWIRE_PETSC(KSPCreate(PETSC_COMM_WORLD, ksp.out()));
    const bool symmetric = step == 0;
    FLOWIRE_PETSC(MatSetOption(a, MAT_SYMMETRIC, symmetric ? PETSC_TRUE : PETSC_FALSE));
    configure_solver(ksp, a, mp, num, opt, symmetric, isu, isp);
    FLOWIRE_PETSC(KSPSolve(ksp, b, x));
    KSPConvergedReason reason;
    FLOWIRE_PETSC(KSPGetConvergedReason(ksp, &reason));
    PetscInt its = 0;
    FLOWIRE_PETSC(KSPGetIterationNumber(ksp, &its));
    sol.solve_seconds += seconds_since(t0);
    if (reason < 0)
      throw_numerical_error(fmt::format("fem: the linear solve failed ({}) after {} iterations",
                                        KSPConvergedReasons[reason], static_cast<long>(its)));
    if (fieldsplit) sol.krylov_iterations += static_cast<int>(its);
    ++sol.picard_iterations;
    unpack();
    if (opt.equations == Equations::Stokes) break;
    if (step > 0) {
      double du = 0.0, umax = 0.0;
      for (size_t n = 0; n < velocity.size(); ++n) {
        du = std::max(du, (velocity[n] - wind[n]).cwiseAbs().maxCoeff());
        umax = std::max(umax, velocity[n].cwiseAbs().maxCoeff());
      }
      change = umax > 0.0 ? du / umax : 0.0;
      if (!std::isfinite(change)) throw_numerical_error("fem: Navier–Stokes Picard iterations produced NaN");
      if (change <= opt.picard_tolerance) {
        wind.clear();
        break;
      }
    }
    wind = velocity;
    if (step + 1 == max_steps)
      throw_numerical_error(fmt::format("fem: Navier–Stokes Picard iterations did not converge in {} steps "
                                        "(last relative change {:.3g}); the Reynolds number may be too high",
                                        opt.picard_max_iterations, change));
  }
  for (const Vec3& u : velocity)
    if (!u.allFinite()) throw_numerical_error("fem: the solution contains NaN");
  sol.velocity = std::move(velocity);
  sol.pressure = std::move(pressure);
  sol.group_flow = group_fluxes(mesh, sol.velocity);
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
