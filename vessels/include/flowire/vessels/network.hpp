#pragma once
/// @file network.hpp
/// @brief The vessel network: centerline branches split into cylindrical segments.
///
/// A network is built once from centerlines (`Centerlines`: one polyline with radii per
/// branch, SI units) and is constant afterwards (constant model, changing state).
/// Nodes are points of the graph; segments are straight tubes between two nodes whose
/// radius runs linearly between the two end radii of their own branch (see `Segment`). Branch ends that meet within a
/// tolerance share a node (junctions); nodes of degree one are ends (inlets/outlets). Loops are allowed and counted as
/// the cyclomatic number E − V + C.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace flowire::vessels {

using Vec3 = Eigen::Vector3d;

/// @brief A point as messages name it: "(x, y, z) mm", two decimals.
[[nodiscard]] std::string mm(const Vec3& x);

/// @brief One centerline branch as read from a file: points and radius at each point (m).
struct Polyline {
  std::string name;
  std::vector<Vec3> points;
  std::vector<double> radii;
};

/// @brief Raw centerlines, in metres, before splitting into segments.
struct Centerlines {
  std::vector<Polyline> branches;
  std::string source;  ///< file name (for messages)
};

/// @brief How branches become segments.
struct BuildOptions {
  /// Segments are no longer than this (m); a branch is split uniformly in arc length.
  double max_segment_length = 5e-3;
  /// Also split where the radius changes by more than this fraction of the segment's radius.
  double radius_change = 0.1;
  /// Also split where the branch bends: no centerline point lies farther from its segment's
  /// axis than this fraction of its radius (a straight segment cuts a bend by its sagitta).
  /// <= 0: no such split.
  double max_chord_deviation = 0.1;
  /// Branch ends closer than this (m) are the same node. <= 0: 1e-3 of the smallest radius.
  double join_tolerance = 0.0;
};

/// @brief A straight piece of vessel between two nodes: a conical frustum whose radius runs
/// linearly from `radius_from` (at `node_from`) to `radius_to` (at `node_to`), both taken
/// from the segment's own branch (a junction node has no radius of its own: each segment
/// meeting there keeps its branch's radius).
///
/// `radius` is the single radius of the cylinder that stands for the segment wherever one
/// radius is needed (wall contact and distance, spatial lookup, FEM meshing, VTK output,
/// velocities from a flow rate): the arc-length mean radius, (radius_from + radius_to) / 2
/// for a linear taper. The flow resistance, inertance and compliance integrate the taper
/// exactly instead (flow/solver.hpp, `segment_resistance`).
struct Segment {
  int node_from = -1;
  int node_to = -1;
  double radius = 0.0;  ///< m, mean radius (see above)
  double length = 0.0;  ///< m
  int branch = -1;
  double radius_from = 0.0;  ///< m, at node_from; <= 0 on input: `radius` (a cylinder)
  double radius_to = 0.0;    ///< m, at node_to; <= 0 on input: `radius`
  /// Its sections' Poiseuille resistance over that of the circles of the same area (1: circular;
  /// (a² + b²)/(2ab) for an ellipse of half-axes a, b; from a lumen surface, sections.hpp).
  double shape = 1.0;
  /// @brief The radius at one of its two nodes.
  [[nodiscard]] double radius_at(int node) const { return node == node_from ? radius_from : radius_to; }
};

struct Branch {
  std::string name;
  std::vector<int> nodes;     ///< ordered along the branch, nodes.size() == segments.size() + 1
  std::vector<int> segments;  ///< ordered along the branch
};

struct NetworkCounts {
  int branches = 0, nodes = 0, segments = 0, junctions = 0, ends = 0, loops = 0, components = 0;
  double total_length = 0.0, radius_min = 0.0, radius_max = 0.0;
};

class Network {
 public:
  Network() = default;

  /// @brief Split centerlines into segments and join branch ends into a graph.
  /// @throws flowire::Error (input) naming `c.source` and the branch / point at fault.
  static Network build(const Centerlines& c, const BuildOptions& opt = {});

  /// @brief Build directly from nodes and segments (generators, svZeroDSolver models).
  /// Each segment becomes its own branch unless `branches` is given.
  static Network from_graph(std::vector<Vec3> nodes, std::vector<Segment> segments, std::vector<Branch> branches = {},
                            std::string source = {});

  [[nodiscard]] int num_nodes() const { return static_cast<int>(nodes_.size()); }
  [[nodiscard]] int num_segments() const { return static_cast<int>(segments_.size()); }
  [[nodiscard]] int num_branches() const { return static_cast<int>(branches_.size()); }

  [[nodiscard]] const Vec3& node(int i) const { return nodes_[static_cast<size_t>(i)]; }
  [[nodiscard]] const std::vector<Vec3>& nodes() const { return nodes_; }
  [[nodiscard]] const Segment& segment(int s) const { return segments_[static_cast<size_t>(s)]; }
  [[nodiscard]] const std::vector<Segment>& segments() const { return segments_; }
  [[nodiscard]] const Branch& branch(int b) const { return branches_[static_cast<size_t>(b)]; }
  [[nodiscard]] const std::vector<Branch>& branches() const { return branches_; }
  [[nodiscard]] const std::string& source() const { return source_; }
  /// @brief The branch named @p name (the last of that name), −1 if there is none.
  [[nodiscard]] int branch_named(const std::string& name) const;
  /// @brief The named branches' names, comma-separated, or "none named": what a message about a
  /// branch name that is not there lists.
  [[nodiscard]] std::string branch_names() const;

  /// @brief Segments incident to node i (CSR view).
  [[nodiscard]] std::pair<const int*, const int*> node_segments(int i) const {
    const auto b = static_cast<size_t>(node_offsets_[static_cast<size_t>(i)]);
    const auto e = static_cast<size_t>(node_offsets_[static_cast<size_t>(i) + 1]);
    return {node_adjacency_.data() + b, node_adjacency_.data() + e};
  }
  [[nodiscard]] int degree(int i) const {
    return node_offsets_[static_cast<size_t>(i) + 1] - node_offsets_[static_cast<size_t>(i)];
  }

  /// @brief Nodes of degree one, in index order.
  [[nodiscard]] std::vector<int> ends() const;
  /// @brief The end with the largest radius there (the default flow inlet).
  [[nodiscard]] int widest_end() const;
  /// @brief Connected component id of each node, and their number.
  [[nodiscard]] std::vector<int> components(int* count = nullptr) const;
  [[nodiscard]] NetworkCounts counts() const;

  /// @brief Distance along the vessels from node `from` to every node (infinity if unreachable).
  [[nodiscard]] std::vector<double> path_lengths_from(int from) const;
  /// @brief The end farthest along the vessels from node `from` (−1 if none): where a wire
  /// enters to be pushed against the flow towards the inlet, as in the published experiment.
  [[nodiscard]] int farthest_end(int from) const;

  /// @brief A copy keeping only the connected piece that holds node `keep`; ids renumbered.
  [[nodiscard]] Network keep_component(int keep) const;

 private:
  void finalize();  ///< builds adjacency, validates
  std::vector<Vec3> nodes_;
  std::vector<Segment> segments_;
  std::vector<Branch> branches_;
  std::vector<int> node_offsets_;
  std::vector<int> node_adjacency_;
  std::string source_;
};

}  // namespace flowire::vessels
