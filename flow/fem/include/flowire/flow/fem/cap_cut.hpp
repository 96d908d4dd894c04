#pragma once
/// @file cap_cut.hpp
/// @brief The network on the domain of a real lumen: every end branch ends where it crosses the
/// plane of its cap.
///
/// A centerline and the lumen it was drawn from need not end at the same place: the Feel++ arch's
/// centerlines run 1–8 mm beyond the surface's open ends, and a closed surface is cut half an end
/// radius before them (lumen.hpp). The 3D model imposes its boundary values on the caps, so a
/// network compared with it must impose them there too, or it counts the resistance of vessel
/// the 3D domain does not have (up to 15% of the drop in the arch's short branches). The cut is
/// made on the straight line of the end's last segments: where the branch crosses the cap's
/// plane from inside (the nodes beyond are dropped, the segment across is shortened in
/// proportion, its end radius interpolated), or, where the cap lies beyond the centerline's end,
/// by lengthening the last segment along its own direction up to the plane.
#include <span>
#include <string>
#include <vector>

#include "flowire/flow/fem/lumen.hpp"
#include "flowire/vessels/network.hpp"

namespace flowire::flow::fem {

/// @brief A network cut at a lumen's caps, and where each input node went.
struct CapCut {
  Network network;
  /// (input num_nodes) the node of `network` an input node became, -1 for a node cut away; the
  /// ends keep their identity (an end moves to its cap's plane)
  std::vector<int> node;
  /// (input num_segments) the segment of `network` an input segment became, -1 for one cut away
  std::vector<int> segment;
  /// (caps) the length cut from the end's branch: > 0 the centerline ran beyond the cap, < 0 the
  /// branch was lengthened to reach it (m)
  std::vector<double> cut_length;
};

/// @brief Cut `net` at `caps` (each names its end node; the normal points out of the lumen).
/// @throws flowire::Error (input) naming `source` and the end: a cap whose plane the end's branch
/// does not cross inside the branch (the whole branch beyond its cap), or a cap facing away from
/// the branch it ends.
CapCut cut_at_caps(const Network& net, std::span<const LumenCap> caps, const std::string& source);

}  // namespace flowire::flow::fem
