#include "flowire/rod/simulator.hpp"

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "kernel_clones.hpp"

namespace flowire::rod {

namespace {
constexpr int kBandwidth = 10;  // stencil (x_{k-1}, θ_{k-1}, x_k, θ_k, x_{k+1}) spans 11 unknowns

Mat3 sym(const Mat3& a) { return 0.5 * (a + a.transpose()); }

bool finite(const Eigen::Ref<const Eigen::VectorXd>& v) { return v.allFinite(); }

/// The symmetric matrix's negative eigenvalues set to zero.
Mat3 positive_part(const Mat3& a) {
  Eigen::SelfAdjointEigenSolver<Mat3> es;
  es.computeDirect(a);
  const Eigen::Vector3d lambda = es.eigenvalues().cwiseMax(0.0);
  return es.eigenvectors() * lambda.asDiagonal() * es.eigenvectors().transpose();
}
Eigen::Matrix<double, 6, 6> positive_part6(const Eigen::Matrix<double, 6, 6>& a) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> es(a);
  const Eigen::Matrix<double, 6, 1> lambda = es.eigenvalues().cwiseMax(0.0);
  return es.eigenvectors() * lambda.asDiagonal() * es.eigenvectors().transpose();
}
}  // namespace

const char* to_string(SolveStatus s) {
  switch (s) {
    case SolveStatus::Converged: return "converged";
    case SolveStatus::MaxIterations: return "maximum Newton iterations reached";
    case SolveStatus::LineSearchFailed: return "line search failed";
    case SolveStatus::NonFinite: return "non-finite values";
    case SolveStatus::SingularMatrix: return "singular matrix";
  }
  return "unknown";
}

Integrator parse_integrator(std::string_view name) {
  if (name == "implicit_euler") return Integrator::ImplicitEuler;
  if (name == "implicit_midpoint") return Integrator::ImplicitMidpoint;
  throw_usage_error(fmt::format("integrator '{}': use implicit_euler or implicit_midpoint", name));
}

const char* to_string(Integrator integrator) {
  return integrator == Integrator::ImplicitMidpoint ? "implicit_midpoint" : "implicit_euler";
}

/// Buffers sized once for the whole wire.
struct RodSimulator::Work {
  int max_dof = 0;
  Eigen::VectorXd q, grad, rhs, dq, mass, damp, fext, fext_bk, q0, qhat, grad_bk;
  Eigen::VectorXd fcons, fcons_bk;  // conservative part of fext (has a potential)
  double ext_energy = 0.0;          // potential energy of the conservative external forces
  double elastic_inertial = 0.0;    // last assembly's potential without ext_energy
  BandedMatrix H;
  BandedLDLT ldlt;
  Eigen::SparseMatrix<double> sparse;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> sparse_ldlt;
  int sparse_pattern_size = -1;
  std::vector<Mat3> ext_k;  // (n_vertices) −∂f/∂x − ∂f/∂v / h, symmetrized
  bool has_ext_k = false;
  std::vector<Eigen::Matrix<double, 6, 6>> ext_edge_k;  // (n_edges) −∂(f_j, f_j+1)/∂(x_j, x_j+1), symmetrized
  bool has_ext_edge_k = false;
  std::vector<EdgeGeometry> edges;  // (n_edges) tangent, length, material frame
  Mat3 moment_k = Mat3::Zero();  // −∂f₁/∂e of the tip couple, symmetrized
  ForceAccumulator acc;
  std::vector<Vec3> vel;      // vertex velocities at the iterate (for externals)
  std::vector<double> spin;   // edge spin rates at the iterate (for externals)
  std::vector<Vec3> tangent;  // edge tangents at the iterate (for externals)
  std::vector<double> ext_spin_k;  // (n_edges) −∂τ/∂ω / h
  // step-start copy (for velocities and rollback)
  std::vector<Vec3> x0, v0;
  // The state an implicit Euler step ended in and its step (for the next step's predictor).
  std::vector<Vec3> x_end;
  double h_end = 0.0;
  std::vector<Vec3> v_guess;         // (vertices) velocity of the initial guess
  std::vector<double> omega_guess;   // (edges)
  std::vector<double> theta0, omega0, twist0;
  std::vector<EdgeFrame> frame0;
  // accepted iterate during a line search
  std::vector<Vec3> xb;
  std::vector<double> thetab, twistb;
  std::vector<EdgeFrame> frameb;
  std::vector<Vec3> xz;
  std::vector<double> tz;
  // resampling (adaptivity): the old state and the plan
  std::vector<double> ru, rtau, rcell, rtheta, romega, rtwist, psi, unew;
  std::vector<Vec3> rx, rv, rT;
  std::vector<EdgeFrame> rframe;
  std::vector<int> source;
  std::vector<char> split, remove;
  // step starts kept for a retry in substeps, one per subdivision level
  struct Saved {
    RodState state;
    double target_angle = 0.0, insertion_speed = 0.0;
    int first_clamped = 0;
    Vec3 base_force = Vec3::Zero(), base_torque = Vec3::Zero();
    size_t trace_size = 0;
  };
  std::vector<Saved> saved;
};

RodSimulator::RodSimulator(const WireSpec& spec)
    : model_(RodModel::from_spec(spec)), work_(std::make_unique<Work>()) {
  // Adaptive refinement may hold up to one vertex per finest edge.
  const int nvmax =
      model_.adapt.enabled
          ? std::max(model_.grid_vertices,
                     static_cast<int>(std::ceil(model_.length / model_.adapt.min_segment_length)) + 4)
          : model_.grid_vertices;
  const int max_dof = 4 * nvmax - 1;
  Work& w = *work_;
  w.max_dof = max_dof;
  for (Eigen::VectorXd* v : {&w.q, &w.grad, &w.rhs, &w.dq, &w.mass, &w.damp, &w.fext, &w.fext_bk,
                             &w.q0, &w.qhat, &w.grad_bk, &w.fcons, &w.fcons_bk})
    v->setZero(max_dof);
  w.H.reserve(max_dof, kBandwidth);
  w.ldlt.reserve(max_dof, kBandwidth);
  w.ext_k.reserve(nvmax);
  w.ext_edge_k.reserve(nvmax);
  w.edges.reserve(nvmax);
  w.acc.reserve(nvmax);
  for (auto* v : {&w.vel, &w.x0, &w.v0, &w.xb, &w.xz, &w.tangent, &w.x_end, &w.v_guess}) v->reserve(nvmax);
  w.spin.reserve(nvmax);
  w.ext_spin_k.reserve(nvmax);
  for (auto* v : {&w.theta0, &w.omega0, &w.twist0, &w.thetab, &w.twistb, &w.tz, &w.ru, &w.rtau,
                  &w.rcell, &w.rtheta, &w.romega, &w.rtwist, &w.psi, &w.unew, &w.omega_guess})
    v->reserve(nvmax);
  for (auto* v : {&w.rx, &w.rv, &w.rT}) v->reserve(nvmax);
  w.rframe.reserve(nvmax);
  w.source.reserve(nvmax);
  w.split.reserve(nvmax);
  w.remove.reserve(nvmax);
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
  w.frameb.reserve(nvmax);
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
    throw_usage_error(fmt::format(
        "WireSpec: inserted_length {} m must be between two segments ({} m) and the length ({} m)",
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
// State construction and feeding
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
  target_angle_ = 0.0;
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
    s.ref_twist[k] = reference_twist(s.frame[k - 1].d1, (s.x[k] - s.x[k - 1]).normalized(),
                                     s.frame[k].d1, (s.x[k + 1] - s.x[k]).normalized(), 0.0);
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
  for (size_t k = 0; k < state_.x.size(); ++k)
    arc_length_[k] = state_.inserted_length - state_.u[k];
}

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
      s.omega.push_back(-rotation_speed_);
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
      work_->tz.push_back(s.theta[k] - s.theta[k - 1] + s.ref_twist[k]);  // total twist
    for (int k = fc; k < std::min(first_clamped_, nv); ++k) {
      s.x[k] = pb - db * (s.u[k] - L);
      s.v[k] = db * feed_speed_;
    }
    for (int j = fc; j < nv - 1; ++j) {
      s.frame[j] = EdgeFrame{base_d1_, base_d2_};
      s.theta[j] = -angle;
      s.omega[j] = -rotation_speed_;
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
      const double m_old = work_->tz[idx];
      const double previous = m_old - (s.theta[k] - s.theta[k - 1]);
      s.ref_twist[k] = reference_twist(s.frame[k - 1].d1, (s.x[k] - s.x[k - 1]).normalized(),
                                       s.frame[k].d1, (s.x[k + 1] - s.x[k]).normalized(), previous);
    }
    work_->tz.clear();
  }
  first_clamped_ = fc;
}

// -----------------------------------------------------------------------------------------
// Adaptivity
// -----------------------------------------------------------------------------------------

namespace {
/// u is a multiple of len (within round-off of the dyadic grid).
bool aligned(double u, double len) {
  const double r = u / len;
  return std::abs(r - std::round(r)) < 1e-7;
}
}  // namespace

bool RodSimulator::adapt() { return adapt_for(0.0); }

bool RodSimulator::adapt_for(double pull_back) {
  if (!model_.adapt.enabled) return false;
  const AdaptSpec& a = model_.adapt;
  const double h = model_.h;
  const double tol = 1e-9 * h;
  bool any = false;
  // Round 0 applies the curvature criteria and the grid near the entry; later rounds only
  // finish restoring the grid near the entry (after a pull-back over a refined part).
  for (int round = 0; round < 8; ++round) {
    RodState& s = state_;
    Work& w = *work_;
    const int nv = s.vertex_count();
    const int fc = first_clamped_;
    // Vertices at or behind `zone` (the entry after the next step's pull-back) must be
    // feeding-grid points h apart.
    const double zone = s.inserted_length - pull_back;
    const int lowest = tip_clamped_ ? 3 : 0;  // a tip clamp holds vertices 0..2 as they are
    auto len = [&](int j) { return s.u[j + 1] - s.u[j]; };
    w.psi.assign(nv, 0.0);
    for (int k = 1; k < nv - 1; ++k) {
      const Vec3 te = (s.x[k] - s.x[k - 1]).normalized();
      const Vec3 tf = (s.x[k + 1] - s.x[k]).normalized();
      const double phi = std::atan2(te.cross(tf).norm(), te.dot(tf));
      const double rest =
          2.0 * std::atan(0.5 * std::hypot(disc_.rest_kappa1[k], disc_.rest_kappa2[k]));
      w.psi[k] = std::max(phi, rest);
    }
    w.split.assign(nv - 1, 0);
    w.remove.assign(nv, 0);
    auto sibling_pair = [&](int k) {  // vertex k is the midpoint of an aligned parent edge
      const double l = len(k - 1);
      return std::abs(len(k) - l) <= 1e-9 * l && aligned(s.u[k - 1], 2.0 * l);
    };
    // At and behind the entry (after the step's pull-back): grid points only (coarse edges
    // reaching there split, refined vertices there removed).
    for (int j = lowest; j < nv - 1; ++j)
      if (s.u[j + 1] > zone + tol && len(j) > h + tol) w.split[j] = 1;
    for (int k = std::max(lowest, 1); k < nv - 1; ++k)
      if (s.u[k] > zone - tol && !aligned(s.u[k], h) && sibling_pair(k) && !w.split[k - 1] &&
          !w.split[k])
        w.remove[k] = 1;
    if (round == 0) {
      auto splittable = [&](int j) {  // the new vertex stays free over the next step
        return j >= lowest && j < fc && 0.5 * (s.u[j] + s.u[j + 1]) < zone - tol &&
               len(j) >= 2.0 * a.min_segment_length - tol;
      };
      for (int j = lowest; j < fc; ++j)
        if (splittable(j) && std::max(w.psi[j], w.psi[j + 1]) > a.split_angle) w.split[j] = 1;
      // 2:1 balance: neighbouring rest lengths differ by at most a factor 2.
      auto final_len = [&](int j) { return w.split[j] ? 0.5 * len(j) : len(j); };
      for (bool again = true; again;) {
        again = false;
        for (int j = 0; j < nv - 1; ++j)
          for (int i : {j - 1, j + 1})
            if (i >= 0 && i < nv - 1 && !w.split[i] && final_len(i) > 2.0 * final_len(j) + tol &&
                splittable(i)) {
              w.split[i] = 1;
              again = true;
            }
      }
      for (int k = std::max(lowest, 1); k < fc; ++k) {
        if (w.remove[k] || !sibling_pair(k)) continue;
        const double l = len(k - 1);
        if (2.0 * l > h + tol && s.u[k + 1] > zone + tol) continue;
        if (2.0 * l > a.max_segment_length + tol || w.split[k - 1] || w.split[k]) continue;
        if (std::max({w.psi[k - 1], w.psi[k], w.psi[k + 1]}) >= a.merge_angle) continue;
        if (k >= 2 && final_len(k - 2) < l - tol) continue;
        if (final_len(k + 1) < l - tol) continue;
        // Lumping the vertex's mass onto its neighbours raises the kinetic energy by
        // (m_k/8)|v_{k−1} − v_{k+1}|² (exact for a linear velocity field): merge only where
        // that is negligible, so a rod swinging through straight is not coarsened.
        const double dke = 0.125 * disc_.mass[k] * (s.v[k - 1] - s.v[k + 1]).squaredNorm();
        const double ke = 0.5 * (disc_.mass[k - 1] * s.v[k - 1].squaredNorm() +
                                 disc_.mass[k] * s.v[k].squaredNorm() +
                                 disc_.mass[k + 1] * s.v[k + 1].squaredNorm());
        if (dke > 1e-4 * ke) continue;
        w.remove[k] = 1;
      }
    }
    w.unew.clear();
    int splits = 0, merges = 0;
    for (int k = 0; k < nv; ++k) {
      if (w.remove[k]) {
        ++merges;
      } else {
        w.unew.push_back(s.u[k]);
      }
      if (k < nv - 1 && w.split[k]) {
        w.unew.push_back(0.5 * (s.u[k] + s.u[k + 1]));
        ++splits;
      }
    }
    if (splits == 0 && merges == 0) break;
    resample(w.unew);
    adapt_splits_ += splits;
    adapt_merges_ += merges;
    any = true;
  }
  return any;
}

void RodSimulator::resample(const std::vector<double>& u_new) {
  RodState& s = state_;
  Work& w = *work_;
  const int nv = s.vertex_count();
  const int nn = static_cast<int>(u_new.size());
  const double tol = 1e-9 * model_.h;
  // The old state.
  w.ru = s.u;
  w.rx = s.x;
  w.rv = s.v;
  w.rtheta = s.theta;
  w.romega = s.omega;
  w.rframe = s.frame;
  w.rtwist = s.ref_twist;
  w.rcell = disc_.cell_length;
  const int old_clamp = first_clamped_;
  // Old twist density (twist per cell length) and vertex tangents.
  w.rtau.assign(nv, 0.0);
  for (int k = 1; k < nv - 1; ++k)
    w.rtau[k] = (w.rtheta[k] - w.rtheta[k - 1] + w.rtwist[k]) / w.rcell[k];
  w.rtau[0] = nv > 2 ? w.rtau[1] : 0.0;
  w.rtau[nv - 1] = nv > 2 ? w.rtau[nv - 2] : 0.0;
  w.rT.resize(nv);
  for (int k = 0; k < nv; ++k) {
    const Vec3 tl = k > 0 ? Vec3((w.rx[k] - w.rx[k - 1]).normalized()) : Vec3::Zero();
    const Vec3 tr = k < nv - 1 ? Vec3((w.rx[k + 1] - w.rx[k]).normalized()) : Vec3::Zero();
    w.rT[k] = (tl + tr).normalized();
  }

  // Vertices: kept ones as they were; new ones on the Hermite curve of their old edge.
  s.u = u_new;
  s.x.resize(nn);
  s.v.resize(nn);
  w.source.assign(nn, -1);
  w.tz.assign(nn, 0.0);  // twist density at the new vertices
  int i = 0;
  for (int m = 0; m < nn; ++m) {
    const double u = u_new[m];
    while (i < nv - 2 && w.ru[i + 1] <= u + tol) ++i;
    if (std::abs(u - w.ru[i]) <= tol || std::abs(u - w.ru[i + 1]) <= tol) {
      const int k = std::abs(u - w.ru[i]) <= tol ? i : i + 1;
      w.source[m] = k;
      s.x[m] = w.rx[k];
      s.v[m] = w.rv[k];
      w.tz[m] = w.rtau[k];
      continue;
    }
    const double t = (u - w.ru[i]) / (w.ru[i + 1] - w.ru[i]);
    const double chord = (w.rx[i + 1] - w.rx[i]).norm();
    const double t2 = t * t, t3 = t2 * t;
    s.x[m] = (2 * t3 - 3 * t2 + 1) * w.rx[i] + (t3 - 2 * t2 + t) * chord * w.rT[i] +
             (-2 * t3 + 3 * t2) * w.rx[i + 1] + (t3 - t2) * chord * w.rT[i + 1];
    s.v[m] = (1.0 - t) * w.rv[i] + t * w.rv[i + 1];
    w.tz[m] = (1.0 - t) * w.rtau[i] + t * w.rtau[i + 1];
  }
  for (int m = 0; m < nn; ++m)
    if (w.source[m] == old_clamp) first_clamped_ = m;
  model_.discretize(s.u, disc_);

  // Edges: the old edge holding the new edge's midpoint gives the frame (transported to
  // the new tangent), the spin rate and a provisional angle.
  s.theta.resize(nn - 1);
  s.omega.resize(nn - 1);
  s.frame.resize(nn - 1);
  s.ref_twist.assign(nn, 0.0);
  i = 0;
  for (int j = 0; j < nn - 1; ++j) {
    const double mid = 0.5 * (u_new[j] + u_new[j + 1]);
    while (i < nv - 2 && w.ru[i + 1] <= mid) ++i;
    const Vec3 t0 = w.rframe[i].d1.cross(w.rframe[i].d2);
    const Vec3 t1 = (s.x[j + 1] - s.x[j]).normalized();
    Vec3 d1 = parallel_transport(w.rframe[i].d1, t0, t1);
    d1 = (d1 - t1 * t1.dot(d1)).normalized();
    s.frame[j] = EdgeFrame{d1, t1.cross(d1)};
    s.omega[j] = w.romega[i];
    s.theta[j] = w.rtheta[i];
  }
  for (int m = 1; m < nn - 1; ++m) {
    const int k = w.source[m];
    const double previous = (k > 0 && k < nv - 1) ? w.rtwist[k] : 0.0;
    s.ref_twist[m] = reference_twist(s.frame[m - 1].d1, (s.x[m] - s.x[m - 1]).normalized(),
                                     s.frame[m].d1, (s.x[m + 1] - s.x[m]).normalized(), previous);
  }
  // Material angles swept from the clamp (whose edges are unchanged): each vertex carries
  // the old twist density times its new cell.
  for (int j = nn - 3; j >= 0; --j) {
    if (j >= first_clamped_) continue;  // clamp edges keep their angle
    const int m = j + 1;
    const double twist = w.tz[m] * disc_.cell_length[m];
    s.theta[j] = s.theta[j + 1] + s.ref_twist[m] - twist;
  }
  refresh_arc_lengths();
  if (!externals_.empty()) {
    const RodView view = current_view(0.0);
    for (auto& e : externals_) e->remap(view, w.source);
  }
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
  return view;
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

// -----------------------------------------------------------------------------------------
// Frames
// -----------------------------------------------------------------------------------------

FLOWIRE_ROD_KERNEL_CLONES
void RodSimulator::transport_frames_to(const std::vector<Vec3>& x_new,
                                       const std::vector<EdgeFrame>& frame_from,
                                       const std::vector<double>& twist_from,
                                       std::vector<EdgeFrame>& frame_to,
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

// -----------------------------------------------------------------------------------------
// Assembly
// -----------------------------------------------------------------------------------------

void RodSimulator::vertex_params(int k, VertexParams& p) const {
  // A clamp vertex owns only the half cell on its free side: the wire behind it is
  // held rigid, so its bending and twisting act over h/2 (this keeps the clamp exactly at
  // the entry and the scheme second-order; a full cell would move the clamp back by h/2).
  double cell = 1.0;
  if (k == first_clamped_) cell = 0.5 * disc_.rest_length[k - 1] / disc_.cell_length[k];
  if (tip_clamped_ && k == 1) cell = 0.5;
  p.bend_stiffness1 = p.bend_stiffness2 = disc_.bend_stiffness[k];
  p.rest_kappa1 = cell * disc_.rest_kappa1[k];
  p.rest_kappa2 = cell * disc_.rest_kappa2[k];
  p.twist_stiffness = disc_.twist_stiffness[k];
  p.rest_twist = 0.0;
  p.voronoi_length = cell * disc_.cell_length[k];
}

void RodSimulator::gather(Eigen::Ref<Eigen::VectorXd> q) const {
  const int nv = state_.vertex_count();
  for (int k = 0; k < nv; ++k) {
    q.segment<3>(4 * k) = state_.x[k];
    if (k < nv - 1) q(4 * k + 3) = state_.theta[k];
  }
}

int RodSimulator::add_point_force(double s, const Vec3& f) {
  point_forces_.push_back({s, f});
  return static_cast<int>(point_forces_.size()) - 1;
}

void RodSimulator::add_external(std::shared_ptr<ExternalForce> force) {
  if (!force) throw_usage_error("RodSimulator::add_external: null force");
  externals_.push_back(std::move(force));
  externals_.back()->start(current_view(0.0));
}

void RodSimulator::evaluate_loads(Mode mode, double h, double load_scale) {
  Work& w = *work_;
  const RodState& s = state_;
  const int nv = s.vertex_count();
  const int nd = dof_count();
  w.fext.head(nd).setZero();
  w.fcons.head(nd).setZero();
  w.ext_energy = 0.0;
  w.has_ext_k = false;
  w.has_ext_edge_k = false;
  w.moment_k.setZero();
  if (gravity_.squaredNorm() > 0.0)
    for (int k = 0; k < nv; ++k) w.fext.segment<3>(4 * k) += load_scale * disc_.mass[k] * gravity_;
  w.fext.segment<3>(0) += load_scale * tip_force_;
  const double L = s.inserted_length;
  for (const PointForce& pf : point_forces_) {
    const double u = L - pf.s;
    if (u < 0.0 || u > L) continue;
    const auto it = std::upper_bound(s.u.begin(), s.u.end(), u);
    const int k = std::clamp(static_cast<int>(it - s.u.begin()) - 1, 0, nv - 2);
    const double a = std::clamp((u - s.u[k]) / (s.u[k + 1] - s.u[k]), 0.0, 1.0);
    w.fext.segment<3>(4 * k) += load_scale * (1.0 - a) * pf.f;
    w.fext.segment<3>(4 * (k + 1)) += load_scale * a * pf.f;
  }
  if (tip_moment_.squaredNorm() > 0.0) {
    const Vec3 M = load_scale * tip_moment_;
    const Vec3 e = s.x[1] - s.x[0];
    const double l2 = e.squaredNorm();
    const Vec3 t = e / std::sqrt(l2);
    w.fext(3) += M.dot(t);
    const Vec3 Mp = M - t * t.dot(M);
    const Vec3 f1 = Mp.cross(e) / l2;  // couple: e × f1 = M⊥
    w.fext.segment<3>(4) += f1;
    w.fext.segment<3>(0) -= f1;
    Mat3 skewM;
    skewM << 0, -Mp.z(), Mp.y(), Mp.z(), 0, -Mp.x(), -Mp.y(), Mp.x(), 0;
    w.moment_k = -sym(skewM / l2 - 2.0 * f1 * e.transpose() / l2);
  }
  if (!externals_.empty()) {
    w.vel.resize(nv);
    w.spin.resize(nv - 1);
    w.tangent.resize(nv - 1);
    for (int k = 0; k < nv; ++k)
      w.vel[k] = mode == Mode::Dynamic ? Vec3((s.x[k] - w.x0[k]) / h) : Vec3::Zero();
    for (int j = 0; j < nv - 1; ++j) {
      w.spin[j] = mode == Mode::Dynamic ? (s.theta[j] - w.theta0[j]) / h : 0.0;
      w.tangent[j] = (s.x[j + 1] - s.x[j]).normalized();
    }
    w.acc.reset(nv);
    RodView view;
    view.positions = s.x;
    view.velocities = w.vel;
    view.arc_length = std::span<const double>(arc_length_.data(), nv);
    view.radius = std::span<const double>(disc_.edge_radius.data(), nv - 1);
    view.rest_lengths = std::span<const double>(disc_.rest_length.data(), nv - 1);
    view.segment_length = model_.h;
    view.spin_rates = w.spin;
    view.tangents = w.tangent;
    view.first_clamped_vertex = first_clamped_;
    view.time = s.time;
    view.dt = mode == Mode::Dynamic ? h : 0.0;
    for (auto& ext : externals_) ext->evaluate(view, w.acc);
    w.ext_k.resize(nv);
    w.ext_spin_k.resize(nv - 1);
    w.has_ext_k = true;
    for (int j = 0; j < nv - 1; ++j) {
      w.fext(4 * j + 3) += w.acc.twist_torques()[j];
      w.ext_spin_k[j] =
          mode == Mode::Dynamic ? -w.acc.twist_torque_spin_derivatives()[j] / h : 0.0;
    }
    w.has_ext_edge_k = w.acc.has_edge_jacobians();
    if (w.has_ext_edge_k) {
      w.ext_edge_k.resize(nv - 1);
      for (int j = 0; j < nv - 1; ++j) {
        const auto& e = w.acc.edge_jacobians()[static_cast<size_t>(j)];
        w.ext_edge_k[j] = -0.5 * (e + e.transpose());
      }
    }
    w.ext_energy = w.acc.energy();
    for (int k = 0; k < nv; ++k) {
      w.fcons.segment<3>(4 * k) = w.acc.conservative_forces()[k];
      w.fext.segment<3>(4 * k) += w.acc.forces()[k];
      w.ext_k[k] = -sym(w.acc.position_jacobians()[k]);
      if (mode == Mode::Dynamic) w.ext_k[k] -= sym(w.acc.velocity_jacobians()[k]) / h;
    }
  }
}

double RodSimulator::assemble(Mode mode, double h, double load_scale, Need need, bool psd,
                              bool reuse_loads) {
  Work& w = *work_;
  const RodState& s = state_;
  const int nv = s.vertex_count();
  const int nd = dof_count();
  const bool need_grad = need != Need::Value;
  const bool need_matrix = need == Need::Matrix;
  auto g = w.grad.head(nd);
  if (need_grad) g.setZero();
  if (need_matrix) w.H.resize(nd);
  double energy = 0.0;
  // Stretching: E = ½ ks ℓ̄ (ℓ/ℓ̄ − 1)², one length and tangent per edge.
  for (int j = 0; j < nv - 1; ++j) {
    const double lbar = disc_.rest_length[j];
    const double ks = disc_.stretch_stiffness[j];
    const Vec3 e = s.x[j + 1] - s.x[j];
    const double l = e.norm();
    const double strain = l / lbar - 1.0;
    energy += 0.5 * ks * lbar * strain * strain;
    if (!need_grad) continue;
    const Vec3 t = e / l;
    const Vec3 ge = ks * strain * t;
    g.segment<3>(4 * j) -= ge;
    g.segment<3>(4 * j + 4) += ge;
    if (need_matrix) {
      // Same matrix as stretch_hessian(): (ks/ℓ̄) t tᵀ + ks (1/ℓ̄ − 1/ℓ)(I − t tᵀ).
      double transverse = ks * (1.0 / lbar - 1.0 / l);
      if (psd) transverse = std::max(transverse, 0.0);
      const Mat3 tt = t * t.transpose();
      const Mat3 he = (ks / lbar - transverse) * tt + transverse * Mat3::Identity();
      // Blocks (x_j, x_j) = (x_{j+1}, x_{j+1}) = he, (x_{j+1}, x_j) = −he; lower band only.
      const int r0 = 4 * j, r1 = 4 * j + 4;
      for (int a = 0; a < 3; ++a) {
        for (int c = 0; c <= a; ++c) {
          w.H.lower(r0 + a, r0 + c) += he(a, c);
          w.H.lower(r1 + a, r1 + c) += he(a, c);
        }
        for (int c = 0; c < 3; ++c) w.H.lower(r1 + a, r0 + c) -= he(a, c);
      }
    }
  }
  // Bending and twisting: per-edge geometry once, then one stencil per interior vertex.
  w.edges.resize(nv - 1);
  for (int j = 0; j < nv - 1; ++j)
    w.edges[j] = edge_geometry(s.x[j], s.x[j + 1], s.frame[j], s.theta[j]);
  VertexParams p;
  Vec11 gs;
  Mat11 hs;
  for (int k = 1; k < nv - 1; ++k) {
    vertex_params(k, p);
    energy += bend_twist(w.edges[k - 1], w.edges[k], s.theta[k - 1], s.theta[k], s.ref_twist[k], p,
                         need_grad ? &gs : nullptr, need_matrix ? &hs : nullptr, psd);
    if (need_grad) g.segment<11>(4 * (k - 1)) += gs;
    if (need_matrix) w.H.add_block(hs, 4 * (k - 1));
  }
  if (!reuse_loads) evaluate_loads(mode, h, load_scale);
  if (need_grad) g -= w.fext.head(nd);
  if (mode == Mode::Dynamic) {
    // Inertia and damping: ½|q − q̂|²_M / h² + ½|q − q₀|²_C / h.
    const double ih2 = 1.0 / (h * h), ih = 1.0 / h;
    for (int d = 0; d < nd; ++d) {
      const double a = w.q(d) - w.qhat(d);
      const double b = w.q(d) - w.q0(d);
      energy += 0.5 * (w.mass(d) * a * a * ih2 + w.damp(d) * b * b * ih);
      if (need_grad) g(d) += w.mass(d) * a * ih2 + w.damp(d) * b * ih;
      if (need_matrix) w.H.lower(d, d) += w.mass(d) * ih2 + w.damp(d) * ih;
    }
  }
  if (need_matrix) {
    for (int k = 0; w.has_ext_k && k < nv; ++k) {
      if (w.ext_k[k].isZero(0.0)) continue;
      const int idx[3] = {4 * k, 4 * k + 1, 4 * k + 2};
      if (psd) {
        // An external stiffness need not be definite (a contact's wall curvature where two
        // vessels are blended): its positive part, so the Gauss–Newton matrix is.
        w.H.add_block(positive_part(w.ext_k[k]), idx, 3);
      } else {
        w.H.add_block(w.ext_k[k], idx, 3);
      }
    }
    for (int j = 0; w.has_ext_k && w.has_ext_edge_k && j < nv - 1; ++j) {
      const Eigen::Matrix<double, 6, 6>& k6 = w.ext_edge_k[j];
      if (k6.isZero(0.0)) continue;
      const int idx[6] = {4 * j, 4 * j + 1, 4 * j + 2, 4 * j + 4, 4 * j + 5, 4 * j + 6};
      w.H.add_block(psd ? positive_part6(k6) : k6, idx, 6);
    }
    for (int j = 0; w.has_ext_k && j < nv - 1; ++j) w.H.lower(4 * j + 3, 4 * j + 3) += w.ext_spin_k[j];
    if (!psd && !w.moment_k.isZero(0.0)) {
      Mat6 b;
      b << w.moment_k, -w.moment_k, -w.moment_k, w.moment_k;
      const int idx[6] = {0, 1, 2, 4, 5, 6};
      w.H.add_block(b, idx, 6);
    }
  }
  // External forces that derive from a potential enter the merit through that potential.
  return energy + w.ext_energy;
}

double RodSimulator::force_scale(double load_scale) const {
  const RodState& s = state_;
  double total_mass = 0.0, ei = 0.0, ea = 0.0;
  for (int k = 0; k < s.vertex_count(); ++k) {
    total_mass += disc_.mass[k];
    ei = std::max(ei, disc_.bend_stiffness[k]);
  }
  double lmin = model_.h;
  for (int j = 0; j < s.edge_count(); ++j) {
    ea = std::max(ea, disc_.stretch_stiffness[j]);
    lmin = std::min(lmin, disc_.rest_length[j]);
  }
  const double L = std::max(s.inserted_length, model_.h);
  double f = std::max({ei / (L * L), load_scale * total_mass * gravity_.norm(),
                       load_scale * tip_force_.norm(), load_scale * tip_moment_.norm() / L});
  for (const auto& pf : point_forces_) f = std::max(f, load_scale * pf.f.norm());
  const double xscale = model_.base_position.norm() + L;
  const double floor = 4.0 * std::numeric_limits<double>::epsilon() * ea * (1.0 + xscale / lmin);
  return settings_.force_tolerance * f + floor;
}

// -----------------------------------------------------------------------------------------
// Newton
// -----------------------------------------------------------------------------------------

StepReport RodSimulator::newton(Mode mode, double h, double load_scale) {
  Work& w = *work_;
  RodState& s = state_;
  const int nv = s.vertex_count();
  const int nd = dof_count();
  const int first_fixed = 4 * first_clamped_;
  const int first_free = tip_clamped_ ? 7 : 0;  // x0, θ0, x1 held by a tip clamp
  StepReport rep;
  rep.tolerance = force_scale(load_scale);
  const int max_it = mode == Mode::Static ? settings_.max_static_iterations : settings_.max_iterations;

  // Max over the free unknowns of |force| and |torque| / rest length (a force too).
  auto residual_norm = [&]() {
    double r = 0.0;
    for (int d = first_free; d < first_fixed && d % 4 != 0; ++d) {  // a partly held vertex
      const double v = (d % 4 == 3) ? w.grad(d) / disc_.rest_length[d / 4] : w.grad(d);
      r = std::max(r, std::abs(v));
    }
    for (int k = (first_free + 3) / 4; 4 * k < first_fixed; ++k) {
      const double* g = w.grad.data() + 4 * k;
      r = std::max({r, std::abs(g[0]), std::abs(g[1]), std::abs(g[2])});
      if (4 * k + 3 < first_fixed) r = std::max(r, std::abs(g[3]) / disc_.rest_length[k]);
    }
    return r;
  };

  using Clock = std::chrono::steady_clock;
  auto seconds = [](Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  auto t_phase = Clock::now();
  gather(w.q);
  double phi = assemble(mode, h, load_scale, Need::Matrix);
  bool matrix_current = true;  // trial points are evaluated without the matrix
  phase_seconds_.assembly += seconds(t_phase);
  if (!std::isfinite(phi) || !finite(w.grad.head(nd))) {
    rep.status = SolveStatus::NonFinite;
    return rep;
  }
  rep.status = SolveStatus::MaxIterations;
  // Chord iterations: once a full Newton step has cut the residual a thousandfold (the
  // quadratic regime, where the iterate is already close), the next iteration solves with
  // the factorization it used instead of assembling and factorizing a new matrix. Its
  // contraction is |H⁻¹ΔH| = O(|Δq|), small there; when it does not at least cut the residual
  // tenfold with a full step, the iteration after it is a Newton one again.
  bool chord = false;
  for (int it = 0; it < max_it; ++it) {
    rep.residual = residual_norm();
    if (rep.residual <= rep.tolerance) {
      rep.status = SolveStatus::Converged;
      break;
    }
    rep.newton_iterations = it + 1;
    const bool chord_step = chord;
    if (chord_step) {
      t_phase = Clock::now();
      auto rhs = w.rhs.head(nd);
      rhs = -w.grad.head(nd);
      rhs.tail(nd - first_fixed).setZero();
      rhs.head(first_free).setZero();
      w.dq.head(nd) = rhs;
      w.ldlt.solve_in_place(w.dq.head(nd));
      ++rep.chord_iterations;
      phase_seconds_.factorize += seconds(t_phase);
    }
    if (!chord_step && !matrix_current) {
      // Same configuration as the accepted trial: its loads and external forces are kept.
      t_phase = Clock::now();
      phi = assemble(mode, h, load_scale, Need::Matrix, false, /*reuse_loads=*/true);
      matrix_current = true;
      phase_seconds_.assembly += seconds(t_phase);
    }
    t_phase = Clock::now();
    bool ok = chord_step;
    if (!chord_step) {
    // Linear solve on the free unknowns: the exact Hessian first; if it is indefinite
    // (strongly bent or compressed states), the Gauss–Newton matrix of the same residual,
    // which is positive semi-definite, with a modified factorization as last resort.
    auto rhs = w.rhs.head(nd);
    rhs = -w.grad.head(nd);
    rhs.tail(nd - first_fixed).setZero();
    rhs.head(first_free).setZero();
    for (int attempt = 0; attempt < 2 && !ok; ++attempt) {
      if (attempt == 1) {
        assemble(mode, h, load_scale, Need::Matrix, /*psd=*/true, /*reuse_loads=*/true);
        ++rep.regularizations;
      }
      for (int d = first_fixed; d < nd; ++d) w.H.set_identity_row(d);
      for (int d = 0; d < first_free; ++d) w.H.set_identity_row(d);
      // (The scale of the diagonal is needed by the fallbacks only.)
      auto scale = [&] { return std::max(w.H.max_diagonal(), 1e-300); };
      if (settings_.linear_solver == LinearSolver::Banded) {
        ok = attempt == 0 ? (w.ldlt.factorize(w.H) && w.ldlt.negative_pivots() == 0)
                          : w.ldlt.factorize(w.H, 1e-12 * scale());
        if (ok) {
          w.dq.head(nd) = rhs;
          w.ldlt.solve_in_place(w.dq.head(nd));
        }
      } else {
        double shift = 0.0;
        for (int tries = 0; tries < (attempt == 0 ? 1 : 12) && !ok; ++tries) {
          if (tries > 0) {
            const double next = tries == 1 ? 1e-12 * scale() : 10.0 * shift;
            w.H.add_to_diagonal(next - shift);
            shift = next;
          }
          w.H.to_sparse_lower(w.sparse);
          if (w.sparse_pattern_size != nd) {
            w.sparse_ldlt.analyzePattern(w.sparse);
            w.sparse_pattern_size = nd;
          }
          w.sparse_ldlt.factorize(w.sparse);
          ok = w.sparse_ldlt.info() == Eigen::Success &&
               (w.sparse_ldlt.vectorD().array() > 0.0).all();
        }
        if (ok) w.dq.head(nd) = w.sparse_ldlt.solve(rhs);
      }
    }
    phase_seconds_.factorize += seconds(t_phase);  // (with the rare positive semi-definite reassembly)
    }
    if (!ok || !finite(w.dq.head(nd))) {
      rep.status = SolveStatus::SingularMatrix;
      break;
    }
    t_phase = Clock::now();
    auto dq = w.dq.head(nd);
    const double slope = w.grad.head(nd).dot(dq);
    // Backtracking line search on φ + E_ext − W: φ the incremental potential, E_ext the
    // potential of conservative external forces (penalty contact), W the trapezoidal work
    // of the remaining loads (dead loads, friction, drag) along the ray.
    w.xb = s.x;
    w.thetab = s.theta;
    w.frameb = s.frame;
    w.twistb = s.ref_twist;
    w.fext_bk.head(nd) = w.fext.head(nd);
    w.fcons_bk.head(nd) = w.fcons.head(nd);
    const double ext_energy_b = w.ext_energy;
    w.grad_bk.head(nd) = w.grad.head(nd);
    const Eigen::VectorXd& qb = w.q;  // unchanged until accepted
    double alpha = 1.0;
    bool accepted = false;
    double max_step = 0.0;
    // Pass 0 measures conservative external forces by their potential. A potential that
    // is not consistent with its forces (e.g. a contact whose wall changes where a vertex
    // is relocated into another vessel) can leave no decrease along the ray; pass 1 then
    // treats every external force as a load (trapezoidal work), as without potentials.
    const int passes = externals_.empty() ? 1 : 2;
    for (int pass = 0; pass < passes && !accepted; ++pass) {
    alpha = 1.0;
    for (int cut = 0; cut <= settings_.max_line_search_cuts; ++cut) {
      for (int k = 0; k < nv; ++k) {
        s.x[k] = w.xb[k] + alpha * dq.segment<3>(4 * k);
        if (k < nv - 1) s.theta[k] = w.thetab[k] + alpha * dq(4 * k + 3);
      }
      if (settings_.curvilinear_update && !tip_clamped_) {
        // Walk from the clamp to the tip keeping each free edge's updated direction but
        // its linearized length: removes the O(α²) spurious stretch of a straight-line
        // step through a rotation, so stiff stretching does not throttle the step.
        Vec3 next_unprojected = s.x[first_clamped_];
        for (int j = first_clamped_ - 1; j >= 0; --j) {
          const Vec3 xn = s.x[j];
          const Vec3 eb = w.xb[j + 1] - w.xb[j];
          const double lb = eb.norm();
          const double target =
              lb + alpha * (eb / lb).dot(dq.segment<3>(4 * (j + 1)) - dq.segment<3>(4 * j));
          const Vec3 d = next_unprojected - xn;
          s.x[j] = s.x[j + 1] - std::max(target, 0.1 * lb) * d / d.norm();
          next_unprojected = xn;
        }
      }
      transport_frames_to(s.x, w.frameb, w.twistb, s.frame, s.ref_twist);
      // Keep q consistent for the inertia terms while evaluating the trial.
      w.rhs.head(nd) = qb.head(nd) + alpha * dq;  // trial unknowns
      for (int k = 0; k < first_clamped_; ++k) w.rhs.segment<3>(4 * k) = s.x[k];
      w.q.head(nd).swap(w.rhs.head(nd));
      // The full step is usually accepted: evaluate its gradient with the value. Shorter
      // trials are evaluated for the merit only; the gradient follows on acceptance.
      const bool with_gradient = cut == 0;
      const double phi_t =
          assemble(mode, h, load_scale, with_gradient ? Need::Gradient : Need::Value);
      matrix_current = false;
      const auto dqt = w.q.head(nd) - w.rhs.head(nd);
      double work = 0.5 * (w.fext_bk.head(nd) + w.fext.head(nd)).dot(dqt);
      double merit0 = phi, merit_t = phi_t;
      if (pass == 0) {
        // Change of the external potential: exact, but never credited below the
        // trapezoidal estimate −½(f_b + f_t)·Δq of the same forces. The two agree for a
        // potential consistent with its forces; where they do not (a vertex relocated
        // through a wall into another vessel makes the contact energy drop at once), the
        // larger one keeps the search from accepting the jump.
        const double w_cons = 0.5 * (w.fcons_bk.head(nd) + w.fcons.head(nd)).dot(dqt);
        work -= w_cons;
        const double de_exact = w.ext_energy - ext_energy_b;
        merit_t += std::max(de_exact, -w_cons) - de_exact;
      } else {
        merit0 -= ext_energy_b;
        merit_t -= w.ext_energy;
      }
      merit_t -= work;
      bool good = std::isfinite(phi_t) &&
                  merit_t <= merit0 + 1e-4 * alpha * slope + 1e-14 * std::abs(merit0);
      if (good && !with_gradient)
        assemble(mode, h, load_scale, Need::Gradient, false, /*reuse_loads=*/true);
      good = good && finite(w.grad.head(nd));
      if (good) {
        accepted = true;
        phi = phi_t;
        max_step = alpha * dq.segment(first_free, first_fixed - first_free).cwiseAbs().maxCoeff();
        break;
      }
      w.q.head(nd).swap(w.rhs.head(nd));  // restore q
      alpha *= 0.5;
      ++rep.line_search_cuts;
    }
    }
    phase_seconds_.line_search += seconds(t_phase);
    if (!accepted) {
      // Restore the last accepted iterate and its derivatives.
      s.x = w.xb;
      s.theta = w.thetab;
      s.frame = w.frameb;
      s.ref_twist = w.twistb;
      gather(w.q);
      phi = assemble(mode, h, load_scale, Need::Matrix);
      matrix_current = true;
      rep.residual = residual_norm();
      // No decrease left along a descent direction: at the round-off level of the
      // stretching forces (within 100× the floor-based tolerance) that is convergence.
      rep.status = rep.residual <= 100.0 * rep.tolerance ? SolveStatus::Converged
                                                         : SolveStatus::LineSearchFailed;
      break;
    }
    const double previous = rep.residual;
    rep.residual = residual_norm();
    if (alpha == 1.0 && max_step <= settings_.step_tolerance * model_.h) {
      rep.status = SolveStatus::Converged;
      break;
    }
    // The banded factorization is the one kept (the sparse path refactorizes each time).
    chord = settings_.chord_iterations && settings_.linear_solver == LinearSolver::Banded && alpha == 1.0 &&
            rep.residual <= (chord_step ? 0.1 : 1e-3) * previous;
    // Round-off plateau: a full Newton step that no longer reduces a residual already
    // within 100× the tolerance.
    if (alpha == 1.0 && rep.residual <= 100.0 * rep.tolerance && rep.residual > 0.5 * previous) {
      rep.status = SolveStatus::Converged;
      break;
    }
  }
  if (rep.status == SolveStatus::MaxIterations) {
    rep.residual = residual_norm();
    if (rep.residual <= 100.0 * rep.tolerance) rep.status = SolveStatus::Converged;
  }
  return rep;
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
  warn(fmt::format("rod: {} at t = {:.6g} s: {} after {} Newton iterations "
                   "(residual {:.3g} N, tolerance {:.3g} N)",
                   what, state_.time, to_string(r.status), r.newton_iterations, r.residual,
                   r.tolerance));
}

void RodSimulator::record_trace() {
  trace_.push_back({state_.time, state_.inserted_length, state_.x.front()});
}

// -----------------------------------------------------------------------------------------
// Stepping
// -----------------------------------------------------------------------------------------

StepReport RodSimulator::step(double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt)) throw_usage_error("RodSimulator::step: dt must be > 0");
  const StepReport rep = step_subdivided(dt, 0);
  report(rep, settings_.integrator == Integrator::ImplicitMidpoint ? "implicit midpoint step"
                                                                   : "implicit Euler step");
  return rep;
}

StepReport RodSimulator::step_subdivided(double dt, int depth) {
  // A step whose Newton solve fails (no descent left, the iteration limit far from
  // convergence, non-finite values) is taken again from its start as two half steps, down
  // to dt/2^max_subdivisions; only the last level's result is kept as it is.
  const bool can_retry = depth < settings_.max_subdivisions;
  if (can_retry) save_state(depth);
  StepReport rep = step_once(dt);
  if (!rep.converged() && can_retry) {
    restore_state(depth);
    StepReport total;
    for (int half = 0; half < 2; ++half) {
      const StepReport r = step_subdivided(0.5 * dt, depth + 1);
      total.status = r.status;
      total.newton_iterations += r.newton_iterations;
      total.chord_iterations += r.chord_iterations;
      total.line_search_cuts += r.line_search_cuts;
      total.regularizations += r.regularizations;
      total.residual = r.residual;
      total.tolerance = r.tolerance;
      total.subdivisions = std::max(total.subdivisions, r.subdivisions);
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

void RodSimulator::save_state(int depth) {
  Work& w = *work_;
  if (static_cast<int>(w.saved.size()) <= depth) w.saved.resize(static_cast<size_t>(depth) + 1);
  Work::Saved& v = w.saved[static_cast<size_t>(depth)];
  v.state = state_;
  v.target_angle = target_angle_;
  v.insertion_speed = insertion_speed_;
  v.first_clamped = first_clamped_;
  v.base_force = base_force_;
  v.base_torque = base_torque_;
  v.trace_size = trace_.size();
}

void RodSimulator::restore_state(int depth) {
  const Work::Saved& v = work_->saved[static_cast<size_t>(depth)];
  state_ = v.state;
  target_angle_ = v.target_angle;
  insertion_speed_ = v.insertion_speed;
  first_clamped_ = v.first_clamped;
  base_force_ = v.base_force;
  base_torque_ = v.base_torque;
  trace_.resize(v.trace_size);
  model_.discretize(state_.u, disc_);
  refresh_arc_lengths();
}

StepReport RodSimulator::step_once(double dt) {
  if (push_force_ > 0.0) return step_force_fed(dt);
  double speed = insertion_speed_;
  if (speed > 0.0 && max_insertion_force_ > 0.0 &&
      base_force_.dot(model_.base_direction) > max_insertion_force_) {
    speed = 0.0;
    ++held_steps_;
  }
  return step_at_feed(dt, speed);
}

StepReport RodSimulator::step_at_feed(double dt, double speed) {
  feed_speed_ = speed;
  adapt_for(std::max(0.0, -feed_speed_ * dt));
  return settings_.integrator == Integrator::ImplicitMidpoint ? step_midpoint(dt)
                                                              : step_euler(dt);
}

StepReport RodSimulator::step_force_fed(double dt) {
  // The feed length of the step is the unknown: the step is taken again from its start until
  // the clamp's axial force at its end, g(v) = base_force()·d, equals the applied force F.
  // g grows with v (the step's inertia m/dt, damping, drag and friction, and the axial
  // stiffness times dt against an obstacle); a secant iteration, started from the last
  // step's speed and slope, solves it. The feed of one step is kept within half a segment.
  const Vec3& d = model_.base_direction;
  const int slot = std::max(settings_.max_subdivisions, 0) + 2;
  const double tol = force_feed_tolerance_ * push_force_;
  const double vmax = 0.5 * model_.h / dt;
  if (!(force_feed_slope_ > 0.0)) {
    double m = 0.0;
    for (double mk : disc_.mass) m += mk;
    force_feed_slope_ = std::max(m / dt + model_.damping * state_.inserted_length, 1e-12);
  }
  save_state(slot);
  double v = std::clamp(force_feed_speed_, -vmax, vmax);
  StepReport rep = step_at_feed(dt, v);
  if (!rep.converged()) return rep;
  double g = base_force_.dot(d) - push_force_;
  int it = 0;
  for (; std::abs(g) > tol && it < kMaxForceFeedIterations; ++it) {
    const double v_new = std::clamp(v - g / force_feed_slope_, -vmax, vmax);
    if (v_new == v) break;  // at the per-step limit
    restore_state(slot);
    rep = step_at_feed(dt, v_new);
    if (!rep.converged()) return rep;
    const double g_new = base_force_.dot(d) - push_force_;
    const double slope = (g_new - g) / (v_new - v);
    if (slope > 0.0 && std::isfinite(slope)) force_feed_slope_ = slope;
    v = v_new;
    g = g_new;
  }
  force_feed_iterations_ += it;
  if (std::abs(g) > tol) ++force_feed_unbalanced_;
  force_feed_speed_ = v;
  return rep;
}

namespace {
double clamp_inserted(double L, const RodModel& m, bool& clamped) {
  const double lo = 2.0 * m.h, hi = m.length;
  clamped = L < lo || L > hi;
  return std::clamp(L, lo, hi);
}
}  // namespace

void RodSimulator::begin_step(double h, bool extrapolate) {
  auto& w = *work_;
  auto& s = state_;
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
    w.mass.segment<3>(4 * k).setConstant(disc_.mass[k]);
    w.damp.segment<3>(4 * k).setConstant(model_.damping * disc_.cell_length[k]);
    if (k < nv - 1) {
      w.q0(4 * k + 3) = s.theta[k];
      w.qhat(4 * k + 3) = s.theta[k] + h * s.omega[k];
      w.mass(4 * k + 3) = disc_.twist_inertia[k];
      w.damp(4 * k + 3) = 0.0;
    }
  }
  for (int k = 0; k < nv; ++k) {
    s.x[k] += h * w.v_guess[k];
    if (k < nv - 1) s.theta[k] += h * w.omega_guess[k];
  }
}

StepReport RodSimulator::step_euler(double dt) {
  Work& w = *work_;
  RodState& s = state_;
  bool clamped = false;
  const double L_new = clamp_inserted(s.inserted_length + feed_speed_ * dt, model_, clamped);
  if (clamped && feed_speed_ != 0.0) {
    warn(fmt::format("rod: inserted length held at {:.6g} m (wire end reached)", L_new));
    insertion_speed_ = 0.0;
    feed_speed_ = 0.0;
  }
  s.base_angle = target_angle_;
  update_vertex_set(L_new);
  const double angle_new = target_angle_ + rotation_speed_ * dt;

  // Initial guess: inertial prediction; prescribed unknowns at their end-of-step values.
  begin_step(dt, settings_.second_order_guess);
  const int nv = s.vertex_count();
  predict_feed(L_new - s.inserted_length, dt);
  set_prescribed(L_new, angle_new, s.x, s.theta);
  transport_frames_to(s.x, w.frame0, w.twist0, s.frame, s.ref_twist);
  s.time += dt;
  s.inserted_length = L_new;
  refresh_arc_lengths();

  StepReport rep = newton(Mode::Dynamic, dt, 1.0);
  if (rep.status == SolveStatus::NonFinite || rep.status == SolveStatus::SingularMatrix) {
    s.x = w.x0;
    s.v = w.v0;
    s.theta = w.theta0;
    s.omega = w.omega0;
    s.frame = w.frame0;
    s.ref_twist = w.twist0;
    set_prescribed(L_new, angle_new, s.x, s.theta);
    transport_frames_to(s.x, w.frame0, w.twist0, s.frame, s.ref_twist);
  }
  for (int k = 0; k < nv; ++k) {
    s.v[k] = (s.x[k] - w.x0[k]) / dt;
    if (k < nv - 1) s.omega[k] = (s.theta[k] - w.theta0[k]) / dt;
  }
  target_angle_ = angle_new;
  s.base_angle = angle_new;
  // Where this step left the vertices, for the next step's predictor.
  w.x_end = s.x;
  w.h_end = dt;
  compute_base_reaction();
  return rep;
}

StepReport RodSimulator::step_midpoint(double dt) {
  Work& w = *work_;
  RodState& s = state_;
  bool clamped = false;
  const double L_start = s.inserted_length;
  const double L_new = clamp_inserted(L_start + feed_speed_ * dt, model_, clamped);
  if (clamped && feed_speed_ != 0.0) {
    warn(fmt::format("rod: inserted length held at {:.6g} m (wire end reached)", L_new));
    insertion_speed_ = 0.0;
    feed_speed_ = 0.0;
  }
  s.base_angle = target_angle_;
  update_vertex_set(L_new);
  const double hh = 0.5 * dt;
  const double L_half = 0.5 * (L_start + L_new);
  const double angle_half = target_angle_ + rotation_speed_ * hh;
  const double angle_new = target_angle_ + rotation_speed_ * dt;

  begin_step(hh, /*extrapolate=*/false);
  const int nv = s.vertex_count();
  predict_feed(L_half - L_start, hh);
  set_prescribed(L_half, angle_half, s.x, s.theta);
  transport_frames_to(s.x, w.frame0, w.twist0, s.frame, s.ref_twist);
  s.time += hh;
  s.inserted_length = L_half;
  refresh_arc_lengths();

  StepReport rep = newton(Mode::Dynamic, hh, 1.0);
  const bool failed =
      rep.status == SolveStatus::NonFinite || rep.status == SolveStatus::SingularMatrix;
  compute_base_reaction();
  if (failed) {
    s.x = w.x0;
    s.theta = w.theta0;
    s.frame = w.frame0;
    s.ref_twist = w.twist0;
    for (auto& v : s.v) v.setZero();
    for (auto& o : s.omega) o = 0.0;
    set_prescribed(L_new, angle_new, s.x, s.theta);
    transport_frames_to(s.x, w.frame0, w.twist0, s.frame, s.ref_twist);
  } else {
    // Extrapolate from the midpoint z: q₁ = 2z − q₀, v₁ = 2 (z − q₀)/(h/2) − v₀.
    w.xz = s.x;
    w.frameb = s.frame;
    w.twistb = s.ref_twist;
    for (int k = 0; k < nv; ++k) {
      s.v[k] = 2.0 * (w.xz[k] - w.x0[k]) / hh - w.v0[k];
      s.x[k] = 2.0 * w.xz[k] - w.x0[k];
      if (k < nv - 1) {
        const double tz = s.theta[k];
        s.omega[k] = 2.0 * (tz - w.theta0[k]) / hh - w.omega0[k];
        s.theta[k] = 2.0 * tz - w.theta0[k];
      }
    }
    set_prescribed(L_new, angle_new, s.x, s.theta);
    transport_frames_to(s.x, w.frameb, w.twistb, s.frame, s.ref_twist);
  }
  s.time += hh;
  s.inserted_length = L_new;
  refresh_arc_lengths();
  target_angle_ = angle_new;
  s.base_angle = angle_new;
  return rep;
}

StepReport RodSimulator::solve_static() {
  StepReport r = solve_static_once();
  // Adaptive: resample at the equilibrium and solve again until the vertex set settles.
  for (int round = 0; round < 12 && r.converged() && adapt(); ++round) {
    trace_.pop_back();
    const StepReport again = solve_static_once();
    r.status = again.status;
    r.newton_iterations += again.newton_iterations;
    r.chord_iterations += again.chord_iterations;
    r.line_search_cuts += again.line_search_cuts;
    r.regularizations += again.regularizations;
    r.residual = again.residual;
    r.tolerance = again.tolerance;
  }
  return r;
}

StepReport RodSimulator::solve_static_once() {
  RodState& s = state_;
  s.base_angle = target_angle_;
  set_prescribed(s.inserted_length, target_angle_, s.x, s.theta);
  transport_frames_to(s.x, s.frame, s.ref_twist, s.frame, s.ref_twist);
  for (auto& v : s.v) v.setZero();
  for (auto& o : s.omega) o = 0.0;
  refresh_arc_lengths();
  const int steps = std::max(1, settings_.static_load_steps);
  StepReport total;
  for (int i = 1; i <= steps; ++i) {
    const StepReport r = newton(Mode::Static, 1.0, static_cast<double>(i) / steps);
    total.newton_iterations += r.newton_iterations;
    total.chord_iterations += r.chord_iterations;
    total.line_search_cuts += r.line_search_cuts;
    total.regularizations += r.regularizations;
    total.residual = r.residual;
    total.tolerance = r.tolerance;
    total.status = r.status;
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

int RodSimulator::static_hessian_negative_eigenvalues() {
  Work& w = *work_;
  const int nd = dof_count();
  gather(w.q);
  assemble(Mode::Static, 1.0, 1.0, Need::Matrix);
  for (int d = 4 * first_clamped_; d < nd; ++d) w.H.set_identity_row(d);
  if (tip_clamped_)
    for (int d = 0; d < 7; ++d) w.H.set_identity_row(d);
  if (!w.ldlt.factorize(w.H)) return -1;
  return w.ldlt.negative_pivots();
}

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
