#include "flowire/rod/banded.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "flowire/common/error.hpp"

namespace flowire::rod {

void BandedMatrix::reserve(int max_n, int bandwidth) {
  if (max_n < 0 || bandwidth < 0) throw_usage_error("BandedMatrix::reserve: negative size");
  b_ = bandwidth;
  data_.reserve(static_cast<size_t>(max_n) * (b_ + 1));
}

void BandedMatrix::resize(int n) {
  n_ = n;
  data_.assign(static_cast<size_t>(n) * (b_ + 1), 0.0);  // within capacity: no allocation
}

void BandedMatrix::set_zero() { std::fill(data_.begin(), data_.end(), 0.0); }

double BandedMatrix::operator()(int i, int j) const {
  if (i < j) std::swap(i, j);
  if (i - j > b_) return 0.0;
  return lower(i, j);
}

void BandedMatrix::set_identity_row(int i) {
  for (int j = std::max(0, i - b_); j < i; ++j) lower(i, j) = 0.0;
  for (int k = i + 1; k <= std::min(n_ - 1, i + b_); ++k) lower(k, i) = 0.0;
  lower(i, i) = 1.0;
}

void BandedMatrix::multiply(const Eigen::Ref<const Eigen::VectorXd>& x,
                            Eigen::Ref<Eigen::VectorXd> y) const {
  y.setZero();
  for (int i = 0; i < n_; ++i) {
    const double* row = &data_[static_cast<size_t>(i) * (b_ + 1)];
    const int j0 = std::max(0, i - b_);
    for (int j = j0; j < i; ++j) {
      const double a = row[j - i + b_];
      y(i) += a * x(j);
      y(j) += a * x(i);
    }
    y(i) += row[b_] * x(i);
  }
}

double BandedMatrix::max_diagonal() const {
  double m = 0.0;
  for (int i = 0; i < n_; ++i) m = std::max(m, std::abs(lower(i, i)));
  return m;
}

void BandedMatrix::add_to_diagonal(double s) {
  for (int i = 0; i < n_; ++i) lower(i, i) += s;
}

void BandedMatrix::to_sparse_lower(Eigen::SparseMatrix<double>& out) const {
  out.resize(n_, n_);
  out.reserve(Eigen::VectorXi::Constant(n_, b_ + 1));
  for (int j = 0; j < n_; ++j)
    for (int i = j; i <= std::min(n_ - 1, j + b_); ++i) out.insert(i, j) = lower(i, j);
  out.makeCompressed();
}

void BandedLDLT::reserve(int max_n, int bandwidth) {
  l_.reserve(max_n, bandwidth);
  work_.reserve(static_cast<size_t>(bandwidth) + 1);
}

namespace {

/// Right-looking LDLᵀ of a band stored by rows (stride b + 1). With B > 0 the half-width is
/// a compile-time constant (the rod's b = 10): the short update loops are then unrolled and
/// vectorized, which is most of the factorization's cost at this bandwidth.
template <int B>
bool factorize_band(double* L, int n, int b_runtime, double tiny, double min_pivot, double* w,
                    int& negative, int& modified, double& min_pivot_seen) {
  const int b = B > 0 ? B : b_runtime;
  const size_t stride = static_cast<size_t>(b) + 1;
  for (int j = 0; j < n; ++j) {
    double* lj = L + static_cast<size_t>(j) * stride;
    double d = lj[b];
    if (!std::isfinite(d)) return false;
    if (d < 0.0) ++negative;
    min_pivot_seen = j == 0 ? d : std::min(min_pivot_seen, d);
    if (min_pivot > 0.0) {
      if (d < min_pivot) {
        d = std::max(std::abs(d), min_pivot);
        ++modified;
      }
    } else if (std::abs(d) <= tiny) {
      return false;
    }
    lj[b] = d;
    const double inv_d = 1.0 / d;
    const int m = std::min(n - 1, j + b) - j;
    if (B > 0 && m == B) {
      // Interior column: fixed trip counts, fully unrolled.
#pragma GCC unroll 16
      for (int r = 0; r < B; ++r) {  // w_r = A(j+1+r, j) before scaling
        double* li = L + static_cast<size_t>(j + 1 + r) * stride;
        w[r] = li[B - 1 - r];
        li[B - 1 - r] = w[r] * inv_d;
      }
#pragma GCC unroll 16
      for (int r = 0; r < B; ++r) {
        double* row = L + static_cast<size_t>(j + 1 + r) * stride + (B - r);  // columns j+1..i
        const double c = w[r] * inv_d;
#pragma GCC unroll 16
        for (int k = 0; k <= r; ++k) row[k] -= c * w[k];
      }
      continue;
    }
    for (int r = 0; r < m; ++r) {
      double* li = L + static_cast<size_t>(j + 1 + r) * stride;
      w[r] = li[b - 1 - r];
      li[b - 1 - r] = w[r] * inv_d;
    }
    for (int r = 0; r < m; ++r) {
      double* row = L + static_cast<size_t>(j + 1 + r) * stride + (b - r);
      const double c = w[r] * inv_d;
      for (int k = 0; k <= r; ++k) row[k] -= c * w[k];
    }
  }
  return true;
}

}  // namespace

bool BandedLDLT::factorize(const BandedMatrix& a, double min_pivot) {
  const int n = a.size();
  const int b = a.bandwidth();
  if (l_.bandwidth() != b) l_.reserve(n, b);
  l_.resize_for_overwrite(n);  // overwritten by the copy of a below
  work_.assign(static_cast<size_t>(b) + 1, 0.0);
  negative_ = 0;
  modified_ = 0;
  min_pivot_ = n > 0 ? a.lower(0, 0) : 0.0;
  const double tiny = 1e-14 * std::max(a.max_diagonal(), 1e-300);
  const size_t stride = static_cast<size_t>(b) + 1;
  std::copy(a.data().begin(), a.data().begin() + static_cast<std::ptrdiff_t>(n * stride),
            l_.data().begin());
  double* L = l_.data().data();
  double* w = work_.data();
  if (b == 10)
    return factorize_band<10>(L, n, b, tiny, min_pivot, w, negative_, modified_, min_pivot_);
  return factorize_band<0>(L, n, b, tiny, min_pivot, w, negative_, modified_, min_pivot_);
}

void BandedLDLT::solve_in_place(Eigen::Ref<Eigen::VectorXd> x) const {
  const int n = l_.size();
  const int b = l_.bandwidth();
  const size_t stride = static_cast<size_t>(b) + 1;
  const double* L = l_.data().data();
  for (int i = 0; i < n; ++i) {  // L y = rhs
    const double* li = L + static_cast<size_t>(i) * stride;
    const int k0 = std::max(0, i - b);
    if (i > k0)
      x(i) -= Eigen::Map<const Eigen::VectorXd>(li + (k0 - i + b), i - k0).dot(x.segment(k0, i - k0));
  }
  for (int i = 0; i < n; ++i) x(i) /= L[static_cast<size_t>(i) * stride + b];  // D z = y
  for (int i = n - 1; i >= 0; --i) {  // Lᵀ x = z
    const double* li = L + static_cast<size_t>(i) * stride;
    const double xi = x(i);
    for (int k = std::max(0, i - b); k < i; ++k) x(k) -= li[k - i + b] * xi;
  }
}

}  // namespace flowire::rod
