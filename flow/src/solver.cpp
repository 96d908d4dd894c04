#include "flowire/flow/solver.hpp"

#include <fmt/format.h>

#include <unistd.h>
#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <cmath>

#include "assembly.hpp"
#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/profile.hpp"
#include "solvers.hpp"

namespace flowire::flow {
namespace {
constexpr double kPi = 3.14159265358979323846;
}

// ---------------------------------------------------------------------------------------
// FlowSolver: common queries

FlowSolver::FlowSolver(const Network& net, FlowSpec spec) : net_(net), spec_(std::move(spec)) {
  const double c = spec_.cycle();
  omega_ = c > 0.0 ? 2.0 * kPi / c : 0.0;
  axis_.resize(static_cast<size_t>(net_.num_segments()));
  for (int s = 0; s < net_.num_segments(); ++s) {
    const auto& seg = net_.segment(s);
    axis_[static_cast<size_t>(s)] = (net_.node(seg.node_to) - net_.node(seg.node_from)).normalized();
  }
}

void FlowSolver::advance(double t) {
  Stopwatch sw;
  do_advance(t);
  time_ = t;
  timings_.frames += sw.seconds();
  ++timings_.frame_count;
}

void FlowSolver::solve_at(double t, std::span<double> node_pressures_out, std::span<double> segment_flows_out) {
  advance(t);
  node_pressures(node_pressures_out);
  segment_flows(segment_flows_out);
}

double FlowSolver::segment_flow(int segment) const {
  const auto& seg = net_.segment(segment);
  return (node_pressure(seg.node_from) - node_pressure(seg.node_to)) / effective_resistance(segment);
}

void FlowSolver::set_occlusion(std::span<const SegmentOcclusion> occlusion) {
  if (!supports_occlusion())
    throw_usage_error(
        fmt::format("flow: the {} solver keeps its matrix; occlusion needs superposition, sparse or rlc", name()));
  if (occlusion.size() != static_cast<size_t>(net_.num_segments()))
    throw_usage_error(
        fmt::format("flow: occlusion for {} segments, the network has {}", occlusion.size(), net_.num_segments()));
  bool changed = occlusion_.empty();
  for (size_t s = 0; s < occlusion.size(); ++s) {
    const auto& o = occlusion[s];
    if (!(o.resistance_factor > 0.0) || !(o.inertance_factor > 0.0) || !(o.gradient_factor >= 1.0) ||
        !std::isfinite(o.resistance_factor) || !std::isfinite(o.inertance_factor) || !std::isfinite(o.gradient_factor))
      throw_usage_error(fmt::format("flow: occlusion of segment {}: factors {}, {} must be finite and > 0, {} >= 1", s,
                                    o.resistance_factor, o.inertance_factor, o.gradient_factor));
    if (!changed && (o.resistance_factor != occlusion_[s].resistance_factor ||
                     o.inertance_factor != occlusion_[s].inertance_factor))
      changed = true;
  }
  occlusion_.assign(occlusion.begin(), occlusion.end());
  if (!changed) return;
  Stopwatch sw;
  apply_occlusion();
  if (!harmonic_.empty() && harmonics_stale()) {
    compute_harmonics();
    harmonics_occlusion_ = occlusion_;
    ++timings_.harmonic_updates;
  }
  timings_.occlusion += sw.seconds();
  ++timings_.occlusion_updates;
}

void FlowSolver::node_pressures(std::span<double> out) const {
  if (out.size() != static_cast<size_t>(net_.num_nodes())) throw_usage_error("node_pressures: span size != num_nodes");
  for (int i = 0; i < net_.num_nodes(); ++i) out[static_cast<size_t>(i)] = node_pressure(i);
}

void FlowSolver::segment_flows(std::span<double> out) const {
  if (out.size() != static_cast<size_t>(net_.num_segments()))
    throw_usage_error("segment_flows: span size != num_segments");
  for (int s = 0; s < net_.num_segments(); ++s) out[static_cast<size_t>(s)] = segment_flow(s);
}

SegmentState FlowSolver::segment_state(int segment) const {
  const auto& seg = net_.segment(segment);
  SegmentState st;
  st.flow_rate = segment_flow(segment);
  st.pressure_from = node_pressure(seg.node_from);
  st.pressure_to = node_pressure(seg.node_to);
  const double r = seg.radius;
  st.mean_velocity = st.flow_rate / (kPi * r * r);
  st.wall_shear_stress = 4.0 * spec_.viscosity * std::abs(st.flow_rate) / (kPi * r * r * r);
  st.reynolds = spec_.density * std::abs(st.mean_velocity) * 2.0 * r / spec_.viscosity;
  st.womersley = omega_ > 0.0 ? womersley_number(r, omega_, spec_.density, spec_.viscosity) : 0.0;
  return st;
}

double FlowSolver::profile_velocity(int segment, double rho2, double t) const {
  if (rho2 >= 1.0) return 0.0;
  const auto& seg = net_.segment(segment);
  const double r = seg.radius;
  const double area = kPi * r * r;
  const double q = t == time_ ? segment_flow(segment) : segment_flow_at(segment, t);
  // Where a wire lies, the undisturbed velocity is the empty tube's under the occupied
  // part's pressure gradient (the annulus passes the segment's flow at a steeper one).
  const double g = occlusion_.empty() ? 1.0 : occlusion_[static_cast<size_t>(segment)].gradient_factor;
  const double laminar = 2.0 / area * (1.0 - rho2);  // the parabola per unit flow
  double u = laminar * q;
  if (harmonic_.empty()) return g * u;
  // Each harmonic swaps its quasi-steady parabola for its Womersley profile.
  const auto base = static_cast<size_t>(segment) * kHarmonics;
  const double rho = std::sqrt(rho2);
  const std::complex<double> step = std::polar(1.0, omega_ * t);
  std::complex<double> phase = 1.0;
  for (int n = 1; n <= kHarmonics; ++n) {
    phase *= step;  // e^{inωt}
    const auto k = base + static_cast<size_t>(n - 1);
    if (harmonic_[k] == 0.0) continue;
    if (!shape_[k]) {
      const double a_n =
          womersley_number(r, omega_, spec_.density, spec_.viscosity) * std::sqrt(static_cast<double>(n));
      auto& cached = shape_by_alpha_[a_n];
      if (!cached) cached = std::make_shared<const WomersleyShape>(a_n);
      shape_[k] = cached;
    }
    const std::complex<double> qn = harmonic_[k] * phase;
    u += ((*shape_[k])(rho)*qn).real() / area - laminar * qn.real();
  }
  return g * u;
}

double FlowSolver::axial_velocity_at(int segment, const Vec3& p) const { return axial_velocity_at(segment, p, time_); }

double FlowSolver::axial_velocity_at(int segment, const Vec3& p, double t) const {
  const auto& seg = net_.segment(segment);
  const Vec3 rel = p - net_.node(seg.node_from);
  const Vec3& e = axis_[static_cast<size_t>(segment)];
  const double d2 = std::max(0.0, rel.squaredNorm() - std::pow(rel.dot(e), 2));
  return profile_velocity(segment, d2 / (seg.radius * seg.radius), t);
}

Vec3 FlowSolver::velocity_at(int segment, const Vec3& p) const {
  return axial_velocity_at(segment, p, time_) * axis_[static_cast<size_t>(segment)];
}

Vec3 FlowSolver::velocity_at(int segment, const Vec3& p, double t) const {
  return axial_velocity_at(segment, p, t) * axis_[static_cast<size_t>(segment)];
}

void FlowSolver::prepare_profile() {
  if (spec_.profile != Profile::Womersley) return;
  const double period = spec_.cycle();
  bool periodic = omega_ > 0.0 && spec_.model == Model::Poiseuille;
  for (const auto& in : spec_.inlets) {
    const double c = in.waveform.cycle();
    if (!(in.waveform.is_constant() || std::abs(c - period) <= 1e-12 * period)) periodic = false;
  }
  if (!periodic) {
    warn(
        "flow.profile: womersley needs the quasi-steady model driven by periodic waveforms of one period; "
        "using the laminar profile");
    return;
  }
  const auto ne = static_cast<size_t>(net_.num_segments());
  shape_.assign(ne * kHarmonics, nullptr);
  compute_harmonics();
}

bool FlowSolver::harmonics_stale() const {
  if (!(harmonics_occlusion_tolerance_ > 0.0) || harmonics_occlusion_.size() != occlusion_.size()) return true;
  const double tol = harmonics_occlusion_tolerance_;
  for (size_t s = 0; s < occlusion_.size(); ++s) {
    const auto &now = occlusion_[s], &then = harmonics_occlusion_[s];
    if (std::abs(now.resistance_factor / then.resistance_factor - 1.0) > tol ||
        std::abs(now.inertance_factor / then.inertance_factor - 1.0) > tol)
      return true;
  }
  return false;
}

void FlowSolver::compute_harmonics() {
  // Q̂_n = (2/M) Σ_m Q(t_m) e^{−inωt_m} over one period (the quasi-steady model gives Q at any t).
  const double period = spec_.cycle();
  const auto ne = static_cast<size_t>(net_.num_segments());
  harmonic_.assign(ne * kHarmonics, 0.0);
  std::vector<double> magnitude(ne, 0.0);
  for (int m = 0; m < kSamplesPerPeriod; ++m) {
    const double tm = period * m / kSamplesPerPeriod;
    const std::complex<double> step = std::polar(1.0, -omega_ * tm);
    for (size_t s = 0; s < ne; ++s) {
      const double q = segment_flow_at(static_cast<int>(s), tm);
      magnitude[s] = std::max(magnitude[s], std::abs(q));
      std::complex<double> phase = 1.0;
      for (int n = 1; n <= kHarmonics; ++n) {
        phase *= step;
        harmonic_[s * kHarmonics + static_cast<size_t>(n - 1)] += (2.0 / kSamplesPerPeriod) * q * phase;
      }
    }
  }
  drop_negligible_harmonics(magnitude);
}

void FlowSolver::drop_negligible_harmonics(std::span<const double> scale) {
  // A harmonic the waveform does not have (a sine has one) is left to the parabola.
  for (size_t s = 0; s < scale.size(); ++s)
    for (int n = 0; n < kHarmonics; ++n)
      if (std::norm(harmonic_[s * kHarmonics + static_cast<size_t>(n)]) <= 1e-18 * scale[s] * scale[s])
        harmonic_[s * kHarmonics + static_cast<size_t>(n)] = 0.0;
}

// ---------------------------------------------------------------------------------------
// Solvers of the quasi-steady model

namespace detail {

ResponseSolver::ResponseSolver(const Network& net, FlowSpec spec) : FlowSolver(net, std::move(spec)) {
  Stopwatch sw;
  a_ = assemble(net_, spec_, resistance_);
  timings_.assemble = sw.seconds();
}

Eigen::MatrixXd ResponseSolver::source_rhs() const {
  const int nu = a_.num_unknowns();
  const int k = a_.num_sources();
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(nu, k);
  Eigen::VectorXd col(nu);
  for (int j = 0; j < k; ++j) {
    col.setZero();
    add_nodal_rhs(net_, a_, a_.sources[static_cast<size_t>(j)], 1.0, col);
    b.col(j) = col;
  }
  return b;
}

void ResponseSolver::set_responses(const Eigen::MatrixXd& x) {
  k_ = a_.num_sources();
  const auto kk = static_cast<size_t>(k_);
  if (!x.allFinite()) throw_numerical_error("flow: the network solve produced non-finite pressures");
  p_.assign(static_cast<size_t>(net_.num_nodes()) * kk, 0.0);
  for (int u = 0; u < a_.num_unknowns(); ++u) {
    const auto i = static_cast<size_t>(a_.node_of_unknown[static_cast<size_t>(u)]);
    for (int k = 0; k < k_; ++k) p_[i * kk + static_cast<size_t>(k)] = x(u, k);
  }
  for (size_t k = 0; k < kk; ++k)
    for (const auto& [node, value] : a_.sources[k].node_values)
      if (a_.dirichlet[static_cast<size_t>(node)]) p_[static_cast<size_t>(node) * kk + k] += value;
  coef_.assign(kk, 0.0);
  a_.coefficients(time_, coef_.data());
}

void ResponseSolver::update_conductances() {
  for (size_t s = 0; s < a_.conductance.size(); ++s)
    a_.conductance[s] = 1.0 / effective_resistance(static_cast<int>(s));
}

void ResponseSolver::compute_harmonics() {
  // The flow is linear in the sources: Q̂_{s,n} = g_s Σ_k (p_k,from − p_k,to) f̂_{k,n}, with
  // f̂_{k,n} the harmonics of source k's waveform, sampled once; a new occlusion then costs
  // num_segments × k × kHarmonics, not a resampling of every segment.
  const double period = spec_.cycle();
  const auto kk = static_cast<size_t>(k_);
  if (source_harmonic_.empty()) {
    source_harmonic_.assign(kk * kHarmonics, 0.0);
    for (size_t k = 1; k < kk; ++k) {
      const Waveform& w = *a_.sources[k].waveform;
      for (int m = 0; m < kSamplesPerPeriod; ++m) {
        const double tm = period * m / kSamplesPerPeriod;
        const std::complex<double> step = std::polar(1.0, -omega_ * tm);
        std::complex<double> phase = 1.0;
        for (int n = 1; n <= kHarmonics; ++n) {
          phase *= step;
          source_harmonic_[k * kHarmonics + static_cast<size_t>(n - 1)] += (2.0 / kSamplesPerPeriod) * w(tm) * phase;
        }
      }
    }
    source_harmonic_size_.assign(kk, 0.0);
    for (size_t k = 1; k < kk; ++k)
      for (int n = 0; n < kHarmonics; ++n)
        source_harmonic_size_[k] += std::abs(source_harmonic_[k * kHarmonics + static_cast<size_t>(n)]);
  }
  const auto ne = static_cast<size_t>(net_.num_segments());
  harmonic_.assign(ne * kHarmonics, 0.0);
  std::vector<double> magnitude(ne, 0.0);
  for (size_t s = 0; s < ne; ++s) {
    const auto& seg = net_.segment(static_cast<int>(s));
    const double* a = p_.data() + static_cast<size_t>(seg.node_from) * kk;
    const double* b = p_.data() + static_cast<size_t>(seg.node_to) * kk;
    const double g = a_.conductance[s];
    magnitude[s] = std::abs(g * (a[0] - b[0]));
    for (size_t k = 1; k < kk; ++k) {
      const double dq = g * (a[k] - b[k]);
      for (int n = 0; n < kHarmonics; ++n)
        harmonic_[s * kHarmonics + static_cast<size_t>(n)] +=
            source_harmonic_[k * kHarmonics + static_cast<size_t>(n)] * dq;
      magnitude[s] += std::abs(dq) * source_harmonic_size_[k];  // Σ_n |f̂_{k,n} dq|, without a modulus each
    }
  }
  drop_negligible_harmonics(magnitude);
}

double ResponseSolver::node_pressure(int node) const {
  const double* row = p_.data() + static_cast<size_t>(node) * static_cast<size_t>(k_);
  double v = 0.0;
  for (int k = 0; k < k_; ++k) v += coef_[static_cast<size_t>(k)] * row[k];
  return v;
}

double ResponseSolver::segment_flow_at(int segment, double t) const {
  const auto& seg = net_.segment(segment);
  const double* a = p_.data() + static_cast<size_t>(seg.node_from) * static_cast<size_t>(k_);
  const double* b = p_.data() + static_cast<size_t>(seg.node_to) * static_cast<size_t>(k_);
  double dp = a[0] - b[0];
  for (int k = 1; k < k_; ++k) dp += (*a_.sources[static_cast<size_t>(k)].waveform)(t) * (a[k] - b[k]);
  return dp * a_.conductance[static_cast<size_t>(segment)];
}

void ResponseSolver::node_pressures(std::span<double> out) const {
  if (out.size() != static_cast<size_t>(net_.num_nodes())) throw_usage_error("node_pressures: span size != num_nodes");
  const auto kk = static_cast<size_t>(k_);
  if (kk == 1) {
    for (size_t i = 0; i < out.size(); ++i) out[i] = coef_[0] * p_[i];
    return;
  }
  for (size_t i = 0; i < out.size(); ++i) {
    const double* row = p_.data() + i * kk;
    double v = 0.0;
    for (size_t k = 0; k < kk; ++k) v += coef_[k] * row[k];
    out[i] = v;
  }
}

void ResponseSolver::segment_flows(std::span<double> out) const {
  if (out.size() != static_cast<size_t>(net_.num_segments()))
    throw_usage_error("segment_flows: span size != num_segments");
  const auto kk = static_cast<size_t>(k_);
  for (size_t s = 0; s < out.size(); ++s) {
    const auto& seg = net_.segment(static_cast<int>(s));
    const double* a = p_.data() + static_cast<size_t>(seg.node_from) * kk;
    const double* b = p_.data() + static_cast<size_t>(seg.node_to) * kk;
    double dp = 0.0;
    for (size_t k = 0; k < kk; ++k) dp += coef_[k] * (a[k] - b[k]);
    out[s] = dp * a_.conductance[s];
  }
}

/// Superposition: the responses solved with one CHOLMOD factorization; an occlusion
/// refactors the same pattern (numeric only) and re-solves the responses.
class SuperpositionSolver final : public ResponseSolver {
 public:
  SuperpositionSolver(const Network& net, FlowSpec spec) : ResponseSolver(net, std::move(spec)) {
    Stopwatch sw;
    g_ = nodal_matrix(net_, a_);
    b_ = source_rhs();
    timings_.assemble += sw.seconds();
    Stopwatch sf;
    if (b_.rows() > 0) chol_.analyzePattern(g_);
    solve_responses();
    timings_.factor = sf.seconds();
  }
  [[nodiscard]] std::string_view name() const override { return "superposition"; }
  [[nodiscard]] bool supports_occlusion() const override { return true; }

 protected:
  void apply_occlusion() override {
    update_conductances();
    g_ = nodal_matrix(net_, a_);
    b_ = source_rhs();  // a pressure source enters through the conductances next to it
    solve_responses();
  }

 private:
  void solve_responses() {
    Eigen::MatrixXd x(b_.rows(), b_.cols());
    if (b_.rows() > 0) {
      chol_.factorize(g_);
      if (chol_.info() != Eigen::Success)
        throw_numerical_error("flow: the nodal conductance matrix could not be factored (not positive definite)");
      x = chol_.solve(b_);
    }
    set_responses(x);
  }
  Eigen::SparseMatrix<double> g_;
  Eigen::MatrixXd b_;
  Eigen::CholmodSimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> chol_;
};

/// Sparse direct reference: the full right-hand side solved every frame (Eigen LDLᵀ).
class SparseSolver final : public FrameSolver {
 public:
  SparseSolver(const Network& net, FlowSpec spec) : FrameSolver(net, std::move(spec)) {
    Stopwatch sw;
    a_ = assemble(net_, spec_, resistance_);
    const auto g = nodal_matrix(net_, a_);
    const int nu = a_.num_unknowns();
    b_.resize(static_cast<size_t>(a_.num_sources()));
    for (size_t k = 0; k < b_.size(); ++k) {
      b_[k] = Eigen::VectorXd::Zero(nu);
      add_nodal_rhs(net_, a_, a_.sources[k], 1.0, b_[k]);
    }
    timings_.assemble = sw.seconds();
    Stopwatch sf;
    if (nu > 0) {
      ldlt_.compute(g);
      if (ldlt_.info() != Eigen::Success) throw_numerical_error("flow: the nodal conductance matrix is singular");
    }
    coef_.resize(b_.size());
    rhs_ = Eigen::VectorXd::Zero(nu);
    x_ = Eigen::VectorXd::Zero(nu);
    timings_.factor = sf.seconds();
    init_arrays();
  }
  [[nodiscard]] std::string_view name() const override { return "sparse"; }
  [[nodiscard]] bool supports_occlusion() const override { return true; }

 protected:
  void apply_occlusion() override {
    for (size_t s = 0; s < a_.conductance.size(); ++s)
      a_.conductance[s] = 1.0 / effective_resistance(static_cast<int>(s));
    for (size_t k = 0; k < b_.size(); ++k) {  // a pressure source enters through the conductances next to it
      b_[k].setZero();
      add_nodal_rhs(net_, a_, a_.sources[k], 1.0, b_[k]);
    }
    if (a_.num_unknowns() > 0) {
      ldlt_.factorize(nodal_matrix(net_, a_));
      if (ldlt_.info() != Eigen::Success) throw_numerical_error("flow: the nodal conductance matrix is singular");
    }
    scratch_q_.clear();
    compute(time_, p_.data(), q_.data());
  }

  void compute(double t, double* p, double* q) const override {
    a_.coefficients(t, coef_.data());
    rhs_.setZero();
    for (size_t k = 0; k < b_.size(); ++k) rhs_.noalias() += coef_[k] * b_[k];
    if (rhs_.size() > 0) x_ = ldlt_.solve(rhs_);
    for (int i = 0; i < net_.num_nodes(); ++i) {
      const int u = a_.unknown_of_node[static_cast<size_t>(i)];
      p[i] = u >= 0 ? x_[u] : 0.0;
    }
    for (size_t k = 0; k < b_.size(); ++k) add_dirichlet(a_, a_.sources[k], coef_[k], p);
    for (int s = 0; s < net_.num_segments(); ++s) {
      const auto& seg = net_.segment(s);
      q[s] = (p[seg.node_from] - p[seg.node_to]) * a_.conductance[static_cast<size_t>(s)];
    }
  }

 private:
  Assembly a_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt_;
  std::vector<Eigen::VectorXd> b_;
  mutable std::vector<double> coef_;
  mutable Eigen::VectorXd rhs_, x_;
};

/// The published method: K = [A 0; C −Aᵀ] over [Q; P], inverted densely once.
/// Rows 0..N−1: node balance (A Q + g_out P = injected flow) or P = prescribed pressure;
/// rows N..N+E−1: R_s Q_s − (P_from − P_to) = 0.
class DenseInverseSolver final : public FrameSolver {
 public:
  DenseInverseSolver(const Network& net, FlowSpec spec) : FrameSolver(net, std::move(spec)) {
    const auto nn = static_cast<Eigen::Index>(net_.num_nodes());
    const auto ne = static_cast<Eigen::Index>(net_.num_segments());
    const Eigen::Index m = nn + ne;
    const double bytes = dense_inverse_bytes(net_.num_nodes(), net_.num_segments());
    const double limit = spec_.dense_memory_limit > 0.0 ? spec_.dense_memory_limit : 0.5 * physical_memory_bytes();
    if (bytes > limit)
      throw_input_error("flow.solver: dense_inverse",
                        fmt::format("the published dense K⁻¹ of this network ({} nodes + {} segments = {}² entries) "
                                    "needs {:.3g} GB, above the limit of {:.3g} GB; use flow.solver: superposition "
                                    "(same answer, factored sparse)",
                                    nn, ne, m, bytes / 1e9, limit / 1e9));
    Stopwatch sw;
    a_ = assemble(net_, spec_, resistance_);
    Eigen::MatrixXd k = Eigen::MatrixXd::Zero(m, m);
    for (Eigen::Index i = 0; i < nn; ++i) {
      if (a_.dirichlet[static_cast<size_t>(i)]) {
        k(i, ne + i) = 1.0;
      } else {
        k(i, ne + i) = a_.outlet_conductance[static_cast<size_t>(i)];
      }
    }
    for (Eigen::Index s = 0; s < ne; ++s) {
      const auto& seg = net_.segment(static_cast<int>(s));
      if (!a_.dirichlet[static_cast<size_t>(seg.node_from)]) k(seg.node_from, s) += 1.0;
      if (!a_.dirichlet[static_cast<size_t>(seg.node_to)]) k(seg.node_to, s) -= 1.0;
      k(nn + s, s) = resistance_[static_cast<size_t>(s)];
      k(nn + s, ne + seg.node_from) = -1.0;
      k(nn + s, ne + seg.node_to) = 1.0;
    }
    timings_.assemble = sw.seconds();
    Stopwatch sf;
    Eigen::PartialPivLU<Eigen::MatrixXd> lu(k);
    k.resize(0, 0);
    const double rc = lu.rcond();
    if (!(rc > 1e-300))
      throw_numerical_error(fmt::format("flow: the published system K is singular (rcond {:.3g})", rc));
    kinv_ = lu.inverse();
    if (!kinv_.allFinite()) throw_numerical_error("flow: the dense inverse of K is not finite");
    coef_.resize(static_cast<size_t>(a_.num_sources()));
    rhs_ = Eigen::VectorXd::Zero(m);
    y_ = Eigen::VectorXd::Zero(m);
    timings_.factor = sf.seconds();
    init_arrays();
  }
  [[nodiscard]] std::string_view name() const override { return "dense_inverse"; }

 protected:
  void compute(double t, double* p, double* q) const override {
    const auto nn = static_cast<Eigen::Index>(net_.num_nodes());
    const auto ne = static_cast<Eigen::Index>(net_.num_segments());
    a_.coefficients(t, coef_.data());
    rhs_.setZero();
    for (size_t k = 0; k < coef_.size(); ++k)
      for (const auto& [node, value] : a_.sources[k].node_values) rhs_[node] += coef_[k] * value;
    y_.noalias() = kinv_ * rhs_;  // the published per-frame cost: a dense (N+E)² product
    for (Eigen::Index s = 0; s < ne; ++s) q[s] = y_[s];
    for (Eigen::Index i = 0; i < nn; ++i) p[i] = y_[ne + i];
  }

 private:
  Assembly a_;
  Eigen::MatrixXd kinv_;
  mutable std::vector<double> coef_;
  mutable Eigen::VectorXd rhs_, y_;
};

double physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
  return pages > 0 && size > 0 ? static_cast<double>(pages) * static_cast<double>(size) : 8e9;
}

double dense_inverse_bytes(int nodes, int segments) {
  const double m = static_cast<double>(nodes) + static_cast<double>(segments);
  return 2.0 * 8.0 * m * m;
}

}  // namespace detail

std::unique_ptr<FlowSolver> make_solver(const Network& net, FlowSpec spec) {
  resolve_nodes(spec, net);
  std::unique_ptr<FlowSolver> s;
  if (spec.model == Model::Rlc) {
    s = detail::make_rlc_solver(net, std::move(spec));
  } else if (spec.has_nonlinear_losses()) {
    // Superposition does not hold for a nonlinear network: every frame is solved by Newton.
    if (spec.solver == SolverKind::DenseInverse || spec.solver == SolverKind::Petsc)
      throw_input_error("flow",
                        fmt::format("nonlinear segment losses (a calibration, flow.losses) need the superposition or "
                                    "sparse solver (solved by Newton's method every frame), not {}",
                                    to_string(spec.solver)));
    s = detail::make_newton_solver(net, std::move(spec));
  } else {
    switch (spec.solver) {
      case SolverKind::Superposition:
        s = std::make_unique<detail::SuperpositionSolver>(net, std::move(spec));
        break;
      case SolverKind::Sparse:
        s = std::make_unique<detail::SparseSolver>(net, std::move(spec));
        break;
      case SolverKind::DenseInverse:
        s = std::make_unique<detail::DenseInverseSolver>(net, std::move(spec));
        break;
      case SolverKind::Petsc:
        s = detail::make_petsc_solver(net, std::move(spec));
        break;
    }
  }
  s->prepare_profile();
  return s;
}

}  // namespace flowire::flow
