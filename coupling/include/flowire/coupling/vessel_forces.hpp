#pragma once
/// @file vessel_forces.hpp
/// @brief What the vessels and the blood do to the wire, as one rod::ExternalForce:
/// locate every free vertex in a segment (window search seeded by the same vertex's
/// previous segment, fallback AABB tree), wall contact (penalty, implicit), Coulomb
/// friction (smooth stick/slip, implicit in velocity), blood drag from the local velocity
/// (the laws of drag.hpp, with their exact velocity Jacobian).
/// The penalty is reported as a conservative force with its energy k/2·δ₊², so the rod's
/// line search uses the exact contact potential; friction and drag are non-conservative.
///
/// Vertices are indexed from the distal tip (rod convention), so a vertex keeps its index,
/// and its lookup hint, while the wire is fed in at the base.
#include <algorithm>
#include <chrono>
#include <functional>
#include <limits>
#include <vector>

#include "flowire/coupling/interaction.hpp"
#include "flowire/rod/external.hpp"
#include "flowire/vessels/spatial.hpp"
#include "flowire/vessels/surface.hpp"

namespace flowire::coupling {

struct ContactParams {
  bool enabled = true;
  double stiffness = 0.0;  ///< penalty stiffness per vertex [N/m]
  /// [m] width of the penalty's smoothed onset around first touch (wall_penalty): the force
  /// ramps in over |δ| < onset/2, so that Newton sees a wall before it reaches it
  double onset = 0.0;
  double friction = 0.1;      ///< Coulomb coefficient, shaft (wire on vessel wall: 0.1–1.0, Tang et al. 2010, §3.3)
  double tip_friction = 0.1;  ///< Coulomb coefficient, tip region
  double tip_length = 0.03;   ///< [m] distal length using tip_friction
  double slip_speed = 1e-4;   ///< [m/s] smooth stick/slip transition width ε
  double viscous_friction = 0.0;  ///< [N s/m²] tangential viscous wall friction per unit length
};

/// @brief Blood velocity at a point located in a segment (e.g. FlowSolver::velocity_at).
using VelocityField = std::function<vessels::Vec3(int segment, const vessels::Vec3& p)>;

struct InteractionStats {
  std::uint64_t evaluations = 0;
  std::uint64_t lookups = 0;
  std::uint64_t contacts = 0;          ///< vertex evaluations in contact
  std::uint64_t wall_queries = 0;      ///< wall distances asked of the network or the lumen surface
  std::uint64_t drag_evaluations = 0;  ///< vertex evaluations of the blood drag
  double max_penetration = 0.0;        ///< over accepted steps [m]
  double max_outside = 0.0;            ///< max over accepted steps of (wall distance of a vertex centre) [m]
  /// Where and when a vertex centre was first more than a wire radius outside the lumen
  /// (outside_time < 0: never).
  double outside_time = -1.0;       ///< [s]
  double outside_arc_length = 0.0;  ///< of that vertex, from the entry [m]
  double outside_distance = 0.0;    ///< its distance outside the wall [m]
  Eigen::Vector3d outside_position = Eigen::Vector3d::Zero();
  double seconds_lookup = 0.0, seconds_contact = 0.0, seconds_drag = 0.0;
  double max_reynolds = 0.0;  ///< largest normal Reynolds number of the drag law over accepted steps [-]
};

/// @brief How deep inside (exact distance) a wire vertex of radius @p a may be before the
/// contact on a lumen surface of smoothing width @p sigma skips it: a + max(2σ, a/2). Exact as
/// long as d_σ < −a wherever d < −(that depth); measured on every real anatomy
/// (tests/coupling/test_surface_contact.cpp, SkippedDeepVerticesHaveNoContactOnTheRealLumens).
inline double surface_skip_depth(double a, double sigma) { return a + std::max(0.5 * sigma, 0.5 * a); }

class VesselForces : public rod::ExternalForce {
 public:
  /// @param index  spatial index of the network (outlives this object)
  /// @param wire_radius the wire's largest radius [m]: it sizes the lumen-surface neighbourhoods
  /// and skip depth; the contact and drag of each vertex take the rod's own radius there
  /// (RodView::vertex_radius), this one only where the view carries none
  /// @param drag the blood drag law (its wire_radius is set to `wire_radius`)
  VesselForces(const vessels::SpatialIndex& index, double wire_radius, ContactParams contact, DragModel drag,
               VelocityField velocity = {});

  void evaluate(const rod::RodView& rod, rod::ForceAccumulator& out) override;
  void end_step(const rod::RodView& rod) override;
  /// The friction's lagged normal forces of the step start (what end_step records).
  void save_checkpoint() override { checkpoint_ = {lag_normal_force_, lag_normal_, lagged_}; }
  void restore_checkpoint() override {
    drag_step_time_ = std::numeric_limits<double>::quiet_NaN();  // the retaken step linearizes anew
    lag_normal_force_ = checkpoint_.normal_force;
    lag_normal_ = checkpoint_.normal;
    lagged_ = checkpoint_.lagged;
  }
  /// Records the contact of a state set outside a step (initial, after a static solve), so
  /// the first step's friction is lagged as every other step's.
  void start(const rod::RodView& rod) override { end_step(rod); }
  /// Carries the segment hints over a resampling and records the step-start contact
  /// (normal force and normal for the lagged friction) of the new vertex set.
  void remap(const rod::RodView& rod, std::span<const int> source) override;

  /// @brief Segment of each vertex found at the last evaluation (−1: not looked up).
  [[nodiscard]] const std::vector<int>& segments() const { return segment_; }
  /// @brief Blood velocity at each vertex at the last evaluation.
  [[nodiscard]] const std::vector<vessels::Vec3>& fluid_velocity() const { return fluid_; }
  /// @brief Total interaction force on each vertex at the last evaluation [N].
  [[nodiscard]] const std::vector<vessels::Vec3>& force() const { return force_; }
  /// @brief The blood's share of force() (drag) [N].
  [[nodiscard]] const std::vector<vessels::Vec3>& drag_force() const { return drag_force_; }
  /// @brief The wall's share of force() (normal contact and friction) [N].
  [[nodiscard]] const std::vector<vessels::Vec3>& contact_force() const { return contact_force_; }
  /// @brief Sum of the drag on the free vertices at the last evaluation [N].
  [[nodiscard]] vessels::Vec3 total_drag() const;
  [[nodiscard]] const DragModel& drag() const { return drag_; }
  [[nodiscard]] const InteractionStats& stats() const { return stats_; }
  void set_velocity_field(VelocityField v) { velocity_ = std::move(v); }
  [[nodiscard]] const ContactParams& contact() const { return contact_; }

  /// @brief Wall contact against a triangulated lumen surface (outlives this object) instead
  /// of the network's capsules: the same penalty law on its signed distance (surface.hpp),
  /// the same friction; the network still locates the vertices for the blood velocity.
  /// Vertices closer than @p entry_margin (arc length) to the entry are not measured for
  /// `outside` (the wire passes the open inlet there).
  /// The wall is the surface's smooth signed distance d_σ of width @p smoothing
  /// (LumenSurface::smooth_distance), whose gradient is continuous. A vertex deeper inside
  /// than its radius plus max(2σ, 0.5 a) by the exact distance is not evaluated: d_σ lies within
  /// that band of the exact distance on the real anatomies (surface_skip_depth).
  void set_surface(const vessels::LumenSurface* surface, double smoothing, double entry_margin = 3e-3) {
    surface_ = surface;
    smoothing_ = smoothing;
    entry_margin_ = entry_margin;
    // A vertex's triangles are gathered again once it has moved a wire radius (or σ) away.
    surf_margin_ = std::max(wire_radius_, smoothing);
    surf_skip_ = surface_skip_depth(wire_radius_, smoothing) + 0.5 * contact_.onset;  // (the onset starts earlier)
  }
  /// @brief The entry as an introducer sheath: a wire vertex within @p reach of the entry
  /// axis may not come back out behind the entry (point @p p, unit direction @p t into the
  /// vessel): the wall penalty on the signed distance (p − x)·t − a to the plane one wire
  /// radius a behind the entry (vertices fed in at the entry itself stay free).
  void set_introducer(const vessels::Vec3& p, const vessels::Vec3& t, double reach) {
    intro_point_ = p;
    intro_dir_ = t.normalized();
    intro_reach_ = reach;
  }
  [[nodiscard]] std::uint64_t introducer_contacts() const { return intro_contacts_; }
  /// @brief Vertices the blood does not reach (a wire inside a catheter): shielded[i] != 0 has
  /// no drag. Set between steps (the catheter's LumenContact knows which); empty: none.
  void set_shielded(std::vector<char> shielded) { shielded_ = std::move(shielded); }
  [[nodiscard]] const std::vector<char>& shielded() const { return shielded_; }

 private:
  std::vector<char> shielded_;
  void ensure_size(int n);
  /// The wall's normal force on a vertex of radius @p a at wall distance @p d (wall_penalty's k φ′) [N].
  [[nodiscard]] double wall_normal_force(double d, double a, double cell_weight) const;
  std::vector<int> remap_segments_;
  std::vector<vessels::Neighbourhood> remap_near_;
  std::vector<vessels::Location> location_;   ///< (vertices) at the last evaluation
  std::vector<vessels::Neighbourhood> near_;  ///< (vertices) segments near each vertex, kept across steps
  const vessels::SpatialIndex& index_;
  double wire_radius_;
  ContactParams contact_;
  DragModel drag_;
  VelocityField velocity_;
  std::vector<int> segment_;
  std::vector<vessels::Vec3> fluid_, force_, drag_force_, contact_force_;
  std::vector<double> reynolds_;  ///< (vertices) normal Reynolds number at the last evaluation
  /// The drag of the step linearized at Newton's initial guess (DragModel::once_per_step):
  /// per vertex the force, its velocity Jacobian and the velocity they were taken at, valid
  /// for the solve drag_step_serial_ (RodView::solve_serial) of the step that ends at
  /// drag_step_time_ with drag_step_dt_.
  struct DragLinearization {
    vessels::Vec3 force = vessels::Vec3::Zero(), v = vessels::Vec3::Zero(), t = vessels::Vec3::UnitX();
    Eigen::Matrix3d dfdv = Eigen::Matrix3d::Zero();
    bool valid = false;
  };
  std::vector<DragLinearization> drag_lin_;
  double drag_step_time_ = std::numeric_limits<double>::quiet_NaN();
  double drag_step_dt_ = 0.0;
  long drag_step_serial_ = -1;
  int free_ = 0;                                             ///< free vertices at the last evaluation
  std::vector<double> cur_normal_force_, lag_normal_force_;  ///< (vertices) at this evaluation / step start
  std::vector<vessels::Vec3> cur_normal_, lag_normal_;
  bool lagged_ = false;
  struct {
    std::vector<double> normal_force;
    std::vector<vessels::Vec3> normal;
    bool lagged = false;
  } checkpoint_;
  InteractionStats stats_;
  /// Wall distance and normal of vertex i (radius @p a) at @p x (the lumen surface's smooth
  /// distance, or the network's blended capsules); false where the vertex is deep inside (no wall near).
  bool wall_at(int i, const Vec3& x, double a, double* d, Vec3* n, Mat3* H);
  /// Smooth wall distance of vertex i from the surface; false if it is deeper than surf_skip_.
  bool surface_wall(int i, const vessels::Vec3& x, double* d, vessels::Vec3* n, Mat3* H);
  const vessels::LumenSurface* surface_ = nullptr;
  double entry_margin_ = 0.0;
  double smoothing_ = 0.0;
  double surf_margin_ = 0.0;                              ///< margin of the vertices' surface neighbourhoods [m]
  double surf_skip_ = 0.0;                                ///< vertices deeper inside than this have no wall contact [m]
  std::vector<vessels::SurfaceNeighbourhood> surf_near_;  ///< (vertices) triangles near each vertex, kept across steps
  std::vector<vessels::SurfaceNeighbourhood> remap_surf_near_;
  vessels::Vec3 intro_point_ = vessels::Vec3::Zero(), intro_dir_ = vessels::Vec3::Zero();
  double intro_reach_ = 0.0;  ///< 0: no introducer
  std::uint64_t intro_contacts_ = 0;
};

}  // namespace flowire::coupling
