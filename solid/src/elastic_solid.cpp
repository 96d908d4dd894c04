// The hyperelastic solid: geometry at the quadrature points computed once, the tangent's
// pattern and each element's place in it found once, then energy, gradient and tangent
// assembled element by element, and Newton with CHOLMOD's supernodal Cholesky.
#include "flowire/solid/elastic_solid.hpp"

#include <fmt/format.h>

#include <omp.h>

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "flowire/common/element.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/kernel_clones.hpp"

namespace flowire::solid {
namespace {

constexpr int kQuad = 4;   // quadrature points a tetrahedron
constexpr int kGeom = 31;  // ∇N (10 × 3) and weight·det J per point
using Grad = Eigen::Matrix<double, 10, 3>;

// The forward solve on one supernode's tail: its columns off .. nscol − 1 (values column-major,
// leading dimension nsrow, the diagonal block first) against @p nrhs right-hand sides gathered on
// its rows off .. nsrow − 1, each contiguous (right-hand side r at x + r·m). Columns are taken
// kBlock at a time: the block's triangle first, then the rows below updated by all its columns
// at once, so that each right-hand side is swept once a block instead of once a column (the
// block's columns stay in cache for the next right-hand side).
FLOWIRE_KERNEL_CLONES
void supernode_forward(const double* lx, int nsrow, int off, int nscol, int nrhs, double* x) {
  constexpr int kBlock = 8;
  const int m = nsrow - off, ncol = nscol - off;
  const auto ld = static_cast<size_t>(nsrow);
  const double* base = lx + static_cast<size_t>(off) * ld + off;  // row i, column j of the tail: base[j·ld + i]
  // Blocks start at the supernode's columns 0, 8, 16, ...: a right-hand side entering at a later
  // column than the tail's has zeros before it, so its sums are the same terms in the same order
  // whichever batch it is solved in.
  for (int j0 = 0; j0 < ncol;) {
    const int jb = std::min(kBlock - (off + j0) % kBlock, ncol - j0);
    const double* __restrict c0 = base + static_cast<size_t>(j0) * ld;
    for (int r = 0; r < nrhs; ++r) {
      double* __restrict xr = x + static_cast<size_t>(r) * static_cast<size_t>(m);
      for (int j = j0; j < j0 + jb; ++j) {  // the block's triangle
        const double* col = base + static_cast<size_t>(j) * ld;
        const double a = (xr[j] /= col[j]);
        for (int i = j + 1; i < j0 + jb; ++i) xr[i] -= col[i] * a;
      }
      double a[kBlock] = {};
      bool any = false;
      for (int jj = 0; jj < jb; ++jj) any = ((a[jj] = xr[j0 + jj]) != 0.0) || any;
      if (!any) continue;  // a load whose reach these columns are not on
      if (jb == kBlock) {
        for (int i = j0 + kBlock; i < m; ++i) {
          double sum = 0.0;
          for (int jj = 0; jj < kBlock; ++jj) sum += c0[static_cast<size_t>(jj) * ld + i] * a[jj];
          xr[i] -= sum;
        }
      } else {  // a narrower block (the first or the last of the tail)
        for (int i = j0 + jb; i < m; ++i) {
          double sum = 0.0;
          for (int jj = 0; jj < jb; ++jj) sum += c0[static_cast<size_t>(jj) * ld + i] * a[jj];
          xr[i] -= sum;
        }
      }
    }
    j0 += jb;
  }
}

Mat3 displacement_gradient(const double* g, const std::array<int, 10>& tet, const Eigen::VectorXd& u) {
  Mat3 e = Mat3::Zero();
  for (int k = 0; k < 10; ++k) {
    const auto uk = u.segment<3>(3 * tet[static_cast<size_t>(k)]);
    for (int b = 0; b < 3; ++b) e.col(b) += uk * g[3 * k + b];
  }
  return e;
}

/// Index into a compressed matrix's values of its (existing) entry (row, col).
int pattern_position(const Eigen::SparseMatrix<double>& pattern, int row, int col) {
  const int* begin = pattern.innerIndexPtr() + pattern.outerIndexPtr()[col];
  const int* end = pattern.innerIndexPtr() + pattern.outerIndexPtr()[col + 1];
  return static_cast<int>(std::lower_bound(begin, end, row) - pattern.innerIndexPtr());
}

/// Every quadrature point of the curved faces of `group` (all groups when `group` < 0):
/// visit(face, shape values (6), point, outward area vector (|·| = the point's weight·dA)).
template <class Visit>
void for_face_points(const mesh::TetMesh& m, int group, Visit&& visit) {
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (group >= 0 && m.face_group[f] != group) continue;
    const auto& face = m.faces[f];
    for (const auto& q : element::tri_quadrature()) {
      double nval[6], ngrad[6][2];
      element::tri_p2(q.xi, nval);
      element::tri_p2_grad(q.xi, ngrad);
      Vec3 x = Vec3::Zero(), ds = Vec3::Zero(), dt = Vec3::Zero();
      for (int k = 0; k < 6; ++k) {
        const Vec3& xk = m.nodes[static_cast<size_t>(face[static_cast<size_t>(k)])];
        x += xk * nval[k];
        ds += xk * ngrad[k][0];
        dt += xk * ngrad[k][1];
      }
      visit(f, nval, x, Vec3(ds.cross(dt) * q.weight));
    }
  }
}

}  // namespace

std::vector<Mat3> ElasticSolid::nodal_stress(const Eigen::VectorXd& u) const {
  // Each tetrahedron's stress at its own ten nodes (the P2 map's gradient there), averaged over
  // the tetrahedra a node belongs to.
  static constexpr std::array<std::array<double, 3>, 10> kNodes{{{0, 0, 0},
                                                                 {1, 0, 0},
                                                                 {0, 1, 0},
                                                                 {0, 0, 1},
                                                                 {0.5, 0, 0},
                                                                 {0.5, 0.5, 0},
                                                                 {0, 0.5, 0},
                                                                 {0, 0, 0.5},
                                                                 {0.5, 0, 0.5},
                                                                 {0, 0.5, 0.5}}};
  std::vector<Mat3> sigma(static_cast<size_t>(mesh_.num_nodes()), Mat3::Zero());
  std::vector<int> count(static_cast<size_t>(mesh_.num_nodes()), 0);
  for (size_t t = 0; t < mesh_.tets.size(); ++t) {
    const auto& tet = mesh_.tets[t];
    for (size_t k = 0; k < 10; ++k) {
      double dref[10][3];
      element::tet_p2_grad(kNodes[k], dref);
      Mat3 jac = Mat3::Zero();
      for (int a = 0; a < 10; ++a)
        for (int b = 0; b < 3; ++b)
          jac.col(b) += mesh_.nodes[static_cast<size_t>(tet[static_cast<size_t>(a)])] * dref[a][b];
      const Mat3 inv = jac.inverse();
      double g[30];
      for (int a = 0; a < 10; ++a)
        for (int b = 0; b < 3; ++b)
          g[3 * a + b] = dref[a][0] * inv(0, b) + dref[a][1] * inv(1, b) + dref[a][2] * inv(2, b);
      const Mat3 h = displacement_gradient(g, tet, u);
      const Mat3 f = Mat3::Identity() + h;
      const auto node = static_cast<size_t>(tet[k]);
      sigma[node] += law_of(static_cast<int>(t)).stress(h) * f.transpose() / f.determinant();
      ++count[node];
    }
  }
  for (size_t n = 0; n < sigma.size(); ++n)
    if (count[n] > 0) sigma[n] /= count[n];
  return sigma;
}

void ElasticSolid::set_laws(std::vector<NeoHookean> laws, std::vector<int> tet_law) {
  if (laws.empty() || tet_law.size() != mesh_.tets.size())
    throw_usage_error(fmt::format("wall: {} laws for {} tetrahedra", tet_law.size(), mesh_.tets.size()));
  for (const auto& l : laws)
    if (!(l.mu > 0.0) || !(l.lambda > -2.0 / 3.0 * l.mu))
      throw_usage_error("wall: the material needs μ > 0 and a positive bulk modulus");
  for (int i : tet_law)
    if (i < 0 || i >= static_cast<int>(laws.size()))
      throw_usage_error(fmt::format("wall: law {} of {}", i, laws.size()));
  laws_ = std::move(laws);
  tet_law_ = std::move(tet_law);
  linearized_ = false;
}

struct ElasticSolid::Factor {
  /// Eigen's supernodal LLᵀ with its CHOLMOD factor in reach (for the sparse solves).
  struct Llt : Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> {
    cholmod_factor* factor() const { return m_cholmodFactor; }
  };
  Factor() {
    cholmod_common& c = llt.cholmod();
    c.print = 0;  // an indefinite tangent is reported by the solid (one error), not also by CHOLMOD
    // Nested dissection always (METIS): its elimination tree is shallow, its top levels the
    // separators, so a forward solve from one node (half_solve) reaches a few per cent of the
    // rows; CHOLMOD's default may keep AMD, whose tree along a long tube is a chain.
    c.nmethods = 1;
    c.method[0].ordering = CHOLMOD_METIS;
  }
  Factor(const Factor&) = delete;
  Factor& operator=(const Factor&) = delete;
  /// Drop the sparse solve's maps (after a new factorization).
  void forget_maps() { col_super.clear(); }
  Llt llt;
  bool analysed = false;
  // For half_solve, made by prepare_half_solve after each factorization: the inverse permutation,
  // each column's supernode, each supernode's parent in the supernodal elimination tree; and the
  // workspace of the calls that bring none.
  std::vector<int> iperm, col_super, parent;
  HalfSolveWork work;
};

ElasticSolid::ElasticSolid(mesh::TetMesh mesh, NeoHookean law)
    : mesh_(std::move(mesh)), laws_{law}, factor_(std::make_unique<Factor>()) {
  if (!(law.mu > 0.0) || !(law.lambda > -2.0 / 3.0 * law.mu))
    throw_usage_error("wall: the material needs μ > 0 and a positive bulk modulus");
  const int n = num_dofs();
  const auto nt = static_cast<size_t>(mesh_.num_tets());
  // Geometry at the quadrature points (curved elements: the Jacobian at each point).
  geometry_.resize(nt * kQuad * kGeom);
  const auto rule = element::tet_quadrature_degree2();
  for (size_t t = 0; t < nt; ++t) {
    const auto& tet = mesh_.tets[t];
    for (int q = 0; q < kQuad; ++q) {
      double dref[10][3];
      element::tet_p2_grad(rule[static_cast<size_t>(q)].xi, dref);
      Mat3 jac = Mat3::Zero();  // jac(a, b) = ∂X_a/∂ξ_b
      for (int k = 0; k < 10; ++k)
        for (int b = 0; b < 3; ++b)
          jac.col(b) += mesh_.nodes[static_cast<size_t>(tet[static_cast<size_t>(k)])] * dref[k][b];
      const double det = jac.determinant();
      if (!(det > 0.0))
        throw_input_error("wall mesh", fmt::format("tetrahedron {} is inverted or flat (det J = {:.3g})", t, det));
      const Mat3 inv = jac.inverse();
      double* g = &geometry_[(t * kQuad + static_cast<size_t>(q)) * kGeom];
      for (int k = 0; k < 10; ++k)
        for (int b = 0; b < 3; ++b) {
          double s = 0.0;
          for (int c = 0; c < 3; ++c) s += dref[k][c] * inv(c, b);  // ∂N/∂X_b = Σ_c ∂N/∂ξ_c ∂ξ_c/∂X_b
          g[3 * k + b] = s;
        }
      g[30] = rule[static_cast<size_t>(q)].weight * det;
    }
  }
  // The tangent's pattern: every node pair of a tetrahedron, 3 × 3 a pair.
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(nt * 900);
  for (const auto& tet : mesh_.tets)
    for (int k : tet)
      for (int l : tet)
        for (int a = 0; a < 3; ++a)
          for (int c = 0; c < 3; ++c) trip.emplace_back(3 * k + a, 3 * l + c, 0.0);
  pattern_.resize(n, n);
  pattern_.setFromTriplets(trip.begin(), trip.end());
  pattern_.makeCompressed();
  scatter_.resize(nt * 300);
  for (size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 10; ++k)
      for (int l = 0; l < 10; ++l)
        for (int c = 0; c < 3; ++c)
          scatter_[t * 300 + static_cast<size_t>(30 * k + 3 * l + c)] = pattern_position(
              pattern_, 3 * mesh_.tets[t][static_cast<size_t>(k)], 3 * mesh_.tets[t][static_cast<size_t>(l)] + c);
  support_.resize(n, n);
  group_pressure_.resize(mesh_.groups.size());
  pressure_forces_ = Eigen::VectorXd::Zero(n);
  nodal_forces_ = Eigen::VectorXd::Zero(n);
  held_.assign(static_cast<size_t>(n), 0);
  u_ = Eigen::VectorXd::Zero(n);
}

ElasticSolid::~ElasticSolid() = default;
ElasticSolid::ElasticSolid(ElasticSolid&&) noexcept = default;
ElasticSolid& ElasticSolid::operator=(ElasticSolid&&) noexcept = default;

void ElasticSolid::hold(int group, std::array<bool, 3> components) {
  for (size_t f = 0; f < mesh_.faces.size(); ++f)
    if (mesh_.face_group[f] == group)
      for (int node : mesh_.faces[f])
        for (int c = 0; c < 3; ++c)
          if (components[static_cast<size_t>(c)]) held_[static_cast<size_t>(3 * node + c)] = 1;
}

void ElasticSolid::support(int group, double stiffness_per_area) {
  if (!(stiffness_per_area >= 0.0) || !std::isfinite(stiffness_per_area))
    throw_usage_error(fmt::format("wall: support stiffness must be >= 0 Pa/m, got {}", stiffness_per_area));
  std::vector<Eigen::Triplet<double>> trip;
  for_face_points(mesh_, group, [&](size_t f, const double* nval, const Vec3&, const Vec3& area) {
    const auto& face = mesh_.faces[f];
    const double w = area.norm() * stiffness_per_area;
    for (int k = 0; k < 6; ++k)
      for (int l = 0; l < 6; ++l)
        for (int c = 0; c < 3; ++c)
          trip.emplace_back(3 * face[static_cast<size_t>(k)] + c, 3 * face[static_cast<size_t>(l)] + c,
                            w * nval[k] * nval[l]);
  });
  Eigen::SparseMatrix<double> add(num_dofs(), num_dofs());
  add.setFromTriplets(trip.begin(), trip.end());
  support_ += add;
  support_.makeCompressed();
  support_scatter_.clear();
  for (int col = 0; col < support_.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(support_, col); it; ++it)
      support_scatter_.push_back(pattern_position(pattern_, static_cast<int>(it.row()), col));
}

void ElasticSolid::set_pressure(int group, double pressure) {
  if (!std::isfinite(pressure)) throw_usage_error("wall: the pressure must be a finite number of Pa");
  set_pressure(group, [pressure](const Vec3&) { return pressure; });
}

void ElasticSolid::set_pressure(int group, std::function<double(const Vec3&)> pressure) {
  if (group < 0 || group >= static_cast<int>(mesh_.groups.size()))
    throw_usage_error(fmt::format("wall: no boundary group {}", group));
  group_pressure_[static_cast<size_t>(group)] = std::move(pressure);
  pressure_forces_.setZero();
  for_face_points(mesh_, -1, [&](size_t f, const double* nval, const Vec3& x, const Vec3& area) {
    const auto& field = group_pressure_[static_cast<size_t>(mesh_.face_group[f])];
    if (!field) return;
    const double p = field(x);
    if (!std::isfinite(p))
      throw_usage_error(fmt::format("wall: the pressure at ({:.4g}, {:.4g}, {:.4g}) m is {}", x.x(), x.y(), x.z(), p));
    for (int k = 0; k < 6; ++k)
      pressure_forces_.segment<3>(3 * mesh_.faces[f][static_cast<size_t>(k)]) -= p * nval[k] * area;
  });
}

Eigen::SparseMatrix<double> ElasticSolid::pressure_basis(
    int group, int fields,
    const std::function<void(const Vec3&, std::vector<std::pair<int, double>>&)>& weights) const {
  if (group < 0 || group >= static_cast<int>(mesh_.groups.size()))
    throw_usage_error(fmt::format("wall: no boundary group {}", group));
  std::vector<Eigen::Triplet<double>> trip;
  std::vector<std::pair<int, double>> w;
  for_face_points(mesh_, group, [&](size_t f, const double* nval, const Vec3& x, const Vec3& area) {
    w.clear();
    weights(x, w);
    for (const auto& [k, wk] : w) {
      if (k < 0 || k >= fields) throw_usage_error(fmt::format("wall: pressure field {} of {}", k, fields));
      for (int a = 0; a < 6; ++a)
        for (int c = 0; c < 3; ++c)
          trip.emplace_back(3 * mesh_.faces[f][static_cast<size_t>(a)] + c, k, -wk * nval[a] * area[c]);
    }
  });
  Eigen::SparseMatrix<double> b(num_dofs(), fields);
  b.setFromTriplets(trip.begin(), trip.end());
  return b;
}

double ElasticSolid::elastic_energy(const Eigen::VectorXd& u) const {
  double e = 0.0;
  for (size_t t = 0; t < mesh_.tets.size(); ++t)
    for (int q = 0; q < kQuad; ++q) {
      const double* g = &geometry_[(t * kQuad + static_cast<size_t>(q)) * kGeom];
      e += g[30] * law_of(static_cast<int>(t)).energy(displacement_gradient(g, mesh_.tets[t], u));
    }
  return e;
}

double ElasticSolid::energy(const Eigen::VectorXd& u) const {
  const double elastic = elastic_energy(u);
  if (!std::isfinite(elastic)) return elastic;
  return elastic + 0.5 * u.dot(support_ * u) - loads().dot(u);
}

Eigen::VectorXd ElasticSolid::gradient(const Eigen::VectorXd& u) const {
  Eigen::VectorXd grad = support_ * u - loads();
  for (size_t t = 0; t < mesh_.tets.size(); ++t) {
    const auto& tet = mesh_.tets[t];
    for (int q = 0; q < kQuad; ++q) {
      const double* g = &geometry_[(t * kQuad + static_cast<size_t>(q)) * kGeom];
      const Mat3 P = law_of(static_cast<int>(t)).stress(displacement_gradient(g, tet, u)) * g[30];
      for (int k = 0; k < 10; ++k)
        grad.segment<3>(3 * tet[static_cast<size_t>(k)]) += P * Vec3(g[3 * k], g[3 * k + 1], g[3 * k + 2]);
    }
  }
  return grad;
}

void ElasticSolid::assemble_hessian(const Eigen::VectorXd& u, Eigen::SparseMatrix<double>& h) const {
  h = pattern_;
  double* values = h.valuePtr();
  for (size_t t = 0; t < mesh_.tets.size(); ++t) {
    const auto& tet = mesh_.tets[t];
    const int* scatter = &scatter_[t * 300];
    for (int q = 0; q < kQuad; ++q) {
      const double* g = &geometry_[(t * kQuad + static_cast<size_t>(q)) * kGeom];
      const Tangent A = law_of(static_cast<int>(t)).tangent(displacement_gradient(g, tet, u)) * g[30];
      // Y_l(a + 3B, c) = Σ_D A(a + 3B, c + 3D) ∂N_l/∂X_D; K(3k + a, 3l + c) = Σ_B ∂N_k/∂X_B Y_l(a + 3B, c).
      for (int l = 0; l < 10; ++l) {
        Eigen::Matrix<double, 9, 3> y;
        for (int c = 0; c < 3; ++c)
          y.col(c) = A.col(c) * g[3 * l] + A.col(c + 3) * g[3 * l + 1] + A.col(c + 6) * g[3 * l + 2];
        for (int k = 0; k < 10; ++k) {
          const Eigen::Matrix3d block =
              y.topRows<3>() * g[3 * k] + y.middleRows<3>(3) * g[3 * k + 1] + y.bottomRows<3>() * g[3 * k + 2];
          for (int c = 0; c < 3; ++c) {
            double* col = values + scatter[30 * k + 3 * l + c];
            col[0] += block(0, c);
            col[1] += block(1, c);
            col[2] += block(2, c);
          }
        }
      }
    }
  }
  size_t s = 0;
  for (int col = 0; col < support_.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(support_, col); it; ++it)
      values[support_scatter_[s++]] += it.value();
}

Eigen::SparseMatrix<double> ElasticSolid::hessian(const Eigen::VectorXd& u) const {
  Eigen::SparseMatrix<double> h;
  assemble_hessian(u, h);
  return h;
}

void ElasticSolid::set_displacement(const Eigen::VectorXd& u) {
  if (u.size() != num_dofs())
    throw_usage_error(fmt::format("wall: a displacement of {} components for {} unknowns", u.size(), num_dofs()));
  u_ = u;
}

bool ElasticSolid::factorize_tangent(const Eigen::VectorXd& u) {
  Eigen::SparseMatrix<double> h;
  assemble_hessian(u, h);
  // Held components: their rows and columns replaced by the identity.
  for (int col = 0; col < h.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(h, col); it; ++it)
      if (held_[static_cast<size_t>(it.row())] || held_[static_cast<size_t>(col)])
        it.valueRef() = it.row() == col ? 1.0 : 0.0;
  if (!factor_->analysed) {
    factor_->llt.analyzePattern(h);
    factor_->analysed = true;
  }
  factor_->forget_maps();
  // CHOLMOD's supernodal factorization updates each large supernode with an OpenMP team of a fixed
  // four threads (its num_threads clause); on a machine with fewer cores they take turns, woken and
  // put to sleep for every supernode, and the factorization took twice as long on two cores (the
  // tortuous example's relinearizations 13.6 → 6.3 s, 4 s of system time gone). Dynamic teams are
  // given no more threads than there are cores free.
  omp_set_dynamic(1);
  factor_->llt.factorize(h);
  return factor_->llt.info() == Eigen::Success;
}

void ElasticSolid::linearize() {
  if (!factorize_tangent(u_))
    throw_numerical_error("wall: the tangent stiffness is not positive definite (is the wall held or supported?)");
  linearized_ = true;
}

void ElasticSolid::tangent_solve(Eigen::MatrixXd& x) const {
  if (!linearized_) throw_usage_error("wall: tangent_solve before linearize");
  for (int i = 0; i < num_dofs(); ++i)
    if (held_[static_cast<size_t>(i)]) x.row(i).setZero();
  x = factor_->llt.solve(x).eval();
}

void ElasticSolid::half_solve(std::span<const std::vector<std::pair<int, double>>> loads, HalfColumns& y) const {
  if (loads.size() > 3) throw_usage_error("wall: half_solve takes at most three loads");
  std::array<std::vector<std::pair<int, double>>, 3> three;
  std::copy(loads.begin(), loads.end(), three.begin());
  half_solve(three, std::span<HalfColumns>(&y, 1));
}

void ElasticSolid::half_solve(std::span<const std::vector<std::pair<int, double>>> loads,
                              std::span<HalfColumns> y) const {
  prepare_half_solve();
  half_solve(loads, y, factor_->work);
}

void ElasticSolid::prepare_half_solve() const {
  if (!linearized_) throw_usage_error("wall: half_solve before linearize");
  Factor& f = *factor_;
  if (!f.col_super.empty()) return;
  const cholmod_factor& l = *f.llt.factor();
  if (!l.is_super || !l.is_ll) throw_numerical_error("wall: the tangent's factor is not a supernodal LLᵀ");
  const int n = num_dofs();
  const auto* super = static_cast<const int*>(l.super);
  const auto* pi = static_cast<const int*>(l.pi);
  const auto* ls = static_cast<const int*>(l.s);
  const auto nsuper = static_cast<int>(l.nsuper);
  const auto* perm = static_cast<const int*>(l.Perm);
  f.iperm.resize(static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) f.iperm[static_cast<size_t>(perm ? perm[k] : k)] = k;
  f.parent.resize(static_cast<size_t>(nsuper));
  std::vector<int> col_super(static_cast<size_t>(n));
  for (int s = 0; s < nsuper; ++s)
    for (int k = super[s]; k < super[s + 1]; ++k) col_super[static_cast<size_t>(k)] = s;
  // A supernode's parent holds its first row below the diagonal block.
  for (int s = 0; s < nsuper; ++s) {
    const int nscol = super[s + 1] - super[s];
    f.parent[static_cast<size_t>(s)] =
        pi[s + 1] - pi[s] > nscol ? col_super[static_cast<size_t>(ls[pi[s] + nscol])] : -1;
  }
  f.col_super = std::move(col_super);  // (last: its being filled says the maps are made)
}

void ElasticSolid::half_solve(std::span<const std::vector<std::pair<int, double>>> loads, std::span<HalfColumns> y,
                              HalfSolveWork& work) const {
  if (!linearized_) throw_usage_error("wall: half_solve before linearize");
  if (y.size() > kHalfSolveBatch || loads.size() != 3 * y.size())
    throw_usage_error(fmt::format("wall: half_solve takes three loads for each of at most {} results ({} for {})",
                                  kHalfSolveBatch, loads.size(), y.size()));
  const Factor& f = *factor_;
  if (f.col_super.empty()) throw_usage_error("wall: half_solve before prepare_half_solve");
  const cholmod_factor& l = *f.llt.factor();
  const int n = num_dofs();
  const auto nrhs = static_cast<int>(loads.size());
  const auto stride = static_cast<size_t>(nrhs);         // x: the right-hand sides row by row
  const auto* super = static_cast<const int*>(l.super);  // supernode s: columns super[s] .. super[s+1) − 1
  const auto* pi = static_cast<const int*>(l.pi);        // its rows: ls[pi[s] .. pi[s+1]), the columns' first
  const auto* px = static_cast<const int*>(l.px);        // its values: column-major from lx[px[s]]
  const auto* ls = static_cast<const int*>(l.s);
  const auto* lx = static_cast<const double*>(l.x);
  const auto nsuper = static_cast<size_t>(l.nsuper);
  HalfSolveWork& w = work;
  if (w.entry.size() != nsuper) w.entry.assign(nsuper, std::numeric_limits<int>::max());
  if (w.x.size() != 3 * kHalfSolveBatch * static_cast<size_t>(n))
    w.x.assign(3 * kHalfSolveBatch * static_cast<size_t>(n), 0.0);
  // The loads in the factor's numbering (x holds the right-hand sides row by row).
  w.starts.clear();
  for (size_t col = 0; col < loads.size(); ++col)
    for (const auto& [dof, value] : loads[col]) {
      if (held_[static_cast<size_t>(dof)] || value == 0.0) continue;
      const int row = f.iperm[static_cast<size_t>(dof)];
      w.starts.push_back(row);
      w.x[stride * static_cast<size_t>(row) + col] += value;
    }
  for (auto& yk : y) {
    yk.index.clear();
    yk.value.clear();
  }
  // The rows of L⁻¹b are the loads' rows and their ancestors in the elimination tree; in a
  // supernode, column k's parent is k + 1, so a solve reaches the tail of each supernode on the
  // paths from the loads' supernodes to the root, from the first column it enters by.
  w.touched.clear();
  for (int row : w.starts) {
    int s = f.col_super[static_cast<size_t>(row)], col = row;
    while (s >= 0) {
      int& entry = w.entry[static_cast<size_t>(s)];
      const bool seen = entry != std::numeric_limits<int>::max();
      if (!seen) w.touched.push_back(s);
      entry = std::min(entry, col);
      if (seen) break;  // its ancestors are already on the list
      const int nscol = super[s + 1] - super[s];
      if (pi[s + 1] - pi[s] == nscol) break;
      col = ls[pi[s] + nscol];
      s = f.parent[static_cast<size_t>(s)];
    }
  }
  // Descendants before ancestors: supernodes are numbered in a postorder.
  std::sort(w.touched.begin(), w.touched.end());
  double* x = w.x.data();
  for (int s : w.touched) {
    const int k0 = super[s], nscol = super[s + 1] - k0, nsrow = pi[s + 1] - pi[s];
    const int off = w.entry[static_cast<size_t>(s)] - k0;
    w.entry[static_cast<size_t>(s)] = std::numeric_limits<int>::max();
    const auto m = static_cast<size_t>(nsrow - off);
    const int* rows = ls + pi[s] + off;
    w.gathered.resize(static_cast<size_t>(nrhs) * m);
    double* g = w.gathered.data();
    for (size_t i = 0; i < m; ++i)
      for (size_t r = 0; r < static_cast<size_t>(nrhs); ++r)
        g[r * m + i] = x[stride * static_cast<size_t>(rows[i]) + r];
    supernode_forward(lx + px[s], nsrow, off, nscol, nrhs, g);
    // The tail's rows are final (returned, and x back to zero there); the rows below belong to
    // ancestors, which take the updates.
    const auto tail = static_cast<size_t>(nscol - off);
    for (size_t i = 0; i < m; ++i) {
      double* xr = x + stride * static_cast<size_t>(rows[i]);
      if (i >= tail) {
        for (size_t r = 0; r < static_cast<size_t>(nrhs); ++r) xr[r] = g[r * m + i];
        continue;
      }
      for (size_t k = 0; k < y.size(); ++k) {
        const double v0 = g[3 * k * m + i], v1 = g[(3 * k + 1) * m + i], v2 = g[(3 * k + 2) * m + i];
        xr[3 * k] = xr[3 * k + 1] = xr[3 * k + 2] = 0.0;
        if (v0 == 0.0 && v1 == 0.0 && v2 == 0.0) continue;  // not reached from these loads
        y[k].index.push_back(rows[i]);
        y[k].value.insert(y[k].value.end(), {v0, v1, v2});
      }
    }
  }
}

SolveReport ElasticSolid::solve(const SolveOptions& options) {
  SolveReport report;
  const int n = num_dofs();
  auto free_gradient = [&](const Eigen::VectorXd& u) {
    Eigen::VectorXd g = gradient(u);
    for (int i = 0; i < n; ++i)
      if (held_[static_cast<size_t>(i)]) g[i] = 0.0;
    return g;
  };
  for (int i = 0; i < n; ++i)
    if (held_[static_cast<size_t>(i)]) u_[i] = 0.0;
  Eigen::VectorXd g = free_gradient(u_);
  Eigen::VectorXd load = loads();
  for (int i = 0; i < n; ++i)
    if (held_[static_cast<size_t>(i)]) load[i] = 0.0;
  const double scale = std::max(load.norm(), g.norm());
  report.residual = g.norm();
  linearized_ = false;
  while (!(report.residual <= options.tolerance * scale)) {
    if (report.iterations >= options.max_iterations) return report;
    if (!std::isfinite(report.residual))
      throw_numerical_error(
          fmt::format("wall: the residual became {} (iteration {})", report.residual, report.iterations));
    if (!factorize_tangent(u_))
      throw_numerical_error(
          fmt::format("wall: the tangent stiffness is not positive definite at iteration {} (is the wall held? or "
                      "the loads beyond what it can carry)",
                      report.iterations));
    const Eigen::VectorXd step = -factor_->llt.solve(g);
    // Backtracking: the energy must not rise (Armijo), or, where its change is below its
    // round-off, the residual must fall; an inverted element is never accepted.
    const double e0 = energy(u_);
    const double slope = g.dot(step);
    double alpha = 1.0;
    for (;;) {
      const Eigen::VectorXd trial = u_ + alpha * step;
      const double e = energy(trial);
      if (std::isfinite(e)) {
        const double round_off = 1e-12 * (std::abs(e0) + std::abs(e) + std::abs(loads().dot(trial)));
        const Eigen::VectorXd gt = free_gradient(trial);
        if (e <= e0 + 1e-4 * alpha * slope || (std::abs(e - e0) <= round_off && gt.norm() < report.residual)) {
          u_ = trial;
          g = gt;
          break;
        }
      }
      alpha *= 0.5;
      if (alpha < 1e-10)
        throw_numerical_error(fmt::format(
            "wall: no step lowers the energy without inverting an element (iteration {}, residual {:.3g} N)",
            report.iterations, report.residual));
    }
    ++report.iterations;
    report.residual = g.norm();
  }
  report.converged = true;
  linearized_ = options.keep_tangent && report.iterations > 0;
  return report;
}

}  // namespace flowire::solid
