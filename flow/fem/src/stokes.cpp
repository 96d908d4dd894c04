// Taylor–Hood P2/P1 Stokes / Navier–Stokes: element matrices computed here, a PETSc AIJ
// matrix with exact (CSR) preallocation, MUMPS or a fieldsplit Schur preconditioner;
// Navier–Stokes by Newton with density continuation and SUPG/LSIC/backflow stabilization.
#include "flowire/fem/stokes.hpp"

#include <fmt/format.h>
#include <mpi.h>
#include <petscksp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <numbers>

#include <Eigen/Dense>

#include "flowire/common/error.hpp"
#include "flowire/fem/element.hpp"
#include "flowire/flow/petsc_runtime.hpp"

namespace flowire::fem {
namespace {

#define FLOWIRE_PETSC(call) ::flowire::flow::check_petsc((call), #call, "fem")

void ensure_petsc() { flow::ensure_petsc("fem"); }

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

/// `fixed_group` >= 0: the nodes of that group carry a prescribed velocity too.
Numbering number(const TetMesh& mesh, int rank, int size, int fixed_group = -1) {
  Numbering num;
  const size_t nn = mesh.nodes.size();
  std::vector<char> wall(nn, 0);
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    if (mesh.groups[static_cast<size_t>(mesh.face_group[f])].kind == BoundaryGroup::Kind::Wall ||
        mesh.face_group[f] == fixed_group)
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
/// `coupled`: every velocity component couples to every other (the Navier–Stokes Jacobian).
void sparsity(const TetMesh& mesh, const Numbering& num, const NodeTets& nt, bool coupled, std::vector<PetscInt>& ia,
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
      for (PetscInt d : vel) {
        if (coupled)
          for (int k = 0; k < 3; ++k) row.push_back(d + k);
        else
          row.push_back(d + c);
      }
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
  double k[10][10];   // viscous block, the same for every component
  double m[10][10];   // velocity mass block (per component)
  double bt[30][4];   // velocity (node i, component c -> row 3i+c) x pressure: -(q, div v)
  double mp[4][4];    // pressure mass / viscosity
};

bool element(const TetMesh& mesh, const Reference& ref, int e, double eta, ElementMatrices& em) {
  const auto& t = mesh.tets[static_cast<size_t>(e)];
  Vec3 x[10];
  for (int i = 0; i < 10; ++i) x[i] = mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(i)])];
  std::fill(&em.k[0][0], &em.k[0][0] + 100, 0.0);
  std::fill(&em.m[0][0], &em.m[0][0] + 100, 0.0);
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
        const double mv = wd * ref.phi[q][i] * ref.phi[q][jj];
        em.m[i][jj] += mv;
        if (jj != i) em.m[jj][i] += mv;
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
/// With `mass_coef` c > 0 the velocity block is K + c·M (time-dependent Stokes), and with
/// `mass` the velocity mass matrix M is assembled there too.
void assemble(const TetMesh& mesh, const Numbering& num, const Mpi& mpi, const StokesOptions& opt, Mat a, Mat mp,
              double mass_coef = 0.0, Mat mass = nullptr) {
  static const Reference ref;
  FLOWIRE_PETSC(MatZeroEntries(a));
  if (mp) FLOWIRE_PETSC(MatZeroEntries(mp));
  if (mass) FLOWIRE_PETSC(MatZeroEntries(mass));
  double mbuf[100];
  const auto [e0, e1] = split(mesh.num_tets(), mpi.size, mpi.rank);
  ElementMatrices em{};
  PetscInt rows_c[10], vrows[30], prows[4], pidx[4];
  double kbuf[100], btbuf[120], bbuf[120];
  int bad = -1;
  for (long e = e0; e < e1; ++e) {
    if (!element(mesh, ref, static_cast<int>(e), opt.viscosity, em)) {
      bad = static_cast<int>(e);
      break;
    }
    const auto& t = mesh.tets[static_cast<size_t>(e)];
    for (int i = 0; i < 10; ++i)
      for (int jj = 0; jj < 10; ++jj) {
        kbuf[i * 10 + jj] = em.k[i][jj] + mass_coef * em.m[i][jj];
        mbuf[i * 10 + jj] = em.m[i][jj];
      }
    for (int c = 0; c < 3; ++c) {
      for (int i = 0; i < 10; ++i) {
        const PetscInt d = num.vdof[static_cast<size_t>(t[static_cast<size_t>(i)])];
        rows_c[i] = d >= 0 ? d + c : -1;
      }
      FLOWIRE_PETSC(MatSetValues(a, 10, rows_c, 10, rows_c, kbuf, ADD_VALUES));
      if (mass) FLOWIRE_PETSC(MatSetValues(mass, 10, rows_c, 10, rows_c, mbuf, ADD_VALUES));
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
  for (Mat extra : {mp, mass})
    if (extra) {
      FLOWIRE_PETSC(MatAssemblyBegin(extra, MAT_FINAL_ASSEMBLY));
      FLOWIRE_PETSC(MatAssemblyEnd(extra, MAT_FINAL_ASSEMBLY));
    }
  int any_bad = bad;
  MPI_Allreduce(&bad, &any_bad, 1, MPI_INT, MPI_MAX, PETSC_COMM_WORLD);
  if (any_bad >= 0)
    throw_numerical_error(fmt::format("fem: tetrahedron {} is inverted or degenerate (non-positive Jacobian of the "
                                      "curved element); use a smaller mesh size", any_bad));
}

/// Add `vals` (count entries) at `rows` of a vector, skipping wall (negative) rows: PETSc
/// vectors do not skip negative indices.
void add_to_vector(Vec b, int count, const PetscInt* rows, const double* vals) {
  PetscInt r[34];
  double v[34];
  PetscInt m = 0;
  for (int k = 0; k < count; ++k)
    if (rows[k] >= 0) {
      r[m] = rows[k];
      v[m++] = vals[k];
    }
  if (m > 0) FLOWIRE_PETSC(VecSetValues(b, m, r, v, ADD_VALUES));
}

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

NsParams ns_params(const StokesOptions& opt) {
  NsParams prm;
  prm.eta = opt.viscosity;
  prm.rho = opt.density;
  prm.backflow = opt.backflow;
  prm.stabilize = opt.stabilization == Stabilization::Supg;
  prm.body_force = &opt.body_force;
  prm.traction = &opt.traction;
  return prm;
}

/// Residual (34: velocity rows 3i+c, then 4 pressure rows) and Jacobian (34 × 34, row
/// major) of one tetrahedron for the Navier–Stokes weak form with SUPG + LSIC (see
/// stokes.hpp). Returns false for a non-positive Jacobian determinant.
bool ns_element(const TetMesh& mesh, const ReferenceNs& ref, int e, const NsParams& prm, const State& st,
                double* res, double* jac) {
  constexpr int n = 34;
  const auto& t = mesh.tets[static_cast<size_t>(e)];
  Vec3 x[10], un[10];
  double pn[4];
  for (int i = 0; i < 10; ++i) {
    x[i] = mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(i)])];
    un[i] = (*st.velocity)[static_cast<size_t>(t[static_cast<size_t>(i)])];
  }
  for (int l = 0; l < 4; ++l)
    pn[l] = (*st.pressure)[static_cast<size_t>(mesh.vertex_index[static_cast<size_t>(t[static_cast<size_t>(l)])])];
  std::fill(res, res + n, 0.0);
  std::fill(jac, jac + n * n, 0.0);
  const double eta = prm.eta, rho = prm.rho;
  // Element size: the edge of the regular tetrahedron of the straight element's volume,
  // halved for quadratic elements.
  const double vol = std::abs((x[1] - x[0]).dot((x[2] - x[0]).cross(x[3] - x[0]))) / 6.0;
  const double h = 0.5 * std::cbrt(6.0 * std::sqrt(2.0) * vol);
  for (int q = 0; q < ref.nq; ++q) {
    Eigen::Matrix3d j = Eigen::Matrix3d::Zero();  // dx/dxi
    for (int i = 0; i < 10; ++i) j += x[i] * Eigen::RowVector3d(ref.dphi[q][i][0], ref.dphi[q][i][1], ref.dphi[q][i][2]);
    const double det = j.determinant();
    if (!(det > 0.0)) return false;
    const Eigen::Matrix3d jinv = j.inverse();
    const Eigen::Matrix3d jinv_t = jinv.transpose();
    const double* phi = ref.phi[q];
    const double* psi = ref.psi[q];
    Eigen::Vector3d g[10];
    for (int i = 0; i < 10; ++i) g[i] = jinv_t * Eigen::Vector3d(ref.dphi[q][i][0], ref.dphi[q][i][1], ref.dphi[q][i][2]);
    Eigen::Vector3d gp[4];
    for (int l = 0; l < 4; ++l) gp[l] = jinv_t * Eigen::Vector3d(ref.dpsi[l][0], ref.dpsi[l][1], ref.dpsi[l][2]);
    // Values at the point.
    Vec3 u = Vec3::Zero(), xq = Vec3::Zero();
    Eigen::Matrix3d grad = Eigen::Matrix3d::Zero();  // grad(a, b) = ∂u_a/∂x_b
    for (int i = 0; i < 10; ++i) {
      u += phi[i] * un[i];
      xq += phi[i] * x[i];
      grad += un[i] * g[i].transpose();
    }
    double p = 0.0;
    Eigen::Vector3d gradp = Eigen::Vector3d::Zero();
    for (int l = 0; l < 4; ++l) {
      p += psi[l] * pn[l];
      gradp += pn[l] * gp[l];
    }
    const Vec3 f = prm.body_force && *prm.body_force ? (*prm.body_force)(xq) : Vec3::Zero();
    const double wd = ref.w[q] * det;
    const double div = grad.trace();
    const Eigen::Vector3d conv = grad * u;  // (u·∇)u
    double taum = 0.0, tauc = 0.0;
    Eigen::Vector3d dtaum = Eigen::Vector3d::Zero(), dtauc = Eigen::Vector3d::Zero();
    double lap[10] = {};
    Eigen::Vector3d rm = Eigen::Vector3d::Zero();  // strong momentum residual
    if (prm.stabilize && rho > 0.0) {
      // Physical second derivatives of the isoparametric basis:
      // ∇²φ = J⁻ᵀ (∇_ξ²φ − Σ_c (∂φ/∂x_c) ∇_ξ² x_c) J⁻¹; only the Laplacian is needed.
      Eigen::Matrix3d xh[3];
      for (auto& m : xh) m.setZero();
      for (int i = 0; i < 10; ++i) {
        const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> hi(&ref.hess[i][0][0]);
        for (int c = 0; c < 3; ++c) xh[c] += x[i][c] * hi;
      }
      const Eigen::Matrix3d jj = jinv * jinv_t;  // for tr(J⁻ᵀ M J⁻¹) = tr(M J⁻¹J⁻ᵀ)
      Eigen::Vector3d lapu = Eigen::Vector3d::Zero();
      for (int i = 0; i < 10; ++i) {
        const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> hi(&ref.hess[i][0][0]);
        const Eigen::Matrix3d m = hi - g[i][0] * xh[0] - g[i][1] * xh[1] - g[i][2] * xh[2];
        lap[i] = (m.cwiseProduct(jj)).sum();
        lapu += lap[i] * un[i];
      }
      const double speed = u.norm();
      const double adv = 2.0 * rho / h;
      taum = 1.0 / std::sqrt(std::pow(adv * speed, 2) + std::pow(12.0 * eta / (h * h), 2));
      const double re_h = rho * speed * h / (2.0 * eta);
      // ∂τ/∂u (times φ_j for node j): τ_M = (a²|u|² + b²)^(−1/2) gives −τ_M³ a² u;
      // τ_C = ρ²h²|u|²/(12η) below Re_h = 3 and ρ|u|h/2 above.
      dtaum = -taum * taum * taum * adv * adv * u;
      if (re_h < 3.0) {
        tauc = rho * rho * h * h * speed * speed / (12.0 * eta);
        dtauc = rho * rho * h * h / (6.0 * eta) * u;
      } else {
        tauc = 0.5 * rho * speed * h;
        dtauc = 0.5 * rho * h / speed * u;
      }
      rm = rho * conv - eta * lapu + gradp - f;
    }
    double ug[10];
    for (int i = 0; i < 10; ++i) ug[i] = u.dot(g[i]);
    for (int i = 0; i < 10; ++i) {
      const Eigen::Vector3d visc = eta * (grad * g[i]);
      for (int a = 0; a < 3; ++a)
        res[3 * i + a] += wd * (visc[a] + rho * conv[a] * phi[i] - p * g[i][a] - f[a] * phi[i] +
                                taum * rho * ug[i] * rm[a] + tauc * div * g[i][a]);
    }
    for (int l = 0; l < 4; ++l) res[30 + l] -= wd * psi[l] * div;
    for (int i = 0; i < 10; ++i)
      for (int jn = 0; jn < 10; ++jn) {
        const double gij = g[i].dot(g[jn]);
        for (int a = 0; a < 3; ++a) {
          double* row = jac + (3 * i + a) * n + 3 * jn;
          for (int c = 0; c < 3; ++c) {
            const double dconv = (a == c ? ug[jn] : 0.0) + grad(a, c) * phi[jn];  // ∂((u·∇)u)_a/∂u_{j,c}
            double v = (a == c ? eta * gij : 0.0) + rho * phi[i] * dconv;
            if (taum > 0.0) {
              const double drm = rho * dconv - (a == c ? eta * lap[jn] : 0.0);
              v += taum * rho * (phi[jn] * g[i][c] * rm[a] + ug[i] * drm);
              v += phi[jn] * (dtaum[c] * rho * ug[i] * rm[a] + dtauc[c] * div * g[i][a]);
            }
            v += tauc * g[i][a] * g[jn][c];
            row[c] += wd * v;
          }
        }
      }
    for (int i = 0; i < 10; ++i)
      for (int a = 0; a < 3; ++a)
        for (int m = 0; m < 4; ++m) {
          const double v = -psi[m] * g[i][a] + taum * rho * ug[i] * gp[m][a];
          jac[(3 * i + a) * n + 30 + m] += wd * v;
          jac[(30 + m) * n + 3 * i + a] -= wd * psi[m] * g[i][a];
        }
  }
  return true;
}

/// Residual and Jacobian of one open-boundary triangle: the pressure and traction
/// terms, and the backflow term on outlets (18 velocity rows 3k+c).
void ns_face(const TetMesh& mesh, size_t f, const NsParams& prm, const State& st, double* res, double* jac,
             bool& any_jac) {
  const auto& tri = mesh.faces[f];
  const int grp = mesh.face_group[f];
  const double pk = (*st.group_pressure)[static_cast<size_t>(grp)];
  const bool outlet = mesh.groups[static_cast<size_t>(grp)].kind == BoundaryGroup::Kind::Outlet;
  const double beta = outlet ? prm.backflow * prm.rho : 0.0;
  std::fill(res, res + 18, 0.0);
  std::fill(jac, jac + 18 * 18, 0.0);
  any_jac = false;
  double phi[6], dphi[6][2];
  for (const QuadPoint& q : tri_quadrature()) {
    tri_p2(q.xi, phi);
    tri_p2_grad(q.xi, dphi);
    Vec3 ts = Vec3::Zero(), tt = Vec3::Zero(), u = Vec3::Zero(), xq = Vec3::Zero();
    for (int k = 0; k < 6; ++k) {
      const auto nd = static_cast<size_t>(tri[static_cast<size_t>(k)]);
      ts += dphi[k][0] * mesh.nodes[nd];
      tt += dphi[k][1] * mesh.nodes[nd];
      u += phi[k] * (*st.velocity)[nd];
      xq += phi[k] * mesh.nodes[nd];
    }
    const Vec3 nds = ts.cross(tt);  // outward normal times the area element
    const double area = nds.norm();
    Vec3 load = pk * nds;            // residual: + p_k ∫ n·v − ∫ g·v
    if (prm.traction && *prm.traction) load -= area * (*prm.traction)(xq, nds / area, grp);
    for (int k = 0; k < 6; ++k)
      for (int c = 0; c < 3; ++c) res[3 * k + c] += q.weight * phi[k] * load[c];
    const double un = u.dot(nds);
    if (beta > 0.0 && un < 0.0) {
      // −(βρ/2) ∫ min(u·n, 0) u·v and its derivative.
      any_jac = true;
      const double c0 = -0.5 * beta * q.weight;
      for (int k = 0; k < 6; ++k) {
        for (int a = 0; a < 3; ++a) res[3 * k + a] += c0 * un * u[a] * phi[k];
        for (int m = 0; m < 6; ++m)
          for (int a = 0; a < 3; ++a)
            for (int c = 0; c < 3; ++c)
              jac[(3 * k + a) * 18 + 3 * m + c] +=
                  c0 * phi[k] * phi[m] * (nds[c] * u[a] + (a == c ? un : 0.0));
      }
    }
  }
}

/// Assemble the Navier–Stokes Jacobian into `a` and the residual into `r` at the state.
/// With `shape` (a velocity per node, nonzero only on prescribed-velocity nodes), also
/// the lifting −J_{free,fixed}·shape into `lift`: the right-hand side of the field that
/// a unit amplitude of the prescribed velocity adds.
void assemble_ns(const TetMesh& mesh, const Numbering& num, const Mpi& mpi, const NsParams& prm, const State& st,
                 const std::vector<Vec3>* shape, Mat a, Vec r, Vec lift) {
  static const ReferenceNs ref;
  FLOWIRE_PETSC(MatZeroEntries(a));
  FLOWIRE_PETSC(VecSet(r, 0.0));
  if (shape) FLOWIRE_PETSC(VecSet(lift, 0.0));
  double lvals[34];
  const auto [e0, e1] = split(mesh.num_tets(), mpi.size, mpi.rank);
  double res[34], jac[34 * 34], prow[4 * 30];
  PetscInt idx[34];
  int bad = -1;
  for (long e = e0; e < e1; ++e) {
    if (!ns_element(mesh, ref, static_cast<int>(e), prm, st, res, jac)) {
      bad = static_cast<int>(e);
      break;
    }
    const auto& t = mesh.tets[static_cast<size_t>(e)];
    for (int i = 0; i < 10; ++i) {
      const PetscInt d = num.vdof[static_cast<size_t>(t[static_cast<size_t>(i)])];
      for (int c = 0; c < 3; ++c) idx[3 * i + c] = d >= 0 ? d + c : -1;
    }
    for (int l = 0; l < 4; ++l)
      idx[30 + l] = num.pdof[static_cast<size_t>(mesh.vertex_index[static_cast<size_t>(t[static_cast<size_t>(l)])])];
    // Velocity rows couple to everything; pressure rows only to velocities (the
    // pressure–pressure block is not in the pattern).
    FLOWIRE_PETSC(MatSetValues(a, 30, idx, 34, idx, jac, ADD_VALUES));
    for (int l = 0; l < 4; ++l) std::copy(jac + (30 + l) * 34, jac + (30 + l) * 34 + 30, prow + 30 * l);
    FLOWIRE_PETSC(MatSetValues(a, 4, idx + 30, 30, idx, prow, ADD_VALUES));
    add_to_vector(r, 34, idx, res);
    if (shape) {
      bool any = false;
      double w[30];
      for (int i = 0; i < 10; ++i)
        for (int c = 0; c < 3; ++c) {
          w[3 * i + c] = idx[3 * i + c] < 0 ? (*shape)[static_cast<size_t>(t[static_cast<size_t>(i)])][c] : 0.0;
          any = any || w[3 * i + c] != 0.0;
        }
      if (any) {
        for (int row = 0; row < 34; ++row) {
          double sum = 0.0;
          for (int col = 0; col < 30; ++col) sum += jac[row * 34 + col] * w[col];
          lvals[row] = -sum;
        }
        add_to_vector(lift, 34, idx, lvals);
      }
    }
  }
  const auto [f0, f1] = split(static_cast<long>(mesh.faces.size()), mpi.size, mpi.rank);
  double fres[18], fjac[18 * 18];
  for (long f = f0; f < f1; ++f) {
    const int g = mesh.face_group[static_cast<size_t>(f)];
    if (mesh.groups[static_cast<size_t>(g)].kind == BoundaryGroup::Kind::Wall) continue;
    bool any_jac = false;
    ns_face(mesh, static_cast<size_t>(f), prm, st, fres, fjac, any_jac);
    const auto& tri = mesh.faces[static_cast<size_t>(f)];
    for (int k = 0; k < 6; ++k) {
      const PetscInt d = num.vdof[static_cast<size_t>(tri[static_cast<size_t>(k)])];
      for (int c = 0; c < 3; ++c) idx[3 * k + c] = d >= 0 ? d + c : -1;
    }
    if (any_jac) FLOWIRE_PETSC(MatSetValues(a, 18, idx, 18, idx, fjac, ADD_VALUES));
    add_to_vector(r, 18, idx, fres);
  }
  FLOWIRE_PETSC(MatAssemblyBegin(a, MAT_FINAL_ASSEMBLY));
  FLOWIRE_PETSC(MatAssemblyEnd(a, MAT_FINAL_ASSEMBLY));
  FLOWIRE_PETSC(VecAssemblyBegin(r));
  FLOWIRE_PETSC(VecAssemblyEnd(r));
  if (shape) {
    FLOWIRE_PETSC(VecAssemblyBegin(lift));
    FLOWIRE_PETSC(VecAssemblyEnd(lift));
  }
  int any_bad = bad;
  MPI_Allreduce(&bad, &any_bad, 1, MPI_INT, MPI_MAX, PETSC_COMM_WORLD);
  if (any_bad >= 0)
    throw_numerical_error(fmt::format("fem: tetrahedron {} is inverted or degenerate (non-positive Jacobian of the "
                                      "curved element); use a smaller mesh size", any_bad));
}

/// Right-hand side: -p_k ∫ n·v over each inlet/outlet face; with `data`, also its body
/// force ∫ f·v and its traction ∫ g·v.
void assemble_rhs(const TetMesh& mesh, const Numbering& num, const Mpi& mpi, std::span<const double> group_pressure,
                  const StokesOptions* data, Vec b) {
  FLOWIRE_PETSC(VecSet(b, 0.0));
  const bool traction = data && data->traction;
  const auto [f0, f1] = split(static_cast<long>(mesh.faces.size()), mpi.size, mpi.rank);
  double phi[6], dphi[6][2];
  PetscInt rows[18];
  double vals[18];
  for (long f = f0; f < f1; ++f) {
    const int g = mesh.face_group[static_cast<size_t>(f)];
    if (mesh.groups[static_cast<size_t>(g)].kind == BoundaryGroup::Kind::Wall) continue;
    const double p = group_pressure[static_cast<size_t>(g)];
    if (p == 0.0 && !traction) continue;
    const auto& tri = mesh.faces[static_cast<size_t>(f)];
    std::fill(vals, vals + 18, 0.0);
    for (const QuadPoint& q : tri_quadrature()) {
      tri_p2(q.xi, phi);
      tri_p2_grad(q.xi, dphi);
      Vec3 ts = Vec3::Zero(), tt = Vec3::Zero(), xq = Vec3::Zero();
      for (int k = 0; k < 6; ++k) {
        const auto& xk = mesh.nodes[static_cast<size_t>(tri[static_cast<size_t>(k)])];
        ts += dphi[k][0] * xk;
        tt += dphi[k][1] * xk;
        xq += phi[k] * xk;
      }
      const Vec3 nds = ts.cross(tt);  // outward normal times the area element
      Vec3 load = -p * nds;
      if (traction) load += nds.norm() * data->traction(xq, nds.normalized(), g);
      for (int k = 0; k < 6; ++k)
        for (int c = 0; c < 3; ++c) vals[3 * k + c] += q.weight * phi[k] * load[c];
    }
    for (int k = 0; k < 6; ++k) {
      const PetscInt d = num.vdof[static_cast<size_t>(tri[static_cast<size_t>(k)])];
      for (int c = 0; c < 3; ++c) rows[3 * k + c] = d >= 0 ? d + c : -1;
    }
    add_to_vector(b, 18, rows, vals);
  }
  if (data && data->body_force) {
    static const Reference ref;
    const auto [e0, e1] = split(mesh.num_tets(), mpi.size, mpi.rank);
    PetscInt erows[30];
    double evals[30];
    for (long e = e0; e < e1; ++e) {
      const auto& t = mesh.tets[static_cast<size_t>(e)];
      std::fill(evals, evals + 30, 0.0);
      for (int q = 0; q < ref.nq; ++q) {
        Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
        Vec3 xq = Vec3::Zero();
        for (int i = 0; i < 10; ++i) {
          const auto& xi = mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(i)])];
          j += xi * Eigen::RowVector3d(ref.dphi[q][i][0], ref.dphi[q][i][1], ref.dphi[q][i][2]);
          xq += ref.phi[q][i] * xi;
        }
        const Vec3 fq = ref.w[q] * j.determinant() * data->body_force(xq);
        for (int i = 0; i < 10; ++i)
          for (int c = 0; c < 3; ++c) evals[3 * i + c] += ref.phi[q][i] * fq[c];
      }
      for (int i = 0; i < 10; ++i) {
        const PetscInt d = num.vdof[static_cast<size_t>(t[static_cast<size_t>(i)])];
        for (int c = 0; c < 3; ++c) erows[3 * i + c] = d >= 0 ? d + c : -1;
      }
      add_to_vector(b, 30, erows, evals);
    }
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

/// Groups whose pressure follows from a flow or resistance condition, and the known
/// pressures (0 on those groups).
void split_conditions(const TetMesh& mesh, std::span<const GroupCondition> cond, std::vector<int>& unknown,
                      std::vector<double>& known) {
  unknown.clear();
  known.assign(mesh.groups.size(), 0.0);
  for (size_t g = 0; g < mesh.groups.size(); ++g) {
    if (mesh.groups[g].kind == BoundaryGroup::Kind::Wall) continue;
    if (cond[g].type == GroupCondition::Type::Pressure) known[g] = cond[g].pressure;
    else unknown.push_back(static_cast<int>(g));
  }
}

/// The unit fields of the factorized matrix (pressure 1 on one unknown group, 0
/// elsewhere; no body force or traction) and their fluxes.
void unit_fields(System& sys, const TetMesh& mesh, const std::vector<int>& unknown, std::vector<StokesSolution>& units,
                 std::vector<std::vector<double>>& flux) {
  units.clear();
  flux.clear();
  for (int g : unknown) {
    std::vector<double> e(mesh.groups.size(), 0.0);
    e[static_cast<size_t>(g)] = 1.0;
    units.push_back(sys.solve(e, false));
    flux.push_back(units.back().group_flow);
  }
}

double max_abs(const std::vector<Vec3>& v) {
  double m = 0.0;
  for (const Vec3& x : v) m = std::max(m, x.cwiseAbs().maxCoeff());
  return m;
}

StokesSolution solve_linear_stokes(const TetMesh& mesh, std::span<const GroupCondition> cond, const StokesOptions& opt) {
  System sys(mesh, opt, false);
  std::vector<int> unknown;
  std::vector<double> known;
  split_conditions(mesh, cond, unknown, known);
  sys.prepare_stokes();
  StokesSolution sol = sys.solve(known, true);
  if (!unknown.empty()) {
    std::vector<StokesSolution> units;
    std::vector<std::vector<double>> flux;
    unit_fields(sys, mesh, unknown, units, flux);
    const std::vector<double> p = boundary_pressures(mesh, cond, unknown, sol.group_flow, flux);
    for (size_t k = 0; k < unknown.size(); ++k) add_scaled(sol, p[static_cast<size_t>(unknown[k])], units[k]);
  }
  sol.unknowns = sys.unknowns();
  sol.krylov_iterations = sys.krylov_iterations;
  sol.factorizations = sys.factorizations;
  sol.assemble_seconds = sys.assemble_seconds;
  sol.solve_seconds = sys.solve_seconds;
  return sol;
}

/// Mean of the (P1) pressure over boundary group g.
double mean_pressure(const TetMesh& mesh, const std::vector<double>& pressure, int g) {
  double sum = 0.0, area = 0.0, phi[6], dphi[6][2];
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.face_group[f] != g) continue;
    const auto& tri = mesh.faces[f];
    double pv[3];
    for (int k = 0; k < 3; ++k)
      pv[k] = pressure[static_cast<size_t>(mesh.vertex_index[static_cast<size_t>(tri[static_cast<size_t>(k)])])];
    for (const QuadPoint& q : tri_quadrature()) {
      tri_p2(q.xi, phi);
      tri_p2_grad(q.xi, dphi);
      Vec3 ts = Vec3::Zero(), tt = Vec3::Zero();
      for (int k = 0; k < 6; ++k) {
        ts += dphi[k][0] * mesh.nodes[static_cast<size_t>(tri[static_cast<size_t>(k)])];
        tt += dphi[k][1] * mesh.nodes[static_cast<size_t>(tri[static_cast<size_t>(k)])];
      }
      const double da = q.weight * ts.cross(tt).norm();
      const double l[3] = {1.0 - q.xi[0] - q.xi[1], q.xi[0], q.xi[1]};
      sum += da * (l[0] * pv[0] + l[1] * pv[1] + l[2] * pv[2]);
      area += da;
    }
  }
  return area > 0.0 ? sum / area : 0.0;
}

/// The prescribed inlet velocity shape of group g (zero elsewhere and on the wall):
/// `user(x)` when given, else the Poiseuille profile −n (1 − r²/R²) of the end disk
/// (centre, outward normal and radius from the faces; peak 1 m/s into the domain).
std::vector<Vec3> inlet_shape(const TetMesh& mesh, int g, const std::function<Vec3(const Vec3&)>& user) {
  std::vector<Vec3> shape(mesh.nodes.size(), Vec3::Zero());
  std::vector<char> wall(mesh.nodes.size(), 0), inlet(mesh.nodes.size(), 0);
  Vec3 centre = Vec3::Zero(), normal = Vec3::Zero();
  double area = 0.0, phi[6], dphi[6][2];
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& tri = mesh.faces[f];
    if (mesh.groups[static_cast<size_t>(mesh.face_group[f])].kind == BoundaryGroup::Kind::Wall)
      for (int n : tri) wall[static_cast<size_t>(n)] = 1;
    if (mesh.face_group[f] != g) continue;
    for (int n : tri) inlet[static_cast<size_t>(n)] = 1;
    for (const QuadPoint& q : tri_quadrature()) {
      tri_p2(q.xi, phi);
      tri_p2_grad(q.xi, dphi);
      Vec3 ts = Vec3::Zero(), tt = Vec3::Zero(), x = Vec3::Zero();
      for (int k = 0; k < 6; ++k) {
        const auto& xk = mesh.nodes[static_cast<size_t>(tri[static_cast<size_t>(k)])];
        ts += dphi[k][0] * xk;
        tt += dphi[k][1] * xk;
        x += phi[k] * xk;
      }
      const Vec3 nds = q.weight * ts.cross(tt);
      normal += nds;
      centre += nds.norm() * x;
      area += nds.norm();
    }
  }
  if (!(area > 0.0)) throw_usage_error(fmt::format("fem: boundary group {} has no faces", g));
  centre /= area;
  normal.normalize();
  const double r2 = area / std::numbers::pi;
  for (size_t n = 0; n < shape.size(); ++n) {
    if (!inlet[n] || wall[n]) continue;
    const Vec3& x = mesh.nodes[n];
    if (user) {
      shape[n] = user(x);
    } else {
      const Vec3 d = x - centre;
      const double rho2 = (d - d.dot(normal) * normal).squaredNorm();
      shape[n] = -std::max(0.0, 1.0 - rho2 / r2) * normal;
    }
  }
  return shape;
}

/// The unknowns of the small boundary system: the amplitude of the prescribed inlet
/// velocity (group `fixed`) and the pressures of the other groups without a pressure
/// condition.
struct BoundarySystem {
  const TetMesh& mesh;
  std::span<const GroupCondition> cond;
  int fixed = -1;              // group with a prescribed velocity shape, or -1
  std::vector<int> unknown;    // groups, `fixed` (if any) first

  /// The pressure of group g in field x: its imposed pressure, or for the fixed group
  /// the mean of the pressure field over it.
  [[nodiscard]] double pressure(const StokesSolution& x, int g) const {
    return g == fixed ? mean_pressure(mesh, x.pressure, g) : x.group_pressure[static_cast<size_t>(g)];
  }
  /// The condition of group g applied to field x (left side) and its target.
  [[nodiscard]] double lhs(const StokesSolution& x, int g) const {
    const auto& c = cond[static_cast<size_t>(g)];
    const double q = x.group_flow[static_cast<size_t>(g)];
    switch (c.type) {
      case GroupCondition::Type::Pressure: return pressure(x, g);
      case GroupCondition::Type::Flow: return q;
      case GroupCondition::Type::Resistance: return pressure(x, g) - c.resistance * q;
    }
    return 0.0;
  }
  [[nodiscard]] double target(int g) const {
    const auto& c = cond[static_cast<size_t>(g)];
    return c.type == GroupCondition::Type::Flow ? c.flow : c.pressure;
  }
  /// The values of the unknowns that make base + Σ z_j units[j] satisfy the conditions.
  [[nodiscard]] std::vector<double> solve(const StokesSolution& base, const std::vector<StokesSolution>& units) const {
    const auto n = static_cast<Eigen::Index>(unknown.size());
    Eigen::MatrixXd a(n, n);
    Eigen::VectorXd rhs(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const int g = unknown[static_cast<size_t>(i)];
      for (Eigen::Index j = 0; j < n; ++j) a(i, j) = lhs(units[static_cast<size_t>(j)], g);
      rhs[i] = target(g) - lhs(base, g);
      const double sc = a.row(i).cwiseAbs().maxCoeff();
      if (sc > 0.0) {
        a.row(i) /= sc;
        rhs[i] /= sc;
      }
    }
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(a);
    if (lu.rank() < n || lu.rcond() < 1e-13)
      throw_usage_error("fem: the boundary conditions do not determine the boundary values");
    const Eigen::VectorXd z = lu.solve(rhs);
    return {z.data(), z.data() + n};
  }
};

/// A Navier–Stokes iterate: the field and the amplitude of the prescribed inlet velocity.
struct NsState {
  StokesSolution x;
  double amplitude = 0.0;
};

/// Newton's method for Navier–Stokes at density `rho`, from `state` (updated in place
/// when it converges). Returns the number of Newton steps, or -1 when the iteration
/// fails (no convergence, growing updates, NaN, a failed factorization).
int newton(System& sys, const BoundarySystem& bs, const std::vector<Vec3>* shape, const StokesOptions& opt, double rho,
           NsState& state, int& steps_done) {
  NsParams prm = ns_params(opt);
  prm.rho = rho;
  const TetMesh& mesh = bs.mesh;
  NsState y = state;
  double last = std::numeric_limits<double>::infinity();
  // ρ = 0 is Stokes: linear, so one step solves it.
  const int max_it = rho == 0.0 ? 1 : std::max(1, opt.newton_max_iterations);
  for (int it = 1; it <= max_it; ++it) {
    const State st{&y.x.velocity, &y.x.pressure, &y.x.group_pressure};
    StokesSolution next;
    double amplitude = y.amplitude;
    try {
      sys.prepare_newton(prm, st, shape);
      ++steps_done;
      // The linearized field is affine in the unknown boundary values z (inlet amplitude,
      // unknown group pressures): x + δx₀ + Σ_j (z'_j − z_j) x_j.
      next = sys.solve_rhs();
      add_scaled(next, 1.0, y.x);
      if (!bs.unknown.empty()) {
        std::vector<StokesSolution> units;
        for (int g : bs.unknown) {
          if (g == bs.fixed) {
            StokesSolution ua = sys.solve_lift();
            for (size_t n = 0; n < ua.velocity.size(); ++n) ua.velocity[n] += (*shape)[n];
            ua.group_flow = group_fluxes(mesh, ua.velocity);
            add_scaled(next, -y.amplitude, ua);
            units.push_back(std::move(ua));
          } else {
            std::vector<double> e(mesh.groups.size(), 0.0);
            e[static_cast<size_t>(g)] = 1.0;
            units.push_back(sys.solve(e, false));
            add_scaled(next, -y.x.group_pressure[static_cast<size_t>(g)], units.back());
          }
        }
        const std::vector<double> z = bs.solve(next, units);
        for (size_t j = 0; j < units.size(); ++j) {
          add_scaled(next, z[j], units[j]);
          if (bs.unknown[j] == bs.fixed) amplitude = z[j];
        }
      }
    } catch (const Error& e) {
      if (e.kind() != ErrorKind::Numerical) throw;
      return -1;
    }
    double du = 0.0;
    for (size_t n = 0; n < next.velocity.size(); ++n)
      du = std::max(du, (next.velocity[n] - y.x.velocity[n]).cwiseAbs().maxCoeff());
    const double umax = max_abs(next.velocity);
    const double change = umax > 0.0 ? du / umax : 0.0;
    if (!std::isfinite(change)) return -1;
    y.x = std::move(next);
    y.amplitude = amplitude;
    if (rho == 0.0 || change <= opt.newton_tolerance) {
      state = std::move(y);
      return it;
    }
    // Newton may take a few long steps before it converges; updates that stay large
    // or grow after that mean the density step was too long.
    if (change > 1e2 || (it >= 6 && change > 0.5 * last)) return -1;
    last = change;
  }
  return -1;
}

double inlet_reynolds(const TetMesh& mesh, const StokesSolution& sol, double rho, double eta) {
  for (size_t g = 0; g < mesh.groups.size(); ++g)
    if (mesh.groups[g].kind == BoundaryGroup::Kind::Inlet) {
      const double area = mesh.area(static_cast<int>(g));
      const double d = 2.0 * std::sqrt(area / std::numbers::pi);
      return rho * std::abs(sol.group_flow[g]) / area * d / eta;
    }
  return 0.0;
}

StokesSolution solve_navier_stokes(const TetMesh& mesh, std::span<const GroupCondition> cond, const StokesOptions& opt) {
  if (!(opt.density >= 0.0) || !std::isfinite(opt.density)) throw_usage_error("fem: density must be >= 0");
  if (!(opt.backflow >= 0.0)) throw_usage_error("fem: the backflow coefficient must be >= 0");
  if (opt.solver != LinearSolver::Mumps)
    throw_usage_error("fem: Navier–Stokes needs the direct solver (mumps): the fieldsplit preconditioner's Schur "
                      "approximation (the pressure mass matrix) ignores convection");
  BoundarySystem bs{mesh, cond, -1, {}};
  if (opt.inlet == InletCondition::Profile) {
    for (size_t g = 0; g < mesh.groups.size(); ++g)
      if (mesh.groups[g].kind == BoundaryGroup::Kind::Inlet) bs.fixed = static_cast<int>(g);
    if (bs.fixed < 0) throw_usage_error("fem: the mesh has no inlet group for the inlet velocity profile");
    if (cond[static_cast<size_t>(bs.fixed)].type == GroupCondition::Type::Resistance)
      throw_usage_error("fem: an inlet with a velocity profile takes a pressure or a flow, not a resistance");
    bs.unknown.push_back(bs.fixed);
  }
  std::vector<int> unknown;
  std::vector<double> known;
  split_conditions(mesh, cond, unknown, known);
  for (int g : unknown)
    if (g != bs.fixed) bs.unknown.push_back(g);
  std::vector<Vec3> shape;
  if (bs.fixed >= 0) {
    shape = inlet_shape(mesh, bs.fixed, opt.inlet_velocity);
    known[static_cast<size_t>(bs.fixed)] = 0.0;
  }
  System sys(mesh, opt, true, bs.fixed);
  NsState state;
  state.x.velocity.assign(mesh.nodes.size(), Vec3::Zero());
  state.x.pressure.assign(static_cast<size_t>(mesh.num_vertices), 0.0);
  state.x.group_flow.assign(mesh.groups.size(), 0.0);
  state.x.group_pressure = known;
  const std::vector<Vec3>* sh = bs.fixed >= 0 ? &shape : nullptr;
  int newton_steps = 0, accepted = 0, tried = 0;
  double s = 0.0, ds = 1.0;
  if (const StokesSolution* guess = opt.initial_guess) {
    if (guess->velocity.size() != mesh.nodes.size() || guess->pressure.size() != state.x.pressure.size() ||
        guess->group_pressure.size() != mesh.groups.size())
      throw_usage_error("fem: the initial guess belongs to another mesh");
    NsState start = state;
    start.x.velocity = guess->velocity;
    start.x.pressure = guess->pressure;
    for (int g : bs.unknown) start.x.group_pressure[static_cast<size_t>(g)] = guess->group_pressure[static_cast<size_t>(g)];
    if (sh) {
      // The inlet velocity must be a multiple of the shape: the least-squares amplitude.
      double uw = 0.0, ww = 0.0;
      for (size_t n = 0; n < shape.size(); ++n) {
        uw += shape[n].dot(guess->velocity[n]);
        ww += shape[n].squaredNorm();
      }
      start.amplitude = ww > 0.0 ? uw / ww : 0.0;
      start.x.group_pressure[static_cast<size_t>(bs.fixed)] = 0.0;
      for (size_t n = 0; n < shape.size(); ++n)
        if (shape[n] != Vec3::Zero()) start.x.velocity[n] = start.amplitude * shape[n];
    }
    start.x.group_flow = group_fluxes(mesh, start.x.velocity);
    ++tried;
    if (newton(sys, bs, sh, opt, opt.density, start, newton_steps) >= 0) {
      state = std::move(start);
      s = 1.0;
      accepted = 1;
    }
  }
  if (s < 1.0 && newton(sys, bs, sh, opt, 0.0, state, newton_steps) < 0)
    throw_numerical_error("fem: the Stokes start of the Navier–Stokes solve failed");
  // Continuation in the density (Re ∝ ρ) from the Stokes solution.
  while (s < 1.0) {
    if (tried == opt.continuation_max_steps || ds < 1e-4) {
      throw_numerical_error(fmt::format(
          "fem: Navier–Stokes did not converge: the density continuation stalled at {:.3g} of the target "
          "(inlet Reynolds number {:.0f} reached; {} Newton steps in {} tries); refine the mesh or lower the "
          "Reynolds number",
          s, inlet_reynolds(mesh, state.x, s * opt.density, opt.viscosity), newton_steps, tried));
    }
    const double s_try = std::min(1.0, s + ds);
    ++tried;
    NsState y = state;
    const int its = newton(sys, bs, sh, opt, s_try * opt.density, y, newton_steps);
    if (its < 0) {
      ds *= 0.25;
      continue;
    }
    state = std::move(y);
    s = s_try;
    ++accepted;
    if (its <= 5) ds *= 2.0;
  }
  StokesSolution x = std::move(state.x);
  for (const Vec3& u : x.velocity)
    if (!u.allFinite()) throw_numerical_error("fem: the solution contains NaN");
  if (bs.fixed >= 0) x.group_pressure[static_cast<size_t>(bs.fixed)] = mean_pressure(mesh, x.pressure, bs.fixed);
  x.unknowns = sys.unknowns();
  x.krylov_iterations = sys.krylov_iterations;
  x.factorizations = sys.factorizations;
  x.newton_iterations = newton_steps;
  x.continuation_steps = accepted;
  x.reynolds = inlet_reynolds(mesh, x, opt.density, opt.viscosity);
  x.assemble_seconds = sys.assemble_seconds;
  x.solve_seconds = sys.solve_seconds;
  return x;
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
  return opt.equations == Equations::NavierStokes ? solve_navier_stokes(mesh, cond, opt)
                                                  : solve_linear_stokes(mesh, cond, opt);
}

StokesBasis::StokesBasis(const TetMesh& mesh, const StokesOptions& opt) : mesh_(mesh) {
  if (opt.equations != Equations::Stokes)
    throw_usage_error("fem: the boundary-value basis is for Stokes only (Navier–Stokes is not linear)");
  if (!(opt.viscosity > 0.0)) throw_usage_error("fem: viscosity must be > 0");
  if (mesh.tets.empty()) throw_usage_error("fem: empty mesh");
  if (opt.body_force || opt.traction)
    throw_usage_error("fem: the boundary-value basis takes no body force or traction");
  ensure_petsc();
  System sys(mesh, opt, false);
  sys.prepare_stokes();
  for (size_t g = 0; g < mesh.groups.size(); ++g) {
    if (mesh.groups[g].kind == BoundaryGroup::Kind::Wall) continue;
    open_.push_back(static_cast<int>(g));
    std::vector<double> e(mesh.groups.size(), 0.0);
    e[g] = 1.0;
    unit_.push_back(sys.solve(e, false));
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
  sol.factorizations = 1;
  return sol;
}

struct UnsteadyStokes::Impl {
  Impl(const TetMesh& m, const StokesOptions& o) : mesh(m), sys(m, o, false) {}
  ~Impl() {
    for (Vec* v : {&prev, &curr, &hist})
      if (*v) VecDestroy(v);
    for (Vec& v : units) VecDestroy(&v);
  }
  const TetMesh& mesh;
  System sys;
  double rho = 0.0, dt = 0.0, time = 0.0;
  int steps = 0;
  std::vector<int> open;
  std::vector<Vec> units;                   // unit fields (pressure 1 on open[k])
  std::vector<std::vector<double>> flux;    // their fluxes
  Vec prev = nullptr, curr = nullptr, hist = nullptr;  // x^{n−1}, x^n, scratch
  StokesSolution current;
};

UnsteadyStokes::UnsteadyStokes(const TetMesh& mesh, const StokesOptions& opt, double dt) {
  if (opt.equations != Equations::Stokes)
    throw_usage_error("fem: time-dependent solves are for Stokes (Navier–Stokes frames are solved one by one)");
  if (opt.body_force || opt.traction) throw_usage_error("fem: time-dependent Stokes takes no body force or traction");
  if (!(opt.viscosity > 0.0)) throw_usage_error("fem: viscosity must be > 0");
  if (!(opt.density > 0.0) || !std::isfinite(opt.density)) throw_usage_error("fem: density must be > 0");
  if (!(dt > 0.0) || !std::isfinite(dt)) throw_usage_error("fem: the time step must be > 0");
  if (mesh.tets.empty()) throw_usage_error("fem: empty mesh");
  ensure_petsc();
  impl_ = std::make_unique<Impl>(mesh, opt);
  Impl& m = *impl_;
  m.rho = opt.density;
  m.dt = dt;
  // BDF2: (3u^{n+1} − 4u^n + u^{n−1})/(2Δt): the matrix is K + (3ρ/2Δt) M.
  m.sys.prepare_unsteady(1.5 * opt.density / dt);
  m.prev = m.sys.new_vector();
  m.curr = m.sys.new_vector();
  m.hist = m.sys.new_vector();
  for (size_t g = 0; g < mesh.groups.size(); ++g) {
    if (mesh.groups[g].kind == BoundaryGroup::Kind::Wall) continue;
    m.open.push_back(static_cast<int>(g));
    std::vector<double> e(mesh.groups.size(), 0.0);
    e[g] = 1.0;
    FLOWIRE_PETSC(VecSet(m.hist, 0.0));
    m.flux.push_back(m.sys.solve_with_history(e, m.hist).group_flow);
    m.units.push_back(m.sys.new_vector());
    FLOWIRE_PETSC(VecCopy(m.sys.x(), m.units.back()));
  }
  m.current.velocity.assign(mesh.nodes.size(), Vec3::Zero());
  m.current.pressure.assign(static_cast<size_t>(mesh.num_vertices), 0.0);
  m.current.group_flow.assign(mesh.groups.size(), 0.0);
  m.current.group_pressure.assign(mesh.groups.size(), 0.0);
}

UnsteadyStokes::~UnsteadyStokes() = default;

const StokesSolution& UnsteadyStokes::step(std::span<const GroupCondition> cond) {
  Impl& m = *impl_;
  // History h = ρ(4u^n − u^{n−1})/(2Δt); the field with zero group pressures, then the
  // group pressures from the conditions (every open group is a column of the small
  // system, as in StokesBasis), then the combination.
  FLOWIRE_PETSC(VecAXPBYPCZ(m.hist, 4.0 * m.rho / (2.0 * m.dt), -m.rho / (2.0 * m.dt), 0.0, m.curr, m.prev));
  const std::vector<double> zero(m.mesh.groups.size(), 0.0);
  const StokesSolution base = m.sys.solve_with_history(zero, m.hist);
  const std::vector<double> p = boundary_pressures(m.mesh, cond, m.open, base.group_flow, m.flux);
  std::swap(m.prev, m.curr);
  FLOWIRE_PETSC(VecCopy(m.sys.x(), m.curr));
  for (size_t k = 0; k < m.open.size(); ++k)
    FLOWIRE_PETSC(VecAXPY(m.curr, p[static_cast<size_t>(m.open[k])], m.units[k]));
  m.current = m.sys.gather(m.curr);
  m.current.group_pressure = p;
  m.current.unknowns = m.sys.unknowns();
  m.current.factorizations = m.sys.factorizations;
  m.current.assemble_seconds = m.sys.assemble_seconds;
  m.current.solve_seconds = m.sys.solve_seconds;
  for (const Vec3& u : m.current.velocity)
    if (!u.allFinite()) throw_numerical_error("fem: time-dependent Stokes produced NaN");
  m.time += m.dt;
  ++m.steps;
  return m.current;
}

const StokesSolution& UnsteadyStokes::current() const { return impl_->current; }
double UnsteadyStokes::time() const { return impl_->time; }
double UnsteadyStokes::dt() const { return impl_->dt; }
const std::vector<std::vector<double>>& UnsteadyStokes::unit_flux() const { return impl_->flux; }
const std::vector<int>& UnsteadyStokes::open_groups() const { return impl_->open; }

std::vector<Vec3> boundary_forces(const TetMesh& mesh, const StokesSolution& sol, const StokesOptions& opt) {
  if (sol.velocity.size() != mesh.nodes.size() || sol.pressure.size() != static_cast<size_t>(mesh.num_vertices) ||
      sol.group_pressure.size() != mesh.groups.size())
    throw_usage_error("fem: boundary_forces: the solution belongs to another mesh");
  static const ReferenceNs ref;
  NsParams prm = ns_params(opt);
  if (opt.equations == Equations::Stokes) prm.rho = 0.0;
  const State st{&sol.velocity, &sol.pressure, &sol.group_pressure};
  // A profile inlet carries a prescribed velocity: its traction is not part of the
  // residual.
  const bool profile = opt.equations == Equations::NavierStokes && opt.inlet == InletCondition::Profile;
  std::vector<Vec3> force(mesh.groups.size(), Vec3::Zero());
  std::vector<int> mark(mesh.nodes.size(), -1);
  double res[34], jac[34 * 34], fres[18], fjac[18 * 18];
  for (size_t g = 0; g < mesh.groups.size(); ++g) {
    if (!mesh.groups[g].no_slip()) continue;
    const int tag = static_cast<int>(g);
    for (size_t f = 0; f < mesh.faces.size(); ++f)
      if (mesh.face_group[f] == tag)
        for (int n : mesh.faces[f]) mark[static_cast<size_t>(n)] = tag;
    Vec3 sum = Vec3::Zero();
    for (int e = 0; e < mesh.num_tets(); ++e) {
      const auto& t = mesh.tets[static_cast<size_t>(e)];
      bool touches = false;
      for (int n : t) touches = touches || mark[static_cast<size_t>(n)] == tag;
      if (!touches) continue;
      if (!ns_element(mesh, ref, e, prm, st, res, jac))
        throw_numerical_error(fmt::format("fem: tetrahedron {} is inverted or degenerate", e));
      for (int i = 0; i < 10; ++i)
        if (mark[static_cast<size_t>(t[static_cast<size_t>(i)])] == tag)
          sum -= Vec3(res[3 * i], res[3 * i + 1], res[3 * i + 2]);
    }
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      const auto& grp = mesh.groups[static_cast<size_t>(mesh.face_group[f])];
      if (grp.no_slip() || (profile && grp.kind == BoundaryGroup::Kind::Inlet)) continue;
      const auto& tri = mesh.faces[f];
      bool touches = false;
      for (int n : tri) touches = touches || mark[static_cast<size_t>(n)] == tag;
      if (!touches) continue;
      bool any = false;
      ns_face(mesh, f, prm, st, fres, fjac, any);
      for (int k = 0; k < 6; ++k)
        if (mark[static_cast<size_t>(tri[static_cast<size_t>(k)])] == tag)
          sum -= Vec3(fres[3 * k], fres[3 * k + 1], fres[3 * k + 2]);
    }
    force[g] = sum;
  }
  return force;
}

std::vector<Vec3> surface_forces(const TetMesh& mesh, const StokesSolution& sol, double viscosity) {
  if (sol.velocity.size() != mesh.nodes.size() || sol.pressure.size() != static_cast<size_t>(mesh.num_vertices))
    throw_usage_error("fem: surface_forces: the solution belongs to another mesh");
  // The tetrahedron behind each boundary triangle and the local vertices of the triangle.
  struct Key {
    std::array<int, 3> v;
    bool operator<(const Key& o) const { return v < o.v; }
  };
  std::map<Key, size_t> face_of;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (!mesh.groups[static_cast<size_t>(mesh.face_group[f])].no_slip()) continue;
    Key k{{mesh.faces[f][0], mesh.faces[f][1], mesh.faces[f][2]}};
    std::sort(k.v.begin(), k.v.end());
    face_of.emplace(k, f);
  }
  static constexpr int kFaceVerts[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  static const std::array<std::array<double, 3>, 4> kVert{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  std::vector<Vec3> force(mesh.groups.size(), Vec3::Zero());
  double phi[6], dphi[6][2], g10[10][3], psi[4];
  for (const auto& t : mesh.tets)
    for (const auto& fv : kFaceVerts) {
      Key k{{t[static_cast<size_t>(fv[0])], t[static_cast<size_t>(fv[1])], t[static_cast<size_t>(fv[2])]}};
      std::sort(k.v.begin(), k.v.end());
      const auto it = face_of.find(k);
      if (it == face_of.end()) continue;
      const auto& tri = mesh.faces[it->second];
      // Tetrahedron-local vertex of each triangle vertex.
      int local[3];
      for (int a = 0; a < 3; ++a)
        for (int l = 0; l < 4; ++l)
          if (t[static_cast<size_t>(l)] == tri[static_cast<size_t>(a)]) local[a] = l;
      Vec3 sum = Vec3::Zero();
      for (const QuadPoint& q : tri_quadrature()) {
        tri_p2(q.xi, phi);
        tri_p2_grad(q.xi, dphi);
        Vec3 ts = Vec3::Zero(), tt = Vec3::Zero();
        for (int m = 0; m < 6; ++m) {
          ts += dphi[m][0] * mesh.nodes[static_cast<size_t>(tri[static_cast<size_t>(m)])];
          tt += dphi[m][1] * mesh.nodes[static_cast<size_t>(tri[static_cast<size_t>(m)])];
        }
        const Vec3 nds = ts.cross(tt);  // outward normal times the area element
        const double lam[3] = {1.0 - q.xi[0] - q.xi[1], q.xi[0], q.xi[1]};
        std::array<double, 3> xi{};
        for (int a = 0; a < 3; ++a)
          for (int c = 0; c < 3; ++c) xi[static_cast<size_t>(c)] += lam[a] * kVert[static_cast<size_t>(local[a])][static_cast<size_t>(c)];
        tet_p2_grad(xi, g10);
        tet_p1(xi, psi);
        Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
        for (int i = 0; i < 10; ++i)
          j += mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(i)])] * Eigen::RowVector3d(g10[i][0], g10[i][1], g10[i][2]);
        const Eigen::Matrix3d jinv_t = j.inverse().transpose();
        Eigen::Matrix3d grad = Eigen::Matrix3d::Zero();
        for (int i = 0; i < 10; ++i)
          grad += sol.velocity[static_cast<size_t>(t[static_cast<size_t>(i)])] *
                  (jinv_t * Eigen::Vector3d(g10[i][0], g10[i][1], g10[i][2])).transpose();
        double p = 0.0;
        for (int l = 0; l < 4; ++l)
          p += psi[l] * sol.pressure[static_cast<size_t>(mesh.vertex_index[static_cast<size_t>(t[static_cast<size_t>(l)])])];
        const Eigen::Matrix3d sigma = -p * Eigen::Matrix3d::Identity() + viscosity * (grad + grad.transpose());
        sum -= q.weight * (sigma * nds);
      }
      force[static_cast<size_t>(mesh.face_group[it->second])] += sum;
    }
  return force;
}

namespace detail {

bool navier_stokes_element(const TetMesh& mesh, int tet, const StokesOptions& opt, const std::vector<Vec3>& velocity,
                           const std::vector<double>& pressure, double* res, double* jac) {
  static const ReferenceNs ref;
  const State st{&velocity, &pressure, nullptr};
  return ns_element(mesh, ref, tet, ns_params(opt), st, res, jac);
}

void navier_stokes_face(const TetMesh& mesh, int face, const StokesOptions& opt, const std::vector<Vec3>& velocity,
                        const std::vector<double>& group_pressure, double* res, double* jac) {
  const State st{&velocity, nullptr, &group_pressure};
  bool any = false;
  ns_face(mesh, static_cast<size_t>(face), ns_params(opt), st, res, jac, any);
}

}  // namespace detail

void initialize() { ensure_petsc(); }

}  // namespace flowire::fem
