// The quasi-steady network with nonlinear losses: every segment obeys
//   Δp = R Q φ(c|Q|) + K |Q| Q     (R = f·R_P × the occlusion's factor, K ≥ 0, φ White's ratio of
//                                    a bend, 1 where straight; FlowSpec::segment_laws),
// mass is conserved at every node, and the boundary values are those of the linear model. The
// flow of a segment as a function of its pressure difference is the root of that law (for a
// straight segment that of a quadratic,
//   Q(Δp) = 2 Δp / (R + √(R² + 4K|Δp|)),   dQ/dΔp = 1 / √(R² + 4K|Δp|);
// for a curved one a scalar Newton iteration, SegmentLaw::flow), increasing in Δp, so the node
// balance F(p) = Σ Q − injections is the gradient of a convex
// function of the unknown pressures and its Jacobian is the nodal conductance matrix of the
// tangent conductances dQ/dΔp: symmetric positive definite, with the pattern of the linear one.
// Newton's method from the last frames' pressures extrapolated to the frame's time (the
// Poiseuille solution at the first), the
// Jacobian refilled in place and refactored by CHOLMOD on the pattern analysed once, and a
// backtracking line search on |F| converge to the tolerance in a few iterations; between frames
// the last factorization is reused (chord steps, one solve each) while it still converges fast; the superposition of
// unit responses does not hold for a nonlinear network, so every frame is solved.
//
// With junction losses (junction.hpp) the static pressure of a collecting branch's end is below
// its junction node's by a drop that depends on every flow at that junction, so a segment
// touching a junction no longer has its flow as a function of its two node pressures alone. The
// flows of those segments join the unknowns and their laws the equations, each divided by the
// segment's linear resistance (a flow, like the node balances):
//   (Δp(Q) − (p_from − δ_from) + (p_to − δ_to)) / R = 0,
// δ the junction's drop at that end (0 at an ordinary node). The Jacobian is no longer symmetric
// (a drop depends on the other branches' flows); it is factored by KLU on the pattern analysed
// once, with the same Newton, chord and line-search steps.
#include <fmt/format.h>
#include <Eigen/CholmodSupport>
#include <Eigen/KLUSupport>
#include <Eigen/Sparse>
#include <algorithm>
#include <array>
#include <cmath>

#include "flowire/common/error.hpp"
#include "solvers.hpp"

namespace flowire::flow::detail {
namespace {

class NewtonSolver final : public FrameSolver {
 public:
  NewtonSolver(const Network& net, FlowSpec spec) : FrameSolver(net, std::move(spec)) {
    Stopwatch sw;
    a_ = assemble(net_, spec_, resistance_);
    if (spec_.segment_laws.empty()) spec_.segment_laws.assign(static_cast<size_t>(net_.num_segments()), SegmentLaw{});
    const int nu = a_.num_unknowns();
    set_up_junctions();
    const int nx = nu + static_cast<int>(jseg_.size());
    x_ = Eigen::VectorXd::Zero(nx);
    f_ = Eigen::VectorXd::Zero(nx);
    inj_ = Eigen::VectorXd::Zero(nx);
    coef_.resize(static_cast<size_t>(a_.num_sources()));
    dq_.resize(static_cast<size_t>(net_.num_segments()));
    if (!jseg_.empty()) {
      tangent_triplets(nullptr, triplets_);
      jac_.resize(nx, nx);
      jac_.setFromTriplets(triplets_.begin(), triplets_.end());
      lu_.analyzePattern(jac_);
    } else if (nu > 0) {
      jac_ = nodal_matrix(net_, a_);
      chol_.analyzePattern(jac_);
      // Where each conductance goes among the matrix's values: refilled in place every factorization.
      auto slot = [&](int r, int c) {
        for (Eigen::Index k = jac_.outerIndexPtr()[c]; k < jac_.outerIndexPtr()[c + 1]; ++k)
          if (jac_.innerIndexPtr()[k] == r) return static_cast<int>(k);
        return -1;
      };
      diag_slot_.resize(static_cast<size_t>(nu));
      for (int u = 0; u < nu; ++u) diag_slot_[static_cast<size_t>(u)] = slot(u, u);
      segment_slot_.resize(static_cast<size_t>(net_.num_segments()));
      for (int k = 0; k < net_.num_segments(); ++k) {
        const auto& seg = net_.segment(k);
        const int uf = a_.unknown_of_node[static_cast<size_t>(seg.node_from)];
        const int ut = a_.unknown_of_node[static_cast<size_t>(seg.node_to)];
        segment_slot_[static_cast<size_t>(k)] = {uf >= 0 ? slot(uf, uf) : -1, ut >= 0 ? slot(ut, ut) : -1,
                                                 uf >= 0 && ut >= 0 ? slot(uf, ut) : -1,
                                                 uf >= 0 && ut >= 0 ? slot(ut, uf) : -1};
      }
    }
    timings_.assemble = sw.seconds();
    harmonics_occlusion_tolerance_ = 0.01;  // a period is 128 Newton solves (solver.hpp)
    // The first guess: the linear network (K = 0) at t = 0.
    Stopwatch sf;
    init_arrays();
    timings_.factor = sf.seconds();
  }
  [[nodiscard]] std::string_view name() const override { return "newton"; }
  [[nodiscard]] bool supports_occlusion() const override { return true; }
  /// Newton iterations over all frames so far.
  [[nodiscard]] long iterations() const { return iterations_; }

 protected:
  void apply_occlusion() override {
    factored_ = false;
    r_eff_.clear();
    scratch_q_.clear();
    compute(time_, p_.data(), q_.data());
  }

  void compute(double t, double* p, double* q) const override {
    const int nn = net_.num_nodes(), nu = a_.num_unknowns();
    a_.coefficients(t, coef_.data());
    // Prescribed pressures and the flows injected at the unknown nodes.
    std::fill(p, p + nn, 0.0);
    inj_.setZero();
    for (size_t k = 0; k < coef_.size(); ++k) {
      add_dirichlet(a_, a_.sources[k], coef_[k], p);
      for (const auto& [node, value] : a_.sources[k].node_values)
        if (!a_.dirichlet[static_cast<size_t>(node)])
          inj_[a_.unknown_of_node[static_cast<size_t>(node)]] += coef_[k] * value;
    }
    const double inj_scale = inj_.size() > 0 ? inj_.cwiseAbs().maxCoeff() : 0.0;
    auto set_unknowns = [&](const Eigen::VectorXd& x) {
      for (int u = 0; u < nu; ++u) p[a_.node_of_unknown[static_cast<size_t>(u)]] = x[u];
    };
    // The linear resistances (with the occlusion's factors), once per change of the occlusion.
    if (r_eff_.empty()) {
      r_eff_.resize(static_cast<size_t>(net_.num_segments()));
      for (int s = 0; s < net_.num_segments(); ++s) r_eff_[static_cast<size_t>(s)] = effective_resistance(s);
    }
    // Segment flows at p and the node balance F (flow out − in); the tangent's conductances are
    // computed where a factorization needs them (chord steps do not).
    auto balance = [&]() {
      double qmax = 0.0;
      for (int s = 0; s < net_.num_segments(); ++s) {
        const auto& seg = net_.segment(s);
        const int k = jindex_.empty() ? -1 : jindex_[static_cast<size_t>(s)];
        if (k >= 0) {
          q[s] = x_[nu + k];
        } else {
          const double dp = p[seg.node_from] - p[seg.node_to];
          q[s] = spec_.segment_laws[static_cast<size_t>(s)].flow(dp, r_eff_[static_cast<size_t>(s)], q[s]);
        }
        qmax = std::max(qmax, std::abs(q[s]));
      }
      f_ = -inj_;
      for (int u = 0; u < nu; ++u) {
        const int i = a_.node_of_unknown[static_cast<size_t>(u)];
        f_[u] += a_.outlet_conductance[static_cast<size_t>(i)] * p[i];
      }
      for (int s = 0; s < net_.num_segments(); ++s) {
        const auto& seg = net_.segment(s);
        const int uf = a_.unknown_of_node[static_cast<size_t>(seg.node_from)];
        const int ut = a_.unknown_of_node[static_cast<size_t>(seg.node_to)];
        if (uf >= 0) f_[uf] += q[s];
        if (ut >= 0) f_[ut] -= q[s];
      }
      if (!jseg_.empty()) junction_residuals(p, q, false);
      return qmax;
    };
    if (x_.size() == 0) {
      (void)balance();
      return;
    }
    // Newton's start: the last three frames' pressures extrapolated to t by the parabola through
    // them (frames follow a waveform: the start is then O(Δt³) from the solution instead of
    // O(Δt)); with two frames the line through them; the last frame's where there is no such
    // history or t does not move forward by a step like the last ones.
    if (history_ >= 2 && t > t_[0] && t - t_[0] <= 4.0 * (t_[0] - t_[1])) {
      if (history_ == 3 && t_[1] > t_[2]) {
        const double l0 = (t - t_[1]) * (t - t_[2]) / ((t_[0] - t_[1]) * (t_[0] - t_[2]));
        const double l1 = (t - t_[0]) * (t - t_[2]) / ((t_[1] - t_[0]) * (t_[1] - t_[2]));
        const double l2 = (t - t_[0]) * (t - t_[1]) / ((t_[2] - t_[0]) * (t_[2] - t_[1]));
        x_ = l0 * xs_[0] + l1 * xs_[1] + l2 * xs_[2];
      } else {
        x_ = xs_[0] + ((t - t_[0]) / (t_[0] - t_[1])) * (xs_[0] - xs_[1]);
      }
    }
    set_unknowns(x_);
    double scale = std::max(balance(), inj_scale);
    double norm = f_.norm();
    constexpr int kMaxIterations = 50;
    int it = 0;
    // The last factorization is kept (a chord step, one solve) while it still cuts the imbalance
    // at least fourfold a step; otherwise the tangent is refactored (a Newton step).
    bool refactor = !factored_, stalled = false;
    const bool cold = !jseg_.empty() && history_ == 0;
    for (; it < kMaxIterations; ++it) {
      if (!(f_.lpNorm<Eigen::Infinity>() > kTolerance * scale)) break;
      // Round-off: a Newton step that no longer halves an imbalance already below the floor.
      if (stalled && !(f_.lpNorm<Eigen::Infinity>() > kFloor * scale)) break;
      const bool newton = refactor;
      if (refactor) {
        if (jseg_.empty())
          factorize_tangent(t, q);
        else
          factorize_mixed(t, p, q);
        refactor = false;
      }
      if (jseg_.empty())
        step_ = chol_.solve(f_);
      else
        step_ = lu_.solve(f_);
      const double before = norm;
      x0_ = x_;
      double alpha = 1.0;
      for (int cut = 0;; ++cut) {
        x_ = x0_ - alpha * step_;
        set_unknowns(x_);
        scale = std::max(balance(), inj_scale);
        const double trial = f_.norm();
        // A cold start with junction losses takes its first step whole: from zero flows (where the
        // drops and their slopes vanish) it is the linear network's solution, the start Newton's
        // method needs for drops that grow as the square of the flows.
        if (trial <= (1.0 - 1e-4 * alpha) * norm || cut == 30 || (cold && it == 0)) {
          norm = trial;
          break;
        }
        alpha *= 0.5;
      }
      if (norm > 0.25 * before) refactor = true;
      stalled = newton && norm > 0.5 * before;
    }
    iterations_ += it;
    if (history_ == 0 || t != t_[0]) {
      std::rotate(xs_.begin(), xs_.begin() + 2, xs_.end());  // (newest first)
      std::rotate(t_.begin(), t_.begin() + 2, t_.end());
      xs_[0] = x_;
      t_[0] = t;
      history_ = std::min(history_ + 1, 3);
    }
    if (f_.lpNorm<Eigen::Infinity>() > kFloor * scale || !std::isfinite(norm))
      throw_numerical_error(fmt::format(
          "flow: Newton's method on the nonlinear losses did not converge at t = {} s ({} iterations, node "
          "imbalance {:.3g} of the largest flow {:.3g} m³/s){}",
          t, it, f_.lpNorm<Eigen::Infinity>() / scale, scale,
          jseg_.empty() ? ""
                        : "; with junction losses the static pressure a junction recovers (where the flow slows "
                          "into wider branches) grows with the square of the flow and can outgrow the network's "
                          "resistance, leaving no steady flow under a prescribed pressure: give the outlets "
                          "resistances or the inlet a flow"));
  }

 private:
  /// The segments that touch a junction get a flow unknown each (after the node pressures).
  void set_up_junctions() {
    if (spec_.junctions.empty()) return;
    jindex_.assign(static_cast<size_t>(net_.num_segments()), -1);
    for (const auto& j : spec_.junctions)
      for (const auto& b : j.branches)
        if (jindex_[static_cast<size_t>(b.segment)] < 0) {
          jindex_[static_cast<size_t>(b.segment)] = static_cast<int>(jseg_.size());
          jseg_.push_back(b.segment);
        }
  }

  /// The junctions' drops at the flows @p q (and their derivatives where @p jacobian), and the
  /// junction segments' scaled law residuals into f_.
  void junction_residuals(const double* p, const double* q, bool jacobian) const {
    const int nu = a_.num_unknowns();
    segment_end_drops(net_, spec_.junctions, spec_.density, q, jdrop_, jacobian ? &jjac_ : nullptr);
    for (size_t k = 0; k < jseg_.size(); ++k) {
      const int s = jseg_[k];
      const auto& seg = net_.segment(s);
      const double r = r_eff_[static_cast<size_t>(s)];
      const double law = spec_.segment_laws[static_cast<size_t>(s)].pressure_drop(q[s], r);
      const auto& d = jdrop_[static_cast<size_t>(s)];
      const double dp = (p[seg.node_from] - d[0]) - (p[seg.node_to] - d[1]);
      f_[nu + static_cast<int>(k)] = (law - dp) / r;
    }
  }

  /// The mixed system's Jacobian (node balances and junction segments' laws against node
  /// pressures and junction segments' flows) at the flows @p q, or its pattern (zeros) without them.
  /// (Into @p t, emptied first: its storage is kept from one factorization to the next.)
  void tangent_triplets(const double* q, std::vector<Eigen::Triplet<double>>& t) const {
    const int nu = a_.num_unknowns();
    t.clear();
    for (int u = 0; u < nu; ++u)
      t.emplace_back(u, u, a_.outlet_conductance[static_cast<size_t>(a_.node_of_unknown[static_cast<size_t>(u)])]);
    for (int s = 0; s < net_.num_segments(); ++s) {
      const auto& seg = net_.segment(s);
      const int uf = a_.unknown_of_node[static_cast<size_t>(seg.node_from)];
      const int ut = a_.unknown_of_node[static_cast<size_t>(seg.node_to)];
      const int k = jindex_[static_cast<size_t>(s)];
      const double r = q ? r_eff_[static_cast<size_t>(s)] : 1.0;
      const double slope = q ? spec_.segment_laws[static_cast<size_t>(s)].slope(q[s], r) : 0.0;
      if (k < 0) {
        const double c = q ? 1.0 / slope : 0.0;
        if (uf >= 0) t.emplace_back(uf, uf, c);
        if (ut >= 0) t.emplace_back(ut, ut, c);
        if (uf >= 0 && ut >= 0) {
          t.emplace_back(uf, ut, -c);
          t.emplace_back(ut, uf, -c);
        }
        continue;
      }
      const int row = nu + k;
      if (uf >= 0) t.emplace_back(uf, row, 1.0);
      if (ut >= 0) t.emplace_back(ut, row, -1.0);
      t.emplace_back(row, row, slope / r);
      if (uf >= 0) t.emplace_back(row, uf, -1.0 / r);
      if (ut >= 0) t.emplace_back(row, ut, 1.0 / r);
    }
    // The drops' dependence on every flow at their junction: +δ at a segment's start, −δ at its end.
    for (size_t i = 0; i < spec_.junctions.size(); ++i) {
      const auto& j = spec_.junctions[i];
      const size_t n = j.branches.size();
      for (size_t b = 0; b < n; ++b) {
        const int s = j.branches[b].segment;
        const double sign = net_.segment(s).node_from == j.node ? 1.0 : -1.0;
        const double r = q ? r_eff_[static_cast<size_t>(s)] : 1.0;
        for (size_t l = 0; l < n; ++l) {
          const auto& bl = j.branches[l];
          const double v = q ? sign * jjac_[i][b * n + l] * bl.outward / r : 0.0;
          t.emplace_back(nu + jindex_[static_cast<size_t>(s)], nu + jindex_[static_cast<size_t>(bl.segment)], v);
        }
      }
    }
  }

  /// The mixed system's Jacobian at @p p, @p q, factored by KLU.
  void factorize_mixed(double t, const double* p, const double* q) const {
    junction_residuals(p, q, true);
    tangent_triplets(q, triplets_);
    jac_.setFromTriplets(triplets_.begin(), triplets_.end());
    lu_.factorize(jac_);
    if (lu_.info() != Eigen::Success)
      throw_numerical_error(
          fmt::format("flow: the network's Jacobian with junction losses is singular at t = {} s", t));
    factored_ = true;
    ++factorizations_;
  }

  /// The tangent conductance matrix at the flows @p q the last balance found (their pressures'
  /// roots: dQ/dΔp = 1 / (dΔp/dQ) there, no law inverted again), refilled in place and factored.
  void factorize_tangent(double t, const double* q) const {
    for (int s = 0; s < net_.num_segments(); ++s)
      dq_[static_cast<size_t>(s)] =
          1.0 / spec_.segment_laws[static_cast<size_t>(s)].slope(q[s], r_eff_[static_cast<size_t>(s)]);
    double* v = jac_.valuePtr();
    std::fill(v, v + jac_.nonZeros(), 0.0);
    for (size_t u = 0; u < diag_slot_.size(); ++u)
      v[diag_slot_[u]] += a_.outlet_conductance[static_cast<size_t>(a_.node_of_unknown[u])];
    for (size_t k = 0; k < segment_slot_.size(); ++k) {
      const auto& sl = segment_slot_[k];
      const double c = dq_[k];
      if (sl[0] >= 0) v[sl[0]] += c;
      if (sl[1] >= 0) v[sl[1]] += c;
      if (sl[2] >= 0) v[sl[2]] -= c;
      if (sl[3] >= 0) v[sl[3]] -= c;
    }
    chol_.factorize(jac_);
    if (chol_.info() != Eigen::Success)
      throw_numerical_error(fmt::format("flow: the tangent conductance matrix is singular at t = {} s", t));
    factored_ = true;
    ++factorizations_;
  }

  static constexpr double kTolerance = 1e-10;  ///< node imbalance / the largest flow: converged
  static constexpr double kFloor = 1e-9;       ///< ... accepted where round-off stalls Newton above kTolerance
  Assembly a_;
  mutable Eigen::SparseMatrix<double> jac_;       // the nodal pattern; values: the tangent conductances
  std::vector<int> diag_slot_;                    // (unknowns) index of the diagonal among jac_'s values
  std::vector<std::array<int, 4>> segment_slot_;  // (segments) from-from, to-to, from-to, to-from; -1: none
  mutable bool factored_ = false;                 // chol_ holds a tangent of this network
  mutable long factorizations_ = 0;
  mutable Eigen::CholmodSimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> chol_;
  // Junction losses: the segments with a flow unknown (k -> segment, segment -> k or -1), every
  // segment's drops at its two ends, each junction's Jacobian of its drops, the mixed system's factor.
  std::vector<int> jseg_, jindex_;
  mutable std::vector<std::array<double, 2>> jdrop_;
  mutable std::vector<std::vector<double>> jjac_;
  mutable std::vector<Eigen::Triplet<double>> triplets_;
  mutable Eigen::KLU<Eigen::SparseMatrix<double>> lu_;
  mutable Eigen::VectorXd x_, f_, inj_, step_, x0_;  // unknown pressures (the last frame's), balance, injections
  mutable std::vector<double> coef_, dq_, r_eff_;    // ..., tangent conductances, linear resistances
  mutable long iterations_ = 0;
  // The last three frames' solutions and times, newest first, for the next frame's start.
  mutable std::array<Eigen::VectorXd, 3> xs_;
  mutable std::array<double, 3> t_{};
  mutable int history_ = 0;
};

}  // namespace

std::unique_ptr<FlowSolver> make_newton_solver(const Network& net, FlowSpec spec) {
  return std::make_unique<NewtonSolver>(net, std::move(spec));
}

}  // namespace flowire::flow::detail
