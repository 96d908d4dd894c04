#include "flowire/flow/rlc.hpp"

#include <fmt/format.h>

#include <Eigen/Sparse>
#include <Eigen/SparseLU>
#include <cmath>

#include "assembly.hpp"
#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "solvers.hpp"

namespace flowire::flow {
namespace {
constexpr double kPi = 3.14159265358979323846;
}

double segment_inertance(Inertance kind, double density, double length, double radius) {
  const double l = density * length / (kPi * radius * radius);
  return kind == Inertance::Womersley ? 4.0 / 3.0 * l : l;
}

double segment_compliance(double youngs_modulus, double thickness_ratio, double length, double radius) {
  if (!(youngs_modulus > 0.0) || !(thickness_ratio > 0.0)) return 0.0;
  return 3.0 * kPi * radius * radius * length / (2.0 * youngs_modulus * thickness_ratio);
}

double segment_inertance(Inertance kind, double density, double length, double r1, double r2) {
  const double l = density * length / (kPi * r1 * r2);
  return kind == Inertance::Womersley ? 4.0 / 3.0 * l : l;
}

double segment_compliance(double youngs_modulus, double thickness_ratio, double length, double r1, double r2) {
  if (!(youngs_modulus > 0.0) || !(thickness_ratio > 0.0)) return 0.0;
  return kPi * length * (r1 * r1 + r1 * r2 + r2 * r2) / (2.0 * youngs_modulus * thickness_ratio);
}

namespace detail {
namespace {

/// Unknown layout: [p (num_nodes) | Q (num_segments) | p_c (num RCR outlets)].
class RlcSolver final : public FlowSolver {
 public:
  RlcSolver(const Network& net, FlowSpec spec) : FlowSolver(net, std::move(spec)) {
    if (!(spec_.dt > 0.0)) throw_usage_error(fmt::format("flow (rlc): time step {} must be positive", spec_.dt));
    if (spec_.profile == Profile::Womersley)
      warn("flow.profile: womersley is not available with flow.model: rlc; using the laminar profile");
    Stopwatch sw;
    a_ = assemble(net_, spec_, resistance_, /*steady_rcr=*/false);
    build();
    timings_.assemble = sw.seconds();
    Stopwatch sf;
    const double rho = std::clamp(spec_.rho_infinity, 0.0, 1.0);
    am_ = 0.5 * (3.0 - rho) / (1.0 + rho);
    af_ = 1.0 / (1.0 + rho);
    gamma_ = 0.5 + am_ - af_;
    const Eigen::SparseMatrix<double> j = am_ * e_ + (af_ * gamma_ * spec_.dt) * f_;
    lu_.analyzePattern(j);
    lu_.factorize(j);
    if (lu_.info() != Eigen::Success)
      throw_numerical_error("flow (rlc): the time-step matrix is singular; check that every piece of the network "
                            "has a pressure reference");
    initial_state();
    settle();
    timings_.factor = sf.seconds();
    prev_y_ = y_;
    prev_t_ = cur_t_ = 0.0;
    interpolate(0.0);
  }

  [[nodiscard]] std::string_view name() const override { return "rlc"; }
  [[nodiscard]] bool supports_occlusion() const override { return true; }
  [[nodiscard]] double node_pressure(int node) const override { return out_[static_cast<size_t>(node)]; }
  [[nodiscard]] double segment_flow(int s) const override { return out_[n_nodes_ + static_cast<size_t>(s)]; }
  [[nodiscard]] double segment_flow_at(int s, double t) const override {
    const size_t k = n_nodes_ + static_cast<size_t>(s);
    if (cur_t_ <= prev_t_) return y_[static_cast<Eigen::Index>(k)];
    const double w = std::clamp((t - prev_t_) / (cur_t_ - prev_t_), 0.0, 1.0);
    return (1.0 - w) * prev_y_[static_cast<Eigen::Index>(k)] + w * y_[static_cast<Eigen::Index>(k)];
  }
  [[nodiscard]] const PeriodicInfo& periodic() const { return periodic_; }

 protected:
  void do_advance(double t) override {
    if (t < cur_t_ - 1e-12 * spec_.dt && t < prev_t_) {
      throw_usage_error(fmt::format("flow (rlc): cannot go back in time from {} to {}", cur_t_, t));
    }
    while (cur_t_ < t - 1e-12 * spec_.dt) {
      prev_y_ = y_;
      prev_t_ = cur_t_;
      step(cur_t_ + t_offset_);
      cur_t_ += spec_.dt;
    }
    interpolate(t);
  }

  /// A wire in a segment scales its resistance and inertance: the step matrix is rebuilt
  /// and refactored (same pattern); the state integrates on from where it is.
  void apply_occlusion() override {
    for (size_t s = 0; s < static_cast<size_t>(net_.num_segments()); ++s) {
      const auto row = static_cast<Eigen::Index>(n_nodes_ + s);
      const auto& o = occlusion_[s];
      f_.coeffRef(row, row) = resistance_[s] * o.resistance_factor;
      e_.coeffRef(row, row) = inertance_[s] * o.inertance_factor;
    }
    lu_.factorize(am_ * e_ + (af_ * gamma_ * spec_.dt) * f_);
    if (lu_.info() != Eigen::Success) throw_numerical_error("flow (rlc): the time-step matrix with the wire is singular");
  }

 private:
  void build() {
    n_nodes_ = static_cast<size_t>(net_.num_nodes());
    const auto ne = static_cast<size_t>(net_.num_segments());
    for (const auto& o : spec_.outlets)
      if (o.type == OutletBC::Type::Rcr) rcr_.push_back(&o);
    n_ = static_cast<Eigen::Index>(n_nodes_ + ne + rcr_.size());
    std::vector<Eigen::Triplet<double>> te, tf;
    const auto qi = [&](size_t s) { return static_cast<int>(n_nodes_ + s); };
    std::vector<double> node_c(n_nodes_, 0.0);
    for (size_t s = 0; s < ne; ++s) {
      const auto& seg = net_.segment(static_cast<int>(s));
      const int row = qi(s);
      inertance_.push_back(segment_inertance(spec_.inertance, spec_.density, seg.length, seg.radius_from, seg.radius_to));
      te.emplace_back(row, row, inertance_.back());
      tf.emplace_back(row, row, resistance_[s]);
      tf.emplace_back(row, seg.node_from, -1.0);
      tf.emplace_back(row, seg.node_to, 1.0);
      const double c = segment_compliance(spec_.wall_youngs_modulus, spec_.wall_thickness_ratio, seg.length, seg.radius_from,
                                          seg.radius_to);
      node_c[static_cast<size_t>(seg.node_from)] += 0.5 * c;
      node_c[static_cast<size_t>(seg.node_to)] += 0.5 * c;
      // Node balance rows (non-Dirichlet): C dp/dt + sum_out Q - sum_in Q + outflow = injected.
      if (!a_.dirichlet[static_cast<size_t>(seg.node_from)]) tf.emplace_back(seg.node_from, row, 1.0);
      if (!a_.dirichlet[static_cast<size_t>(seg.node_to)]) tf.emplace_back(seg.node_to, row, -1.0);
    }
    for (size_t i = 0; i < n_nodes_; ++i) {
      const int r = static_cast<int>(i);
      if (a_.dirichlet[i]) {
        tf.emplace_back(r, r, 1.0);
        continue;
      }
      if (node_c[i] > 0.0) te.emplace_back(r, r, node_c[i]);
      if (a_.outlet_conductance[i] > 0.0) tf.emplace_back(r, r, a_.outlet_conductance[i]);
    }
    for (size_t k = 0; k < rcr_.size(); ++k) {
      const auto& o = *rcr_[k];
      if (!(o.rp > 0.0) || !(o.rd > 0.0) || !(o.c >= 0.0))
        throw_usage_error(fmt::format("flow (rlc): RCR outlet at node {} needs Rp > 0, Rd > 0, C >= 0", o.node));
      const int row = static_cast<int>(n_nodes_ + ne + k);
      // Outflow (p_i - p_c)/Rp leaves node i.
      tf.emplace_back(o.node, o.node, 1.0 / o.rp);
      tf.emplace_back(o.node, row, -1.0 / o.rp);
      // C dp_c/dt - (p_i - p_c)/Rp + (p_c - Pd)/Rd = 0  (Pd in the source vector).
      if (o.c > 0.0) te.emplace_back(row, row, o.c);
      tf.emplace_back(row, o.node, -1.0 / o.rp);
      tf.emplace_back(row, row, 1.0 / o.rp + 1.0 / o.rd);
    }
    e_.resize(n_, n_);
    f_.resize(n_, n_);
    e_.setFromTriplets(te.begin(), te.end());
    f_.setFromTriplets(tf.begin(), tf.end());
    // Source vectors per BC source: rows of the node values (pressure at Dirichlet rows,
    // injected flow elsewhere), RCR distal pressures in the constant part.
    src_.assign(a_.sources.size(), Eigen::VectorXd::Zero(n_));
    for (size_t k = 0; k < a_.sources.size(); ++k)
      for (const auto& [node, value] : a_.sources[k].node_values) src_[k][node] += value;
    for (size_t k = 0; k < rcr_.size(); ++k)
      src_[0][static_cast<Eigen::Index>(n_nodes_ + ne + k)] += rcr_[k]->distal_pressure / rcr_[k]->rd;
    coef_.resize(a_.sources.size());
    y_ = Eigen::VectorXd::Zero(n_);
    yd_ = Eigen::VectorXd::Zero(n_);
    out_.assign(static_cast<size_t>(n_), 0.0);
  }

  /// b(t): the residual is E ydot + F y - b(t) = 0.
  void source(double t, Eigen::VectorXd& b) const {
    a_.coefficients(t, coef_.data());
    b.setZero(n_);
    for (size_t k = 0; k < src_.size(); ++k) b.noalias() += coef_[k] * src_[k];
  }

  void initial_state() {
    Eigen::SparseLU<Eigen::SparseMatrix<double>> steady(f_);
    if (steady.info() != Eigen::Success) throw_numerical_error("flow (rlc): the steady system is singular");
    source(0.0, b_);
    y_ = steady.solve(b_);
    yd_.setZero();
    if (!y_.allFinite()) throw_numerical_error("flow (rlc): the initial state is not finite");
  }

  void step(double t) {
    // Unknown x = ydot_{n+1}: (am E + af γ dt F) x = b(t + af dt) - E (1 - am) ydot_n - F (y_n + af dt (1 - γ) ydot_n).
    const double dt = spec_.dt;
    source(t + af_ * dt, b_);
    tmp_ = y_ + (af_ * dt * (1.0 - gamma_)) * yd_;
    b_.noalias() -= f_ * tmp_;
    b_.noalias() -= (1.0 - am_) * (e_ * yd_);
    x_ = lu_.solve(b_);
    y_ += dt * ((1.0 - gamma_) * yd_ + gamma_ * x_);
    yd_ = x_;
  }

  void settle() {
    const double period = spec_.cycle();
    if (!(period > 0.0)) return;
    const long steps = std::lround(period / spec_.dt);
    if (std::abs(steps * spec_.dt - period) > 1e-9 * period)
      warn(fmt::format("flow (rlc): the step {} s does not divide the period {} s; periodic detection is approximate",
                       spec_.dt, period));
    Eigen::VectorXd start = y_;
    double t = 0.0;
    for (int c = 1; c <= spec_.max_cycles; ++c) {
      for (long k = 0; k < steps; ++k, t += spec_.dt) step(t);
      const double scale = std::max(y_.lpNorm<Eigen::Infinity>(), 1e-300);
      periodic_.cycles = c;
      periodic_.last_change = (y_ - start).lpNorm<Eigen::Infinity>() / scale;
      if (periodic_.last_change <= spec_.periodic_tolerance) {
        periodic_.converged = true;
        t_offset_ = static_cast<double>(steps) * spec_.dt * c - static_cast<double>(c) * period;
        return;
      }
      start = y_;
    }
    periodic_.converged = false;
    warn(fmt::format("flow (rlc): no periodic state after {} cycles (last relative change {:.3g}); continuing",
                     spec_.max_cycles, periodic_.last_change));
  }

  void interpolate(double t) {
    const double w = cur_t_ > prev_t_ ? std::clamp((t - prev_t_) / (cur_t_ - prev_t_), 0.0, 1.0) : 1.0;
    for (Eigen::Index i = 0; i < n_; ++i) out_[static_cast<size_t>(i)] = (1.0 - w) * prev_y_[i] + w * y_[i];
  }

  Assembly a_;
  std::vector<const OutletBC*> rcr_;
  std::vector<double> inertance_;  // (num_segments) without occlusion
  size_t n_nodes_ = 0;
  Eigen::Index n_ = 0;
  Eigen::SparseMatrix<double> e_, f_;
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu_;
  std::vector<Eigen::VectorXd> src_;
  mutable std::vector<double> coef_;
  Eigen::VectorXd y_, yd_, prev_y_, b_, tmp_, x_;
  std::vector<double> out_;
  double am_ = 1.0, af_ = 1.0, gamma_ = 0.5;
  double cur_t_ = 0.0, prev_t_ = 0.0, t_offset_ = 0.0;
  PeriodicInfo periodic_;
};

}  // namespace

std::unique_ptr<FlowSolver> make_rlc_solver(const Network& net, FlowSpec spec) {
  return std::make_unique<RlcSolver>(net, std::move(spec));
}

}  // namespace detail

PeriodicInfo periodic_info(const FlowSolver& solver) {
  if (const auto* r = dynamic_cast<const detail::RlcSolver*>(&solver)) return r->periodic();
  return {};
}

}  // namespace flowire::flow
