#include "flowire/rod/stepper.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/kernel_clones.hpp"
#include "rod_internal.hpp"

namespace flowire::rod {

using detail::finite;
using detail::kBandwidth;

Integrator parse_integrator(std::string_view name) {
  if (name == "implicit_euler") return Integrator::ImplicitEuler;
  if (name == "implicit_midpoint") return Integrator::ImplicitMidpoint;
  throw_usage_error(fmt::format("integrator '{}': use implicit_euler or implicit_midpoint", name));
}

const char* to_string(Integrator integrator) {
  return integrator == Integrator::ImplicitMidpoint ? "implicit_midpoint" : "implicit_euler";
}

TimeStepper::Work::Work(int nvmax, int max_subdivisions) : max_dof(4 * nvmax - 1) {
  for (Eigen::VectorXd* v : {&q, &grad, &rhs, &mass, &damp, &fext, &fext_accepted, &q0, &qhat, &fcons, &fcons_accepted})
    v->setZero(max_dof);
  H.reserve(max_dof, kBandwidth);
  ext_k.reserve(nvmax);
  ext_edge_k.reserve(nvmax);
  edges.reserve(nvmax);
  acc.reserve(nvmax);
  for (auto* v :
       {&vel, &x0, &v0, &x_accepted, &x_mid, &tangent, &x_end, &v_guess, &path_x, &guess_slide, &guess_inertial})
    v->reserve(nvmax);
  spin.reserve(nvmax);
  ext_spin_k.reserve(nvmax);
  for (auto* v : {&theta0, &omega0, &twist0, &theta_accepted, &twist_accepted, &omega_guess, &path_u})
    v->reserve(nvmax);
  saved.resize(static_cast<size_t>(std::max(max_subdivisions, 0)) + 4);
  for (auto& v : saved) v.state.reserve(nvmax);
  frame0.reserve(nvmax);
  frame_accepted.reserve(nvmax);
}

TimeStepper::TimeStepper(RodBody& body, Feeder& feeder, const Loads& loads, const ExternalForces& externals)
    : body_(body),
      feeder_(feeder),
      loads_(loads),
      externals_(externals),
      work_(std::make_unique<Work>(body.max_vertices(), SolverSettings{}.max_subdivisions)) {
  newton_.reserve(work_->max_dof, kBandwidth);
  trace_.reserve(1 << 14);
}

TimeStepper::~TimeStepper() = default;

bool TimeStepper::adapt() {
  return feeder_.adapt([this](const std::vector<int>& new_source) {
    if (externals_.empty()) return;
    const RodView view = current_view(0.0);
    for (const auto& e : externals_) e->remap(view, new_source);
  });
}

RodView TimeStepper::current_view(double dt) {
  Work& w = *work_;
  const RodState& s = body_.state;
  const int nv = s.vertex_count();
  RodView view;
  view.positions = s.x;
  view.velocities = s.v;
  view.arc_length = feeder_.arc_lengths();
  view.radius = std::span<const double>(body_.disc.edge_radius.data(), nv - 1);
  view.rest_lengths = std::span<const double>(body_.disc.rest_length.data(), nv - 1);
  view.segment_length = body_.model.h;
  w.tangent.resize(nv - 1);
  for (int j = 0; j < nv - 1; ++j) w.tangent[j] = (s.x[j + 1] - s.x[j]).normalized();
  view.spin_rates = s.omega;
  view.tangents = w.tangent;
  view.first_clamped_vertex = feeder_.first_clamped();
  view.time = s.time;
  view.dt = dt;
  view.solve_serial = solve_serial_;
  return view;
}

void TimeStepper::reset_trace() {
  trace_.clear();
  record_trace();
}

void TimeStepper::compute_base_reaction() {
  const Work& w = *work_;
  const RodState& s = body_.state;
  const int nv = s.vertex_count();
  base_force_.setZero();
  base_torque_.setZero();
  for (int k = feeder_.first_clamped(); k < nv; ++k) {
    const Vec3 f = w.grad.segment<3>(4 * k);
    base_force_ += f;
    base_torque_ += (s.x[k] - body_.model.base_position).cross(f);
    if (k < nv - 1) {
      const Vec3 t = (s.x[k + 1] - s.x[k]).normalized();
      base_torque_ += w.grad(4 * k + 3) * t;
    }
  }
}

void TimeStepper::report(const StepReport& r, const char* what) {
  last_report_ = r;
  if (r.converged()) return;
  warn(
      fmt::format("rod: {} at t = {:.6g} s: {} after {} Newton iterations "
                  "(residual {:.3g} N, tolerance {:.3g} N)",
                  what, body_.state.time, to_string(r.status), r.newton_iterations, r.residual, r.tolerance));
}

void TimeStepper::record_trace() {
  trace_.push_back({body_.state.time, body_.state.inserted_length, body_.state.x.front()});
}

// -----------------------------------------------------------------------------------------
// Stepping
// -----------------------------------------------------------------------------------------

StepReport TimeStepper::step(double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt)) throw_usage_error("TimeStepper::step: dt must be > 0");
  const StepReport rep = step_subdivided(dt, 0);
  totals_.add(rep);
  report(rep, settings_.integrator == Integrator::ImplicitMidpoint ? "implicit midpoint step" : "implicit Euler step");
  return rep;
}

StepReport TimeStepper::step_subdivided(double dt, int depth) {
  // A step whose Newton solve fails (no descent left, the iteration limit far from
  // convergence, non-finite values) is taken again from its start as two half steps, down
  // to dt/2^max_subdivisions; only the last level's result is kept as it is.
  const bool can_retry = depth < settings_.max_subdivisions;
  if (can_retry) save_state(depth);
  StepReport rep = step_once(dt);
  if (!rep.converged() && can_retry) {
    restore_state(depth);
    // The failed attempt's work counts too: the step cost it (the totals and per-step
    // figures would otherwise show only the halves that converged).
    StepReport total;
    total.add_work(rep);
    for (int half = 0; half < 2; ++half) {
      const StepReport r = step_subdivided(0.5 * dt, depth + 1);
      total.then(r);
      if (!r.converged()) break;
    }
    total.subdivisions = std::max(total.subdivisions, depth + 1);
    return total;
  }
  last_report_ = rep;
  record_trace();
  if (!externals_.empty()) {
    const RodView view = current_view(dt);
    for (auto& e : externals_) e->end_step(view);
  }
  return rep;
}

void TimeStepper::save_state(int depth) {
  Work& w = *work_;
  if (static_cast<int>(w.saved.size()) <= depth) w.saved.resize(static_cast<size_t>(depth) + 1);
  Work::Saved& v = w.saved[static_cast<size_t>(depth)];
  v.state = body_.state;
  v.target_angle = feeder_.drive().base_angle();
  v.insertion_speed = feeder_.drive().insertion_speed();
  v.first_clamped = feeder_.first_clamped();
  v.base_force = base_force_;
  v.base_torque = base_torque_;
  v.trace_size = trace_.size();
}

void TimeStepper::restore_state(int depth) {
  const Work::Saved& v = work_->saved[static_cast<size_t>(depth)];
  body_.state = v.state;
  feeder_.drive().set_base_angle(v.target_angle);
  feeder_.drive().set_insertion_speed(v.insertion_speed);
  feeder_.set_first_clamped(v.first_clamped);
  base_force_ = v.base_force;
  base_torque_ = v.base_torque;
  trace_.resize(v.trace_size);
  body_.rediscretize();
  feeder_.refresh_arc_lengths();
}

StepReport TimeStepper::step_once(double dt) {
  if (feeder_.drive().force_driven()) return step_force_fed(dt);
  return step_at_feed(dt, feeder_.drive().kinematic_speed(base_force_.dot(body_.model.base_direction)));
}

void TimeStepper::begin_step(double h, bool extrapolate) {
  auto& w = *work_;
  auto& s = body_.state;
  ++solve_serial_;
  const int nv = s.vertex_count();
  // Newton's initial guess. Inertial: q + h q̇. With `extrapolate` (implicit Euler), where the
  // vertex is where the last step of the same h left it (not moved since: not resampled, not
  // set from outside; feeding keeps the indices from the tip), also + h (q̇ − q̇_prev), the
  // last step's acceleration held: the guess is then O(h³) from the solution instead of
  // O(h²), and Newton's first step usually lands within the tolerance (one factorization a
  // step). w.v0 still holds the last step's starting velocities here.
  const bool history = extrapolate && h == w.h_end;
  const int nk = history ? std::min({nv, static_cast<int>(w.x_end.size()), static_cast<int>(w.v0.size())}) : 0;
  auto held = [&](int k) { return k < nk && s.x[k] == w.x_end[k]; };
  w.v_guess.resize(nv);
  w.omega_guess.resize(std::max(nv - 1, 0));
  for (int k = 0; k < nv; ++k) {
    w.qhat.segment<3>(4 * k) = s.x[k] + h * s.v[k];  // the inertial prediction (the merit's q̂)
    w.v_guess[k] = held(k) ? Vec3(2.0 * s.v[k] - w.v0[k]) : s.v[k];
    if (k < nv - 1) w.omega_guess[k] = held(k) && held(k + 1) ? 2.0 * s.omega[k] - w.omega0[k] : s.omega[k];
  }
  w.x0 = s.x;
  w.v0 = s.v;
  w.theta0 = s.theta;
  w.omega0 = s.omega;
  w.frame0 = s.frame;
  w.twist0 = s.ref_twist;
  for (int k = 0; k < nv; ++k) {
    w.q0.segment<3>(4 * k) = s.x[k];
    w.mass.segment<3>(4 * k).setConstant(body_.disc.mass[k]);
    w.damp.segment<3>(4 * k).setConstant(body_.model.damping * body_.disc.cell_length[k] +
                                         body_.model.mass_damping * body_.disc.mass[k]);
    if (k < nv - 1) {
      w.q0(4 * k + 3) = s.theta[k];
      w.qhat(4 * k + 3) = s.theta[k] + h * s.omega[k];
      w.mass(4 * k + 3) = body_.disc.twist_inertia[k];
      w.damp(4 * k + 3) = 0.0;
    }
  }
  for (int k = 0; k < nv; ++k) {
    s.x[k] += h * w.v_guess[k];
    if (k < nv - 1) s.theta[k] += h * w.omega_guess[k];
  }
}

void TimeStepper::start_stage(double L, double angle, double fed, double h) {
  Work& w = *work_;
  RodState& s = body_.state;
  feeder_.predict_feed(fed, h, w.x0, w.v0);
  if (!w.guess_x.empty()) {  // a caller's guess (restore_checkpoint), for the free unknowns
    if (w.guess_x.size() == s.x.size() && w.guess_theta.size() == s.theta.size())
      s.x = w.guess_x, s.theta = w.guess_theta;
    w.guess_x.clear(), w.guess_theta.clear();
  }
  feeder_.set_prescribed(L, angle, s.x, s.theta);
  detail::transport_frames_to(s.x, w.frame0, w.twist0, s.frame, s.ref_twist);
  s.time += h;
  s.inserted_length = L;
  feeder_.refresh_arc_lengths();
}

StepReport TimeStepper::step_euler(double dt) {
  Work& w = *work_;
  RodState& s = body_.state;
  const double L_new = feeder_.feed_vertex_set(dt);
  const double angle_new = feeder_.drive().angle_after(dt);
  begin_euler_step(dt, L_new, angle_new, /*may_slide=*/true);

  StepReport rep = newton(Mode::Dynamic, dt, 1.0);
  if (rep.status == SolveStatus::NonFinite || rep.status == SolveStatus::SingularMatrix) {
    rewind_to_step_start();
    s.v = w.v0;
    s.omega = w.omega0;
    feeder_.set_prescribed(L_new, angle_new, s.x, s.theta);
    detail::transport_frames_to(s.x, w.frame0, w.twist0, s.frame, s.ref_twist);
  }
  end_euler_step(dt, angle_new, rep.converged());
  return rep;
}

void TimeStepper::begin_euler_step(double dt, double L_new, double angle_new, bool may_slide) {
  Work& w = *work_;
  RodState& s = body_.state;
  // Newton's start; prescribed unknowns at their end-of-step values.
  // - The inertial prediction, second-order where the last step of the same length left the
  //   vertex (begin_step); with the feed predictor (the wire slid along its own path) where a
  //   feed starts or changes speed and the inertial guess has nothing to go on.
  // - While the wire is fed, or was fed the step before, and the last step was as long and left
  //   the wire where it is, also the slide (Feeder::predict_slide): its path extrapolated in
  //   time at each place along it. Where the feed jerks (vertices riding over the walls'
  //   creases, the clamp's boundary moving by an edge), the inertial guess carries the jerk on
  //   into the next steps; the slide follows the path the walls hold. Where the motion is
  //   smooth the inertial guess is the closer. Newton starts from whichever of the two came
  //   closer to the last step's solution. Not while the base turns (the wire's shape turns with
  //   it, off its path), nor where a step feeds half a segment or more (the clamp's boundary
  //   moves every step or two, the feed is steady, and the slide cost Newton iterations: the
  //   arch at 0.25 mm segments pushed at 2 cm/s, 5.2 → 6.1 a step; turned, 8.3 against 7.9; with
  //   the clamp's support at the entry, 5.2 → 5.6 pushed, 5.8 → 5.5 pulled).
  const double L_start = s.inserted_length;
  bool untouched = may_slide && settings_.slide_guess && dt == w.h_end && !w.path_x.empty() &&
                   feeder_.drive().rotation_speed() == 0.0 && std::abs(L_new - L_start) < 0.5 * body_.model.h;
  // (A grid point the feed has just inserted at the entry is new: the vertices before it must
  // be where the last step left them.)
  const int last_old =
      std::min({feeder_.first_clamped(), static_cast<int>(w.x_end.size()), static_cast<int>(w.path_u.size())});
  for (int k = 0; untouched && k < last_old && s.u[k] == w.path_u[k]; ++k) untouched = s.x[k] == w.x_end[k];
  bool slide = untouched && (L_new != L_start || L_start != w.path_inserted);
  // (A step after a subdivided one is as steady: its inertial guess, first-order there, holds
  // a J tip's hook where the feed predictor would slide it along its own path.)
  const bool steady_feed = settings_.second_order_guess && w.h_end > 0.0 && feeder_.feed_speed() == w.feed_end;
  begin_step(dt, settings_.second_order_guess);
  const auto free = static_cast<size_t>(feeder_.first_clamped());
  w.guess_slide.clear();
  if (slide) {
    w.guess_inertial.assign(s.x.begin(), s.x.begin() + free);
    feeder_.predict_slide(L_new, {w.x0, s.u, L_start}, {w.path_x, w.path_u, w.path_inserted});
    w.guess_slide.assign(s.x.begin(), s.x.begin() + free);
    if (w.inertial_miss >= 0.0 && w.inertial_miss < w.slide_miss) {
      std::copy(w.guess_inertial.begin(), w.guess_inertial.end(), s.x.begin());
      slide = false;
    }
  }
  w.h_newton = dt;
  w.inserted0 = L_start;
  start_stage(L_new, angle_new, slide || steady_feed ? 0.0 : L_new - L_start, dt);
}

void TimeStepper::end_euler_step(double dt, double angle_new, bool converged) {
  Work& w = *work_;
  RodState& s = body_.state;
  const int nv = s.vertex_count();
  for (int k = 0; k < nv; ++k) {
    s.v[k] = (s.x[k] - w.x0[k]) / dt;
    if (k < nv - 1) s.omega[k] = (s.theta[k] - w.theta0[k]) / dt;
  }
  feeder_.drive().set_base_angle(angle_new);
  s.base_angle = angle_new;
  // How far each guess was from where the step converged, for the next step's choice.
  w.slide_miss = w.inertial_miss = -1.0;
  if (converged && !w.guess_slide.empty()) {
    w.slide_miss = w.inertial_miss = 0.0;
    for (size_t k = 0; k < w.guess_slide.size(); ++k) {
      w.slide_miss = std::max(w.slide_miss, (w.guess_slide[k] - s.x[k]).squaredNorm());
      w.inertial_miss = std::max(w.inertial_miss, (w.guess_inertial[k] - s.x[k]).squaredNorm());
    }
  }
  // Where this step left the vertices and the path it started from, for the next step's predictor.
  w.x_end = s.x;
  w.h_end = dt;
  w.feed_end = feeder_.feed_speed();
  w.path_x = w.x0;
  w.path_u = s.u;
  w.path_inserted = w.inserted0;
  compute_base_reaction();
}

StepReport TimeStepper::step_midpoint(double dt) {
  Work& w = *work_;
  RodState& s = body_.state;
  const double L_start = s.inserted_length;
  const double L_new = feeder_.feed_vertex_set(dt);
  const double hh = 0.5 * dt;
  const double L_half = 0.5 * (L_start + L_new);
  const double angle_half = feeder_.drive().angle_after(hh);
  const double angle_new = feeder_.drive().angle_after(dt);

  begin_step(hh, /*extrapolate=*/false);
  const int nv = s.vertex_count();
  start_stage(L_half, angle_half, L_half - L_start, hh);

  StepReport rep = newton(Mode::Dynamic, hh, 1.0);
  const bool failed = rep.status == SolveStatus::NonFinite || rep.status == SolveStatus::SingularMatrix;
  compute_base_reaction();
  if (failed) {
    rewind_to_step_start();
    for (auto& v : s.v) v.setZero();
    for (auto& o : s.omega) o = 0.0;
    feeder_.set_prescribed(L_new, angle_new, s.x, s.theta);
    detail::transport_frames_to(s.x, w.frame0, w.twist0, s.frame, s.ref_twist);
  } else {
    // Extrapolate from the midpoint z: q₁ = 2z − q₀, v₁ = 2 (z − q₀)/(h/2) − v₀.
    w.x_mid = s.x;
    w.frame_accepted = s.frame;
    w.twist_accepted = s.ref_twist;
    for (int k = 0; k < nv; ++k) {
      s.v[k] = 2.0 * (w.x_mid[k] - w.x0[k]) / hh - w.v0[k];
      s.x[k] = 2.0 * w.x_mid[k] - w.x0[k];
      if (k < nv - 1) {
        const double tz = s.theta[k];
        s.omega[k] = 2.0 * (tz - w.theta0[k]) / hh - w.omega0[k];
        s.theta[k] = 2.0 * tz - w.theta0[k];
      }
    }
    feeder_.set_prescribed(L_new, angle_new, s.x, s.theta);
    detail::transport_frames_to(s.x, w.frame_accepted, w.twist_accepted, s.frame, s.ref_twist);
  }
  s.time += hh;
  s.inserted_length = L_new;
  feeder_.refresh_arc_lengths();
  feeder_.drive().set_base_angle(angle_new);
  s.base_angle = angle_new;
  return rep;
}

StepReport TimeStepper::solve_static() {
  StepReport r = solve_static_once();
  // Adaptive: resample at the equilibrium and solve again until the vertex set settles.
  for (int round = 0; round < 12 && r.converged() && adapt(); ++round) {
    trace_.pop_back();
    r.then(solve_static_once());
  }
  return r;
}

double TimeStepper::static_imbalance() {
  Work& w = *work_;
  gather(w.q);
  (void)assemble(Mode::Static, 1.0, 1.0, Need::Gradient);
  return residual_norm(feeder_.tip_clamped() ? 7 : 0, 4 * feeder_.first_clamped()) / force_scale(1.0);
}

void TimeStepper::save_checkpoint() {
  Work& w = *work_;
  Work::Checkpoint& c = w.checkpoint;
  c.at.state = body_.state;
  c.at.target_angle = feeder_.drive().base_angle();
  c.at.insertion_speed = feeder_.drive().insertion_speed();
  c.at.first_clamped = feeder_.first_clamped();
  c.at.base_force = base_force_;
  c.at.base_torque = base_torque_;
  c.at.trace_size = trace_.size();
  c.x_end = w.x_end, c.v0 = w.v0, c.omega0 = w.omega0;
  c.h_end = w.h_end, c.feed_end = w.feed_end;
  c.path_x = w.path_x, c.path_u = w.path_u, c.path_inserted = w.path_inserted;
  c.slide_miss = w.slide_miss, c.inertial_miss = w.inertial_miss;
  c.valid = true;
  for (auto& e : externals_) e->save_checkpoint();
}

void TimeStepper::restore_checkpoint(bool guess_from_current) {
  Work& w = *work_;
  const Work::Checkpoint& c = w.checkpoint;
  if (!c.valid) throw_usage_error("TimeStepper::restore_checkpoint: no checkpoint was saved");
  w.guess_x.clear(), w.guess_theta.clear();
  if (guess_from_current) w.guess_x = body_.state.x, w.guess_theta = body_.state.theta;
  body_.state = c.at.state;
  feeder_.drive().set_base_angle(c.at.target_angle);
  feeder_.drive().set_insertion_speed(c.at.insertion_speed);
  feeder_.set_first_clamped(c.at.first_clamped);
  base_force_ = c.at.base_force;
  base_torque_ = c.at.base_torque;
  trace_.resize(c.at.trace_size);
  w.x_end = c.x_end, w.v0 = c.v0, w.omega0 = c.omega0;
  w.h_end = c.h_end, w.feed_end = c.feed_end;
  w.path_x = c.path_x, w.path_u = c.path_u, w.path_inserted = c.path_inserted;
  w.slide_miss = c.slide_miss, w.inertial_miss = c.inertial_miss;
  for (auto& e : externals_) e->restore_checkpoint();
  body_.rediscretize();
  feeder_.refresh_arc_lengths();
}

double TimeStepper::step_imbalance() {
  Work& w = *work_;
  if (settings_.integrator != Integrator::ImplicitEuler || !(w.h_newton > 0.0))
    throw_usage_error("TimeStepper::step_imbalance: only after an implicit Euler step");
  gather(w.q);
  (void)assemble(Mode::Dynamic, w.h_newton, 1.0, Need::Gradient);
  return residual_norm(feeder_.tip_clamped() ? 7 : 0, 4 * feeder_.first_clamped()) / force_scale(1.0);
}

StepReport TimeStepper::solve_static_once() {
  RodState& s = body_.state;
  s.base_angle = feeder_.drive().base_angle();
  feeder_.set_prescribed(s.inserted_length, feeder_.drive().base_angle(), s.x, s.theta);
  detail::transport_frames_to(s.x, s.frame, s.ref_twist, s.frame, s.ref_twist);
  for (auto& v : s.v) v.setZero();
  for (auto& o : s.omega) o = 0.0;
  feeder_.refresh_arc_lengths();
  const int steps = std::max(1, settings_.static_load_steps);
  StepReport total;
  for (int i = 1; i <= steps; ++i) {
    const double load = static_cast<double>(i) / steps;
    const int start_slot = std::max(settings_.max_subdivisions, 0) + 1;
    save_state(start_slot);  // the load step's start, for the continuation below
    StepReport r = newton(Mode::Static, 1.0, load);
    if (!r.converged()) {
      // Newton from the start could not find the equilibrium (a wire free between walls has
      // nearly singular static modes; a pre-shaped tip squeezed into a tight lumen snaps):
      // walk to it in pseudo-time from the load step's start instead.
      restore_state(start_slot);
      r.then(relax_to_static(load, settings_.max_static_iterations - r.newton_iterations));
    }
    total.then(r);
    if (!r.converged()) break;
  }
  compute_base_reaction();
  report(total, "static solve");
  record_trace();
  if (!externals_.empty()) {
    const RodView view = current_view(0.0);
    for (auto& e : externals_) e->start(view);
  }
  return total;
}

StepReport TimeStepper::relax_to_static(double load_scale, int budget) {
  // Pseudo-transient continuation (Kelley & Keyes 1998): implicit Euler steps of pseudo-time
  // τ from rest, each from the last one's end with the velocity reset to zero, so the inertia
  // M/τ² regularizes the matrix that alone is nearly singular; τ grows while the steps come
  // easily, and once the wire has stopped moving, Newton on the static equations finishes
  // from there. The fixed point of the pseudo-steps (x = x₀, so every velocity-dependent
  // force, friction and drag, is that of a wire at rest) is the static equilibrium itself.
  Work& w = *work_;
  RodState& s = body_.state;
  StepReport total;
  total.status = SolveStatus::MaxIterations;
  double tau = 1e-3;
  for (int k = 0; k < 200 && tau > 1e-9 && total.newton_iterations < budget; ++k) {
    for (auto& v : s.v) v.setZero();
    for (auto& o : s.omega) o = 0.0;
    begin_step(tau, /*extrapolate=*/false);
    detail::transport_frames_to(s.x, w.frame0, w.twist0, s.frame, s.ref_twist);
    const StepReport r = newton(Mode::Dynamic, tau, load_scale);
    total.add_work(r);
    if (!r.converged()) {
      rewind_to_step_start();
      tau *= 0.25;
      continue;
    }
    double moved = 0.0;
    for (int i = 0; i < feeder_.first_clamped(); ++i) moved = std::max(moved, (s.x[i] - w.x0[i]).norm());
    if (r.newton_iterations <= 4) tau *= 4.0;
    if (moved > 1e-3 * body_.model.h && k % 8 != 7) continue;
    // Nearly at rest (or every eighth step): try to finish with static Newton, keeping the
    // pseudo-step's end if it cannot.
    const int try_budget = std::min(40, budget - total.newton_iterations);
    if (try_budget <= 0) break;
    const int try_slot = std::max(settings_.max_subdivisions, 0) + 3;
    save_state(try_slot);
    const StepReport st = newton(Mode::Static, 1.0, load_scale, try_budget);
    total.add_work(st);
    total.residual = st.residual;
    total.tolerance = st.tolerance;
    if (st.converged()) {
      total.status = SolveStatus::Converged;
      break;
    }
    restore_state(try_slot);
  }
  for (auto& v : s.v) v.setZero();
  for (auto& o : s.omega) o = 0.0;
  return total;
}

void TimeStepper::rewind_to_step_start() {
  const Work& w = *work_;
  detail::set_configuration(body_.state, w.x0, w.theta0, w.frame0, w.twist0);
}

int TimeStepper::static_hessian_negative_eigenvalues() {
  Work& w = *work_;
  gather(w.q);
  assemble(Mode::Static, 1.0, 1.0, Need::Matrix);
  return newton_.negative_pivots(w.H, feeder_.tip_clamped() ? 7 : 0, 4 * feeder_.first_clamped());
}

StepReport TimeStepper::step_at_feed(double dt, double speed) {
  feeder_.set_feed_speed(speed);
  adapt();
  return settings_.integrator == Integrator::ImplicitMidpoint ? step_midpoint(dt) : step_euler(dt);
}

StepReport TimeStepper::step_force_fed(double dt) {
  // The feed length of the step is the unknown: the step is taken again from its start until
  // the clamp's axial force at its end, base_force()·d, equals the applied force (the drive's
  // secant). The feed of one step is kept within half a segment.
  const Vec3& d = body_.model.base_direction;
  const int slot = std::max(settings_.max_subdivisions, 0) + 2;
  double m = 0.0;
  for (double mk : body_.disc.mass) m += mk;
  const double slope_guess =
      std::max(m / dt + body_.model.damping * body_.state.inserted_length + body_.model.mass_damping * m, 1e-12);
  save_state(slot);
  StepReport rep = step_at_feed(dt, feeder_.drive().force_feed_begin(0.5 * body_.model.h / dt, slope_guess));
  if (!rep.converged()) return rep;
  while (const auto v = feeder_.drive().force_feed_next(base_force_.dot(d))) {
    restore_state(slot);
    rep = step_at_feed(dt, *v);
    if (!rep.converged()) return rep;
  }
  return rep;
}

}  // namespace flowire::rod
