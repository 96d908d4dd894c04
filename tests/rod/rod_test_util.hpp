#pragma once
// Shared helpers of the rod tests.
#include <cmath>
#include <vector>

#include "flowire/rod/model.hpp"
#include "flowire_test.hpp"

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

using flowire::testing::loglog_slope;

}  // namespace flowire::rod
