#include "flowire/rod/simulator.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "rod_internal.hpp"

namespace flowire::rod {

RodSimulator::RodSimulator(const WireSpec& spec)
    : body_{RodModel::from_spec(spec), {}, {}}, feeder_(body_), stepper_(body_, feeder_, loads_, externals_) {
  const int nvmax = body_.max_vertices();
  body_.state.reserve(nvmax);
  body_.disc.reserve(nvmax);
  const RodModel& model = body_.model;
  const double inserted = spec.inserted_length < 0.0 ? spec.length : spec.inserted_length;
  if (inserted < 2.0 * model.h || inserted > spec.length + 1e-12)
    throw_usage_error(
        fmt::format("WireSpec: inserted_length {} m must be between two segments ({} m) and the length ({} m)",
                    inserted, 2.0 * model.h, spec.length));
  feeder_.build(inserted);
  stepper_.reset_trace();
  if (model.adapt.enabled) {
    // Resolve the rest shape (a pre-shaped tip) before the first step, then lay it out
    // again on the refined vertices.
    for (int round = 0; round < 12 && adapt(); ++round) {
    }
    feeder_.layout_rest_shape();
    stepper_.reset_trace();
  }
}

RodSimulator::~RodSimulator() = default;

// -----------------------------------------------------------------------------------------
// Frames
// -----------------------------------------------------------------------------------------

// -----------------------------------------------------------------------------------------
// Stepping, loads and clamps: handed to the parts
// -----------------------------------------------------------------------------------------

StepReport RodSimulator::step(double dt) { return stepper_.step(dt); }
StepReport RodSimulator::solve_static() { return stepper_.solve_static(); }
double RodSimulator::static_imbalance() { return stepper_.static_imbalance(); }
double RodSimulator::step_imbalance() { return stepper_.step_imbalance(); }
void RodSimulator::save_checkpoint() { stepper_.save_checkpoint(); }
void RodSimulator::restore_checkpoint(bool guess_from_current) { stepper_.restore_checkpoint(guess_from_current); }
bool RodSimulator::adapt() { return stepper_.adapt(); }
int RodSimulator::static_hessian_negative_eigenvalues() { return stepper_.static_hessian_negative_eigenvalues(); }

int RodSimulator::add_point_force(double s, const Vec3& f) {
  loads_.point_forces.points.push_back({s, f});
  return static_cast<int>(loads_.point_forces.points.size()) - 1;
}

void RodSimulator::add_external(std::shared_ptr<ExternalForce> force) {
  if (!force) throw_usage_error("RodSimulator::add_external: null force");
  externals_.push_back(std::move(force));
  externals_.back()->start(stepper_.current_view(0.0));
}

void RodSimulator::clamp_tip(const Vec3& tip, const Vec3& next) { feeder_.clamp_tip(tip, next); }

void RodSimulator::lay_along(const std::function<Vec3(double)>& along) {
  feeder_.lay_along(along);
  stepper_.reset_trace();
}

std::pair<Vec3, Vec3> RodSimulator::material_frame(int edge) const {
  const EdgeFrame& f = body_.state.frame.at(edge);
  const double c = std::cos(body_.state.theta[edge]), s = std::sin(body_.state.theta[edge]);
  return {c * f.d1 + s * f.d2, -s * f.d1 + c * f.d2};
}

// -----------------------------------------------------------------------------------------
// Diagnostics
// -----------------------------------------------------------------------------------------

RodEnergy RodSimulator::energy() const {
  const RodState& s = body_.state;
  RodEnergy e;
  const int nv = s.vertex_count();
  for (int k = 0; k < nv; ++k) {
    e.kinetic += 0.5 * body_.disc.mass[k] * s.v[k].squaredNorm();
    if (k < nv - 1) e.kinetic += 0.5 * body_.disc.twist_inertia[k] * s.omega[k] * s.omega[k];
  }
  for (int j = 0; j < nv - 1; ++j)
    e.stretching += stretch_energy(s.x[j], s.x[j + 1], body_.disc.stretch_stiffness[j], body_.disc.rest_length[j]);
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
    feeder_.vertex_params(k, p);
    e.bending_twisting += bend_twist(st, p, nullptr, nullptr);
  }
  return e;
}

double RodSimulator::max_strain() const {
  double m = 0.0;
  for (int j = 0; j < feeder_.first_clamped(); ++j)
    m = std::max(m, std::abs((body_.state.x[j + 1] - body_.state.x[j]).norm() / body_.disc.rest_length[j] - 1.0));
  return m;
}

double RodSimulator::length_drift() const {
  double l = 0.0;
  const int ne = body_.state.edge_count();
  double rest = 0.0;
  for (int j = 0; j < ne; ++j) {
    l += (body_.state.x[j + 1] - body_.state.x[j]).norm();
    rest += body_.disc.rest_length[j];
  }
  return std::abs(l - rest) / rest;
}

}  // namespace flowire::rod
