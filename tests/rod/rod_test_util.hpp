#pragma once
// Shared helpers of the rod tests.
#include <cmath>
#include <vector>

#include "flowire/rod/model.hpp"

namespace flowire::rod {

/// A unit cantilever along +x from the origin: L = 1, EI = 1, GJ = 1, ρA = 1, nearly
/// inextensible (EA = 1e7), no tip, no gravity, clamped at the origin.
inline WireSpec unit_rod_spec(int segments) {
  WireSpec spec;
  spec.length = 1.0;
  spec.radius = 0.01;
  spec.youngs_modulus = 1e9;
  spec.density = 1000.0;
  spec.segments = segments;
  spec.tip.length = 0.0;
  spec.bending_stiffness = 1.0;
  spec.twist_stiffness = 1.0;
  spec.stretch_stiffness = 1e7;
  spec.mass_per_length = 1.0;
  spec.base_position = Eigen::Vector3d::Zero();
  spec.base_direction = Eigen::Vector3d::UnitX();
  spec.base_normal = Eigen::Vector3d::UnitZ();
  return spec;
}

/// Least-squares slope of log(y) against log(x).
inline double loglog_slope(const std::vector<double>& x, const std::vector<double>& y) {
  const size_t n = x.size();
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < n; ++i) {
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

}  // namespace flowire::rod
