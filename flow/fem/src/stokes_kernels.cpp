// Taylor–Hood P2/P1 element matrices (Stokes) and element residuals and Jacobians
// (Navier–Stokes with SUPG/LSIC/backflow), and their assembly into PETSc objects.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numbers>

#include "stokes_internal.hpp"

namespace flowire::flow::fem::internal {

namespace {
/// @p bad: the first inverted tetrahedron this rank met, or −1. Every rank throws if any met one.
void throw_if_any_inverted(int bad) {
  int any_bad = bad;
  MPI_Allreduce(&bad, &any_bad, 1, MPI_INT, MPI_MAX, PETSC_COMM_WORLD);
  if (any_bad >= 0)
    throw_numerical_error(
        fmt::format("fem: tetrahedron {} is inverted or degenerate (non-positive Jacobian of the "
                    "curved element); use a smaller mesh size",
                    any_bad));
}
}  // namespace

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
    for (int i = 0; i < 10; ++i)
      j += x[i] * Eigen::RowVector3d(ref.dphi[q][i][0], ref.dphi[q][i][1], ref.dphi[q][i][2]);
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

void assemble(const TetMesh& mesh, const Numbering& num, const Mpi& mpi, const StokesOptions& opt, Mat a, Mat mp,
              double mass_coef, Mat mass) {
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
  throw_if_any_inverted(bad);
}

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

bool ns_element(const TetMesh& mesh, const ReferenceNs& ref, int e, const NsParams& prm, const State& st, double* res,
                double* jac) {
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
    for (int i = 0; i < 10; ++i)
      j += x[i] * Eigen::RowVector3d(ref.dphi[q][i][0], ref.dphi[q][i][1], ref.dphi[q][i][2]);
    const double det = j.determinant();
    if (!(det > 0.0)) return false;
    const Eigen::Matrix3d jinv = j.inverse();
    const Eigen::Matrix3d jinv_t = jinv.transpose();
    const double* phi = ref.phi[q];
    const double* psi = ref.psi[q];
    Eigen::Vector3d g[10];
    for (int i = 0; i < 10; ++i)
      g[i] = jinv_t * Eigen::Vector3d(ref.dphi[q][i][0], ref.dphi[q][i][1], ref.dphi[q][i][2]);
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
    Vec3 load = pk * nds;  // residual: + p_k ∫ n·v − ∫ g·v
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
              jac[(3 * k + a) * 18 + 3 * m + c] += c0 * phi[k] * phi[m] * (nds[c] * u[a] + (a == c ? un : 0.0));
      }
    }
  }
}

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
  throw_if_any_inverted(bad);
}

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

}  // namespace flowire::flow::fem::internal

namespace flowire::flow::fem::detail {

using internal::ns_element;
using internal::ns_face;
using internal::ns_params;
using internal::ReferenceNs;
using internal::State;

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

}  // namespace flowire::flow::fem::detail
