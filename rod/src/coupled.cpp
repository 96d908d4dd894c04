// One implicit Euler step's parts for a Newton iteration over several rods (simulator.hpp,
// "One implicit Euler step solved together with other bodies"). Each part is the matching
// piece of step_euler, newton and line_search, on this rod's unknowns alone; the caller joins
// the rods' systems and merits.
#include <algorithm>
#include <cmath>

#include "flowire/common/error.hpp"
#include "flowire/rod/simulator.hpp"
#include "simulator_internal.hpp"

namespace flowire::rod {

void RodSimulator::coupled_begin(double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt)) throw_usage_error("RodSimulator::coupled_begin: dt must be > 0");
  if (settings_.integrator != Integrator::ImplicitEuler || drive_.force_driven())
    throw_usage_error("RodSimulator::coupled_begin: implicit Euler with kinematic feeding only");
  Work& w = *work_;
  RodState& s = state_;
  // step_once and step_at_feed: the feed speed, held at the force limit.
  feed_speed_ = drive_.kinematic_speed(base_force_.dot(model_.base_direction));
  adapt_for(std::max(0.0, -feed_speed_ * dt));
  // step_euler up to its Newton solve.
  const double L_new = feed_vertex_set(dt);
  coupled_angle_ = drive_.angle_after(dt);
  const bool steady_feed = settings_.second_order_guess && dt == w.h_end && feed_speed_ == w.feed_end;
  begin_step(dt, settings_.second_order_guess);
  w.h_newton = dt;
  start_stage(L_new, coupled_angle_, steady_feed ? 0.0 : L_new - s.inserted_length, dt);
  gather(w.q);
}

double RodSimulator::coupled_assemble(bool matrix, bool psd) {
  Work& w = *work_;
  gather(w.q);
  coupled_phi_ = assemble(Mode::Dynamic, w.h_newton, 1.0, matrix ? Need::Matrix : Need::Gradient, psd);
  return coupled_phi_;
}

double RodSimulator::coupled_residual() const {
  return residual_norm(tip_clamped_ ? 7 : 0, 4 * first_clamped_) / force_scale(1.0);
}

void RodSimulator::coupled_rhs(Eigen::Ref<Eigen::VectorXd> rhs) const {
  const Work& w = *work_;
  const int nd = dof_count();
  rhs = -w.grad.head(nd);
  rhs.tail(nd - 4 * first_clamped_).setZero();
  if (tip_clamped_) rhs.head(7).setZero();
}

bool RodSimulator::coupled_free_vertex(int k) const { return k < first_clamped_ && !(tip_clamped_ && k < 2); }

void RodSimulator::coupled_matrix(std::vector<Eigen::Triplet<double>>& out, int offset) const {
  const Work& w = *work_;
  const int nd = dof_count();
  const int first_fixed = 4 * first_clamped_, first_free = tip_clamped_ ? 7 : 0;
  const int b = w.H.bandwidth();
  auto held = [&](int d) { return d >= first_fixed || d < first_free; };
  for (int j = 0; j < nd; ++j) {
    if (held(j)) {
      out.emplace_back(offset + j, offset + j, 1.0);
      continue;
    }
    for (int i = j; i <= std::min(nd - 1, j + b); ++i)
      if (!held(i) && w.H.lower(i, j) != 0.0) out.emplace_back(offset + i, offset + j, w.H.lower(i, j));
  }
}

void RodSimulator::coupled_velocities(std::vector<Eigen::Vector3d>& out) const {
  const Work& w = *work_;
  const int nv = state_.vertex_count();
  out.resize(static_cast<size_t>(nv));
  for (int k = 0; k < nv; ++k) out[static_cast<size_t>(k)] = (state_.x[k] - w.x0[k]) / w.h_newton;
}

void RodSimulator::coupled_accept() {
  Work& w = *work_;
  const int nd = dof_count();
  keep_iterate();
  w.fext_accepted = w.fext.head(nd);
  w.fcons_accepted = w.fcons.head(nd);
  w.q_accepted = w.q.head(nd);
}

double RodSimulator::coupled_max_step(const Eigen::Ref<const Eigen::VectorXd>& dq) const {
  // The trust region on the motion (line_search's too): no vertex moves more than half its
  // shortest edge and no edge turns about its tangent more than 0.5 rad in one iteration. The
  // discrete rod's energy is far from quadratic beyond that (edges rotate by O(step/ℓ)), so a
  // longer Newton step, which a nearly singular matrix gives (a snapping pre-shaped tip, a
  // wire free between walls), is only cut back by the line search after costly trials.
  const int nv = state_.vertex_count();
  const int first_fixed = 4 * first_clamped_, first_free = tip_clamped_ ? 7 : 0;
  double lmin = model_.h;
  for (int j = 0; j < nv - 1; ++j) lmin = std::min(lmin, disc_.rest_length[j]);
  double sx = 0.0, st = 0.0;
  for (int k = first_free / 4; 4 * k < first_fixed; ++k) {
    sx = std::max(sx, dq.segment<3>(4 * k).norm());
    if (4 * k + 3 < first_fixed) st = std::max(st, std::abs(dq(4 * k + 3)));
  }
  double alpha = 1.0;
  if (sx > 0.5 * lmin) alpha = 0.5 * lmin / sx;
  if (st > 0.5) alpha = std::min(alpha, 0.5 / st);
  return alpha;
}

void RodSimulator::coupled_trial(const Eigen::Ref<const Eigen::VectorXd>& dq, double alpha) {
  Work& w = *work_;
  move_along(dq, alpha);  // as one trial of line_search
  w.q.head(dof_count()) = w.q_accepted + alpha * dq;
  for (int k = 0; k < first_clamped_; ++k) w.q.segment<3>(4 * k) = state_.x[k];
}

double RodSimulator::coupled_nonconservative_work() const {
  const Work& w = *work_;
  const int nd = dof_count();
  const auto dqt = w.q.head(nd) - w.q_accepted;
  return 0.5 * ((w.fext_accepted - w.fcons_accepted) + (w.fext.head(nd) - w.fcons.head(nd))).dot(dqt);
}

void RodSimulator::coupled_reject() {
  Work& w = *work_;
  const int nd = dof_count();
  back_to_kept_iterate();
  w.q.head(nd) = w.q_accepted;
}

void RodSimulator::coupled_finish(double dt, const StepReport& rep) {
  end_euler_step(dt, coupled_angle_);
  last_report_ = rep;
  record_trace();
  if (!externals_.empty()) {
    const RodView view = current_view(dt);
    for (auto& e : externals_) e->end_step(view);
  }
  totals_.add(rep);
}

}  // namespace flowire::rod
