#include "flowire/rod/stepper.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "flowire/common/error.hpp"
#include "flowire/common/kernel_clones.hpp"
#include "rod_internal.hpp"

namespace flowire::rod {

using detail::positive_part;
using detail::positive_part6;
using detail::sym;

// -----------------------------------------------------------------------------------------
// Assembly
// -----------------------------------------------------------------------------------------

void TimeStepper::gather(Eigen::Ref<Eigen::VectorXd> q) const {
  const int nv = body_.state.vertex_count();
  for (int k = 0; k < nv; ++k) {
    q.segment<3>(4 * k) = body_.state.x[k];
    if (k < nv - 1) q(4 * k + 3) = body_.state.theta[k];
  }
}

LoadSite TimeStepper::load_site() const {
  const auto nv = static_cast<size_t>(body_.state.vertex_count());
  return {body_.state.x, std::span<const double>(body_.state.u.data(), nv),
          std::span<const double>(body_.disc.mass.data(), nv), body_.state.inserted_length};
}

void TimeStepper::evaluate_loads(Mode mode, double h, double load_scale) {
  Work& w = *work_;
  const RodState& s = body_.state;
  const int nv = s.vertex_count();
  const int nd = dof_count();
  w.fext.head(nd).setZero();
  w.fcons.head(nd).setZero();
  w.ext_energy = 0.0;
  w.has_ext_k = false;
  w.has_ext_edge_k = false;
  w.coupled.clear();
  w.moment_k.setZero();
  LoadTerms terms{w.fext.head(nd), w.moment_k};
  loads_.add(load_site(), load_scale, terms);
  if (!externals_.empty()) {
    w.vel.resize(nv);
    w.spin.resize(nv - 1);
    w.tangent.resize(nv - 1);
    for (int k = 0; k < nv; ++k) w.vel[k] = mode == Mode::Dynamic ? Vec3((s.x[k] - w.x0[k]) / h) : Vec3::Zero();
    for (int j = 0; j < nv - 1; ++j) {
      w.spin[j] = mode == Mode::Dynamic ? (s.theta[j] - w.theta0[j]) / h : 0.0;
      w.tangent[j] = (s.x[j + 1] - s.x[j]).normalized();
    }
    w.acc.reset(nv);
    RodView view;
    view.positions = s.x;
    view.velocities = w.vel;
    view.arc_length = std::span<const double>(feeder_.arc_lengths().data(), nv);
    view.radius = std::span<const double>(body_.disc.edge_radius.data(), nv - 1);
    view.rest_lengths = std::span<const double>(body_.disc.rest_length.data(), nv - 1);
    view.segment_length = body_.model.h;
    view.spin_rates = w.spin;
    view.tangents = w.tangent;
    view.first_clamped_vertex = feeder_.first_clamped();
    view.time = s.time;
    view.dt = mode == Mode::Dynamic ? h : 0.0;
    view.solve_serial = solve_serial_;
    for (auto& ext : externals_) ext->evaluate(view, w.acc);
    w.ext_k.resize(nv);
    w.ext_spin_k.resize(nv - 1);
    w.has_ext_k = true;
    for (int j = 0; j < nv - 1; ++j) {
      w.fext(4 * j + 3) += w.acc.twist_torques()[j];
      w.ext_spin_k[j] = mode == Mode::Dynamic ? -w.acc.twist_torque_spin_derivatives()[j] / h : 0.0;
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
    if (!w.acc.coupled_vertices().empty()) {
      for (int v : w.acc.coupled_vertices()) w.coupled.dofs.push_back(4 * v);
      w.coupled.directions = w.acc.coupled_directions();
      w.coupled.core = w.acc.coupled_core();
    }
    for (int k = 0; k < nv; ++k) {
      w.fcons.segment<3>(4 * k) = w.acc.conservative_forces()[k];
      w.fext.segment<3>(4 * k) += w.acc.forces()[k];
      w.ext_k[k] = -sym(w.acc.position_jacobians()[k]);
      if (mode == Mode::Dynamic) w.ext_k[k] -= sym(w.acc.velocity_jacobians()[k]) / h;
    }
  }
}

double TimeStepper::assemble(Mode mode, double h, double load_scale, Need need, bool psd, bool reuse_loads) {
  Work& w = *work_;
  const RodState& s = body_.state;
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
    const double lbar = body_.disc.rest_length[j];
    const double ks = body_.disc.stretch_stiffness[j];
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
  for (int j = 0; j < nv - 1; ++j) w.edges[j] = edge_geometry(s.x[j], s.x[j + 1], s.frame[j], s.theta[j]);
  VertexParams p;
  Vec11 gs;
  Mat11 hs;
  for (int k = 1; k < nv - 1; ++k) {
    feeder_.vertex_params(k, p);
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

double TimeStepper::force_scale(double load_scale) const {
  const RodState& s = body_.state;
  double ei = 0.0, ea = 0.0;
  for (int k = 0; k < s.vertex_count(); ++k) ei = std::max(ei, body_.disc.bend_stiffness[k]);
  double lmin = body_.model.h;
  for (int j = 0; j < s.edge_count(); ++j) {
    ea = std::max(ea, body_.disc.stretch_stiffness[j]);
    lmin = std::min(lmin, body_.disc.rest_length[j]);
  }
  const double L = std::max(s.inserted_length, body_.model.h);
  const double f = loads_.force_scale(load_site(), load_scale, L, ei / (L * L));
  const double xscale = body_.model.base_position.norm() + L;
  const double floor = 4.0 * std::numeric_limits<double>::epsilon() * ea * (1.0 + xscale / lmin);
  return settings_.force_tolerance * f + floor;
}

}  // namespace flowire::rod
