#include "flowire/rod/simulator.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "kernel_clones.hpp"
#include "simulator_internal.hpp"

namespace flowire::rod {

using detail::kBandwidth;

Integrator parse_integrator(std::string_view name) {
  if (name == "implicit_euler") return Integrator::ImplicitEuler;
  if (name == "implicit_midpoint") return Integrator::ImplicitMidpoint;
  throw_usage_error(fmt::format("integrator '{}': use implicit_euler or implicit_midpoint", name));
}

const char* to_string(Integrator integrator) {
  return integrator == Integrator::ImplicitMidpoint ? "implicit_midpoint" : "implicit_euler";
}

RodSimulator::RodSimulator(const WireSpec& spec) : model_(RodModel::from_spec(spec)), work_(std::make_unique<Work>()) {
  // Adaptive refinement may hold up to one vertex per finest edge.
  const int nvmax = model_.adapt.enabled
                        ? std::max(model_.grid_vertices,
                                   static_cast<int>(std::ceil(model_.length / model_.adapt.min_segment_length)) + 4)
                        : model_.grid_vertices;
  const int max_dof = 4 * nvmax - 1;
  Work& w = *work_;
  w.max_dof = max_dof;
  for (Eigen::VectorXd* v : {&w.q, &w.grad, &w.rhs, &w.mass, &w.damp, &w.fext, &w.fext_accepted, &w.q0, &w.qhat,
                             &w.fcons, &w.fcons_accepted})
    v->setZero(max_dof);
  w.H.reserve(max_dof, kBandwidth);
  newton_.reserve(max_dof, kBandwidth);
  w.ext_k.reserve(nvmax);
  w.ext_edge_k.reserve(nvmax);
  w.edges.reserve(nvmax);
  w.acc.reserve(nvmax);
  for (auto* v : {&w.vel, &w.x0, &w.v0, &w.x_accepted, &w.x_mid, &w.tangent, &w.x_end, &w.v_guess}) v->reserve(nvmax);
  w.spin.reserve(nvmax);
  w.ext_spin_k.reserve(nvmax);
  for (auto* v : {&w.theta0, &w.omega0, &w.twist0, &w.theta_accepted, &w.twist_accepted, &w.new_twist_density,
                  &w.feed_twist, &w.old_u, &w.old_twist_density, &w.old_cell, &w.old_theta, &w.old_omega,
                  &w.old_ref_twist, &w.turn_angle, &w.new_u, &w.omega_guess})
    v->reserve(nvmax);
  for (auto* v : {&w.old_x, &w.old_v, &w.old_tangent}) v->reserve(nvmax);
  w.old_frame.reserve(nvmax);
  w.new_source.reserve(nvmax);
  w.split_edge.reserve(nvmax);
  w.remove_vertex.reserve(nvmax);
  w.saved.resize(static_cast<size_t>(std::max(settings_.max_subdivisions, 0)) + 4);
  for (auto& v : w.saved) {
    v.state.x.reserve(nvmax);
    v.state.v.reserve(nvmax);
    v.state.theta.reserve(nvmax);
    v.state.omega.reserve(nvmax);
    v.state.frame.reserve(nvmax);
    v.state.ref_twist.reserve(nvmax);
    v.state.u.reserve(nvmax);
  }
  w.frame0.reserve(nvmax);
  w.frame_accepted.reserve(nvmax);
  state_.x.reserve(nvmax);
  state_.v.reserve(nvmax);
  state_.theta.reserve(nvmax);
  state_.omega.reserve(nvmax);
  state_.frame.reserve(nvmax);
  state_.ref_twist.reserve(nvmax);
  state_.u.reserve(nvmax);
  disc_.reserve(nvmax);
  arc_length_.reserve(nvmax);
  trace_.reserve(1 << 14);

  const Vec3 t = -model_.base_direction;  // clamped edges point from tip side to holder
  base_d2_ = model_.base_normal;
  base_d1_ = base_d2_.cross(t);
  double inserted = spec.inserted_length < 0.0 ? spec.length : spec.inserted_length;
  if (inserted < 2.0 * model_.h || inserted > spec.length + 1e-12)
    throw_usage_error(
        fmt::format("WireSpec: inserted_length {} m must be between two segments ({} m) and the length ({} m)",
                    inserted, 2.0 * model_.h, spec.length));
  build_initial_state(inserted);
  if (model_.adapt.enabled) {
    // Resolve the rest shape (a pre-shaped tip) before the first step, then lay it out
    // again on the refined vertices.
    for (int round = 0; round < 12 && adapt(); ++round) {
    }
    layout_rest_shape();
    record_trace_reset();
  }
}

RodSimulator::~RodSimulator() = default;

// -----------------------------------------------------------------------------------------
// State construction
// -----------------------------------------------------------------------------------------

void RodSimulator::build_initial_state(double inserted) {
  const double h = model_.h;
  const int kc = static_cast<int>(std::ceil(inserted / h - 1e-9));
  const int nv = kc + 2;
  RodState& s = state_;
  s.x.assign(nv, Vec3::Zero());
  s.v.assign(nv, Vec3::Zero());
  s.theta.assign(nv - 1, 0.0);
  s.omega.assign(nv - 1, 0.0);
  s.frame.assign(nv - 1, EdgeFrame{});
  s.ref_twist.assign(nv, 0.0);
  s.u.resize(nv);
  for (int k = 0; k < nv; ++k) s.u[k] = model_.u(k);
  model_.discretize(s.u, disc_);
  s.inserted_length = inserted;
  s.base_angle = 0.0;
  s.time = 0.0;
  first_clamped_ = kc;
  drive_.set_base_angle(0.0);
  layout_rest_shape();
  record_trace_reset();
}

void RodSimulator::record_trace_reset() {
  trace_.clear();
  record_trace();
}

void RodSimulator::layout_rest_shape() {
  RodState& s = state_;
  const int nv = s.vertex_count();
  const int kc = first_clamped_;
  const double inserted = s.inserted_length;
  const Vec3& pb = model_.base_position;
  const Vec3& db = model_.base_direction;
  const Vec3 a = model_.base_normal;
  for (int k = kc; k < nv; ++k) s.x[k] = pb - db * (s.u[k] - inserted);
  // Lay out the rest shape from the clamp to the tip (planar bends about the base normal).
  Vec3 tf = -db;
  for (int k = kc; k >= 1; --k) {
    const double kappa = disc_.rest_kappa1[k];
    const double phi = 2.0 * std::atan(0.5 * kappa);
    const Eigen::AngleAxisd rot(-phi, a);
    const Vec3 te = k == kc && k == nv - 1 ? tf : (rot * tf).normalized();
    s.x[k - 1] = s.x[k] - disc_.rest_length[k - 1] * te;
    tf = te;
  }
  for (auto& v : s.v) v.setZero();
  for (int j = 0; j < nv - 1; ++j) {
    s.theta[j] = 0.0;
    s.omega[j] = 0.0;
  }
  for (int j = 0; j < nv - 1; ++j) {
    const Vec3 t = (s.x[j + 1] - s.x[j]).normalized();
    s.frame[j].d2 = (a - t * t.dot(a)).normalized();
    s.frame[j].d1 = s.frame[j].d2.cross(t);
  }
  for (int k = 1; k < nv - 1; ++k)
    s.ref_twist[k] = reference_twist(s.frame[k - 1].d1, (s.x[k] - s.x[k - 1]).normalized(), s.frame[k].d1,
                                     (s.x[k + 1] - s.x[k]).normalized(), 0.0);
  refresh_arc_lengths();
}

void RodSimulator::lay_along(const std::function<Vec3(double)>& along) {
  RodState& s = state_;
  const int nv = s.vertex_count();
  const int kc = first_clamped_;
  for (int k = 0; k < kc; ++k) s.x[k] = along(arc_length_[k]);
  for (auto& v : s.v) v.setZero();
  for (int j = 0; j < nv - 1; ++j) s.theta[j] = s.omega[j] = 0.0;
  // Frames from the clamp towards the tip, each transported from its neighbour.
  for (int j = std::min(kc, nv - 2) - 1; j >= 0; --j) {
    const Vec3 tn = (s.x[j + 2] - s.x[j + 1]).normalized();
    const Vec3 t = (s.x[j + 1] - s.x[j]).normalized();
    Vec3 d1 = parallel_transport(s.frame[j + 1].d1, tn, t);
    d1 = (d1 - t * t.dot(d1)).normalized();
    s.frame[j].d1 = d1;
    s.frame[j].d2 = t.cross(d1);
  }
  for (int k = 1; k < nv - 1; ++k)
    s.ref_twist[k] = reference_twist(s.frame[k - 1].d1, (s.x[k] - s.x[k - 1]).normalized(), s.frame[k].d1,
                                     (s.x[k + 1] - s.x[k]).normalized(), 0.0);
  record_trace_reset();
}

void RodSimulator::refresh_arc_lengths() {
  arc_length_.resize(state_.x.size());
  for (size_t k = 0; k < state_.x.size(); ++k) arc_length_[k] = state_.inserted_length - state_.u[k];
}

RodView RodSimulator::current_view(double dt) {
  Work& w = *work_;
  const RodState& s = state_;
  const int nv = s.vertex_count();
  RodView view;
  view.positions = s.x;
  view.velocities = s.v;
  view.arc_length = arc_length_;
  view.radius = std::span<const double>(disc_.edge_radius.data(), nv - 1);
  view.rest_lengths = std::span<const double>(disc_.rest_length.data(), nv - 1);
  view.segment_length = model_.h;
  w.tangent.resize(nv - 1);
  for (int j = 0; j < nv - 1; ++j) w.tangent[j] = (s.x[j + 1] - s.x[j]).normalized();
  view.spin_rates = s.omega;
  view.tangents = w.tangent;
  view.first_clamped_vertex = first_clamped_;
  view.time = s.time;
  view.dt = dt;
  view.solve_serial = solve_serial_;
  return view;
}

// -----------------------------------------------------------------------------------------
// Frames
// -----------------------------------------------------------------------------------------

FLOWIRE_ROD_KERNEL_CLONES
void RodSimulator::transport_frames_to(const std::vector<Vec3>& x_new, const std::vector<EdgeFrame>& frame_from,
                                       const std::vector<double>& twist_from, std::vector<EdgeFrame>& frame_to,
                                       std::vector<double>& twist_to) const {
  // One pass: edge j's frame, then the reference twist at the vertex before it from the
  // two new frames (their tangents kept, not re-derived as d1 × d2). In place is allowed.
  const int nv = static_cast<int>(x_new.size());
  Vec3 t_prev = Vec3::Zero(), d1_prev = Vec3::Zero();
  for (int j = 0; j < nv - 1; ++j) {
    const EdgeFrame& from = frame_from[j];
    const Vec3 t0 = from.d1.cross(from.d2);
    const Vec3 t1 = (x_new[j + 1] - x_new[j]).normalized();
    Vec3 d1 = parallel_transport(from.d1, t0, t1);
    d1 = (d1 - t1 * t1.dot(d1)).normalized();
    frame_to[j].d1 = d1;
    frame_to[j].d2 = t1.cross(d1);
    if (j > 0) twist_to[j] = reference_twist(d1_prev, t_prev, d1, t1, twist_from[j]);
    t_prev = t1;
    d1_prev = d1;
  }
}

std::pair<Vec3, Vec3> RodSimulator::material_frame(int edge) const {
  const EdgeFrame& f = state_.frame.at(edge);
  const double c = std::cos(state_.theta[edge]), s = std::sin(state_.theta[edge]);
  return {c * f.d1 + s * f.d2, -s * f.d1 + c * f.d2};
}

void RodSimulator::compute_base_reaction() {
  const Work& w = *work_;
  const RodState& s = state_;
  const int nv = s.vertex_count();
  base_force_.setZero();
  base_torque_.setZero();
  for (int k = first_clamped_; k < nv; ++k) {
    const Vec3 f = w.grad.segment<3>(4 * k);
    base_force_ += f;
    base_torque_ += (s.x[k] - model_.base_position).cross(f);
    if (k < nv - 1) {
      const Vec3 t = (s.x[k + 1] - s.x[k]).normalized();
      base_torque_ += w.grad(4 * k + 3) * t;
    }
  }
}

void RodSimulator::report(const StepReport& r, const char* what) {
  last_report_ = r;
  if (r.converged()) return;
  warn(
      fmt::format("rod: {} at t = {:.6g} s: {} after {} Newton iterations "
                  "(residual {:.3g} N, tolerance {:.3g} N)",
                  what, state_.time, to_string(r.status), r.newton_iterations, r.residual, r.tolerance));
}

void RodSimulator::record_trace() { trace_.push_back({state_.time, state_.inserted_length, state_.x.front()}); }

// -----------------------------------------------------------------------------------------
// Diagnostics
// -----------------------------------------------------------------------------------------

RodEnergy RodSimulator::energy() const {
  const RodState& s = state_;
  RodEnergy e;
  const int nv = s.vertex_count();
  for (int k = 0; k < nv; ++k) {
    e.kinetic += 0.5 * disc_.mass[k] * s.v[k].squaredNorm();
    if (k < nv - 1) e.kinetic += 0.5 * disc_.twist_inertia[k] * s.omega[k] * s.omega[k];
  }
  for (int j = 0; j < nv - 1; ++j)
    e.stretching += stretch_energy(s.x[j], s.x[j + 1], disc_.stretch_stiffness[j], disc_.rest_length[j]);
  VertexStencil st;
  VertexParams p;
  for (int k = 1; k < nv - 1; ++k) {
    st.x0 = s.x[k - 1];
    st.x1 = s.x[k];
    st.x2 = s.x[k + 1];
    st.theta_e = s.theta[k - 1];
    st.theta_f = s.theta[k];
    st.frame_e = s.frame[k - 1];
    st.frame_f = s.frame[k];
    st.ref_twist = s.ref_twist[k];
    vertex_params(k, p);
    e.bending_twisting += bend_twist(st, p, nullptr, nullptr);
  }
  return e;
}

double RodSimulator::max_strain() const {
  double m = 0.0;
  for (int j = 0; j < first_clamped_; ++j)
    m = std::max(m, std::abs((state_.x[j + 1] - state_.x[j]).norm() / disc_.rest_length[j] - 1.0));
  return m;
}

double RodSimulator::length_drift() const {
  double l = 0.0;
  const int ne = state_.edge_count();
  double rest = 0.0;
  for (int j = 0; j < ne; ++j) {
    l += (state_.x[j + 1] - state_.x[j]).norm();
    rest += disc_.rest_length[j];
  }
  return std::abs(l - rest) / rest;
}

}  // namespace flowire::rod
