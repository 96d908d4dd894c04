// One implicit Euler step's parts for a Newton iteration over several rods (simulator.hpp,
// "One implicit Euler step solved together with other bodies"). Each part is the matching
// piece of step_euler, newton and line_search, on this rod's unknowns alone; the caller joins
// the rods' systems and merits.
#include <algorithm>
#include <cmath>

#include "flowire/common/error.hpp"
#include "flowire/rod/stepper.hpp"
#include "rod_internal.hpp"

namespace flowire::rod {

void TimeStepper::coupled_begin(double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt)) throw_usage_error("TimeStepper::coupled_begin: dt must be > 0");
  if (settings_.integrator != Integrator::ImplicitEuler || feeder_.drive().force_driven())
    throw_usage_error("TimeStepper::coupled_begin: implicit Euler with kinematic feeding only");
  Work& w = *work_;
  // step_once and step_at_feed: the feed speed, held at the force limit.
  feeder_.set_feed_speed(feeder_.drive().kinematic_speed(base_force_.dot(body_.model.base_direction)));
  adapt();
  // step_euler up to its Newton solve.
  const double L_new = feeder_.feed_vertex_set(dt);
  coupled_angle_ = feeder_.drive().angle_after(dt);
  // (A wire in a catheter slides along a path that moves with it: there the inertial guess is
  // the closer one. The catheter example: 5.5 Newton iterations a step with it, 8.5 with the slide.)
  begin_euler_step(dt, L_new, coupled_angle_, /*may_slide=*/false);
  gather(w.q);
}

double TimeStepper::coupled_assemble(bool matrix, bool psd) {
  Work& w = *work_;
  gather(w.q);
  return assemble(Mode::Dynamic, w.h_newton, 1.0, matrix ? Need::Matrix : Need::Gradient, psd);
}

double TimeStepper::coupled_residual() const {
  return residual_norm(feeder_.tip_clamped() ? 7 : 0, 4 * feeder_.first_clamped()) / force_scale(1.0);
}

void TimeStepper::coupled_rhs(Eigen::Ref<Eigen::VectorXd> rhs) const {
  const Work& w = *work_;
  const int nd = dof_count();
  rhs = -w.grad.head(nd);
  rhs.tail(nd - 4 * feeder_.first_clamped()).setZero();
  if (feeder_.tip_clamped()) rhs.head(7).setZero();
}

void TimeStepper::coupled_matrix(std::vector<Eigen::Triplet<double>>& out, int offset) const {
  const Work& w = *work_;
  const int nd = dof_count();
  const int first_fixed = 4 * feeder_.first_clamped(), first_free = feeder_.tip_clamped() ? 7 : 0;
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
  // The external forces' stiffness off the band (a deformable wall's contacts coupled through
  // it), U R Uᵀ, lower triangle.
  const LowRankStiffness& lr = w.coupled;
  for (int p = 0; p < lr.rank(); ++p)
    for (int q = 0; q < lr.rank(); ++q) {
      const int rp = lr.dofs[static_cast<size_t>(p)], cq = lr.dofs[static_cast<size_t>(q)];
      if (rp < cq || held(rp) || held(cq) || lr.core(p, q) == 0.0) continue;
      const Mat3 block =
          lr.core(p, q) * lr.directions[static_cast<size_t>(p)] * lr.directions[static_cast<size_t>(q)].transpose();
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          if (block(i, j) != 0.0 && (rp > cq || i >= j))
            out.emplace_back(offset + rp + i, offset + cq + j, block(i, j));
    }
}

void TimeStepper::coupled_velocities(std::vector<Eigen::Vector3d>& out) const {
  const Work& w = *work_;
  const int nv = body_.state.vertex_count();
  out.resize(static_cast<size_t>(nv));
  for (int k = 0; k < nv; ++k) out[static_cast<size_t>(k)] = (body_.state.x[k] - w.x0[k]) / w.h_newton;
}

void TimeStepper::coupled_accept() {
  Work& w = *work_;
  const int nd = dof_count();
  keep_iterate();
  w.fext_accepted = w.fext.head(nd);
  w.fcons_accepted = w.fcons.head(nd);
  w.q_accepted = w.q.head(nd);
}

double TimeStepper::coupled_max_step(const Eigen::Ref<const Eigen::VectorXd>& dq) const {
  // The trust region on the motion (line_search's too): no vertex moves more than half its
  // shortest edge and no edge turns about its tangent more than 0.5 rad in one iteration. The
  // discrete rod's energy is far from quadratic beyond that (edges rotate by O(step/ℓ)), so a
  // longer Newton step, which a nearly singular matrix gives (a snapping pre-shaped tip, a
  // wire free between walls), is only cut back by the line search after costly trials.
  const int nv = body_.state.vertex_count();
  const int first_fixed = 4 * feeder_.first_clamped(), first_free = feeder_.tip_clamped() ? 7 : 0;
  // (The boundary edge at the entry, whose rest length follows the feed down to half its
  // neighbour's, counts as its neighbour: a step that turns it twice as far as the others is
  // still in the trust region, and a step throttled by it would throttle the whole wire.)
  const int boundary = feeder_.first_clamped() - 1;
  double lmin = body_.model.h;
  for (int j = 0; j < nv - 1; ++j)
    if (j != boundary) lmin = std::min(lmin, body_.disc.rest_length[j]);
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

void TimeStepper::coupled_trial(const Eigen::Ref<const Eigen::VectorXd>& dq, double alpha) {
  Work& w = *work_;
  move_along(dq, alpha);  // as one trial of line_search
  w.q.head(dof_count()) = w.q_accepted + alpha * dq;
  for (int k = 0; k < feeder_.first_clamped(); ++k) w.q.segment<3>(4 * k) = body_.state.x[k];
}

double TimeStepper::coupled_nonconservative_work() const {
  const Work& w = *work_;
  const int nd = dof_count();
  const auto dqt = w.q.head(nd) - w.q_accepted;
  return 0.5 * ((w.fext_accepted - w.fcons_accepted) + (w.fext.head(nd) - w.fcons.head(nd))).dot(dqt);
}

void TimeStepper::coupled_reject() {
  Work& w = *work_;
  const int nd = dof_count();
  back_to_kept_iterate();
  w.q.head(nd) = w.q_accepted;
}

void TimeStepper::coupled_finish(double dt, const StepReport& rep) {
  end_euler_step(dt, coupled_angle_, rep.converged());
  last_report_ = rep;
  record_trace();
  if (!externals_.empty()) {
    const RodView view = current_view(dt);
    for (auto& e : externals_) e->end_step(view);
  }
  totals_.add(rep);
}

}  // namespace flowire::rod
