#pragma once
/// @file wall_thickness.hpp
/// @brief A vessel wall's thickness: one value, a fraction of the local lumen radius, or a branch's
/// own (an absolute thickness or a fraction), shared by the walls around tubes and around surfaces.
#include <vector>

namespace flowire::solid {

/// @brief A branch's own wall thickness, where it differs from the rest.
struct BranchThickness {
  int branch = -1;
  double thickness = 0.0;  ///< (m) > 0: this branch's thickness
  double ratio = 0.0;      ///< used where thickness is 0: a fraction of the local radius
};

/// @brief The wall's thickness at a point of branch @p branch whose lumen radius is @p radius:
/// the branch's own where @p branches gives one, else @p thickness where > 0, else @p ratio ×
/// @p radius.
[[nodiscard]] inline double wall_thickness_at(double thickness, double ratio,
                                              const std::vector<BranchThickness>& branches, int branch, double radius) {
  for (const BranchThickness& b : branches)
    if (b.branch == branch) return b.thickness > 0.0 ? b.thickness : b.ratio * radius;
  return thickness > 0.0 ? thickness : ratio * radius;
}

}  // namespace flowire::solid
