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
  // capacitors and inductors, about a quarter): the residual runs over each one's nonzeros.
  auto build = [&](const std::vector<double>& v, Compact& m) {
    m.rows.clear();
    m.cols.clear();
    m.values.clear();
    for (int j = 0; j < n_; ++j)
      for (int k = colptr_[static_cast<size_t>(j)]; k < colptr_[static_cast<size_t>(j) + 1]; ++k)
        if (v[static_cast<size_t>(k)] != 0.0) {
          m.rows.push_back(rows_[static_cast<size_t>(k)]);
          m.cols.push_back(j);
          m.values.push_back(v[static_cast<size_t>(k)]);
        }
  };
  build(e_, e_compact_);
  build(f_, f_compact_);
  compact_stale_ = false;
}

void System::update_solution(double t, const Eigen::VectorXd& y, const Eigen::VectorXd& yd) {
  for (Block* b : nonlinear_blocks_) b->assemble_nonlinear(asm_, t, y, yd);
}

void System::residual(const Eigen::VectorXd& y, const Eigen::VectorXd& yd, Eigen::VectorXd& f) const {
  residual(y, yd, 1.0, f);
}

double System::residual(const Eigen::VectorXd& y, const Eigen::VectorXd& yd, double yd_scale, Eigen::VectorXd& f) const {
  assert(!compact_stale_);
  double* out = f.data();
  const double* c = c_.data();
  if (nonlinear()) {
    for (int i = 0; i < n_; ++i) out[i] = c[i] + c_nl_[static_cast<size_t>(i)];
  } else {
    std::copy(c, c + n_, out);
  }
  auto add = [&](const Compact& m, const double* x, double scale) {
    const int* ri = m.rows.data();
    const int* ci = m.cols.data();
    const double* v = m.values.data();
    const size_t nnz = m.values.size();
    for (size_t k = 0; k < nnz; ++k) out[ri[k]] += scale * (v[k] * x[ci[k]]);
  };
  add(e_compact_, yd.data(), yd_scale);
  add(f_compact_, y.data(), 1.0);
  return f.cwiseAbs().maxCoeff();
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
  changed_ = false;
  a_yd_ = a_yd;
  a_y_ = a_y;
  ++factorizations_;
}

void System::solve(Eigen::VectorXd& b) const {
  klu_solve(klu_->symbolic, klu_->numeric, n_, 1, b.data(), &klu_->common);
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
