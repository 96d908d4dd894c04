// One solve of the rod as the problem Newton's method (newton.hpp) minimizes: the incremental
// potential of an implicit stage of length h (inertia, damping, elasticity, the loads at their
// ramp, the potential energy of the external forces that report one) or the static potential,
// over the rod's unknowns (x_k, θ_k interleaved) with the clamp's (and a tip clamp's) held.
// The line search's merit is that potential minus the trapezoidal work of the other loads and
// forces along the ray; a second merit, tried where the first finds no decrease, treats every
// external force by its work (a potential inconsistent with its forces, e.g. a contact whose wall
// changes where a vertex is relocated into another vessel, can leave none).
#include <algorithm>
#include <cmath>

#include "flowire/rod/stepper.hpp"
#include "rod_internal.hpp"

namespace flowire::rod {

class TimeStepper::Stage final : public NewtonProblem {
 public:
  Stage(TimeStepper& sim, Mode mode, double h, double load_scale)
      : sim_(sim),
        w_(*sim.work_),
        mode_(mode),
        h_(h),
        load_scale_(load_scale),
        nd_(sim.dof_count()),
        first_free_(sim.feeder_.first_free_dof()),
        first_fixed_(sim.feeder_.first_fixed_dof()) {}

  [[nodiscard]] int dofs() const override { return nd_; }
  [[nodiscard]] int first_free() const override { return first_free_; }
  [[nodiscard]] int first_fixed() const override { return first_fixed_; }
  double assemble(Need need, bool psd, bool reuse_loads) override {
    return sim_.assemble(mode_, h_, load_scale_, need, psd, reuse_loads);
  }
  double assemble_current(Need need) override {
    sim_.gather(w_.q);
    return assemble(need, false, false);
  }
  [[nodiscard]] const Eigen::VectorXd& gradient() const override { return w_.grad; }
  BandedMatrix& matrix() override { return w_.H; }
  [[nodiscard]] const LowRankStiffness* low_rank() const override { return w_.coupled.empty() ? nullptr : &w_.coupled; }
  [[nodiscard]] double residual() const override { return sim_.residual_norm(first_free_, first_fixed_); }
  [[nodiscard]] double tolerance() const override { return sim_.force_scale(load_scale_); }
  [[nodiscard]] double max_step(const Eigen::Ref<const Eigen::VectorXd>& dq) const override {
    return sim_.coupled_max_step(dq);  // (first_free, first_fixed: the rod's own)
  }
  void keep() override {
    sim_.keep_iterate();
    w_.fext_accepted.head(nd_) = w_.fext.head(nd_);
    w_.fcons_accepted.head(nd_) = w_.fcons.head(nd_);
    ext_energy_base_ = w_.ext_energy;
  }
  void trial(const Eigen::Ref<const Eigen::VectorXd>& dq, double alpha) override {
    sim_.move_along(dq, alpha);
    // The trial's unknowns (for the inertia terms), the base's kept in w.rhs until accepted.
    w_.rhs.head(nd_) = w_.q.head(nd_) + alpha * dq;
    for (int k = 0; k < sim_.feeder_.first_clamped(); ++k) w_.rhs.segment<3>(4 * k) = sim_.body_.state.x[k];
    w_.q.head(nd_).swap(w_.rhs.head(nd_));
  }
  void merits(int pass, double phi_base, double phi_trial, double* at_base, double* at_trial) const override {
    const auto dqt = w_.q.head(nd_) - w_.rhs.head(nd_);
    double work = 0.5 * (w_.fext_accepted.head(nd_) + w_.fext.head(nd_)).dot(dqt);
    double merit0 = phi_base, merit_t = phi_trial;
    if (pass == 0) {
      // Change of the external potential: exact, but never credited below the
      // trapezoidal estimate −½(f_b + f_t)·Δq of the same forces. The two agree for a
      // potential consistent with its forces; where they do not (a vertex relocated
      // through a wall into another vessel makes the contact energy drop at once), the
      // larger one keeps the search from accepting the jump.
      const double w_cons = 0.5 * (w_.fcons_accepted.head(nd_) + w_.fcons.head(nd_)).dot(dqt);
      work -= w_cons;
      const double de_exact = w_.ext_energy - ext_energy_base_;
      merit_t += std::max(de_exact, -w_cons) - de_exact;
    } else {
      merit0 -= ext_energy_base_;
      merit_t -= w_.ext_energy;
    }
    merit_t -= work;
    *at_base = merit0;
    *at_trial = merit_t;
  }
  [[nodiscard]] int merit_passes() const override { return sim_.externals_.empty() ? 1 : 2; }
  void reject_trial() override { w_.q.head(nd_).swap(w_.rhs.head(nd_)); }
  void back_to_base() override { sim_.back_to_kept_iterate(); }

 private:
  TimeStepper& sim_;
  Work& w_;
  Mode mode_;
  double h_, load_scale_;
  int nd_, first_free_, first_fixed_;
  double ext_energy_base_ = 0.0;
};

// The rod's pieces the stage is made of.

double TimeStepper::residual_norm(int first_free, int first_fixed) const {
  // Max over the free unknowns of |force| and |torque| / rest length (a force too).
  const Work& w = *work_;
  double r = 0.0;
  for (int d = first_free; d < first_fixed && d % 4 != 0; ++d) {  // a partly held vertex
    const double v = (d % 4 == 3) ? w.grad(d) / body_.disc.rest_length[d / 4] : w.grad(d);
    r = std::max(r, std::abs(v));
  }
  for (int k = (first_free + 3) / 4; 4 * k < first_fixed; ++k) {
    const double* g = w.grad.data() + 4 * k;
    r = std::max({r, std::abs(g[0]), std::abs(g[1]), std::abs(g[2])});
    if (4 * k + 3 < first_fixed) r = std::max(r, std::abs(g[3]) / body_.disc.rest_length[k]);
  }
  return r;
}

void TimeStepper::keep_iterate() {
  Work& w = *work_;
  w.x_accepted = body_.state.x;
  w.theta_accepted = body_.state.theta;
  w.frame_accepted = body_.state.frame;
  w.twist_accepted = body_.state.ref_twist;
}

void TimeStepper::back_to_kept_iterate() {
  const Work& w = *work_;
  detail::set_configuration(body_.state, w.x_accepted, w.theta_accepted, w.frame_accepted, w.twist_accepted);
}

void TimeStepper::move_along(const Eigen::Ref<const Eigen::VectorXd>& dq, double alpha) {
  Work& w = *work_;
  RodState& s = body_.state;
  const int nv = s.vertex_count();
  for (int k = 0; k < nv; ++k) {
    s.x[k] = w.x_accepted[k] + alpha * dq.segment<3>(4 * k);
    if (k < nv - 1) s.theta[k] = w.theta_accepted[k] + alpha * dq(4 * k + 3);
  }
  if (settings_.curvilinear_update && !feeder_.tip_clamped()) {
    // Walk from the clamp to the tip keeping each free edge's updated direction but
    // its linearized length: removes the O(α²) spurious stretch of a straight-line
    // step through a rotation, so stiff stretching does not throttle the step.
    Vec3 next_unprojected = s.x[feeder_.first_clamped()];
    for (int j = feeder_.first_clamped() - 1; j >= 0; --j) {
      const Vec3 xn = s.x[j];
      const Vec3 eb = w.x_accepted[j + 1] - w.x_accepted[j];
      const double lb = eb.norm();
      const double target = lb + alpha * (eb / lb).dot(dq.segment<3>(4 * (j + 1)) - dq.segment<3>(4 * j));
      const Vec3 d = next_unprojected - xn;
      s.x[j] = s.x[j + 1] - std::max(target, 0.1 * lb) * d / d.norm();
      next_unprojected = xn;
    }
  }
  detail::transport_frames_to(s.x, w.frame_accepted, w.twist_accepted, s.frame, s.ref_twist);
}

StepReport TimeStepper::newton(Mode mode, double h, double load_scale, int max_iterations) {
  Stage stage(*this, mode, h, load_scale);
  NewtonOptions o;
  o.max_iterations = max_iterations >= 0    ? max_iterations
                     : mode == Mode::Static ? settings_.max_static_iterations
                                            : settings_.max_iterations;
  o.max_line_search_cuts = settings_.max_line_search_cuts;
  o.linear_solver = settings_.linear_solver;
  o.chord_iterations = settings_.chord_iterations;
  o.step_tolerance = settings_.step_tolerance * body_.model.h;
  o.quadratic_backtracking = mode == Mode::Dynamic;
  return newton_.solve(stage, o);
}

}  // namespace flowire::rod
