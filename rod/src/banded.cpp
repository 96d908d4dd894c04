#include "flowire/rod/banded.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "flowire/common/error.hpp"
#include "flowire/common/kernel_clones.hpp"

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

void BandedMatrix::multiply(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const {
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

/// (Both kernels are inlined into their callers, which are compiled per instruction set.)
/// Right-looking LDLᵀ of a band stored by rows (stride b + 1). With B > 0 the half-width is
/// a compile-time constant (the rod's b = 10): the short update loops are then unrolled and
/// vectorized, which is most of the factorization's cost at this bandwidth. The multipliers
/// of the current column live in a local array: it cannot alias the factor, so they stay in
/// registers across the rank-1 update.
/// Two doubles, for the explicitly paired rank-1 update (GCC/Clang vector extension).
typedef double V2 __attribute__((vector_size(16)));

template <int B>
__attribute__((always_inline)) inline bool factorize_band(double* __restrict L, int n, int b_runtime, double tiny,
                                                          double min_pivot, double* __restrict w, int& negative,
                                                          int& modified, double& min_pivot_seen) {
  const int b = B > 0 ? B : b_runtime;
  const size_t stride = static_cast<size_t>(b) + 1;
  double w_local[B > 0 ? B : 1];
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
    if constexpr (B > 0) {
      if (m == B) {
        // Interior column: fixed trip counts, fully unrolled; w_local is not aliased.
        double c[B];
#pragma GCC unroll 16
        for (int r = 0; r < B; ++r) {  // w_r = A(j+1+r, j) before scaling
          double* li = L + static_cast<size_t>(j + 1 + r) * stride;
          w_local[r] = li[B - 1 - r];
          c[r] = w_local[r] * inv_d;
          li[B - 1 - r] = c[r];
        }
#pragma GCC unroll 16
        for (int r = 0; r < B; ++r) {
          double* row = L + static_cast<size_t>(j + 1 + r) * stride + (B - r);  // cols j+1..i
          const V2 cr = {c[r], c[r]};
#pragma GCC unroll 16
          for (int k = 0; k + 1 <= r; k += 2) {
            V2 a, x;
            __builtin_memcpy(&a, row + k, sizeof a);
            __builtin_memcpy(&x, w_local + k, sizeof x);
            a -= cr * x;
            __builtin_memcpy(row + k, &a, sizeof a);
          }
          if (r % 2 == 0) row[r] -= c[r] * w_local[r];
        }
        continue;
      }
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

/// Forward (L y = r), diagonal and backward (Lᵀ x = z) substitution in place; with B > 0
/// the interior rows run with a compile-time bandwidth.
template <int B>
__attribute__((always_inline)) inline void solve_band(const double* __restrict L, int n, int b_runtime,
                                                      double* __restrict x, int first) {
  const int b = B > 0 ? B : b_runtime;
  const size_t stride = static_cast<size_t>(b) + 1;
  for (int i = first; i < n; ++i) {  // L y = rhs (zero above row first: y too)
    const double* li = L + static_cast<size_t>(i) * stride;
    if (B > 0 && i >= B) {
      // Only x[i−1] was just computed: sum the older terms in independent pairs so the
      // row-to-row dependency is one multiply-subtract, not a chain of B.
      const double* xi = x + (i - B);
      V2 acc = {0.0, 0.0};
#pragma GCC unroll 16
      for (int k = 0; k + 1 < B - 1; k += 2) {
        V2 l, v;
        __builtin_memcpy(&l, li + k, sizeof l);
        __builtin_memcpy(&v, xi + k, sizeof v);
        acc += l * v;
      }
      double older = acc[0] + acc[1];
      if ((B - 1) % 2 == 1) older += li[B - 2] * xi[B - 2];
      x[i] = (x[i] - older) - li[B - 1] * xi[B - 1];
      continue;
    }
    const int k0 = std::max(0, i - b);
    double s = x[i];
    for (int k = k0; k < i; ++k) s -= li[k - i + b] * x[k];
    x[i] = s;
  }
  for (int i = first; i < n; ++i) x[i] /= L[static_cast<size_t>(i) * stride + b];  // D z = y
  for (int i = n - 1; i >= 0; --i) {                                               // Lᵀ x = z
    const double* li = L + static_cast<size_t>(i) * stride;
    const double xi = x[i];
    if (B > 0 && i >= B) {
      double* xk = x + (i - B);
#pragma GCC unroll 16
      for (int k = 0; k < B; ++k) xk[k] -= li[k] * xi;
      continue;
    }
    for (int k = std::max(0, i - b); k < i; ++k) x[k] -= li[k - i + b] * xi;
  }
}

}  // namespace

FLOWIRE_KERNEL_CLONES
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
  std::copy(a.data().begin(), a.data().begin() + static_cast<std::ptrdiff_t>(n * stride), l_.data().begin());
  double* L = l_.data().data();
  double* w = work_.data();
  if (b == 10) return factorize_band<10>(L, n, b, tiny, min_pivot, w, negative_, modified_, min_pivot_);
  return factorize_band<0>(L, n, b, tiny, min_pivot, w, negative_, modified_, min_pivot_);
}

FLOWIRE_KERNEL_CLONES
void BandedLDLT::solve_in_place(Eigen::Ref<Eigen::VectorXd> x, int first) const {
  const int n = l_.size();
  const int b = l_.bandwidth();
  assert(x.size() == n);
  first = std::clamp(first, 0, n);
  if (b == 10)
    solve_band<10>(l_.data().data(), n, b, x.data(), first);
  else
    solve_band<0>(l_.data().data(), n, b, x.data(), first);
}

void LowRankStiffness::multiply_add(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const {
  const int m = rank();
  Eigen::VectorXd ux(m);
  for (int j = 0; j < m; ++j)
    ux[j] = directions[static_cast<size_t>(j)].dot(x.segment<3>(dofs[static_cast<size_t>(j)]));
  const Eigen::VectorXd r = core * ux;
  for (int j = 0; j < m; ++j) y.segment<3>(dofs[static_cast<size_t>(j)]) += r[j] * directions[static_cast<size_t>(j)];
}

}  // namespace flowire::rod
