#pragma once
/// @file wall.hpp
/// @brief The wall a wire vertex touches, as the contact law sees it: a signed distance d
/// (> 0 outside the lumen), its gradient n (the outward normal) and Hessian, per vertex, with
/// each vertex's own caches. Two walls: the union of the network's capsules (`NetworkWall`,
/// blended at junctions, read from the vertices' locations) and a triangulated lumen surface
/// (`SurfaceWall`, its smooth signed distance). The contact law (wall_contact.hpp) takes either
/// and knows neither; another wall (a deforming one) is a third implementation.
#include <algorithm>
#include <span>
#include <vector>

#include "flowire/coupling/interaction.hpp"
#include "flowire/coupling/wire_location.hpp"
#include "flowire/vessels/surface.hpp"

namespace flowire::coupling {

/// @brief How deep inside (exact distance) a wire vertex of radius @p a may be before the
/// contact on a lumen surface of smoothing width @p sigma skips it: a + max(2σ, a/2). Exact as
/// long as d_σ < −a wherever d < −(that depth); measured on every real anatomy
/// (tests/coupling/test_surface_contact.cpp, SkippedDeepVerticesHaveNoContactOnTheRealLumens).
inline double surface_skip_depth(double a, double sigma) { return a + std::max(0.5 * sigma, 0.5 * a); }

/// @brief The wall at a vertex of an accepted state (the end of a step): what the friction of
/// the next step and the "outside the lumen" record need.
struct AcceptedWall {
  double contact_distance = 0.0;  ///< the distance the contact law uses [m]
  Vec3 normal = Vec3::UnitX();    ///< its gradient
  double distance = 0.0;          ///< the exact distance, that measures how far outside the vertex is [m]
  bool measured = true;           ///< false where the vertex is not measured for "outside" (near an open inlet)
};

class Wall {
 public:
  virtual ~Wall() = default;
  /// @brief Room for @p n vertices' caches.
  virtual void ensure_size(int n) = 0;
  /// @brief The wall distance @p d, normal @p n and Hessian @p H (may be null) at vertex @p i
  /// (position @p x, radius @p a) during a solve; false where the vertex is so deep inside that
  /// no wall is within @p reach of its surface (then nothing is written).
  virtual bool at(int i, const Vec3& x, double a, double reach, double* d, Vec3* n, Mat3* H) = 0;
  /// @brief The wall at vertex @p i of an accepted state, arc length @p s from the entry;
  /// false where the vertex is deep inside (nothing to record).
  virtual bool accepted(int i, const Vec3& x, double a, double reach, double s, AcceptedWall* out) = 0;
  /// @brief The rod resampled its vertices (rod::ExternalForce::remap).
  virtual void remap(std::span<const int> source, int n) = 0;
};

/// @brief The union of the network's capsules, blended at junctions (vessels::SpatialIndex).
class NetworkWall final : public Wall {
 public:
  /// @param where the vertices' locations (outlives this object), looked up before every use
  explicit NetworkWall(WireLocation& where) : where_(where) {}
  void ensure_size(int n) override { where_.ensure_size(n); }
  bool at(int i, const Vec3& x, double a, double reach, double* d, Vec3* n, Mat3* H) override;
  bool accepted(int i, const Vec3& x, double a, double reach, double s, AcceptedWall* out) override;
  void remap(std::span<const int> /*source*/, int /*n*/) override {}  // the locations remap themselves

 private:
  /// Whether a vertex of radius @p a at @p x is deeper than @p reach inside the capsule of
  /// @p segment (the union's wall is then farther still).
  [[nodiscard]] bool deep_inside(int segment, const Vec3& x, double a, double reach) const;
  WireLocation& where_;
};

/// @brief A triangulated lumen surface's smooth signed distance d_σ of width σ
/// (LumenSurface::smooth_distance), whose gradient is continuous. A vertex deeper inside than
/// surface_skip_depth(a, σ) + reach by the exact distance is not evaluated: d_σ lies within that
/// band of the exact distance on the real anatomies.
class SurfaceWall final : public Wall {
 public:
  /// @param surface the lumen (outlives this object)
  /// @param smoothing σ [m]
  /// @param wire_radius the wire's largest radius [m]: sizes the neighbourhoods and the skip depth
  /// @param reach how far outside the vertex's surface the contact begins (half the penalty's onset) [m]
  /// @param entry_margin vertices closer than this arc length to the entry are not measured for
  /// "outside" (the wire passes the open inlet there) [m]
  SurfaceWall(const vessels::LumenSurface& surface, double smoothing, double wire_radius, double reach,
              double entry_margin);
  void ensure_size(int n) override;
  bool at(int i, const Vec3& x, double a, double reach, double* d, Vec3* n, Mat3* H) override;
  bool accepted(int i, const Vec3& x, double a, double reach, double s, AcceptedWall* out) override;
  void remap(std::span<const int> source, int n) override;

 private:
  const vessels::LumenSurface& surface_;
  double smoothing_;
  double margin_;        ///< a vertex's triangles are gathered again once it has moved this far [m]
  double skip_;          ///< vertices deeper inside than this have no wall contact [m]
  double entry_margin_;  ///< [m]
  std::vector<vessels::SurfaceNeighbourhood> near_;  ///< (vertices) triangles near each vertex, kept across steps
  std::vector<vessels::SurfaceNeighbourhood> remap_near_;
};

}  // namespace flowire::coupling
