#pragma once
// A faceted tube as a lumen surface, for the contact and wall tests: radius R along z from −L/2 to L/2,
// n facets around (alternate rings turned by half a facet), m rings, open at both ends.
#include <cmath>
#include <numbers>

#include "flowire/vessels/surface.hpp"

namespace flowire::test {

inline vessels::LumenSurface faceted_tube(int n, int m, double R, double L) {
  vessels::SurfaceMesh mesh;
  for (int j = 0; j <= m; ++j)
    for (int i = 0; i < n; ++i) {
      const double a = 2.0 * std::numbers::pi * i / n + (j % 2) * std::numbers::pi / n;
      mesh.vertices.emplace_back(R * std::cos(a), R * std::sin(a), L * j / m - 0.5 * L);
    }
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * n + i, b = j * n + (i + 1) % n, c = (j + 1) * n + i, d = (j + 1) * n + (i + 1) % n;
      mesh.triangles.push_back({a, b, c});
      mesh.triangles.push_back({b, d, c});
    }
  mesh.source = "faceted tube";
  return vessels::LumenSurface(std::move(mesh), {vessels::Vec3::Zero()});
}

}  // namespace flowire::test
