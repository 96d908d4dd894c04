#pragma once
/// @file param.hpp
/// @brief A block parameter of an svZeroDSolver model: a number, or a table over time
/// repeated with its period (linear interpolation), replaced by the table's arithmetic mean
/// in the steady initial phase.
#include <algorithm>
#include <cmath>
#include <vector>

namespace flowire::flow::svzerod {

class Param {
 public:
  Param() = default;
  explicit Param(double value) : value_(value) {}
  /// @brief A periodic table; `t` strictly increasing, same size as `v` (at least 2).
  Param(std::vector<double> t, std::vector<double> v) : constant_(false), t_(std::move(t)), v_(std::move(v)) {
    cycle_ = t_.back() - t_.front();
    double s = 0.0;
    for (double x : v_) s += x;
    mean_ = s / static_cast<double>(v_.size());
  }

  [[nodiscard]] bool constant() const { return constant_; }
  /// @brief Period of the table (0 for a number).
  [[nodiscard]] double cycle() const { return cycle_; }
  [[nodiscard]] double mean() const { return constant_ ? value_ : mean_; }

  /// @brief Value at time `time`; the mean in the steady phase.
  [[nodiscard]] double get(double time, bool steady = false) const {
    if (constant_) return value_;
    if (steady) return mean_;
    const double rt = std::fmod(time, cycle_);
    auto k = static_cast<size_t>(std::lower_bound(t_.begin(), t_.end(), rt) - t_.begin());
    if (k == t_.size())
      k = t_.size() - 1;
    else if (t_[k] == rt)
      return v_[k];
    const size_t m = k ? k - 1 : 1;
    return v_[m] + (v_[k] - v_[m]) / (t_[k] - t_[m]) * (rt - t_[m]);
  }

 private:
  bool constant_ = true;
  double value_ = 0.0;
  std::vector<double> t_, v_;
  double cycle_ = 0.0, mean_ = 0.0;
};

}  // namespace flowire::flow::svzerod
