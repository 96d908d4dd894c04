#pragma once
/// @file banded.hpp
/// @brief Symmetric banded matrices and their LDLᵀ factorization, O(n·b²).
///
/// The rod's unknowns are interleaved per vertex (x_0, θ_0, x_1, θ_1, …, x_n), so every
/// stencil couples unknowns at most 10 apart and the Hessian is a band of half-width 10.
/// Storage is the lower band by rows: row i holds columns i−b … i contiguously, so the
/// factorization and both triangular solves run over contiguous memory. All storage is
/// reserved up front (`reserve`); `resize` within that capacity does not allocate.
#include <cassert>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SparseCore>
#include <vector>

namespace flowire::rod {

/// @brief Symmetric matrix with half-bandwidth b (A(i,j) = 0 for |i − j| > b).
class BandedMatrix {
 public:
  BandedMatrix() = default;
  BandedMatrix(int n, int bandwidth) {
    reserve(n, bandwidth);
    resize(n);
  }
  /// @brief Allocate room for up to @p max_n rows with half-bandwidth @p bandwidth.
  void reserve(int max_n, int bandwidth);
  /// @brief Set the size (≤ reserved) and zero the entries.
  void resize(int n);
  /// @brief Set the size (≤ reserved) leaving the entries unspecified (to be overwritten).
  void resize_for_overwrite(int n) {
    n_ = n;
    data_.resize(static_cast<size_t>(n) * (b_ + 1));
  }
  void set_zero();
  [[nodiscard]] int size() const { return n_; }
  [[nodiscard]] int bandwidth() const { return b_; }
  /// @brief Entry (i, j) of the lower band, i ≥ j, i − j ≤ b (asserted).
  [[nodiscard]] double& lower(int i, int j) { return data_[static_cast<size_t>(i) * (b_ + 1) + (j - i + b_)]; }
  [[nodiscard]] double lower(int i, int j) const { return data_[static_cast<size_t>(i) * (b_ + 1) + (j - i + b_)]; }
  /// @brief A(i, j) for any i, j (0 outside the band).
  [[nodiscard]] double operator()(int i, int j) const;
  /// @brief Add a dense symmetric block whose rows/columns map to global indices @p idx.
  template <typename Derived>
  void add_block(const Eigen::MatrixBase<Derived>& block, const int* idx, int count) {
    for (int a = 0; a < count; ++a)
      for (int c = 0; c < count; ++c)
        if (idx[a] >= idx[c]) lower(idx[a], idx[c]) += block(a, c);
  }
  /// @brief Add a dense symmetric block on the contiguous index range [first, first + size).
  /// A fixed-size block (the 11×11 stencil) is added with compile-time trip counts.
  template <typename Derived>
  void add_block(const Eigen::MatrixBase<Derived>& block, int first) {
    constexpr int M = Derived::RowsAtCompileTime;
    const int m = M != Eigen::Dynamic ? M : static_cast<int>(block.rows());
    assert(m <= b_ + 1 && first + m <= n_);
    // Row first+a holds columns first … first+a contiguously from offset b − a, i.e. rows
    // are b steps apart in the storage.
    double* row = data_.data() + static_cast<size_t>(first) * (b_ + 1) + b_;
    for (int a = 0; a < m; ++a, row += b_)
      for (int c = 0; c <= a; ++c) row[c] += block(a, c);
  }
  /// @brief Replace row and column @p i by those of the identity (a prescribed unknown).
  void set_identity_row(int i);
  /// @brief y = A x.
  void multiply(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const;
  /// @brief Largest |A(i,i)|.
  [[nodiscard]] double max_diagonal() const;
  /// @brief Add s to every diagonal entry.
  void add_to_diagonal(double s);
  /// @brief The same matrix in compressed sparse form (lower triangle), for the general path.
  void to_sparse_lower(Eigen::SparseMatrix<double>& out) const;
  [[nodiscard]] const std::vector<double>& data() const { return data_; }
  [[nodiscard]] std::vector<double>& data() { return data_; }

 private:
  int n_ = 0;
  int b_ = 0;
  std::vector<double> data_;
};

/// @brief LDLᵀ factorization of a BandedMatrix (no pivoting; fails on a zero pivot).
///
/// Without pivoting the inertia (number of negative pivots) equals the number of negative
/// eigenvalues (Sylvester), which the simulator uses to detect indefinite Hessians and
/// the tests use to find buckling loads.
class BandedLDLT {
 public:
  void reserve(int max_n, int bandwidth);
  /// @brief Factorize @p a. Returns false if a pivot is zero, tiny (|d| ≤ 1e-14·max|a_ii|)
  /// or not finite.
  ///
  /// With @p min_pivot > 0 the factorization is *modified* instead: every pivot below
  /// min_pivot is replaced by max(|d|, min_pivot) (counted in modified_pivots()), which
  /// turns an indefinite Newton matrix into a nearby positive definite one while leaving
  /// the well-conditioned directions untouched; only non-finite values then fail.
  bool factorize(const BandedMatrix& a, double min_pivot = 0.0);
  /// @brief Solve A x = rhs in place (after a successful factorize). With @p first > 0, rhs is
  /// zero above row @p first, and the forward sweep starts there (the same result).
  void solve_in_place(Eigen::Ref<Eigen::VectorXd> x, int first = 0) const;
  /// @brief Number of negative pivots of the last factorization.
  [[nodiscard]] int negative_pivots() const { return negative_; }
  /// @brief Number of pivots replaced by a modified factorization.
  [[nodiscard]] int modified_pivots() const { return modified_; }
  /// @brief Smallest pivot of the last factorization.
  [[nodiscard]] double min_pivot() const { return min_pivot_; }

 private:
  BandedMatrix l_;  // unit lower factor (diagonal slot holds D)
  std::vector<double> work_;
  int negative_ = 0;
  int modified_ = 0;
  double min_pivot_ = 0.0;
};

/// @brief A symmetric stiffness of low rank that couples unknowns far apart in the band:
/// K = U R Uᵀ, column j of U the 3-vector `directions[j]` at unknowns `dofs[j]` … `dofs[j] + 2`.
/// A deformable wall's contacts give one (a push at one contact moves the wall under another):
/// R is then their condensed stiffness, m × m for m contacts.
struct LowRankStiffness {
  std::vector<int> dofs;                    ///< first unknown of each column's 3-vector
  std::vector<Eigen::Vector3d> directions;  ///< each column's 3-vector
  Eigen::MatrixXd core;                     ///< R (m × m, symmetric)
  [[nodiscard]] bool empty() const { return dofs.empty(); }
  [[nodiscard]] int rank() const { return static_cast<int>(dofs.size()); }
  void clear() {
    dofs.clear();
    directions.clear();
    core.resize(0, 0);
  }
  /// @brief y += U R Uᵀ x.
  void multiply_add(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const;
};

/// @brief Solves with H + U R Uᵀ from a solver of H (Sherman–Morrison–Woodbury):
/// (H + U R Uᵀ)⁻¹ b = x − Y (I + R W)⁻¹ R Uᵀ x, with x = H⁻¹ b, Y = H⁻¹ U, W = Uᵀ Y.
/// R need not be invertible (no R⁻¹ is formed); the m × m system is solved by LU. U is kept as
/// its columns' 3-vectors: Uᵀ Y and Uᵀ x are read at three rows a column.
class LowRankSolve {
 public:
  /// @brief Y and the small system for @p term with the solver @p solve_h (solve_h(x, first):
  /// x ← H⁻¹ x in place, x zero above row first) of an n × n H; the columns' entries at unknowns
  /// outside [first_free, first_fixed) (held) are dropped. Returns false if I + R W is singular.
  template <class SolveH>
  bool prepare(const LowRankStiffness& term, int n, int first_free, int first_fixed, SolveH&& solve_h) {
    active_ = !term.empty();
    if (!active_) return true;
    const int m = term.rank();
    dofs_ = term.dofs;
    directions_.resize(static_cast<size_t>(m));
    y_.setZero(n, m);
    for (int j = 0; j < m; ++j) {
      const int d0 = dofs_[static_cast<size_t>(j)];
      Eigen::Vector3d& u = directions_[static_cast<size_t>(j)];
      for (int c = 0; c < 3; ++c)
        u[c] = d0 + c >= first_free && d0 + c < first_fixed ? term.directions[static_cast<size_t>(j)][c] : 0.0;
      y_.col(j).segment<3>(d0) = u;
      solve_h(y_.col(j), d0);
    }
    w_.resize(m, m);
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i)
        w_(i, j) = directions_[static_cast<size_t>(i)].dot(y_.col(j).segment<3>(dofs_[static_cast<size_t>(i)]));
    r_ = term.core;
    small_.compute(Eigen::MatrixXd::Identity(m, m) + r_ * w_);
    return std::abs(small_.determinant()) > 0.0 && std::isfinite(small_.determinant());
  }
  /// @brief x ← (H + U R Uᵀ)⁻¹ b given x = H⁻¹ b (no-op without a term).
  void correct(Eigen::Ref<Eigen::VectorXd> x) const {
    if (!active_) return;
    const auto m = static_cast<Eigen::Index>(dofs_.size());
    Eigen::VectorXd ux(m);
    for (Eigen::Index j = 0; j < m; ++j)
      ux[j] = directions_[static_cast<size_t>(j)].dot(x.segment<3>(dofs_[static_cast<size_t>(j)]));
    const Eigen::VectorXd z = small_.solve(r_ * ux);
    x.noalias() -= y_ * z;
  }
  [[nodiscard]] bool active() const { return active_; }

 private:
  bool active_ = false;
  std::vector<int> dofs_;                    ///< U's columns: first unknown of each 3-vector
  std::vector<Eigen::Vector3d> directions_;  ///< and the 3-vector (held unknowns' entries zero)
  Eigen::MatrixXd y_, w_, r_;
  Eigen::PartialPivLU<Eigen::MatrixXd> small_;
};

}  // namespace flowire::rod
