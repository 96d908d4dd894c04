// Wire and catheter in one Newton iteration (catheter.hpp, step_pair_newton): the coupling
// blocks of the lumen contact, and the joint step.
#include <fmt/format.h>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>

#include "flowire/common/diagnostics.hpp"
#include "flowire/coupling/catheter.hpp"
#include "flowire/rod/banded.hpp"

namespace flowire::coupling {

void LumenContact::sync(const rod::RodSimulator& wire, const rod::RodSimulator& catheter) {
  // The iterates' velocities, (x − x₀)/Δt, which friction depends on (velocities() is the step's start).
  wire_snapshot.assign(wire.positions().begin(), wire.positions().end());
  wire.coupled_velocities(wire_velocity);
  wire_arc.assign(wire.arc_lengths().begin(), wire.arc_lengths().end());
  catheter_snapshot.assign(catheter.positions().begin(), catheter.positions().end());
  catheter.coupled_velocities(catheter_velocity);
  catheter_arc.assign(catheter.arc_lengths().begin(), catheter.arc_lengths().end());
}

void LumenContact::cross_matrix(std::vector<Eigen::Triplet<double>>& out, const std::vector<char>& wire_free,
                                const std::vector<char>& catheter_free, int catheter_offset, double dt) const {
  const int nc = static_cast<int>(catheter_snapshot.size());
  // Block (catheter vertex c, wire vertex i) of the lower triangle: the transpose of ∂²E/∂x_i∂a_c.
  auto put = [&](int i, int c, const Eigen::Matrix3d& b) {
    if (static_cast<size_t>(i) >= wire_free.size() || !wire_free[static_cast<size_t>(i)] ||
        static_cast<size_t>(c) >= catheter_free.size() || !catheter_free[static_cast<size_t>(c)])
      return;
    for (int r = 0; r < 3; ++r)
      for (int q = 0; q < 3; ++q)
        if (b(q, r) != 0.0) out.emplace_back(catheter_offset + 4 * c + r, 4 * i + q, b(q, r));
  };
  for (size_t i = 0; i < wire_snapshot.size() && i < wire_edge.size(); ++i) {
    const int j = wire_edge[i];
    if (j < 0 || j + 1 >= nc) continue;
    const LumenPenalty p = lumen_penalty(wire_snapshot[i], catheter_snapshot[static_cast<size_t>(j)],
                                         catheter_snapshot[static_cast<size_t>(j) + 1], clearance_,
                                         stiffness_ * weight(i), j == 0, onset_);
    if (!(p.energy > 0.0)) continue;
    put(static_cast<int>(i), j, p.hess_xa);
    put(static_cast<int>(i), j + 1, p.hess_xb);
  }
  if (!(friction_ > 0.0) || !(dt > 0.0)) return;
  for (size_t i = 0; i < friction_contact.size() && i < wire_velocity.size(); ++i) {
    const FrictionContact& fc = friction_contact[i];
    if (fc.edge < 0 || fc.edge + 1 >= nc) continue;
    const auto j = static_cast<size_t>(fc.edge);
    const FrictionResult fr = friction_at(fc, wire_velocity[i], catheter_velocity[j], catheter_velocity[j + 1]);
    // ∂²(Δt D)/∂x_w∂x_a = −∂f/∂v (−(1 − α))/Δt·(−1): (1 − α) ∂f/∂v / Δt, and α ∂f/∂v / Δt for b.
    put(static_cast<int>(i), fc.edge, (1.0 - fc.alpha) * fr.dfdv / dt);
    put(static_cast<int>(i), fc.edge + 1, fc.alpha * fr.dfdv / dt);
  }
}

namespace {

using SpMat = Eigen::SparseMatrix<double>;

/// One try at the step (no halving): Newton on both rods from their begun state.
rod::StepReport newton_pair(rod::RodSimulator& wire, rod::RodSimulator& cath, LumenContact& contact, double dt,
                            int max_band, rod::StepReport& cath_rep) {
  rod::StepReport rep;
  rep.status = rod::SolveStatus::MaxIterations;
  const int nw = wire.coupled_dofs(), nc = cath.coupled_dofs(), n = nw + nc;
  const int max_it = wire.settings().max_iterations;
  Eigen::VectorXd rhs(n), dq(n);
  std::vector<Eigen::Triplet<double>> trip;
  // The unknowns of both rods interleaved by arc length from the entry: a wire vertex is coupled
  // to the catheter's vertices at about its own arc length, so in this order the joint matrix is
  // banded and factorizes in its natural order without fill beyond the band (a fill-reducing
  // ordering cost more than the factorization itself).
  std::vector<int> perm(static_cast<size_t>(n));
  {
    struct Key {
      double arc;
      int rod, vertex;
    };
    std::vector<Key> keys;
    for (int r = 0; r < 2; ++r) {
      const rod::RodSimulator& body = r == 0 ? wire : cath;
      for (int k = 0; k < body.vertex_count(); ++k) keys.push_back({body.arc_lengths()[static_cast<size_t>(k)], r, k});
    }
    std::stable_sort(keys.begin(), keys.end(), [](const Key& a, const Key& b) { return a.arc > b.arc; });
    int next = 0;
    for (const Key& key : keys) {
      const rod::RodSimulator& body = key.rod == 0 ? wire : cath;
      const int dofs = key.vertex < body.vertex_count() - 1 ? 4 : 3, base = key.rod == 0 ? 0 : nw;
      for (int c = 0; c < dofs; ++c) perm[static_cast<size_t>(base + 4 * key.vertex + c)] = next++;
    }
  }
  std::vector<char> wire_free(static_cast<size_t>(wire.vertex_count())),
      cath_free(static_cast<size_t>(cath.vertex_count()));
  for (int k = 0; k < wire.vertex_count(); ++k) wire_free[static_cast<size_t>(k)] = wire.coupled_free_vertex(k);
  for (int k = 0; k < cath.vertex_count(); ++k) cath_free[static_cast<size_t>(k)] = cath.coupled_free_vertex(k);
  // In that order the band is a few vertices of each rod wide; a wider one (a wire looping back
  // within the catheter's reach) takes the sparse path.
  bool banded = true;
  rod::BandedMatrix H;
  rod::BandedLDLT hldlt;
  Eigen::SimplicialLDLT<SpMat, Eigen::Lower, Eigen::NaturalOrdering<int>> ldlt;
  SpMat A(n, n);
  Eigen::VectorXd prhs(n);
  // The sparse path: the matrix, or with @p shifted growing diagonal shifts until positive.
  auto sparse_factorize = [&](SpMat& m, bool shifted) {
    double dmax = 0.0, shift = 0.0;
    for (int k = 0; k < n; ++k) dmax = std::max(dmax, std::abs(m.coeff(k, k)));
    for (int tries = 0; tries < (shifted ? 12 : 1); ++tries) {
      if (shifted) {
        const double next = tries == 0 ? 1e-12 * dmax : 10.0 * shift;
        for (int k = 0; k < n; ++k) m.coeffRef(k, k) += next - shift;
        shift = next;
      }
      ldlt.compute(m);  // the pattern changes with the matrix and the shift
      if (ldlt.info() == Eigen::Success && (ldlt.vectorD().array() > 0.0).all()) return true;
    }
    return false;
  };
  auto evaluate = [&](bool matrix, bool psd) {
    contact.sync(wire, cath);
    return wire.coupled_assemble(matrix, psd) + cath.coupled_assemble(matrix, psd);
  };
  auto residual = [&] { return std::max(wire.coupled_residual(), cath.coupled_residual()); };
  double phi = evaluate(true, false);
  if (!std::isfinite(phi)) {
    rep.status = rod::SolveStatus::NonFinite;
    return rep;
  }
  for (int it = 0; it < max_it; ++it) {
    rep.residual = residual();
    if (rep.residual <= 1.0) {
      rep.status = rod::SolveStatus::Converged;
      break;
    }
    rep.newton_iterations = it + 1;
    wire.coupled_rhs(rhs.head(nw));
    cath.coupled_rhs(rhs.tail(nc));
    // The exact matrix first; where it is indefinite (a bent or compressed rod, the contact's
    // distance to a segment), the rods' positive semi-definite ones, then growing diagonal
    // shifts, as each rod's own sparse fallback.
    bool ok = false;
    for (int attempt = 0; attempt < 3 && !ok; ++attempt) {
      if (attempt <= 1) {
        if (attempt == 1) {
          phi = evaluate(true, true);
          ++rep.regularizations;
        }
        trip.clear();
        wire.coupled_matrix(trip, 0);
        cath.coupled_matrix(trip, nw);
        contact.cross_matrix(trip, wire_free, cath_free, nw, dt);
        int band = 0;
        for (auto& t : trip) {  // into the interleaved order, kept in the lower triangle
          const int i = perm[static_cast<size_t>(t.row())], j = perm[static_cast<size_t>(t.col())];
          t = Eigen::Triplet<double>(std::max(i, j), std::min(i, j), t.value());
          band = std::max(band, std::abs(i - j));
        }
        banded = band <= max_band;
        if (banded) {
          H = rod::BandedMatrix(n, band);
          for (const auto& t : trip) H.lower(t.row(), t.col()) += t.value();
        } else {
          A.setFromTriplets(trip.begin(), trip.end());
        }
      }
      if (banded) {
        ok = hldlt.factorize(H) && hldlt.negative_pivots() == 0;
        // Growing diagonal shifts until positive definite: a direction between Newton's and the
        // gradient's, which is what carried the violent start of a pulled pair (the modified
        // factorization's did not).
        const double dmax = std::max(H.max_diagonal(), 1e-300);
        double shift = 0.0;
        for (int tries = 0; attempt == 2 && !ok && tries < 12; ++tries) {
          const double next = tries == 0 ? 1e-12 * dmax : 10.0 * shift;
          H.add_to_diagonal(next - shift);
          shift = next;
          ok = hldlt.factorize(H) && hldlt.negative_pivots() == 0;
        }
      } else {
        ok = sparse_factorize(A, attempt == 2);
      }
    }
    if (!ok) {
      rep.status = rod::SolveStatus::SingularMatrix;
      break;
    }
    for (int k = 0; k < n; ++k) prhs(perm[static_cast<size_t>(k)]) = rhs(k);
    if (banded)
      hldlt.solve_in_place(prhs);
    else
      prhs = ldlt.solve(Eigen::VectorXd(prhs));
    for (int k = 0; k < n; ++k) dq(k) = prhs(perm[static_cast<size_t>(k)]);
    if (!dq.allFinite()) {
      rep.status = rod::SolveStatus::NonFinite;
      break;
    }
    const double slope = -rhs.dot(dq);  // gradient · direction
    wire.coupled_accept();
    cath.coupled_accept();
    const double residual_before = rep.residual;
    double alpha = std::min(wire.coupled_max_step(dq.head(nw)), cath.coupled_max_step(dq.tail(nc)));
    bool accepted = false;
    for (int cut = 0; cut <= wire.settings().max_line_search_cuts; ++cut) {
      wire.coupled_trial(dq.head(nw), alpha);
      cath.coupled_trial(dq.tail(nc), alpha);
      const double phi_t = evaluate(false, false);
      const double change = phi_t - phi - wire.coupled_nonconservative_work() - cath.coupled_nonconservative_work();
      bool good = std::isfinite(phi_t) && change <= 1e-4 * alpha * slope + 1e-14 * std::abs(phi);
      // Near convergence the merit's round-off hides the decrease: judge the step by the
      // residual it leaves (as the rod's own line search).
      if (!good && std::isfinite(phi_t) && -slope <= 1e-10 * std::abs(phi)) good = residual() <= 0.5 * residual_before;
      if (good) {
        accepted = true;
        phi = phi_t;
        break;
      }
      wire.coupled_reject();
      cath.coupled_reject();
      const double curvature = change - slope * alpha;
      double next = 0.5 * alpha;
      if (std::isfinite(change) && curvature > 0.0)
        next = std::clamp(-slope * alpha * alpha / (2.0 * curvature), 0.25 * alpha, 0.5 * alpha);
      alpha = next;
      ++rep.line_search_cuts;
    }
    if (!accepted) {
      phi = evaluate(true, false);  // the accepted iterate's derivatives again
      rep.residual = residual();
      rep.status = rep.residual <= 100.0 ? rod::SolveStatus::Converged : rod::SolveStatus::LineSearchFailed;
      break;
    }
    phi = evaluate(true, false);  // the matrix at the new iterate
  }
  if (rep.status == rod::SolveStatus::MaxIterations && residual() <= 100.0) rep.status = rod::SolveStatus::Converged;
  // Residuals in each rod's own force units for the reports.
  rep.residual = wire.coupled_residual();
  rep.tolerance = 1.0;
  cath_rep = rep;
  cath_rep.residual = cath.coupled_residual();
  return rep;
}

/// The step of @p dt, taken again as two halves where Newton fails (down to the rods' limit).
PairStepReport step_halving(rod::RodSimulator& wire, rod::RodSimulator& cath, LumenContact& contact, double dt,
                            int max_band, int depth) {
  PairStepReport out;
  const bool can_retry = depth < wire.settings().max_subdivisions;
  if (can_retry) wire.coupled_save(depth), cath.coupled_save(depth);
  // Friction's normal forces, the edges each wire vertex presses on: of the step's start.
  contact.hold_catheter(cath);
  contact.hold_wire(wire);
  contact.lag_friction();
  wire.coupled_begin(dt);
  cath.coupled_begin(dt);
  contact.sync(wire, cath);                  // the vertex sets after feeding; the edges as assigned at the start
  contact.wire_weight = cell_weights(wire);  // constant through the step's iterations
  if (contact.wire_edge.size() != contact.wire_snapshot.size()) contact.assign_edges();
  rod::StepReport cr;
  rod::StepReport wr = newton_pair(wire, cath, contact, dt, max_band, cr);
  if (!wr.converged() && can_retry) {
    wire.coupled_restore(depth), cath.coupled_restore(depth);
    PairStepReport total;
    total.wire.add_work(wr), total.catheter.add_work(cr);
    for (int half = 0; half < 2; ++half) {
      const PairStepReport r = step_halving(wire, cath, contact, 0.5 * dt, max_band, depth + 1);
      total.wire.then(r.wire), total.catheter.then(r.catheter);
      total.converged = r.converged;
      if (!r.converged) break;
    }
    total.wire.subdivisions = std::max(total.wire.subdivisions, depth + 1);
    total.catheter.subdivisions = total.wire.subdivisions;
    return total;
  }
  wire.coupled_finish(dt, wr);
  cath.coupled_finish(dt, cr);
  out.wire = wr;
  out.catheter = cr;
  out.converged = wr.converged();
  return out;
}

}  // namespace

PairStepReport step_pair_newton(rod::RodSimulator& wire, rod::RodSimulator& catheter, LumenContact& contact, double dt,
                                int max_band) {
  // The catheter's side leaves the contact's energy to the wire's for this step, also when a
  // numerical failure ends it early.
  struct EnergyOnWireSide {
    LumenContact& c;
    explicit EnergyOnWireSide(LumenContact& contact) : c(contact) { c.catheter_reports_energy = false; }
    ~EnergyOnWireSide() { c.catheter_reports_energy = true; }
    EnergyOnWireSide(const EnergyOnWireSide&) = delete;
    EnergyOnWireSide& operator=(const EnergyOnWireSide&) = delete;
  };
  PairStepReport rep;
  {
    const EnergyOnWireSide guard(contact);
    rep = step_halving(wire, catheter, contact, dt, max_band, 0);
  }
  rep.sweeps = 1;
  rep.imbalance = rep.converged ? 0.0 : rep.wire.residual;
  contact.hold_catheter(catheter);
  contact.hold_wire(wire);
  if (!rep.converged)
    warn(
        fmt::format("wire and catheter: implicit Euler step at t = {:.6g} s: {} after {} Newton iterations (residual "
                    "{:.3g} of the tolerance)",
                    wire.time(), rod::to_string(rep.wire.status), rep.wire.newton_iterations, rep.wire.residual));
  return rep;
}

}  // namespace flowire::coupling
