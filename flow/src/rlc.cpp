#include "flowire/flow/rlc.hpp"

#include <fmt/format.h>

#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>

#include "assembly.hpp"
#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/steps.hpp"
#include "flowire/flow/svzerod/block.hpp"
#include "flowire/flow/svzerod/integrator.hpp"
#include "flowire/flow/svzerod/system.hpp"
#include "solvers.hpp"

namespace flowire::flow {
namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kLossTolerance = 1e-8;  // Newton's absolute tolerance with nonlinear losses
}  // namespace

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

/// E and F of the network: rows [node balances and pressures (num_nodes) | segments], over
/// the unknowns [p (num_nodes) | Q (num_segments) | per outlet block its outflow and its own
/// unknowns]: constant within a phase, rewritten only when a wire changes a segment.
class RlcNetwork final : public svzerod::Block {
 public:
  RlcNetwork(Eigen::SparseMatrix<double> e, Eigen::SparseMatrix<double> f)
      : Block("rlc network"), e_(std::move(e)), f_(std::move(f)) {}
  [[nodiscard]] const char* type() const override { return "RlcNetwork"; }
  [[nodiscard]] std::string check_connections() const override { return {}; }
  [[nodiscard]] int num_equations() const override { return static_cast<int>(f_.rows()); }
  /// The steady phase has no capacitor or inductor terms: E = 0.
  void assemble(svzerod::Assembler& a, double /*t*/) const override {
    if (!a.steady())
      for (Eigen::Index j = 0; j < e_.outerSize(); ++j)
        for (Eigen::SparseMatrix<double>::InnerIterator it(e_, j); it; ++it)
          a.e(static_cast<int>(it.row()), static_cast<int>(it.col()), it.value());
    for (Eigen::Index j = 0; j < f_.outerSize(); ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator it(f_, j); it; ++it)
        a.f(static_cast<int>(it.row()), static_cast<int>(it.col()), it.value());
  }
  /// Resistance and inertance of the segment whose flow is unknown `row`.
  void set_segment(Eigen::Index row, double resistance, double inertance) {
    f_.coeffRef(row, row) = resistance;
    e_.coeffRef(row, row) = inertance;
  }

 private:
  Eigen::SparseMatrix<double> e_, f_;
};

/// The boundary values c(t) = −Σ_k w_k(t) s_k: imposed pressures on Dirichlet rows, injected
/// flows on node rows, R_d⁻¹ P_d on RCR rows. Writes no matrix entry, so J stays constant.
class RlcBoundary final : public svzerod::Block {
 public:
  RlcBoundary(const Assembly& a, const std::vector<Eigen::VectorXd>& sources)
      : Block("rlc boundary"), a_(a), coef_(sources.size()) {
    const Eigen::Index n = sources.empty() ? 0 : sources[0].size();
    for (Eigen::Index i = 0; i < n; ++i) {
      bool any = false;
      for (const auto& s : sources) any = any || s[i] != 0.0;
      if (!any) continue;
      rows_.push_back(static_cast<int>(i));
      for (const auto& s : sources) values_.push_back(s[i]);
    }
    for (const auto& s : a_.sources) time_dependent_ = time_dependent_ || s.waveform != nullptr;
  }
  [[nodiscard]] const char* type() const override { return "RlcBoundary"; }
  [[nodiscard]] std::string check_connections() const override { return {}; }
  [[nodiscard]] int num_equations() const override { return 0; }
  void assemble(svzerod::Assembler& a, double t) const override {
    a_.coefficients(t, coef_.data());
    const size_t nk = coef_.size();
    for (size_t r = 0; r < rows_.size(); ++r) {
      double b = 0.0;
      for (size_t k = 0; k < nk; ++k) b += coef_[k] * values_[r * nk + k];
      a.c(rows_[r], -b);
    }
  }

 private:
  const Assembly& a_;
  mutable std::vector<double> coef_;
  std::vector<int> rows_;       // rows with a boundary value
  std::vector<double> values_;  // (rows × sources)
};

/// The segments' nonlinear losses (FlowSpec::segment_laws: a stenosis, a bend, a calibration):
/// what each lossy segment's law adds to its linear drop R Q, Δp(Q) − R Q, on its row
/// (R Q + L Q̇ − p_from + p_to + [Δp(Q) − R Q] = 0), and the junctions' static pressure changes
/// (junction.hpp): a segment's end at a junction is at p_J − δ, which adds +δ at its start and −δ
/// at its end to its row, δ a function of every flow at that junction. These are the system's only
/// nonlinear terms, so that the integrator iterates Newton's method within a step where a scene has
/// them. (The assembler sets entries, so each row's terms are summed here before they are written.)
class RlcLosses final : public svzerod::Block {
 public:
  struct Lossy {
    int row = -1;  // the segment's flow unknown, which is also its row
    SegmentLaw law;
    double resistance = 0.0;  // R: f R_P
  };
  RlcLosses(std::vector<Lossy> lossy, std::vector<Junction> junctions, std::vector<int> junction_rows,
            std::vector<std::vector<double>> junction_signs, double density)
      : Block("rlc losses"),
        lossy_(std::move(lossy)),
        junctions_(std::move(junctions)),
        rows_(std::move(junction_rows)),
        signs_(std::move(junction_signs)),
        density_(density) {}
  [[nodiscard]] const char* type() const override { return "RlcLosses"; }
  [[nodiscard]] std::string check_connections() const override { return {}; }
  [[nodiscard]] int num_equations() const override { return 0; }
  [[nodiscard]] bool nonlinear() const override { return true; }
  void assemble(svzerod::Assembler& /*a*/, double /*t*/) const override {}
  void assemble_nonlinear(svzerod::Assembler& a, double /*t*/, const Eigen::VectorXd& y,
                          const Eigen::VectorXd& /*yd*/) const override {
    c_.clear();
    d_.clear();
    for (const Lossy& l : lossy_) {
      const double q = y[l.row];
      c_[l.row] += l.law.pressure_drop(q, l.resistance) - l.resistance * q;
      d_[{l.row, l.row}] += l.law.slope(q, l.resistance) - l.resistance;
    }
    size_t first = 0;  // each junction's branches' rows and signs, in rows_ / signs_ order
    for (size_t i = 0; i < junctions_.size(); ++i) {
      const auto& j = junctions_[i];
      const size_t n = j.branches.size();
      outward_.resize(n);
      drop_.resize(n);
      jac_.resize(n * n);
      for (size_t b = 0; b < n; ++b) outward_[b] = j.branches[b].outward * y[rows_[first + b]];
      unified_junction_drops(j, density_, outward_.data(), drop_.data(), jac_.data());
      for (size_t b = 0; b < n; ++b) {
        const int row = rows_[first + b];
        const double sign = signs_[i][b];
        c_[row] += sign * drop_[b];
        for (size_t l = 0; l < n; ++l) d_[{row, rows_[first + l]}] += sign * jac_[b * n + l] * j.branches[l].outward;
      }
      first += n;
    }
    for (const auto& [row, v] : c_) a.c_nl(row, v);
    for (const auto& [rc, v] : d_) a.dy(rc.first, rc.second, v);
  }

 private:
  std::vector<Lossy> lossy_;
  std::vector<Junction> junctions_;
  std::vector<int> rows_;                   // every junction's branches' flow rows, junction after junction
  std::vector<std::vector<double>> signs_;  // +1: the branch's segment starts at its junction, −1: ends there
  double density_;
  mutable std::map<int, double> c_;
  mutable std::map<std::pair<int, int>, double> d_;
  mutable std::vector<double> outward_, drop_, jac_;
};

/// Unknown layout: [p (num_nodes) | Q (num_segments) | per RCR or coronary outlet its outflow and its own unknowns].
/// The equations E ẏ + F y + c(t) = 0 are two blocks on an svzerod::System, stepped by its generalized-α integrator: J
/// = α_m E + α_f γ Δt F is factorized (KLU) once for the phase and again only when a wire changes a segment.
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
    initial_state();
    for (auto& b : outlets_) b->prepare(st_.y, st_.yd, /*after_steady=*/true, spec_.cycle());
    system_->set_phase(/*steady=*/false, 0.0);
    factorize("the time-step matrix is singular; check that every piece of the network has a pressure reference");
    settle();
    timings_.factor = sf.seconds();
    prev_y_ = st_.y;
    prev_t_ = cur_t_ = 0.0;
    interpolate(0.0);
  }

  [[nodiscard]] std::string_view name() const override { return "rlc"; }
  [[nodiscard]] bool supports_occlusion() const override { return true; }
  [[nodiscard]] double node_pressure(int node) const override { return out_[static_cast<size_t>(node)]; }
  [[nodiscard]] double segment_flow(int s) const override { return out_[n_nodes_ + static_cast<size_t>(s)]; }
  [[nodiscard]] double segment_flow_at(int s, double t) const override {
    const auto k = static_cast<Eigen::Index>(n_nodes_ + static_cast<size_t>(s));
    if (cur_t_ <= prev_t_) return st_.y[k];
    const double w = std::clamp((t - prev_t_) / (cur_t_ - prev_t_), 0.0, 1.0);
    return (1.0 - w) * prev_y_[k] + w * st_.y[k];
  }
  [[nodiscard]] const PeriodicInfo& periodic() const { return periodic_; }
  [[nodiscard]] long factorizations() const { return system_->factorizations(); }

 protected:
  void do_advance(double t) override {
    if (t < cur_t_ - 1e-12 * spec_.dt && t < prev_t_) {
      throw_usage_error(fmt::format("flow (rlc): cannot go back in time from {} to {}", cur_t_, t));
    }
    while (cur_t_ < t - 1e-12 * spec_.dt) {
      prev_y_ = st_.y;
      prev_t_ = cur_t_;
      integrator_->step(st_, cur_t_ + t_offset_);
      cur_t_ += spec_.dt;
    }
    interpolate(t);
  }

  /// A wire in a segment scales its resistance and inertance: the segment rows are written
  /// again and J refactorized on the same pattern; the state integrates on from where it is.
  void apply_occlusion() override {
    for (size_t s = 0; s < static_cast<size_t>(net_.num_segments()); ++s) {
      const auto& o = occlusion_[s];
      network_->set_segment(static_cast<Eigen::Index>(n_nodes_ + s), resistance_[s] * o.resistance_factor,
                            inertance_[s] * o.inertance_factor);
    }
    system_->update_block(*network_, cur_t_ + t_offset_);
    factorize("the time-step matrix with the wire is singular");
  }

 private:
  void build() {
    n_nodes_ = static_cast<size_t>(net_.num_nodes());
    const auto ne = static_cast<size_t>(net_.num_segments());
    // Outlets with state (RCR, coronary) are their svZeroDSolver blocks, connected to their
    // node through an outflow unknown; each brings as many rows as unknowns.
    int next = static_cast<int>(n_nodes_ + ne);
    double period = spec_.cycle() > 0.0 ? spec_.cycle() : -1.0;
    for (const auto& o : spec_.outlets) {
      if (!o.dynamic() && o.type != OutletBC::Type::Rcr) continue;
      const std::string name = fmt::format("outlet at node {}", o.node);
      const nlohmann::json bc = o.to_svzerod(name);
      svzerod::BlockInput in(bc.at("bc_values"), "flow (rlc)", name, period);
      auto block = svzerod::Registry::instance().create(svzerod::Section::BoundaryCondition,
                                                        bc.at("bc_type").get<std::string>(), in);
      const int q = next++;
      block->add_inlet({name, q, o.node});
      const int own = static_cast<int>(block->internal_unknowns().size());
      block->place(q, next);
      next += own;
      outflow_.emplace_back(o.node, q);
      outlets_.push_back(std::move(block));
    }
    n_ = next;
    const auto n_rows = static_cast<Eigen::Index>(n_nodes_ + ne);
    std::vector<Eigen::Triplet<double>> te, tf;
    const auto qi = [&](size_t s) { return static_cast<int>(n_nodes_ + s); };
    std::vector<double> node_c(n_nodes_, 0.0);
    for (size_t s = 0; s < ne; ++s) {
      const auto& seg = net_.segment(static_cast<int>(s));
      const int row = qi(s);
      inertance_.push_back(
          segment_inertance(spec_.inertance, spec_.density, seg.length, seg.radius_from, seg.radius_to));
      te.emplace_back(row, row, inertance_.back());
      tf.emplace_back(row, row, resistance_[s]);
      tf.emplace_back(row, seg.node_from, -1.0);
      tf.emplace_back(row, seg.node_to, 1.0);
      const double c = spec_.segment_compliance(net_, static_cast<int>(s));
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
    for (const auto& [node, q] : outflow_)  // the outlet block's inflow leaves the node
      if (!a_.dirichlet[static_cast<size_t>(node)]) tf.emplace_back(node, q, 1.0);
    Eigen::SparseMatrix<double> e(n_rows, n_), f(n_rows, n_);
    e.setFromTriplets(te.begin(), te.end());
    f.setFromTriplets(tf.begin(), tf.end());
    // Boundary values per BC source: rows of the node values (pressure at Dirichlet rows,
    // injected flow elsewhere); the outlet blocks write their own.
    std::vector<Eigen::VectorXd> src(a_.sources.size(), Eigen::VectorXd::Zero(n_));
    for (size_t k = 0; k < a_.sources.size(); ++k)
      for (const auto& [node, value] : a_.sources[k].node_values) src[k][node] += value;
    network_ = std::make_unique<RlcNetwork>(std::move(e), std::move(f));
    boundary_ = std::make_unique<RlcBoundary>(a_, src);
    network_->place(0, static_cast<int>(n_nodes_));
    std::vector<svzerod::Block*> blocks{network_.get(), boundary_.get()};
    std::vector<RlcLosses::Lossy> lossy;
    for (size_t s = 0; s < spec_.segment_laws.size(); ++s)
      if (spec_.segment_laws[s].nonlinear()) lossy.push_back({qi(s), spec_.segment_laws[s], resistance_[s]});
    std::vector<int> jrows;
    std::vector<std::vector<double>> jsigns;
    for (const auto& j : spec_.junctions) {
      jsigns.emplace_back();
      for (const auto& b : j.branches) {
        jrows.push_back(qi(static_cast<size_t>(b.segment)));
        jsigns.back().push_back(net_.segment(b.segment).node_from == j.node ? 1.0 : -1.0);
      }
    }
    if (!lossy.empty() || !spec_.junctions.empty()) {
      losses_ = std::make_unique<RlcLosses>(std::move(lossy), spec_.junctions, std::move(jrows), std::move(jsigns),
                                            spec_.density);
      blocks.push_back(losses_.get());
    }
    for (auto& b : outlets_) blocks.push_back(b.get());
    system_ = std::make_unique<svzerod::System>(blocks, static_cast<int>(n_), spec_.cycle(), "flow (rlc)");
    // A linear system: one solve per step (tolerance 0 never skips it). With nonlinear losses,
    // Newton's method within each step to svZeroDSolver's absolute tolerance (the segment rows are
    // in Pa; the node balances are linear, so Newton leaves them at round-off).
    integrator_ =
        std::make_unique<svzerod::GeneralizedAlpha>(*system_, std::clamp(spec_.rho_infinity, 0.0, 1.0), spec_.dt,
                                                    losses_ ? kLossTolerance : 0.0, losses_ ? 30 : 1, "flow (rlc)");
    st_.y = Eigen::VectorXd::Zero(n_);
    st_.yd = Eigen::VectorXd::Zero(n_);
    prev_y_ = Eigen::VectorXd::Zero(n_);
    out_.assign(static_cast<size_t>(n_), 0.0);
  }

  /// J = α_m E + α_f γ Δt F for the step; `what` names a singular J.
  void factorize(const char* what) {
    try {
      system_->factorize(integrator_->alpha_m(), integrator_->alpha_f() * integrator_->gamma() * spec_.dt);
    } catch (const Error& e) {
      if (e.kind() != ErrorKind::Numerical) throw;
      throw_numerical_error(fmt::format("flow (rlc): {}", what));
    }
  }

  /// The steady solution at t = 0: F y + c(0) = 0 (J = F in the steady phase).
  void initial_state() {
    system_->set_phase(/*steady=*/true, 0.0);
    try {
      system_->factorize(0.0, 1.0);
    } catch (const Error& e) {
      if (e.kind() != ErrorKind::Numerical) throw;
      throw_numerical_error("flow (rlc): the steady system is singular");
    }
    st_.y.setZero();
    st_.yd.setZero();
    system_->residual(st_.y, st_.yd, prev_y_);  // c(0)
    system_->solve(prev_y_);
    st_.y = -prev_y_;
    // Nonlinear losses: Newton's method from the linear network's state.
    for (int it = 0; losses_; ++it) {
      system_->update_solution(0.0, st_.y, st_.yd);
      if (system_->residual(st_.y, st_.yd, 1.0, prev_y_) < kLossTolerance) break;
      if (it == 50 || !st_.y.allFinite())
        throw_numerical_error(
            fmt::format("flow (rlc): the steady state with nonlinear losses did not converge in {} Newton iterations "
                        "(residual {:.3g})",
                        it, prev_y_.lpNorm<Eigen::Infinity>()));
      system_->factorize(0.0, 1.0);
      system_->solve(prev_y_);
      st_.y -= prev_y_;
    }
    if (!st_.y.allFinite()) throw_numerical_error("flow (rlc): the initial state is not finite");
  }

  void settle() {
    const double period = spec_.cycle();
    if (!(period > 0.0)) return;
    const long steps = step_count(period, spec_.dt, "flow (rlc)", "the inlet period / solve.dt");
    if (std::abs(steps * spec_.dt - period) > 1e-9 * period)
      warn(fmt::format("flow (rlc): the step {} s does not divide the period {} s; periodic detection is approximate",
                       spec_.dt, period));
    Eigen::VectorXd start = st_.y;
    double t = 0.0;
    for (int c = 1; c <= spec_.max_cycles; ++c) {
      for (long k = 0; k < steps; ++k, t += spec_.dt) integrator_->step(st_, t);
      const double scale = std::max(st_.y.lpNorm<Eigen::Infinity>(), 1e-300);
      periodic_.cycles = c;
      periodic_.last_change = (st_.y - start).lpNorm<Eigen::Infinity>() / scale;
      if (periodic_.last_change <= spec_.periodic_tolerance) {
        periodic_.converged = true;
        t_offset_ = static_cast<double>(steps) * spec_.dt * c - static_cast<double>(c) * period;
        return;
      }
      start = st_.y;
    }
    periodic_.converged = false;
    warn(fmt::format("flow (rlc): no periodic state after {} cycles (last relative change {:.3g}); continuing",
                     spec_.max_cycles, periodic_.last_change));
  }

  void interpolate(double t) {
    const double w = cur_t_ > prev_t_ ? std::clamp((t - prev_t_) / (cur_t_ - prev_t_), 0.0, 1.0) : 1.0;
    for (Eigen::Index i = 0; i < n_; ++i) out_[static_cast<size_t>(i)] = (1.0 - w) * prev_y_[i] + w * st_.y[i];
  }

  Assembly a_;
  std::vector<std::unique_ptr<svzerod::Block>> outlets_;  // RCR and coronary outlets
  std::vector<std::pair<int, int>> outflow_;              // (node, outflow unknown) of each
  std::vector<double> inertance_;                         // (num_segments) without occlusion
  size_t n_nodes_ = 0;
  Eigen::Index n_ = 0;
  std::unique_ptr<RlcNetwork> network_;
  std::unique_ptr<RlcBoundary> boundary_;
  std::unique_ptr<RlcLosses> losses_;  // null without nonlinear losses
  std::unique_ptr<svzerod::System> system_;
  std::unique_ptr<svzerod::GeneralizedAlpha> integrator_;
  svzerod::State st_;
  Eigen::VectorXd prev_y_;
  std::vector<double> out_;
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

long rlc_factorizations(const FlowSolver& solver) {
  if (const auto* r = dynamic_cast<const detail::RlcSolver*>(&solver)) return r->factorizations();
  return 0;
}

}  // namespace flowire::flow
