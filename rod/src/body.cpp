#include "flowire/rod/body.hpp"

#include <algorithm>
#include <cmath>

namespace flowire::rod {

void RodState::reserve(int vertices) {
  const auto n = static_cast<size_t>(vertices);
  x.reserve(n);
  v.reserve(n);
  theta.reserve(n);
  omega.reserve(n);
  frame.reserve(n);
  ref_twist.reserve(n);
  u.reserve(n);
}

int RodBody::max_vertices() const {
  // Adaptive refinement may hold up to one vertex per finest edge.
  if (!model.adapt.enabled) return model.grid_vertices;
  return std::max(model.grid_vertices, static_cast<int>(std::ceil(model.length / model.adapt.min_segment_length)) + 4);
}

}  // namespace flowire::rod
