#pragma once
/// @file wire_location.hpp
/// @brief Where each free vertex of the wire lies in the network: its segment (the nearest
/// capsule's, window search seeded by the same vertex's previous segment, else by its
/// neighbour towards the base; the AABB tree beyond the window) and the segments near it, kept
/// across steps. The wall of the network's capsules (wall.hpp) and the blood drag
/// (blood_drag.hpp) read it; neither looks a vertex up itself.
///
/// Vertices are indexed from the distal tip (rod convention), so a vertex keeps its index,
/// and its lookup hint, while the wire is fed in at the base.
#include <span>
#include <vector>

#include "flowire/coupling/interaction.hpp"
#include "flowire/rod/external.hpp"
#include "flowire/vessels/spatial.hpp"

namespace flowire::coupling {

class WireLocation {
 public:
  /// @param index spatial index of the network (outlives this object)
  explicit WireLocation(const vessels::SpatialIndex& index) : index_(index) {}

  /// @brief Locate the free vertices (index < @p free) of @p rod, from the base towards the tip.
  void locate(const rod::RodView& rod, int free, InteractionStats& stats);
  /// @brief The rod resampled its vertices (rod::ExternalForce::remap): hints and neighbourhoods
  /// carried over from each vertex's source, new free vertices located.
  void remap(const rod::RodView& rod, std::span<const int> source, InteractionStats& stats);
  /// @brief Room for @p n vertices (new ones not looked up yet: segment −1).
  void ensure_size(int n);

  [[nodiscard]] const vessels::SpatialIndex& index() const { return index_; }
  /// @brief (vertices) segment of each vertex at the last lookup (−1: not looked up).
  [[nodiscard]] const std::vector<int>& segments() const { return segment_; }
  [[nodiscard]] int segment(int i) const { return segment_[static_cast<size_t>(i)]; }
  [[nodiscard]] const vessels::Location& location(int i) const { return location_[static_cast<size_t>(i)]; }
  /// @brief The segments near vertex @p i (a cache the index refreshes as the vertex moves).
  [[nodiscard]] vessels::Neighbourhood& near(int i) { return near_[static_cast<size_t>(i)]; }

 private:
  const vessels::SpatialIndex& index_;
  std::vector<int> segment_;                  ///< (vertices) at the last lookup
  std::vector<vessels::Location> location_;   ///< (vertices) at the last lookup
  std::vector<vessels::Neighbourhood> near_;  ///< (vertices) kept across steps
  std::vector<int> remap_segments_;           ///< remap's copies, kept for their capacity
  std::vector<vessels::Neighbourhood> remap_near_;
};

}  // namespace flowire::coupling
