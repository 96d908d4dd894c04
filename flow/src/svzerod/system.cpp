#include "flowire/flow/svzerod/system.hpp"

#include <fmt/format.h>
#include <klu.h>

#include <algorithm>
#include <cassert>
#include <cmath>

#include "flowire/common/error.hpp"
#include "flowire/flow/svzerod/block.hpp"

namespace flowire::flow::svzerod {

// ---------------------------------------------------------------- Assembler

void Assembler::set_matrix(std::vector<double>& values, int row, int col, double v) {
  if (s_.recording_) {
    s_.recorded_.emplace_back(row, col);
    return;
  }
  const int k = s_.slot(row, col);
  auto& x = values[static_cast<size_t>(k)];
  if (x != v) {
    x = v;
    s_.changed_ = true;
  }
}

void Assembler::e(int row, int col, double v) {
  set_matrix(s_.e_, row, col, v);
  s_.compact_stale_ = s_.compact_stale_ || s_.changed_;
}
void Assembler::f(int row, int col, double v) {
  set_matrix(s_.f_, row, col, v);
  s_.compact_stale_ = s_.compact_stale_ || s_.changed_;
}
void Assembler::dy(int row, int col, double v) { set_matrix(s_.dy_, row, col, v); }
void Assembler::dyd(int row, int col, double v) { set_matrix(s_.dyd_, row, col, v); }
void Assembler::c(int row, double v) {
  if (!s_.recording_) s_.c_[static_cast<size_t>(row)] = v;
}
void Assembler::c_nl(int row, double v) {
  if (!s_.recording_) s_.c_nl_[static_cast<size_t>(row)] = v;
}

// ---------------------------------------------------------------- KLU

struct System::Klu {
  klu_common common{};
  klu_symbolic* symbolic = nullptr;
  klu_numeric* numeric = nullptr;
  Klu() { klu_defaults(&common); }
  ~Klu() {
    if (numeric) klu_free_numeric(&numeric, &common);
    if (symbolic) klu_free_symbolic(&symbolic, &common);
  }
  Klu(const Klu&) = delete;
  Klu& operator=(const Klu&) = delete;
};

// ---------------------------------------------------------------- System

System::System(const std::vector<Block*>& blocks, int unknowns, double period, std::string file)
    : blocks_(blocks), n_(unknowns), file_(std::move(file)), asm_(*this), klu_(std::make_unique<Klu>()) {
  asm_.period_ = period;
  for (Block* b : blocks_) {
    if (b->time_dependent()) time_blocks_.push_back(b);
    if (b->nonlinear()) nonlinear_blocks_.push_back(b);
  }
  // The pattern: every entry any block writes, in both phases.
  c_.assign(static_cast<size_t>(n_), 0.0);
  c_nl_.assign(static_cast<size_t>(n_), 0.0);
  recording_ = true;
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n_);
  for (bool steady : {true, false}) {
    asm_.steady_ = steady;
    for (Block* b : blocks_) {
      b->assemble(asm_, 0.0);
      if (b->nonlinear()) b->assemble_nonlinear(asm_, 0.0, zero, zero);
    }
  }
  recording_ = false;
  auto& rec = recorded_;
  std::sort(rec.begin(), rec.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second < b.second : a.first < b.first;
  });
  rec.erase(std::unique(rec.begin(), rec.end()), rec.end());
  colptr_.assign(static_cast<size_t>(n_) + 1, 0);
  rows_.reserve(rec.size());
  for (const auto& [r, c] : rec) {
    if (r < 0 || r >= n_ || c < 0 || c >= n_)
      throw_input_error(file_, fmt::format("an equation refers to unknown {} of {}; check the connections", c, n_));
    ++colptr_[static_cast<size_t>(c) + 1];
    rows_.push_back(r);
  }
  for (int j = 0; j < n_; ++j) colptr_[static_cast<size_t>(j) + 1] += colptr_[static_cast<size_t>(j)];
  recorded_.clear();
  recorded_.shrink_to_fit();
  const size_t nnz = rows_.size();
  e_.assign(nnz, 0.0);
  f_.assign(nnz, 0.0);
  dy_.assign(nnz, 0.0);
  dyd_.assign(nnz, 0.0);
  j_.assign(nnz, 0.0);
  klu_->symbolic = klu_analyze(n_, colptr_.data(), rows_.data(), &klu_->common);
  if (!klu_->symbolic)
    throw_numerical_error(fmt::format("{}: the system's structure is singular; check the model's connections", file_));
}

System::~System() = default;

int System::slot(int row, int col) const {
  const auto b = rows_.begin() + colptr_[static_cast<size_t>(col)];
  const auto e = rows_.begin() + colptr_[static_cast<size_t>(col) + 1];
  const auto it = std::lower_bound(b, e, row);
  assert(it != e && *it == row);
  return static_cast<int>(it - rows_.begin());
}

void System::set_phase(bool steady, double t) {
  asm_.steady_ = steady;
  std::fill(e_.begin(), e_.end(), 0.0);
  std::fill(f_.begin(), f_.end(), 0.0);
  std::fill(dy_.begin(), dy_.end(), 0.0);
  std::fill(dyd_.begin(), dyd_.end(), 0.0);
  std::fill(c_.begin(), c_.end(), 0.0);
  std::fill(c_nl_.begin(), c_nl_.end(), 0.0);
  changed_ = true;
  if (klu_->numeric) klu_free_numeric(&klu_->numeric, &klu_->common);  // new phase: pivot afresh
  for (Block* b : blocks_) b->assemble(asm_, t);
  compact();
}

void System::update_time(double t) {
  for (Block* b : time_blocks_) b->assemble(asm_, t);
  compact();
}

void System::update_block(const Block& b, double t) {
  b.assemble(asm_, t);
  compact();
}

void System::compact() {
  if (!compact_stale_) return;
  // E and F share the union pattern, but each holds values on part of it only (E: the
  // capacitors and inductors, about a quarter): the residual runs over each one's nonzeros,
  // by rows (each row of f summed in a register, written once).
  auto build = [&](const std::vector<double>& v, Rows& m) {
    m.ptr.assign(static_cast<size_t>(n_) + 1, 0);
    for (size_t k = 0; k < rows_.size(); ++k)
      if (v[k] != 0.0) ++m.ptr[static_cast<size_t>(rows_[k]) + 1];
    for (int i = 0; i < n_; ++i) m.ptr[static_cast<size_t>(i) + 1] += m.ptr[static_cast<size_t>(i)];
    const auto nnz = static_cast<size_t>(m.ptr[static_cast<size_t>(n_)]);
    m.cols.resize(nnz);
    m.values.resize(nnz);
    next_.assign(m.ptr.begin(), m.ptr.end() - 1);
    for (int j = 0; j < n_; ++j)
      for (int k = colptr_[static_cast<size_t>(j)]; k < colptr_[static_cast<size_t>(j) + 1]; ++k)
        if (v[static_cast<size_t>(k)] != 0.0) {
          const auto at = static_cast<size_t>(next_[static_cast<size_t>(rows_[static_cast<size_t>(k)])]++);
          m.cols[at] = j;
          m.values[at] = v[static_cast<size_t>(k)];
        }
  };
  build(e_, e_rows_);
  build(f_, f_rows_);
  compact_stale_ = false;
}

void System::update_solution(double t, const Eigen::VectorXd& y, const Eigen::VectorXd& yd) {
  for (Block* b : nonlinear_blocks_) b->assemble_nonlinear(asm_, t, y, yd);
}

void System::residual(const Eigen::VectorXd& y, const Eigen::VectorXd& yd, Eigen::VectorXd& f) const {
  residual(y, yd, 1.0, f);
}

double System::residual(const Eigen::VectorXd& y, const Eigen::VectorXd& yd, double yd_scale,
                        Eigen::VectorXd& f) const {
  assert(!compact_stale_);
  double* out = f.data();
  const double* c = c_.data();
  const double* c_nl = nonlinear() ? c_nl_.data() : nullptr;
  const int *ep = e_rows_.ptr.data(), *ec = e_rows_.cols.data(), *fp = f_rows_.ptr.data(), *fc = f_rows_.cols.data();
  const double *ev = e_rows_.values.data(), *fv = f_rows_.values.data(), *x = y.data(), *xd = yd.data();
  double worst = 0.0;
  for (int i = 0; i < n_; ++i) {
    double e = 0.0, a = c[i];
    if (c_nl) a += c_nl[i];
    for (int k = ep[i]; k < ep[i + 1]; ++k) e += ev[k] * xd[ec[k]];
    for (int k = fp[i]; k < fp[i + 1]; ++k) a += fv[k] * x[fc[k]];
    a += yd_scale * e;
    out[i] = a;
    worst = std::max(worst, std::abs(a));
  }
  return worst;
}

void System::factorize(double a_yd, double a_y) {
  if (!changed_ && a_yd == a_yd_ && a_y == a_y_ && klu_->numeric) return;
  const size_t nnz = rows_.size();
  for (size_t k = 0; k < nnz; ++k) j_[k] = a_yd * (e_[k] + dyd_[k]) + a_y * (f_[k] + dy_[k]);
  // Within a phase the values change (stenosis, tables) but rarely the good pivots: refactorize
  // on the previous pivot order, without allocating, unless its pivots got much smaller
  // (KLU's rcond estimate, min/max |U_ii|) than those of the last factorization with pivoting.
  bool done = false;
  if (klu_->numeric) {
    done = klu_refactor(colptr_.data(), rows_.data(), j_.data(), klu_->symbolic, klu_->numeric, &klu_->common) == 1 &&
           klu_rcond(klu_->symbolic, klu_->numeric, &klu_->common) == 1 && klu_->common.rcond >= 1e-3 * rcond_pivoted_;
    if (!done) klu_free_numeric(&klu_->numeric, &klu_->common);
  }
  if (!done) {
    klu_->numeric = klu_factor(colptr_.data(), rows_.data(), j_.data(), klu_->symbolic, &klu_->common);
    if (!klu_->numeric || klu_->common.status != KLU_OK)
      throw_numerical_error(fmt::format(
          "{}: the system is singular; check the model's connections, boundary conditions and parameters", file_));
    rcond_pivoted_ = klu_rcond(klu_->symbolic, klu_->numeric, &klu_->common) == 1 ? klu_->common.rcond : 0.0;
  }
  // A new pivot order sizes the copy (so that later copies on the same pivots allocate
  // nothing); new values on the same pivots are copied only if they serve a second solve.
  factors_current_ = !done;
  if (factors_current_) extract_factors();
  solves_since_factorization_ = 0;
  changed_ = false;
  a_yd_ = a_yd;
  a_y_ = a_y;
  ++factorizations_;
}

void System::extract_factors() {
  const klu_numeric* num = klu_->numeric;
  klu_symbolic* sym = klu_->symbolic;
  Factors& x = factors_;
  const auto n = static_cast<size_t>(n_);
  x.p.resize(n);
  x.q.resize(n);
  x.blocks.resize(static_cast<size_t>(sym->nblocks) + 1);
  x.cp.resize(n + 1);
  x.ci.resize(std::max(static_cast<size_t>(std::max({num->lnz, num->unz, num->nzoff})), n));
  x.cx.resize(x.ci.size());
  auto* nm = const_cast<klu_numeric*>(num);
  auto extract = [&](int* lp, int* li, double* lx, int* up, int* ui, double* ux, int* fp, int* fi, double* fx, int* p,
                     int* q, double* rs, int* r) {
    if (klu_extract(nm, sym, lp, li, lx, up, ui, ux, fp, fi, fx, p, q, rs, r, &klu_->common) != 1)
      throw_numerical_error(fmt::format("{}: KLU's factors could not be read", file_));
  };
  // Permutations, block boundaries, row scales (1 without scaling).
  extract(nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, x.p.data(), x.q.data(),
          x.cx.data(), x.blocks.data());
  x.r_inv.resize(n);
  for (size_t k = 0; k < n; ++k) x.r_inv[k] = 1.0 / x.cx[k];
  // A factor as KLU gives it (by columns, in x.cp/ci/cx) by rows, without its diagonal; the
  // reciprocals of the diagonal to `diag_inv` when asked.
  auto by_rows = [&](Rows& m, std::vector<double>* diag_inv) {
    m.ptr.assign(n + 1, 0);
    if (diag_inv) diag_inv->assign(n, 0.0);
    for (size_t j = 0; j < n; ++j)
      for (int k = x.cp[j]; k < x.cp[j + 1]; ++k) {
        const auto i = static_cast<size_t>(x.ci[static_cast<size_t>(k)]);
        if (i != j)
          ++m.ptr[i + 1];
        else if (diag_inv)
          (*diag_inv)[i] = 1.0 / x.cx[static_cast<size_t>(k)];
      }
    for (size_t i = 0; i < n; ++i) m.ptr[i + 1] += m.ptr[i];
    m.cols.resize(static_cast<size_t>(m.ptr[n]));
    m.values.resize(m.cols.size());
    next_.assign(m.ptr.begin(), m.ptr.end() - 1);
    for (size_t j = 0; j < n; ++j)
      for (int k = x.cp[j]; k < x.cp[j + 1]; ++k) {
        const auto i = static_cast<size_t>(x.ci[static_cast<size_t>(k)]);
        if (i == j) continue;
        const auto at = static_cast<size_t>(next_[i]++);
        m.cols[at] = static_cast<int>(j);
        m.values[at] = x.cx[static_cast<size_t>(k)];
      }
  };
  extract(x.cp.data(), x.ci.data(), x.cx.data(), nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr,
          nullptr, nullptr);
  by_rows(x.l, nullptr);
  extract(nullptr, nullptr, nullptr, x.cp.data(), x.ci.data(), x.cx.data(), nullptr, nullptr, nullptr, nullptr, nullptr,
          nullptr, nullptr);
  by_rows(x.u, &x.u_inv);
  extract(nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, x.cp.data(), x.ci.data(), x.cx.data(), nullptr, nullptr,
          nullptr, nullptr);
  by_rows(x.off, nullptr);
  x_.resize(n);
}

void System::solve(Eigen::VectorXd& b) {
  if (!factors_current_) {
    if (solves_since_factorization_++ == 0) {
      klu_solve(klu_->symbolic, klu_->numeric, n_, 1, b.data(), &klu_->common);
      return;
    }
    extract_factors();
    factors_current_ = true;
  }
  const Factors& fa = factors_;
  double* x = x_.data();
  double* out = b.data();
  const int* p = fa.p.data();
  const double* r_inv = fa.r_inv.data();
  for (int k = 0; k < n_; ++k) x[k] = out[p[k]] * r_inv[k];
  const int *lp = fa.l.ptr.data(), *lc = fa.l.cols.data(), *up = fa.u.ptr.data(), *uc = fa.u.cols.data();
  const int *op = fa.off.ptr.data(), *oc = fa.off.cols.data();
  const double *lv = fa.l.values.data(), *uv = fa.u.values.data(), *ov = fa.off.values.data(), *u_inv = fa.u_inv.data();
  // Block upper triangular: the last block first; a block's rows take the off-diagonal
  // terms of the blocks already solved, then its L and U sweeps.
  for (auto blk = static_cast<int>(fa.blocks.size()) - 2; blk >= 0; --blk) {
    const int k1 = fa.blocks[static_cast<size_t>(blk)], k2 = fa.blocks[static_cast<size_t>(blk) + 1];
    if (k2 - k1 == 1) {
      double v = x[k1];
      for (int k = op[k1]; k < op[k1 + 1]; ++k) v -= ov[k] * x[oc[k]];
      x[k1] = v * u_inv[k1];
      continue;
    }
    for (int i = k1; i < k2; ++i) {
      double v = x[i];
      for (int k = op[i]; k < op[i + 1]; ++k) v -= ov[k] * x[oc[k]];
      for (int k = lp[i]; k < lp[i + 1]; ++k) v -= lv[k] * x[lc[k]];
      x[i] = v;
    }
    for (int i = k2 - 1; i >= k1; --i) {
      double v = x[i];
      for (int k = up[i]; k < up[i + 1]; ++k) v -= uv[k] * x[uc[k]];
      x[i] = v * u_inv[i];
    }
  }
  const int* q = fa.q.data();
  for (int k = 0; k < n_; ++k) out[q[k]] = x[k];
}

Eigen::SparseMatrix<double> System::dfdy() const {
  Eigen::SparseMatrix<double> m(n_, n_);
  std::vector<Eigen::Triplet<double>> t;
  for (int j = 0; j < n_; ++j)
    for (int k = colptr_[static_cast<size_t>(j)]; k < colptr_[static_cast<size_t>(j) + 1]; ++k)
      t.emplace_back(rows_[static_cast<size_t>(k)], j, f_[static_cast<size_t>(k)] + dy_[static_cast<size_t>(k)]);
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

Eigen::SparseMatrix<double> System::dfdyd() const {
  Eigen::SparseMatrix<double> m(n_, n_);
  std::vector<Eigen::Triplet<double>> t;
  for (int j = 0; j < n_; ++j)
    for (int k = colptr_[static_cast<size_t>(j)]; k < colptr_[static_cast<size_t>(j) + 1]; ++k)
      t.emplace_back(rows_[static_cast<size_t>(k)], j, e_[static_cast<size_t>(k)] + dyd_[static_cast<size_t>(k)]);
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

}  // namespace flowire::flow::svzerod
