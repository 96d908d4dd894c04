#include "flowire/rod/newton.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace flowire::rod {

namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
bool finite(const Eigen::Ref<const Eigen::VectorXd>& v) { return v.allFinite(); }
}  // namespace

const char* to_string(SolveStatus s) {
  switch (s) {
    case SolveStatus::Converged:
      return "converged";
    case SolveStatus::MaxIterations:
      return "maximum Newton iterations reached";
    case SolveStatus::LineSearchFailed:
      return "line search failed";
    case SolveStatus::NonFinite:
      return "non-finite values";
    case SolveStatus::SingularMatrix:
      return "singular matrix";
  }
  return "unknown";
}

void NewtonSolver::reserve(int max_dofs, int bandwidth) {
  rhs_.setZero(max_dofs);
  dq_.setZero(max_dofs);
  ldlt_.reserve(max_dofs, bandwidth);
}

StepReport NewtonSolver::solve(NewtonProblem& p, const NewtonOptions& o) {
  const int nd = p.dofs();
  StepReport rep;
  rep.tolerance = p.tolerance();

  auto t_phase = Clock::now();
  double phi = p.assemble_current(Need::Matrix);
  bool matrix_current = true;  // trial points are evaluated without the matrix
  phase_seconds_.assembly += seconds_since(t_phase);
  if (!std::isfinite(phi) || !finite(p.gradient().head(nd))) {
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
  for (int it = 0; it < o.max_iterations; ++it) {
    rep.residual = p.residual();
    if (rep.residual <= rep.tolerance) {
      rep.status = SolveStatus::Converged;
      break;
    }
    rep.newton_iterations = it + 1;
    const bool chord_step = chord;
    if (!chord_step && !matrix_current) {
      // Same configuration as the accepted trial: its loads and external forces are kept.
      t_phase = Clock::now();
      phi = p.assemble(Need::Matrix, false, /*reuse_loads=*/true);
      matrix_current = true;
      phase_seconds_.assembly += seconds_since(t_phase);
    }
    t_phase = Clock::now();
    const bool ok = direction(p, o, chord_step, rep);
    phase_seconds_.factorize += seconds_since(t_phase);  // (with the rare positive semi-definite reassembly)
    if (!ok || !finite(dq_.head(nd))) {
      rep.status = SolveStatus::SingularMatrix;
      break;
    }
    t_phase = Clock::now();
    double max_step = 0.0;
    const double alpha = line_search(p, o, phi, max_step, rep);
    matrix_current = false;
    phase_seconds_.line_search += seconds_since(t_phase);
    if (alpha == 0.0) {
      // Restore the last accepted iterate and its derivatives.
      p.back_to_base();
      phi = p.assemble_current(Need::Matrix);
      matrix_current = true;
      rep.residual = p.residual();
      // No decrease left along a descent direction: at the round-off level of the
      // stretching forces (within 100× the floor-based tolerance) that is convergence.
      rep.status = rep.residual <= 100.0 * rep.tolerance ? SolveStatus::Converged : SolveStatus::LineSearchFailed;
      break;
    }
    const double previous = rep.residual;
    rep.residual = p.residual();
    if (alpha == 1.0 && max_step <= o.step_tolerance) {
      rep.status = SolveStatus::Converged;
      break;
    }
    // The banded factorization is the one kept (the sparse path refactorizes each time).
    chord = o.chord_iterations && o.linear_solver == LinearSolver::Banded && alpha == 1.0 &&
            rep.residual <= (chord_step ? 0.1 : 1e-3) * previous;
    // Round-off plateau: a full Newton step that no longer reduces a residual already
    // within 100× the tolerance.
    if (alpha == 1.0 && rep.residual <= 100.0 * rep.tolerance && rep.residual > 0.5 * previous) {
      rep.status = SolveStatus::Converged;
      break;
    }
  }
  if (rep.status == SolveStatus::MaxIterations) {
    rep.residual = p.residual();
    if (rep.residual <= 100.0 * rep.tolerance) rep.status = SolveStatus::Converged;
  }
  return rep;
}

bool NewtonSolver::direction(NewtonProblem& p, const NewtonOptions& o, bool chord_step, StepReport& rep) {
  const int nd = p.dofs(), first_free = p.first_free(), first_fixed = p.first_fixed();
  // Right-hand side: −gradient on the free unknowns, 0 on the held ones.
  auto rhs = rhs_.head(nd);
  rhs = -p.gradient().head(nd);
  rhs.tail(nd - first_fixed).setZero();
  rhs.head(first_free).setZero();
  if (chord_step) {
    dq_.head(nd) = rhs;
    ldlt_.solve_in_place(dq_.head(nd));
    low_rank_.correct(dq_.head(nd));
    ++rep.chord_iterations;
    return true;
  }
  static const LowRankStiffness kNone;
  const LowRankStiffness& low_rank = p.low_rank() ? *p.low_rank() : kNone;
  // The exact Hessian first; if it is indefinite (strongly bent or compressed states), the
  // Gauss–Newton matrix of the same residual, which is positive semi-definite, with a
  // modified factorization as last resort.
  bool ok = false;
  for (int attempt = 0; attempt < 2 && !ok; ++attempt) {
    if (attempt == 1) {
      p.assemble(Need::Matrix, /*psd=*/true, /*reuse_loads=*/true);
      ++rep.regularizations;
    }
    BandedMatrix& H = p.matrix();
    for (int d = first_fixed; d < nd; ++d) H.set_identity_row(d);
    for (int d = 0; d < first_free; ++d) H.set_identity_row(d);
    // (The scale of the diagonal is needed by the fallbacks only.)
    auto scale = [&] { return std::max(H.max_diagonal(), 1e-300); };
    if (o.linear_solver == LinearSolver::Banded) {
      ok = attempt == 0 ? (ldlt_.factorize(H) && ldlt_.negative_pivots() == 0) : ldlt_.factorize(H, 1e-12 * scale());
      if (ok)
        ok = low_rank_.prepare(low_rank, nd, first_free, first_fixed,
                               [&](auto col, int first) { ldlt_.solve_in_place(col, first); });
      if (ok) {
        dq_.head(nd) = rhs;
        ldlt_.solve_in_place(dq_.head(nd));
        low_rank_.correct(dq_.head(nd));
      }
    } else {
      double shift = 0.0;
      for (int tries = 0; tries < (attempt == 0 ? 1 : 12) && !ok; ++tries) {
        if (tries > 0) {
          const double next = tries == 1 ? 1e-12 * scale() : 10.0 * shift;
          H.add_to_diagonal(next - shift);
          shift = next;
        }
        H.to_sparse_lower(sparse_);
        if (sparse_pattern_size_ != nd) {
          sparse_ldlt_.analyzePattern(sparse_);
          sparse_pattern_size_ = nd;
        }
        sparse_ldlt_.factorize(sparse_);
        ok = sparse_ldlt_.info() == Eigen::Success && (sparse_ldlt_.vectorD().array() > 0.0).all();
      }
      if (ok)
        ok = low_rank_.prepare(low_rank, nd, first_free, first_fixed, [&](auto col, int) {
          const Eigen::VectorXd x = sparse_ldlt_.solve(col);
          col = x;
        });
      if (ok) {
        dq_.head(nd) = sparse_ldlt_.solve(rhs);
        low_rank_.correct(dq_.head(nd));
      }
    }
  }
  return ok;
}

double NewtonSolver::line_search(NewtonProblem& p, const NewtonOptions& o, double& phi, double& max_step,
                                 StepReport& rep) {
  const int nd = p.dofs(), first_free = p.first_free(), first_fixed = p.first_fixed();
  auto dq = dq_.head(nd);
  const double slope = p.gradient().head(nd).dot(dq);
  const double residual_before = p.residual();
  p.keep();
  // The trust region on the motion (the problem's): a longer Newton step, which a nearly
  // singular matrix gives, is only cut back by the line search after costly trials.
  const double alpha_max = p.max_step(dq);
  double alpha = alpha_max;
  bool accepted = false;
  // A problem with a second merit tries it where the first finds no decrease along the ray.
  for (int pass = 0; pass < p.merit_passes() && !accepted; ++pass) {
    alpha = alpha_max;
    for (int cut = 0; cut <= o.max_line_search_cuts; ++cut) {
      p.trial(dq, alpha);
      // The full step is usually accepted: evaluate its gradient with the value. Shorter
      // trials are evaluated for the merit only; the gradient follows on acceptance.
      const bool with_gradient = cut == 0;
      const double phi_t = p.assemble(with_gradient ? Need::Gradient : Need::Value);
      double merit0 = 0.0, merit_t = 0.0;
      p.merits(pass, phi, phi_t, &merit0, &merit_t);
      bool good = std::isfinite(phi_t) && merit_t <= merit0 + 1e-4 * alpha * slope + 1e-14 * std::abs(merit0);
      if (!good && with_gradient && std::isfinite(phi_t) && -slope <= 1e-10 * std::abs(merit0)) {
        // Near convergence the decrease a full step promises (−slope) is below what the merit
        // can resolve (its round-off, ~1e-16·|merit| per term summed over the wire), so the
        // energy test can no longer tell a good step from a bad one: there the full step is
        // judged by the residual it leaves (the gradient norm, a merit of its own that
        // round-off does not hide), and accepted if that at least halves.
        good = finite(p.gradient().head(nd)) && p.residual() <= 0.5 * residual_before;
      }
      if (good && !with_gradient) p.assemble(Need::Gradient, false, /*reuse_loads=*/true);
      good = good && finite(p.gradient().head(nd));
      if (good) {
        accepted = true;
        phi = phi_t;
        max_step = alpha * dq.segment(first_free, first_fixed - first_free).cwiseAbs().maxCoeff();
        break;
      }
      p.reject_trial();
      // Next trial at the minimizer of the quadratic through the merit at 0 (value and
      // slope) and at α, kept within [α/4, α/2]: where the ray's useful length is a small
      // fraction of the Newton step (a soft mode's overshoot), it is found in a few trials
      // instead of a halving each. (Dynamic steps: the static continuation of a pressed
      // wire and catheter converges only by halving.)
      const double curvature = merit_t - merit0 - slope * alpha;
      double next = 0.5 * alpha;
      if (o.quadratic_backtracking && std::isfinite(merit_t) && curvature > 0.0)
        next = std::clamp(-slope * alpha * alpha / (2.0 * curvature), 0.25 * alpha, 0.5 * alpha);
      alpha = next;
      ++rep.line_search_cuts;
    }
  }
  return accepted ? alpha : 0.0;
}

int NewtonSolver::negative_pivots(BandedMatrix& matrix, int first_free, int first_fixed) {
  for (int d = first_fixed; d < matrix.size(); ++d) matrix.set_identity_row(d);
  for (int d = 0; d < first_free; ++d) matrix.set_identity_row(d);
  if (!ldlt_.factorize(matrix)) return -1;
  return ldlt_.negative_pivots();
}

}  // namespace flowire::rod
