#pragma once
/// @file spatial.hpp
/// @brief Spatial queries on a network: which segment holds a point, distance to the wall.
///
/// The lumen is the union of the segments' capsules (cylinder of radius r around the
/// segment's axis, closed by half-spheres at the nodes). `locate` searches first a window
/// of ±`window` segments (by index, plus the segments sharing a node with the hint) around
/// a hint — the previous query's answer, as in the published method — and falls back to an
/// AABB tree when no segment of the window holds the point, so the answer is never wrong:
/// the returned segment holds the point whenever any segment does; otherwise it is the
/// segment whose wall is nearest and `inside` is false.
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "flowire/vessels/network.hpp"

namespace flowire::vessels {

/// @brief Closest point on a segment's axis.
struct AxisProjection {
  double t = 0.0;         ///< parameter along the axis, clamped to [0, 1]
  double distance = 0.0;  ///< distance from the point to the axis point
};
AxisProjection project_on_axis(const Vec3& p, const Vec3& a, const Vec3& b);

struct Location {
  int segment = -1;
  bool inside = false;
  double t = 0.0;              ///< axial parameter in [0, 1] from node_from
  double axis_distance = 0.0;  ///< distance to the axis (m)
  bool from_window = false;    ///< found by the window search (else by the fallback)
};

struct LocatorStats {
  std::uint64_t window_hits = 0;
  std::uint64_t fallbacks = 0;
  std::uint64_t gathers = 0;  ///< neighbourhoods (re)gathered from the tree
};

/// @brief The segments near a point, gathered once from the tree and reused by the queries
/// at points close to it (a wire vertex moves little between Newton iterates and steps).
///
/// Holds every segment whose box lies within `reach` of `centre`, in the tree's traversal
/// order. A query at p with |p − centre| = δ needs only the segments whose box lies within
/// some radius ρ of p; when ρ + δ ≤ reach they are all here, in the order the tree would
/// visit them, so the answer is the general path's to the last bit. Otherwise the query
/// gathers again around p (`SpatialIndex::locate(p, hint, nb)`, `wall_distance(p, loc, nb)`).
struct Neighbourhood {
  Vec3 centre = Vec3::Zero();
  double reach = -1.0;        ///< < 0: empty
  std::vector<int> segments;  ///< (segments near centre) in traversal order
  void clear() {
    reach = -1.0;
    segments.clear();
  }
};

class SpatialIndex {
 public:
  explicit SpatialIndex(const Network& net, int window = 4);

  /// @brief The segment holding `p`, searched around `hint` first (hint < 0: no hint).
  Location locate(const Vec3& p, int hint = -1) const;
  /// @brief Reference answer by checking every segment (for tests and benchmarks).
  Location locate_brute_force(const Vec3& p) const;

  /// @brief Signed distance to the wall of the union of capsules (negative inside), with a
  /// smooth minimum of width `blend` (m) across junctions; gradient (outward normal) if asked.
  /// Only segments within reach of `hint` are considered when hint >= 0. With @p hessian,
  /// also its exact second derivative (capsule curvature terms plus the blend's own
  /// −(g_a − g_b)(g_a − g_b)ᵀ/(2k)), which a penalty contact needs for Newton to converge
  /// quadratically near junctions and bends.
  double wall_distance(const Vec3& p, int hint = -1, Vec3* gradient = nullptr,
                       Eigen::Matrix3d* hessian = nullptr) const;

  /// @brief locate(p, hint) answered from a neighbourhood (gathered again around p when it
  /// does not cover the query): the same answer, without descending the tree.
  Location locate(const Vec3& p, int hint, Neighbourhood& nb) const;
  /// @brief wall_distance(p, loc.segment, …) for @p loc = locate(p, …), answered from a
  /// neighbourhood (gathered again around p when it does not cover the query): the same
  /// value, gradient and Hessian to the last bit.
  double wall_distance(const Vec3& p, const Location& loc, Neighbourhood& nb, Vec3* gradient = nullptr,
                       Eigen::Matrix3d* hessian = nullptr) const;
  /// @brief Fill @p nb with every segment whose box lies within @p reach of @p centre.
  void gather(const Vec3& centre, double reach, Neighbourhood& nb) const;

  [[nodiscard]] const LocatorStats& stats() const { return stats_; }
  void reset_stats() const { stats_ = {}; }
  [[nodiscard]] const Network& network() const { return net_; }
  [[nodiscard]] int window() const { return window_; }

 private:
  struct BvhNode {
    Eigen::AlignedBox3d box;
    int left = -1, right = -1;  ///< children (internal) or -1
    int first = 0, count = 0;   ///< leaf range in order_
  };
  int build_bvh(int first, int count, int depth);
  bool test_segment(const Vec3& p, int s, Location& best) const;
  Location fallback(const Vec3& p) const;
  /// Keeps in @p best the segment whose wall is nearest (ties: the lower index).
  void nearest_wall_candidate(const Vec3& p, int s, double& best_d, Location& best) const;
  /// The hint, then its window: true if a segment of them holds p (the best one in @p best).
  bool holds_in_window(const Vec3& p, int hint, Location& best) const;
  /// The first stage of both locate() overloads: holds_in_window, counted in stats() as a
  /// window hit (and @p best marked `from_window`) or as a fallback to come. False: the
  /// caller falls back.
  bool locate_in_window(const Vec3& p, int hint, Location& best) const;
  void nearby_segments(const Vec3& p, double radius, std::vector<int>& out) const;
  /// Radius around p that wall_distance searches when p is located in @p loc.
  double wall_search_radius(const Location& loc) const;
  /// Union-of-capsules distance over @p cand (in traversal order), blended at junctions.
  double blended_distance(const Vec3& p, const std::vector<int>& cand, const Location& loc, Vec3* gradient,
                          Eigen::Matrix3d* hessian) const;
  /// Reach gathered around a point located in @p loc: the wall search radius plus room
  /// for the point to move.
  double gather_reach(const Location& loc) const;

  const Network& net_;
  int window_;
  std::vector<Eigen::AlignedBox3d> seg_boxes_;
  std::vector<int> order_;
  std::vector<BvhNode> bvh_;
  mutable LocatorStats stats_;
};

}  // namespace flowire::vessels
