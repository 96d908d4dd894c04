#include "flowire/coupling/wall_friction.hpp"

namespace flowire::coupling {

void WallFriction::evaluate(const rod::RodView& rod, int free, const WallContact& contact, rod::ForceAccumulator& out,
                            std::span<Vec3> tally) const {
  const int n = rod.vertex_count();
  const double tip_s = rod.arc_length.empty() ? 0.0 : rod.arc_length[0];
  // The first step (nothing lagged yet) presses with the current normal forces.
  const bool lag = contact.lagged();
  for (int i = 0; i < free; ++i) {
    const auto k = static_cast<size_t>(i);
    const double normal_force = contact.normal_force(i);
    if (normal_force <= 0.0) continue;
    const Vec3& nrm = contact.normal(i);
    const double mu = (tip_s - rod.arc_length[k] <= params_.tip_length) ? params_.tip_friction : params_.friction;
    const auto fr = coulomb_friction(rod.velocity(i), nrm, normal_force, mu, params_.slip_speed);
    if (lag && rod.dt > 0.0) {
      // With the normal force fixed over the step, friction is −∇_v D(v) with v = (x − x₀)/Δt:
      // the gradient in x of Δt·D, an exact incremental potential (as in IPC). Reported as
      // one, the line search measures friction exactly instead of by the work along its ray,
      // which across the stick/slip band of width ε is far off.
      out.add_conservative_force(i, fr.force);
      out.add_energy(rod.dt * fr.dissipation);
    } else {
      out.add_force(i, fr.force);
    }
    out.add_velocity_jacobian(i, fr.dfdv);
    tally[k] += fr.force;
    if (params_.viscous_friction > 0.0) {
      const Vec3& x = rod.position(i);
      const double ell = 0.5 * ((i > 0 ? (x - rod.position(i - 1)).norm() : 0.0) +
                                (i + 1 < n ? (rod.position(i + 1) - x).norm() : 0.0));
      const Mat3 C = params_.viscous_friction * ell * (Mat3::Identity() - nrm * nrm.transpose());
      out.add_force(i, -C * rod.velocity(i));
      out.add_velocity_jacobian(i, -C);
      tally[k] -= C * rod.velocity(i);
    }
  }
}

}  // namespace flowire::coupling
