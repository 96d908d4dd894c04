#include "flowire/coupling/wire_location.hpp"

namespace flowire::coupling {

void WireLocation::ensure_size(int n) {
  if (static_cast<int>(segment_.size()) >= n) return;
  segment_.resize(static_cast<size_t>(n), -1);
  location_.resize(static_cast<size_t>(n));
  near_.resize(static_cast<size_t>(n));
}

void WireLocation::locate(const rod::RodView& rod, int free, InteractionStats& stats) {
  const int n = rod.vertex_count();
  ensure_size(n);
  // Hint: the same vertex's segment at the previous lookup, else the neighbour towards the
  // base (vertices are found from the base towards the tip). Beyond the hint's window, the
  // vertex's neighbourhood answers instead of the tree.
  for (int i = free - 1; i >= 0; --i) {
    const auto k = static_cast<size_t>(i);
    int hint = segment_[k];
    if (hint < 0 && i + 1 < n) hint = segment_[k + 1];
    location_[k] = index_.locate(rod.position(i), hint, near_[k]);
    segment_[k] = location_[k].segment;
    ++stats.lookups;
  }
}

void WireLocation::remap(const rod::RodView& rod, std::span<const int> source, InteractionStats& stats) {
  const int n = rod.vertex_count();
  remap_segments_.assign(segment_.begin(), segment_.end());
  remap_near_.swap(near_);
  near_.resize(remap_near_.size());
  ensure_size(n);
  for (int i = 0; i < n; ++i) {
    const int k = source[static_cast<size_t>(i)];
    const bool kept = k >= 0 && k < static_cast<int>(remap_segments_.size());
    segment_[static_cast<size_t>(i)] = kept ? remap_segments_[static_cast<size_t>(k)] : -1;
    // A neighbourhood is valid for any point within its margin, whichever vertex made it.
    auto& nb = near_[static_cast<size_t>(i)];
    if (kept && k < static_cast<int>(remap_near_.size()))
      nb = remap_near_[static_cast<size_t>(k)];  // within capacity after the first remaps
    else
      nb.clear();
  }
  // New vertices: located from the neighbour towards the base, as in locate().
  const int free = std::min(rod.first_clamped_vertex, n);
  for (int i = free - 1; i >= 0; --i) {
    if (segment_[static_cast<size_t>(i)] >= 0) continue;
    const int hint = i + 1 < n ? segment_[static_cast<size_t>(i + 1)] : -1;
    location_[static_cast<size_t>(i)] = index_.locate(rod.position(i), hint, near_[static_cast<size_t>(i)]);
    segment_[static_cast<size_t>(i)] = location_[static_cast<size_t>(i)].segment;
    ++stats.lookups;
  }
}

}  // namespace flowire::coupling
