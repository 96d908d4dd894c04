#pragma once
/// @file feeder.hpp
/// @brief Which part of the wire is simulated, and where its held unknowns are.
///
/// **Feeding.** The free wire lies on a fixed grid in the material coordinate (model.hpp), from
/// the tip to the last grid point within [h/2, 3h/2) of the entry. Then come the clamp's two
/// held vertices: the boundary vertex, the material point at the entry itself (u = inserted
/// length), and one a segment behind it on the insertion line. The last free edge (the boundary
/// edge) thus has a rest length that follows the feed: the next grid point is inserted on it when
/// it would pass 3h/2 and its last free vertex removed when it would fall below h/2 (their twist
/// kept continuous). The clamp's support stays at the entry, so the free wire and the clamp's
/// force change continuously with the inserted length (a grid vertex as the clamp's support would
/// jump back by a segment each time the feed frees one). `set_prescribed` puts the held unknowns
/// where the clamp (and an optional tip clamp) holds them; `predict_feed` gives Newton a start in
/// which the wire slid along itself, `predict_slide` one in which the wire's path also changes as
/// it did over the last step.
///
/// **Adaptivity** (`WireSpec::adapt`): `adapt` splits free edges where the wire is bent and
/// merges them where it is straight, on a dyadic hierarchy in the material coordinate, and
/// carries the state over (resample: positions on the Hermite curve through the old vertices and
/// tangents, velocities interpolated, frames transported, twist density kept). The boundary
/// edge follows the level of the edge before it (ℓ instead of h above): refining that edge
/// refines the boundary, and the feed then inserts points of that level.
///
/// The feeder moves vertices of the body's state and changes its vertex set; it solves
/// nothing (the TimeStepper, stepper.hpp, does).
#include <Eigen/Core>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "flowire/rod/body.hpp"
#include "flowire/rod/drive.hpp"

namespace flowire::rod {

/// @brief The curve the wire lay on at one instant: its vertices, their material coordinates
/// (increasing from the tip) and the inserted length, which places each vertex at arc length
/// σ = inserted − u from the entry (the insertion line behind it).
struct WirePath {
  std::span<const Eigen::Vector3d> x;
  std::span<const double> u;
  double inserted = 0.0;
  /// The vertices' tangents if already known (as Feeder::path_point defines them); empty: computed.
  std::span<const Eigen::Vector3d> tangent = {};
};

class Feeder {
 public:
  /// @p body: the rod this feeder lays out (kept by reference; it must outlive the feeder).
  explicit Feeder(RodBody& body);
  ~Feeder();
  Feeder(const Feeder&) = delete;
  Feeder& operator=(const Feeder&) = delete;

  /// @brief The vertex set of @p inserted metres inserted, laid out in the rest shape from the
  /// clamp (a pre-shaped tip bent about the base normal), at rest, base angle 0.
  void build(double inserted);
  /// @brief Positions, frames and zero velocities/angles of the rest shape on the current vertices.
  void layout_rest_shape();
  /// @brief The free part laid on a curve at rest: vertex k at @p along(s_k), s_k its arc length
  /// from the entry; frames parallel-transported from the clamp (no twist).
  void lay_along(const std::function<Eigen::Vector3d(double)>& along);

  /// @brief The clamp's drive (feeding and turning rules).
  Drive& drive() { return drive_; }
  [[nodiscard]] const Drive& drive() const { return drive_; }
  /// @brief This step's feed speed [m/s] (the drive's, unless held at the wire's ends).
  [[nodiscard]] double feed_speed() const { return feed_speed_; }
  void set_feed_speed(double speed) { feed_speed_ = speed; }

  /// @brief The inserted length at the end of a step of @p dt at the feed speed (held between
  /// two segments and the wire's length, with a warning and the feed stopped), with the vertex
  /// set updated to it; the state's base angle set to the drive's.
  double feed_vertex_set(double dt);
  /// @brief The vertex set for inserted length @p inserted (free points inserted at or removed
  /// from the boundary edge; the held ones placed where that material lay at the current one).
  void update_vertex_set(double inserted);
  /// @brief The held unknowns of @p x, @p theta where the clamp at inserted length @p inserted
  /// and base angle @p angle (and a tip clamp) put them.
  void set_prescribed(double inserted, double angle, std::vector<Eigen::Vector3d>& x, std::vector<double>& theta) const;
  /// @brief Newton's start while feeding @p fed metres in a stage of length @p h: each free
  /// vertex where material u − fed lay at the stage's start (@p x0, @p v0), plus its velocity
  /// across the wire. No-op for fed = 0.
  void predict_feed(double fed, double h, std::span<const Eigen::Vector3d> x0, std::span<const Eigen::Vector3d> v0);
  /// @brief Newton's start for a step of the same length as the last one, ending at inserted
  /// length @p inserted, from the wire's path at this step's start (@p now) and at the last
  /// step's (@p before): each free vertex at 2·now(σ) − before(σ), σ its arc length from the
  /// entry at the step's end (the path extrapolated in time at a fixed place along it: exact for
  /// a wire sliding along a path that is fixed in space or changes at a steady rate). The tip
  /// goes where the path has not been, and a pre-shaped one carries its shape with the
  /// material: there (the tip vertex, or the pre-shaped length) the state's own guess is kept,
  /// blended into the slide over `kSlideBlend` behind it.
  void predict_slide(double inserted, const WirePath& now, const WirePath& before);
  /// @brief The point of @p path at arc length @p sigma from the entry: on the cubic Hermite
  /// curve through the vertices (tangents from the neighbouring edges), on the insertion line
  /// behind the entry; past the tip on the first edge's cubic for one edge, then straight on.
  [[nodiscard]] Eigen::Vector3d path_point(const WirePath& path, double sigma) const;
  /// The length over which predict_slide passes from the tip's own guess to the slide [m].
  static constexpr double kSlideBlend = 0.01;

  /// @brief Index of the first clamped vertex (the boundary vertex, at the entry).
  [[nodiscard]] int first_clamped() const { return first_clamped_; }
  /// @brief For a step taken again from a kept start (the vertex set of that start).
  void set_first_clamped(int k) { first_clamped_ = k; }
  /// @brief (n_vertices) arc length from the entry point [m]: > 0 inserted, ≤ 0 clamped.
  [[nodiscard]] std::span<const double> arc_lengths() const { return arc_length_; }
  /// @brief arc_lengths() for the state's inserted length and vertices.
  void refresh_arc_lengths();
  /// @brief The first unknown that is not held by a tip clamp (x0, θ0, x1 are).
  [[nodiscard]] int first_free_dof() const { return tip_clamped_ ? 7 : 0; }
  /// @brief The first unknown held by the base clamp (4 · first clamped vertex).
  [[nodiscard]] int first_fixed_dof() const { return 4 * first_clamped_; }
  /// @brief Whether vertex @p k's position is an unknown.
  [[nodiscard]] bool free_vertex(int k) const { return k < first_clamped_ && !(tip_clamped_ && k < 2); }
  /// @brief Bending parameters of interior vertex @p k: a clamp vertex owns only the half cell
  /// on its free side (the wire behind it is rigid), as does vertex 1 under a tip clamp.
  void vertex_params(int k, VertexParams& p) const;

  /// @brief Hold the distal edge: vertex 0 at @p tip, vertex 1 at @p next, its angle as it is.
  void clamp_tip(const Eigen::Vector3d& tip, const Eigen::Vector3d& next);
  void release_tip() { tip_clamped_ = false; }
  [[nodiscard]] bool tip_clamped() const { return tip_clamped_; }

  /// @brief Resample the free part (a no-op unless adaptivity is on); @p on_resample is told,
  /// after a resampling, the old vertex each new one copies (−1: a new vertex). True if the set
  /// changed.
  bool adapt(const std::function<void(const std::vector<int>&)>& on_resample);
  /// @brief Vertices added and removed by adaptivity so far.
  [[nodiscard]] long adapt_splits() const { return adapt_splits_; }
  [[nodiscard]] long adapt_merges() const { return adapt_merges_; }

 private:
  struct Scratch;
  /// Whether the boundary edge from a last free vertex at @p u_last (the one before it at
  /// @p u_prev) to the entry at @p inserted needs a vertex inserted (+1), its last free vertex
  /// removed (−1, if @p removable) or neither (0): it stays within [ℓ/2, 3ℓ/2), ℓ = u_last − u_prev.
  [[nodiscard]] int boundary_change(double inserted, double u_prev, double u_last, bool removable) const;
  /// The material coordinate of the vertex inserted after @p u_last (the next one of its level).
  [[nodiscard]] double next_boundary_point(double u_prev, double u_last) const;
  /// Free material coordinates @p u (from the tip) completed or cut so that the boundary edge
  /// to the entry at @p inserted is within [ℓ/2, 3ℓ/2) of the edge before it.
  void boundary_vertices(double inserted, std::vector<double>& u) const;
  /// Replace the vertex set by the one at material coordinates @p u_new (a dyadic refinement
  /// or coarsening of the current one), carrying the state over.
  void resample(const std::vector<double>& u_new);

  RodBody& body_;
  std::unique_ptr<Scratch> scratch_;
  Drive drive_;
  double feed_speed_ = 0.0;
  int first_clamped_ = 0;
  std::vector<double> arc_length_;
  Eigen::Vector3d base_d1_ = Eigen::Vector3d::Zero();  // the clamp's frame at zero rotation
  Eigen::Vector3d base_d2_ = Eigen::Vector3d::Zero();
  bool tip_clamped_ = false;
  Eigen::Vector3d tip_clamp_x0_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d tip_clamp_x1_ = Eigen::Vector3d::Zero();
  double tip_clamp_theta_ = 0.0;
  long adapt_splits_ = 0, adapt_merges_ = 0;
};

}  // namespace flowire::rod
