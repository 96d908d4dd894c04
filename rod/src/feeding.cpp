#include "flowire/rod/simulator.hpp"

#include <algorithm>
#include <cmath>

#include "flowire/common/error.hpp"
#include "simulator_internal.hpp"

namespace flowire::rod {

// -----------------------------------------------------------------------------------------
// Feeding: the inserted length decides which vertices are free, which are held by the
// clamp, and where the prescribed ones are.
// -----------------------------------------------------------------------------------------

void RodSimulator::update_vertex_set(double new_inserted) {
  // The clamp vertex is the first feeding-grid point at or behind the entry, followed by
  // one more grid point. Near the entry every edge is a grid edge (adapt() keeps it so),
  // so feeding only appends or drops grid points at the proximal end.
  RodState& s = state_;
  const double h = model_.h;
  const int kc = static_cast<int>(std::ceil(new_inserted / h - 1e-9));
  const int k_last = std::min(kc + 1, model_.grid_vertices - 1);
  const int k_old_last = static_cast<int>(std::lround(s.u.back() / h));
  const int nv_old = s.vertex_count();
  const Vec3& pb = model_.base_position;
  const Vec3& db = model_.base_direction;
  const double L = s.inserted_length;
  const double angle = s.base_angle;
  if (k_last > k_old_last) {
    for (int k = k_old_last + 1; k <= k_last; ++k) {
      s.u.push_back(model_.u(k));
      s.x.push_back(pb - db * (model_.u(k) - L));
      s.v.push_back(db * feed_speed_);
      s.theta.push_back(-angle);
      s.omega.push_back(-drive_.rotation_speed());
      s.frame.push_back(EdgeFrame{base_d1_, base_d2_});
      s.ref_twist.push_back(0.0);
    }
  } else if (k_last < k_old_last) {
    const int nv_new = nv_old - (k_old_last - k_last);
    s.u.resize(nv_new);
    s.x.resize(nv_new);
    s.v.resize(nv_new);
    s.theta.resize(nv_new - 1);
    s.omega.resize(nv_new - 1);
    s.frame.resize(nv_new - 1);
    s.ref_twist.resize(nv_new);
    s.ref_twist.back() = 0.0;
  }
  const int nv = s.vertex_count();
  if (nv != nv_old) model_.discretize(s.u, disc_);
  const int fc = nv - 2;
  if (fc < first_clamped_) {
    // Pulled back: vertices fc … first_clamped_−1 enter the clamp. Keep the material twist
    // continuous at the vertices whose edges are reset.
    const int k_lo = std::max(fc, 1);
    for (int k = k_lo; k < std::min(first_clamped_ + 1, nv - 1); ++k)
      work_->feed_twist.push_back(s.theta[k] - s.theta[k - 1] + s.ref_twist[k]);  // total twist
    for (int k = fc; k < std::min(first_clamped_, nv); ++k) {
      s.x[k] = pb - db * (s.u[k] - L);
      s.v[k] = db * feed_speed_;
    }
    for (int j = fc; j < nv - 1; ++j) {
      s.frame[j] = EdgeFrame{base_d1_, base_d2_};
      s.theta[j] = -angle;
      s.omega[j] = -drive_.rotation_speed();
    }
    // Re-transport the free edge that touches the clamp, then rebuild reference twists.
    if (fc >= 1) {
      const int j = fc - 1;
      const Vec3 t0 = s.frame[j].d1.cross(s.frame[j].d2);
      const Vec3 t1 = (s.x[j + 1] - s.x[j]).normalized();
      s.frame[j].d1 = parallel_transport(s.frame[j].d1, t0, t1);
      s.frame[j].d1 = (s.frame[j].d1 - t1 * t1.dot(s.frame[j].d1)).normalized();
      s.frame[j].d2 = t1.cross(s.frame[j].d1);
    }
    int idx = 0;
    for (int k = k_lo; k < std::min(first_clamped_ + 1, nv - 1); ++k, ++idx) {
      const double m_old = work_->feed_twist[idx];
      const double previous = m_old - (s.theta[k] - s.theta[k - 1]);
      s.ref_twist[k] = reference_twist(s.frame[k - 1].d1, (s.x[k] - s.x[k - 1]).normalized(), s.frame[k].d1,
                                       (s.x[k + 1] - s.x[k]).normalized(), previous);
    }
    work_->feed_twist.clear();
  }
  first_clamped_ = fc;
}

void RodSimulator::set_prescribed(double inserted, double angle, std::vector<Vec3>& x,
                                  std::vector<double>& theta) const {
  const Vec3& pb = model_.base_position;
  const Vec3& db = model_.base_direction;
  const int nv = static_cast<int>(x.size());
  for (int k = first_clamped_; k < nv; ++k) x[k] = pb - db * (state_.u[k] - inserted);
  // Clamped edges point from the tip side to the holder (−base_direction); the base angle
  // is right-handed about +base_direction, hence the sign.
  for (int j = first_clamped_; j < nv - 1; ++j) theta[j] = -angle;
  if (tip_clamped_) {
    x[0] = tip_clamp_x0_;
    x[1] = tip_clamp_x1_;
    theta[0] = tip_clamp_theta_;
  }
}

void RodSimulator::clamp_tip(const Vec3& tip, const Vec3& next) {
  if (first_clamped_ < 3) throw_usage_error("RodSimulator::clamp_tip: the wire is too short");
  if ((next - tip).norm() <= 0.0) throw_usage_error("RodSimulator::clamp_tip: tip and next coincide");
  tip_clamped_ = true;
  tip_clamp_x0_ = tip;
  tip_clamp_x1_ = next;
  tip_clamp_theta_ = state_.theta[0];
}

void RodSimulator::predict_feed(double fed, double h) {
  // Initial Newton guess while feeding: each free vertex follows the wire — it moves to
  // where material u_k − fed lay at the step start (on the old polyline, on the insertion
  // line behind the entry, or past the tip along the tip edge) — plus its velocity across
  // the wire. The plain inertial guess x + h v can fold the wire at the entry when the
  // feed per step exceeds a segment.
  if (fed == 0.0) return;
  const Work& w = *work_;
  const Vec3& pb = model_.base_position;
  const Vec3& db = model_.base_direction;
  const int nv = static_cast<int>(w.x0.size());
  const double L_old = state_.inserted_length;
  const std::vector<double>& uk = state_.u;
  int i = 0;  // old edge holding material u (u increases with k: a forward walk)
  // (Measured: in vessels, where walls make the wire slide along its own path, this guess
  // takes half the Newton work of the second-order inertial one, which it replaces while
  // feeding; a pre-shaped tip in free space would rather keep the latter.)
  for (int k = 0; k < first_clamped_; ++k) {
    const double u = uk[k] - fed;
    Vec3 p;
    if (u >= L_old) {
      p = pb + db * (L_old - u);
    } else if (u < 0.0) {
      p = w.x0[0] + (w.x0[0] - w.x0[1]) * (-u / (uk[1] - uk[0]));
    } else {
      while (i < nv - 2 && uk[i + 1] <= u) ++i;
      const double a = (u - uk[i]) / (uk[i + 1] - uk[i]);
      p = (1.0 - a) * w.x0[i] + a * w.x0[i + 1];
    }
    const Vec3 t = k + 1 < nv ? Vec3((w.x0[k + 1] - w.x0[k]).normalized()) : db;
    const Vec3 v = w.v0[k];
    state_.x[k] = p + h * (v - t * t.dot(v));
  }
}

StepReport RodSimulator::step_at_feed(double dt, double speed) {
  feed_speed_ = speed;
  adapt_for(std::max(0.0, -feed_speed_ * dt));
  return settings_.integrator == Integrator::ImplicitMidpoint ? step_midpoint(dt) : step_euler(dt);
}

StepReport RodSimulator::step_force_fed(double dt) {
  // The feed length of the step is the unknown: the step is taken again from its start until
  // the clamp's axial force at its end, base_force()·d, equals the applied force (the drive's
  // secant). The feed of one step is kept within half a segment.
  const Vec3& d = model_.base_direction;
  const int slot = std::max(settings_.max_subdivisions, 0) + 2;
  double m = 0.0;
  for (double mk : disc_.mass) m += mk;
  const double slope_guess =
      std::max(m / dt + model_.damping * state_.inserted_length + model_.mass_damping * m, 1e-12);
  save_state(slot);
  StepReport rep = step_at_feed(dt, drive_.force_feed_begin(0.5 * model_.h / dt, slope_guess));
  if (!rep.converged()) return rep;
  while (const auto v = drive_.force_feed_next(base_force_.dot(d))) {
    restore_state(slot);
    rep = step_at_feed(dt, *v);
    if (!rep.converged()) return rep;
  }
  return rep;
}

}  // namespace flowire::rod
