#include "flowire/rod/simulator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "simulator_internal.hpp"

namespace flowire::rod {

using detail::finite;

// -----------------------------------------------------------------------------------------
// Newton
// -----------------------------------------------------------------------------------------

namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
}  // namespace

double RodSimulator::residual_norm(int first_free, int first_fixed) const {
  // Max over the free unknowns of |force| and |torque| / rest length (a force too).
  const Work& w = *work_;
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
}

StepReport RodSimulator::newton(Mode mode, double h, double load_scale, int max_iterations) {
  Work& w = *work_;
  const int nd = dof_count();
  const int first_fixed = 4 * first_clamped_;
  const int first_free = tip_clamped_ ? 7 : 0;  // x0, θ0, x1 held by a tip clamp
  StepReport rep;
  rep.tolerance = force_scale(load_scale);
  const int max_it = max_iterations >= 0    ? max_iterations
                     : mode == Mode::Static ? settings_.max_static_iterations
                                            : settings_.max_iterations;

  auto t_phase = Clock::now();
  gather(w.q);
  double phi = assemble(mode, h, load_scale, Need::Matrix);
  bool matrix_current = true;  // trial points are evaluated without the matrix
  phase_seconds_.assembly += seconds_since(t_phase);
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
    rep.residual = residual_norm(first_free, first_fixed);
    if (rep.residual <= rep.tolerance) {
      rep.status = SolveStatus::Converged;
      break;
    }
    rep.newton_iterations = it + 1;
    const bool chord_step = chord;
    if (!chord_step && !matrix_current) {
      // Same configuration as the accepted trial: its loads and external forces are kept.
      t_phase = Clock::now();
      phi = assemble(mode, h, load_scale, Need::Matrix, false, /*reuse_loads=*/true);
      matrix_current = true;
      phase_seconds_.assembly += seconds_since(t_phase);
    }
    t_phase = Clock::now();
    const bool ok = solve_direction(mode, h, load_scale, chord_step, first_free, first_fixed, rep);
    phase_seconds_.factorize += seconds_since(t_phase);  // (with the rare positive semi-definite reassembly)
    if (!ok || !finite(w.dq.head(nd))) {
      rep.status = SolveStatus::SingularMatrix;
      break;
    }
    t_phase = Clock::now();
    double max_step = 0.0;
    const double alpha = line_search(mode, h, load_scale, first_free, first_fixed, phi, max_step, rep);
    matrix_current = false;
    phase_seconds_.line_search += seconds_since(t_phase);
    if (alpha == 0.0) {
      // Restore the last accepted iterate and its derivatives.
      back_to_kept_iterate();
      gather(w.q);
      phi = assemble(mode, h, load_scale, Need::Matrix);
      matrix_current = true;
      rep.residual = residual_norm(first_free, first_fixed);
      // No decrease left along a descent direction: at the round-off level of the
      // stretching forces (within 100× the floor-based tolerance) that is convergence.
      rep.status = rep.residual <= 100.0 * rep.tolerance ? SolveStatus::Converged : SolveStatus::LineSearchFailed;
      break;
    }
    const double previous = rep.residual;
    rep.residual = residual_norm(first_free, first_fixed);
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
    rep.residual = residual_norm(first_free, first_fixed);
    if (rep.residual <= 100.0 * rep.tolerance) rep.status = SolveStatus::Converged;
  }
  return rep;
}

bool RodSimulator::solve_direction(Mode mode, double h, double load_scale, bool chord_step, int first_free,
                                   int first_fixed, StepReport& rep) {
  Work& w = *work_;
  const int nd = dof_count();
  // Right-hand side: −gradient on the free unknowns, 0 on the held ones.
  auto rhs = w.rhs.head(nd);
  rhs = -w.grad.head(nd);
  rhs.tail(nd - first_fixed).setZero();
  rhs.head(first_free).setZero();
  if (chord_step) {
    w.dq.head(nd) = rhs;
    w.ldlt.solve_in_place(w.dq.head(nd));
    ++rep.chord_iterations;
    return true;
  }
  // The exact Hessian first; if it is indefinite (strongly bent or compressed states), the
  // Gauss–Newton matrix of the same residual, which is positive semi-definite, with a
  // modified factorization as last resort.
  bool ok = false;
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
        ok = w.sparse_ldlt.info() == Eigen::Success && (w.sparse_ldlt.vectorD().array() > 0.0).all();
      }
      if (ok) w.dq.head(nd) = w.sparse_ldlt.solve(rhs);
    }
  }
  return ok;
}

void RodSimulator::keep_iterate() {
  Work& w = *work_;
  w.x_accepted = state_.x;
  w.theta_accepted = state_.theta;
  w.frame_accepted = state_.frame;
  w.twist_accepted = state_.ref_twist;
}

void RodSimulator::back_to_kept_iterate() {
  const Work& w = *work_;
  state_.x = w.x_accepted;
  state_.theta = w.theta_accepted;
  state_.frame = w.frame_accepted;
  state_.ref_twist = w.twist_accepted;
}

void RodSimulator::move_along(const Eigen::Ref<const Eigen::VectorXd>& dq, double alpha) {
  Work& w = *work_;
  RodState& s = state_;
  const int nv = s.vertex_count();
  for (int k = 0; k < nv; ++k) {
    s.x[k] = w.x_accepted[k] + alpha * dq.segment<3>(4 * k);
    if (k < nv - 1) s.theta[k] = w.theta_accepted[k] + alpha * dq(4 * k + 3);
  }
  if (settings_.curvilinear_update && !tip_clamped_) {
    // Walk from the clamp to the tip keeping each free edge's updated direction but
    // its linearized length: removes the O(α²) spurious stretch of a straight-line
    // step through a rotation, so stiff stretching does not throttle the step.
    Vec3 next_unprojected = s.x[first_clamped_];
    for (int j = first_clamped_ - 1; j >= 0; --j) {
      const Vec3 xn = s.x[j];
      const Vec3 eb = w.x_accepted[j + 1] - w.x_accepted[j];
      const double lb = eb.norm();
      const double target = lb + alpha * (eb / lb).dot(dq.segment<3>(4 * (j + 1)) - dq.segment<3>(4 * j));
      const Vec3 d = next_unprojected - xn;
      s.x[j] = s.x[j + 1] - std::max(target, 0.1 * lb) * d / d.norm();
      next_unprojected = xn;
    }
  }
  transport_frames_to(s.x, w.frame_accepted, w.twist_accepted, s.frame, s.ref_twist);
}

double RodSimulator::line_search(Mode mode, double h, double load_scale, int first_free, int first_fixed, double& phi,
                                 double& max_step, StepReport& rep) {
  Work& w = *work_;
  RodState& s = state_;
  const int nd = dof_count();
  auto dq = w.dq.head(nd);
  const double slope = w.grad.head(nd).dot(dq);
  const double residual_before = residual_norm(first_free, first_fixed);
  // Backtracking line search on φ + E_ext − W: φ the incremental potential, E_ext the
  // potential of conservative external forces (penalty contact), W the trapezoidal work
  // of the remaining loads (dead loads, friction, drag) along the ray.
  keep_iterate();
  w.fext_accepted.head(nd) = w.fext.head(nd);
  w.fcons_accepted.head(nd) = w.fcons.head(nd);
  const double ext_energy_b = w.ext_energy;
  const Eigen::VectorXd& qb = w.q;  // unchanged until accepted
  // Trust region on the motion: no vertex moves more than half its shortest edge and no edge
  // turns about its tangent more than 0.5 rad in one iteration. The discrete rod's energy is
  // far from quadratic beyond that (edges rotate by O(step/ℓ)), so a longer Newton step,
  // which a nearly singular matrix gives (a snapping pre-shaped tip, a wire free between
  // walls), is only cut back by the line search after costly trials.
  const double alpha_max = coupled_max_step(dq);  // (first_free, first_fixed: the rod's own)
  double alpha = alpha_max;
  bool accepted = false;
  // Pass 0 measures conservative external forces by their potential. A potential that
  // is not consistent with its forces (e.g. a contact whose wall changes where a vertex
  // is relocated into another vessel) can leave no decrease along the ray; pass 1 then
  // treats every external force as a load (trapezoidal work), as without potentials.
  const int passes = externals_.empty() ? 1 : 2;
  for (int pass = 0; pass < passes && !accepted; ++pass) {
    alpha = alpha_max;
    for (int cut = 0; cut <= settings_.max_line_search_cuts; ++cut) {
      move_along(dq, alpha);
      // Keep q consistent for the inertia terms while evaluating the trial.
      w.rhs.head(nd) = qb.head(nd) + alpha * dq;  // trial unknowns
      for (int k = 0; k < first_clamped_; ++k) w.rhs.segment<3>(4 * k) = s.x[k];
      w.q.head(nd).swap(w.rhs.head(nd));
      // The full step is usually accepted: evaluate its gradient with the value. Shorter
      // trials are evaluated for the merit only; the gradient follows on acceptance.
      const bool with_gradient = cut == 0;
      const double phi_t = assemble(mode, h, load_scale, with_gradient ? Need::Gradient : Need::Value);
      const auto dqt = w.q.head(nd) - w.rhs.head(nd);
      double work = 0.5 * (w.fext_accepted.head(nd) + w.fext.head(nd)).dot(dqt);
      double merit0 = phi, merit_t = phi_t;
      if (pass == 0) {
        // Change of the external potential: exact, but never credited below the
        // trapezoidal estimate −½(f_b + f_t)·Δq of the same forces. The two agree for a
        // potential consistent with its forces; where they do not (a vertex relocated
        // through a wall into another vessel makes the contact energy drop at once), the
        // larger one keeps the search from accepting the jump.
        const double w_cons = 0.5 * (w.fcons_accepted.head(nd) + w.fcons.head(nd)).dot(dqt);
        work -= w_cons;
        const double de_exact = w.ext_energy - ext_energy_b;
        merit_t += std::max(de_exact, -w_cons) - de_exact;
      } else {
        merit0 -= ext_energy_b;
        merit_t -= w.ext_energy;
      }
      merit_t -= work;
      bool good = std::isfinite(phi_t) && merit_t <= merit0 + 1e-4 * alpha * slope + 1e-14 * std::abs(merit0);
      if (!good && with_gradient && std::isfinite(phi_t) && -slope <= 1e-10 * std::abs(merit0)) {
        // Near convergence the decrease a full step promises (−slope) is below what the merit
        // can resolve (its round-off, ~1e-16·|merit| per term summed over the wire), so the
        // energy test can no longer tell a good step from a bad one: there the full step is
        // judged by the residual it leaves (the gradient norm, a merit of its own that
        // round-off does not hide), and accepted if that at least halves.
        good = finite(w.grad.head(nd)) && residual_norm(first_free, first_fixed) <= 0.5 * residual_before;
      }
      if (good && !with_gradient) assemble(mode, h, load_scale, Need::Gradient, false, /*reuse_loads=*/true);
      good = good && finite(w.grad.head(nd));
      if (good) {
        accepted = true;
        phi = phi_t;
        max_step = alpha * dq.segment(first_free, first_fixed - first_free).cwiseAbs().maxCoeff();
        break;
      }
      w.q.head(nd).swap(w.rhs.head(nd));  // restore q
      // Next trial at the minimizer of the quadratic through the merit at 0 (value and
      // slope) and at α, kept within [α/10, α/2]: where the ray's useful length is a small
      // fraction of the Newton step (a soft mode's overshoot), it is found in a few trials
      // instead of a halving each. (Dynamic steps: the static continuation of a pressed
      // wire and catheter converges only by halving.)
      const double curvature = merit_t - merit0 - slope * alpha;
      double next = 0.5 * alpha;
      if (mode == Mode::Dynamic && std::isfinite(merit_t) && curvature > 0.0)
        next = std::clamp(-slope * alpha * alpha / (2.0 * curvature), 0.25 * alpha, 0.5 * alpha);
      alpha = next;
      ++rep.line_search_cuts;
    }
  }
  return accepted ? alpha : 0.0;
}

}  // namespace flowire::rod
