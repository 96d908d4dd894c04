#pragma once
/// @file wall_friction.hpp
/// @brief The wall's friction on the wire: smooth Coulomb friction (interaction.hpp,
/// `coulomb_friction`) pressed by the normal force and along the normal of the step's start
/// (WallContact's lagged record, as in IPC: the force is then a function of the velocity
/// alone and its Jacobian exact, which keeps Newton quadratic at high μ), reported with its
/// incremental potential Δt·D(v) so that the rod's line search measures it exactly; the tip's
/// own coefficient over `tip_length`; and an optional viscous wall friction, tangential and
/// linear in the velocity.
#include <span>

#include "flowire/coupling/wall_contact.hpp"

namespace flowire::coupling {

class WallFriction {
 public:
  explicit WallFriction(const ContactParams& params) : params_(params) {}
  /// @brief Add the friction on the free vertices (index < @p free), pressed as @p contact
  /// records, to @p out, and each vertex's force to @p tally.
  void evaluate(const rod::RodView& rod, int free, const WallContact& contact, rod::ForceAccumulator& out,
                std::span<Vec3> tally) const;

 private:
  ContactParams params_;
};

}  // namespace flowire::coupling
