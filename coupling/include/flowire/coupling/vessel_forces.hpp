#pragma once
/// @file vessel_forces.hpp
/// @brief What the vessels and the blood do to the wire, as one rod::ExternalForce made of
/// parts with one job each, evaluated in this order at every Newton iterate:
/// - `WireLocation` (wire_location.hpp): the segment of each free vertex;
/// - `WallContact` (wall_contact.hpp): the wall's normal force (penalty, implicit, with its
///   potential) against a `Wall` (wall.hpp): the network's capsules, or a lumen surface;
/// - `WallFriction` (wall_friction.hpp): smooth Coulomb friction, pressed as the contact
///   recorded at the step's start;
/// - `BloodDrag` (blood_drag.hpp): the blood drag from the local velocity.
/// Every part reads the wire's radius at each vertex from the rod (RodView::vertex_radius).
///
/// Vertices are indexed from the distal tip (rod convention), so a vertex keeps its index,
/// and its lookup hint, while the wire is fed in at the base.
#include <memory>
#include <vector>

#include "flowire/coupling/blood_drag.hpp"
#include "flowire/coupling/interaction.hpp"
#include "flowire/coupling/wall.hpp"
#include "flowire/coupling/wall_contact.hpp"
#include "flowire/coupling/wall_friction.hpp"
#include "flowire/coupling/wire_location.hpp"
#include "flowire/rod/external.hpp"
#include "flowire/vessels/spatial.hpp"
#include "flowire/vessels/surface.hpp"

namespace flowire::coupling {

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
  void save_checkpoint() override { contact_law_.save_checkpoint(); }
  void restore_checkpoint() override {
    drag_law_.invalidate();  // the retaken step linearizes anew
    contact_law_.restore_checkpoint();
  }
  /// Records the contact of a state set outside a step (initial, after a static solve), so
  /// the first step's friction is lagged as every other step's.
  void start(const rod::RodView& rod) override { end_step(rod); }
  /// Carries the segment hints over a resampling and records the step-start contact
  /// (normal force and normal for the lagged friction) of the new vertex set.
  void remap(const rod::RodView& rod, std::span<const int> source) override;

  /// @brief Segment of each vertex found at the last evaluation (−1: not looked up).
  [[nodiscard]] const std::vector<int>& segments() const { return where_.segments(); }
  /// @brief Blood velocity at each vertex at the last evaluation.
  [[nodiscard]] const std::vector<vessels::Vec3>& fluid_velocity() const { return drag_law_.fluid_velocity(); }
  /// @brief Total interaction force on each vertex at the last evaluation [N].
  [[nodiscard]] const std::vector<vessels::Vec3>& force() const { return force_; }
  /// @brief The blood's share of force() (drag) [N].
  [[nodiscard]] const std::vector<vessels::Vec3>& drag_force() const { return drag_force_; }
  /// @brief The wall's share of force() (normal contact and friction) [N].
  [[nodiscard]] const std::vector<vessels::Vec3>& contact_force() const { return contact_force_; }
  /// @brief Sum of the drag on the free vertices at the last evaluation [N].
  [[nodiscard]] vessels::Vec3 total_drag() const;
  [[nodiscard]] const DragModel& drag() const { return drag_law_.model(); }
  [[nodiscard]] const InteractionStats& stats() const { return stats_; }
  void set_velocity_field(VelocityField v) { drag_law_.set_velocity_field(std::move(v)); }
  [[nodiscard]] const ContactParams& contact() const { return contact_law_.params(); }
  /// @brief The wall contact's potential energy at the last evaluation (WallContact::energy) [J].
  [[nodiscard]] double contact_energy() const { return contact_law_.energy(); }

  /// @brief Wall contact against a triangulated lumen surface (outlives this object) instead
  /// of the network's capsules (SurfaceWall: its smooth signed distance of width @p smoothing);
  /// the same penalty law, the same friction; the network still locates the vertices for the
  /// blood velocity. Vertices closer than @p entry_margin (arc length) to the entry are not
  /// measured for `outside` (the wire passes the open inlet there).
  void set_surface(const vessels::LumenSurface* surface, double smoothing, double entry_margin = 3e-3);
  /// @brief A wall that yields to the wire (compliant_wall.hpp; outlives this object): the
  /// contact meets it where it has moved, and the wall takes the contact forces' opposites.
  void set_deformable(CompliantWall* wall) { contact_law_.set_deformable(wall); }
  /// @brief The entry as an introducer sheath (WallContact::set_introducer).
  void set_introducer(const vessels::Vec3& p, const vessels::Vec3& t, double reach) {
    contact_law_.set_introducer(p, t, reach);
  }
  [[nodiscard]] std::uint64_t introducer_contacts() const { return contact_law_.introducer_contacts(); }
  /// @brief Vertices the blood does not reach (a wire inside a catheter): shielded[i] != 0 has
  /// no drag. Set between steps (the catheter's LumenContact knows which); empty: none.
  void set_shielded(std::vector<char> shielded) { drag_law_.set_shielded(std::move(shielded)); }
  [[nodiscard]] const std::vector<char>& shielded() const { return drag_law_.shielded(); }

 private:
  void ensure_size(int n);
  double wire_radius_;
  WireLocation where_;
  std::unique_ptr<Wall> wall_;  ///< the network's capsules, or the lumen surface of set_surface
  WallContact contact_law_;
  WallFriction friction_law_;
  BloodDrag drag_law_;
  int free_ = 0;                                                   ///< free vertices at the last evaluation
  std::vector<vessels::Vec3> force_, drag_force_, contact_force_;  ///< (vertices) at the last evaluation
  InteractionStats stats_;
};

}  // namespace flowire::coupling
