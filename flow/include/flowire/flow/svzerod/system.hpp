#pragma once
/// @file system.hpp
/// @brief The network's equations on one fixed sparse pattern:
/// \f[ f(y, \dot y, t) = E(t)\,\dot y + F(t)\,y + c(t) + c_{nl}(y, \dot y, t) = 0 \f]
/// with the linear part (E, F, c) written by every block when a phase starts and again each
/// step only by the blocks whose parameters vary in time, and the nonlinear part
/// \f$ c_{nl} \f$ with its derivatives \f$ D_y = \partial c_{nl}/\partial y \f$,
/// \f$ D_{\dot y} = \partial c_{nl}/\partial \dot y \f$ written by the nonlinear blocks only.
/// Each equation row belongs to one block, so every write sets a value.
///
/// The iteration matrix \f$ J = a_{\dot y}(E + D_{\dot y}) + a_y(F + D_y) \f$ is factorized
/// with KLU: the symbolic analysis (block triangular form, AMD ordering) once for the
/// pattern, the numeric factorization with pivoting once per phase, and again only when a
/// value of J changed: then on the same pivots (no allocation) unless they got much worse.
/// The solves run on a copy of KLU's factors, taken after a factorization with pivoting and
/// after a refactorization once it serves a second solve (a Newton iteration that
/// refactorizes at every solve keeps KLU's own solve),
/// \f$ L U + F_{off} = R^{-1} P J Q \f$, stored by rows with the reciprocals of the row
/// scales and of U's diagonal: one gather, row-wise (dot-product) triangular sweeps block by
/// block and one scatter, with no division (a step of a linear model is mostly this solve and
/// the residual).
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <vector>

namespace flowire::flow::svzerod {

class Block;
class System;

/// @brief Write access of the blocks to the system. In recording mode it only collects the pattern.
class Assembler {
 public:
  /// @brief \f$ E_{row,col} = v \f$ (coefficient of \f$ \dot y_{col} \f$).
  void e(int row, int col, double v);
  /// @brief \f$ F_{row,col} = v \f$ (coefficient of \f$ y_{col} \f$).
  void f(int row, int col, double v);
  /// @brief \f$ c_{row} = v \f$.
  void c(int row, double v);
  /// @brief Nonlinear term \f$ c_{nl,row} = v \f$.
  void c_nl(int row, double v);
  /// @brief \f$ \partial c_{nl,row}/\partial y_{col} = v \f$.
  void dy(int row, int col, double v);
  /// @brief \f$ \partial c_{nl,row}/\partial \dot y_{col} = v \f$.
  void dyd(int row, int col, double v);
  /// @brief True in the steady initial phase (tables at their mean, capacitors removed).
  [[nodiscard]] bool steady() const { return steady_; }
  /// @brief The cardiac period of the model.
  [[nodiscard]] double period() const { return period_; }

 private:
  friend class System;
  explicit Assembler(System& s) : s_(s) {}
  void set_matrix(std::vector<double>& values, int row, int col, double v);
  System& s_;
  bool steady_ = false;
  double period_ = 1.0;
};

/// @brief The network's sparse system and its KLU factorization. Allocates only when built.
class System {
 public:
  /// @param blocks the model's blocks, equation rows and unknowns already placed
  /// @param unknowns number of unknowns (= number of equations)
  /// @param period cardiac period (for blocks whose parameters follow the cycle)
  /// @param file model file, for messages
  System(const std::vector<Block*>& blocks, int unknowns, double period, std::string file);
  ~System();
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  [[nodiscard]] int size() const { return n_; }
  [[nodiscard]] long nonzeros() const { return static_cast<long>(rows_.size()); }
  [[nodiscard]] bool nonlinear() const { return !nonlinear_blocks_.empty(); }

  /// @brief Start a phase: every block writes its linear part at time `t`.
  void set_phase(bool steady, double t);
  /// @brief Blocks whose parameters vary in time write their linear part at `t`.
  void update_time(double t);
  /// @brief Block `b`, whose parameters changed within the phase (not with time), writes its
  /// linear part again; the next factorize() refactorizes on the same pattern.
  void update_block(const Block& b, double t);
  /// @brief Nonlinear blocks write \f$ c_{nl} \f$, \f$ D_y \f$, \f$ D_{\dot y} \f$ at (y, ẏ).
  void update_solution(double t, const Eigen::VectorXd& y, const Eigen::VectorXd& yd);
  /// @brief \f$ f = E\dot y + F y + c + c_{nl} \f$ (no allocation).
  void residual(const Eigen::VectorXd& y, const Eigen::VectorXd& yd, Eigen::VectorXd& f) const;
  /// @brief \f$ f = E(s\,\dot y) + F y + c + c_{nl} \f$; returns \f$ \|f\|_\infty \f$.
  double residual(const Eigen::VectorXd& y, const Eigen::VectorXd& yd, double yd_scale, Eigen::VectorXd& f) const;
  /// @brief Factorize \f$ J = a_{\dot y}(E + D_{\dot y}) + a_y(F + D_y) \f$ unless it is unchanged
  /// since the last factorization. @throws flowire::Error (numerical) when J is singular.
  void factorize(double a_yd, double a_y);
  /// @brief Solve \f$ J x = b \f$ in place.
  void solve(Eigen::VectorXd& b);
  /// @brief Numeric factorizations done so far.
  [[nodiscard]] long factorizations() const { return factorizations_; }

  /// @brief \f$ \partial f/\partial y = F + D_y \f$ at the last update (for tests).
  [[nodiscard]] Eigen::SparseMatrix<double> dfdy() const;
  /// @brief \f$ \partial f/\partial \dot y = E + D_{\dot y} \f$ at the last update (for tests).
  [[nodiscard]] Eigen::SparseMatrix<double> dfdyd() const;

 private:
  friend class Assembler;
  [[nodiscard]] int slot(int row, int col) const;
  /// Rebuild E's and F's nonzero lists after their values changed.
  void compact();

  std::vector<Block*> blocks_, time_blocks_, nonlinear_blocks_;
  int n_;
  std::string file_;
  Assembler asm_;
  // CSC pattern (union of E, F, D_y, D_ẏ) and values on it
  std::vector<int> colptr_, rows_;
  std::vector<double> e_, f_, dy_, dyd_, j_;
  std::vector<double> c_, c_nl_;
  /// A sparse matrix by rows.
  struct Rows {
    std::vector<int> ptr, cols;
    std::vector<double> values;
  };
  Rows e_rows_, f_rows_;  ///< E's and F's nonzeros by row, for the residual
  bool compact_stale_ = true;
  /// Copy KLU's factors into `factors_` after a factorization.
  void extract_factors();
  struct Factors {
    Rows l, u, off;                 ///< strict lower L, strict upper U, off-diagonal blocks; permuted indices
    std::vector<double> u_inv;      ///< 1/U_kk
    std::vector<double> r_inv;      ///< 1/(row scale) of permuted row k
    std::vector<int> p, q, blocks;  ///< row and column permutations, block boundaries
    std::vector<int> cp, ci;        ///< extraction scratch
    std::vector<double> cx;
  };
  Factors factors_;
  bool factors_current_ = false;  ///< factors_ holds the last factorization
  int solves_since_factorization_ = 0;
  std::vector<double> x_;  ///< the solve's permuted vector
  std::vector<int> next_;  ///< scratch of the conversions to rows
  bool recording_ = false;
  std::vector<std::pair<int, int>> recorded_;
  bool changed_ = true;
  double a_yd_ = 0.0, a_y_ = 0.0;
  long factorizations_ = 0;
  double rcond_pivoted_ = 0.0;  // KLU's rcond of the last factorization with pivoting
  struct Klu;
  std::unique_ptr<Klu> klu_;
};

}  // namespace flowire::flow::svzerod
