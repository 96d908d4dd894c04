#pragma once
// Internal: factories of the solvers that live in their own files.
#include <memory>

#include <Eigen/Dense>
#include <complex>
#include <vector>

#include "assembly.hpp"
#include "flowire/flow/solver.hpp"

namespace flowire::flow::detail {

/// A quasi-steady solver that stores the node-pressure response p_k to each source k
/// (unit value, all others zero); a frame is p(t) = sum_k f_k(t) p_k, evaluated only
/// where asked. Subclasses solve G X = B and call set_responses(X).
class ResponseSolver : public FlowSolver {
 public:
  [[nodiscard]] double node_pressure(int node) const override;
  [[nodiscard]] double segment_flow_at(int segment, double t) const override;
  void node_pressures(std::span<double> out) const override;
  void segment_flows(std::span<double> out) const override;
  [[nodiscard]] int num_sources() const { return k_; }

 protected:
  ResponseSolver(const Network& net, FlowSpec spec);
  void do_advance(double t) override { a_.coefficients(t, coef_.data()); }
  /// Right-hand sides of the nodal system, one column per source (num_unknowns x k).
  [[nodiscard]] Eigen::MatrixXd source_rhs() const;
  /// Store the solutions over unknown nodes (num_unknowns x k).
  void set_responses(const Eigen::MatrixXd& x);
  /// Conductances 1/(R × resistance_factor) after an occlusion.
  void update_conductances();
  /// Harmonics from the sources' waveform harmonics (no resampling of the segments).
  void compute_harmonics() override;
  Assembly a_;
  int k_ = 0;
  std::vector<double> p_;                              // (num_nodes x k) node pressure response to each source
  std::vector<double> coef_;                           // (k) f_k(time)
  std::vector<std::complex<double>> source_harmonic_;  // (k x kHarmonics) of each waveform, once
  std::vector<double> source_harmonic_size_;           // (k) Σ_n |f̂_{k,n}|, once
};

/// Base of the solvers that compute full arrays every frame.
class FrameSolver : public FlowSolver {
 public:
  [[nodiscard]] double node_pressure(int node) const override { return p_[static_cast<size_t>(node)]; }
  [[nodiscard]] double segment_flow(int segment) const override { return q_[static_cast<size_t>(segment)]; }
  [[nodiscard]] double segment_flow_at(int segment, double t) const override {
    if (t == time_) return q_[static_cast<size_t>(segment)];
    if (scratch_time_ != t || scratch_q_.empty()) {
      scratch_p_.resize(p_.size());
      scratch_q_.resize(q_.size());
      compute(t, scratch_p_.data(), scratch_q_.data());
      scratch_time_ = t;
    }
    return scratch_q_[static_cast<size_t>(segment)];
  }

 protected:
  FrameSolver(const Network& net, FlowSpec spec) : FlowSolver(net, std::move(spec)) {}
  void do_advance(double t) override { compute(t, p_.data(), q_.data()); }
  /// Full node pressures and segment flows at time t.
  virtual void compute(double t, double* p, double* q) const = 0;
  void init_arrays() {
    p_.assign(static_cast<size_t>(net_.num_nodes()), 0.0);
    q_.assign(static_cast<size_t>(net_.num_segments()), 0.0);
    compute(0.0, p_.data(), q_.data());
  }
  std::vector<double> p_, q_;
  mutable std::vector<double> scratch_p_, scratch_q_;
  mutable double scratch_time_ = 0.0;
};

/// Bytes the dense_inverse solver needs for K and K⁻¹.
double dense_inverse_bytes(int nodes, int segments);
/// Physical memory of the machine (bytes).
double physical_memory_bytes();
/// The rlc (resistance–inertance–compliance) model, rlc.cpp.
std::unique_ptr<FlowSolver> make_rlc_solver(const Network& net, FlowSpec spec);
/// The quasi-steady network with quadratic losses (FlowSpec::segment_laws), Newton's method
/// every frame (newton_solver.cpp).
std::unique_ptr<FlowSolver> make_newton_solver(const Network& net, FlowSpec spec);
/// PETSc solver (petsc_solver.cpp), or an input error when PETSc is not built in.
std::unique_ptr<FlowSolver> make_petsc_solver(const Network& net, FlowSpec spec);

}  // namespace flowire::flow::detail
