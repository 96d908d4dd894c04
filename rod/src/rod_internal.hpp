#pragma once
// The rod's private pieces shared by its source files: the parts' work buffers and a few small
// helpers. The sources, by part:
//   simulator.cpp          the façade: construction, diagnostics (energy, strain)
//   feeder.cpp             the vertex set, the clamps, the rest layout, the feed predictor
//   adapt.cpp              the feeder's adaptive refinement and resampling
//   stepper.cpp            the integrators (implicit Euler, implicit midpoint, statics), substeps,
//                          checkpoints, speed- and force-driven feeding of a step
//   stepper_assembly.cpp   loads, energy, gradient and banded Hessian of a stage
//   stepper_stage.cpp      a solve as the problem of Newton's method (newton.hpp, its own part):
//                          the merit, the trial moves along a direction, the residual
//   stepper_coupled.cpp    one step's parts for a Newton iteration over several rods
#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <vector>

#include "flowire/rod/banded.hpp"
#include "flowire/rod/feeder.hpp"
#include "flowire/rod/stepper.hpp"

namespace flowire::rod::detail {

inline constexpr int kBandwidth = 10;  // stencil (x_{k-1}, θ_{k-1}, x_k, θ_k, x_{k+1}) spans 11 unknowns

inline Mat3 sym(const Mat3& a) { return 0.5 * (a + a.transpose()); }

inline bool finite(const Eigen::Ref<const Eigen::VectorXd>& v) { return v.allFinite(); }

/// The symmetric matrix's negative eigenvalues set to zero.
inline Mat3 positive_part(const Mat3& a) {
  Eigen::SelfAdjointEigenSolver<Mat3> es;
  es.computeDirect(a);
  const Eigen::Vector3d lambda = es.eigenvalues().cwiseMax(0.0);
  return es.eigenvectors() * lambda.asDiagonal() * es.eigenvectors().transpose();
}
inline Eigen::Matrix<double, 6, 6> positive_part6(const Eigen::Matrix<double, 6, 6>& a) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> es(a);
  const Eigen::Matrix<double, 6, 1> lambda = es.eigenvalues().cwiseMax(0.0);
  return es.eigenvectors() * lambda.asDiagonal() * es.eigenvectors().transpose();
}

/// The inserted length held between two segments and the wire's length.
/// The cubic Hermite curve from @p x0 to @p x1 with unit tangents @p t0, @p t1 scaled by the
/// @p chord, at parameter @p a (0 at x0, 1 at x1).
inline Vec3 hermite(const Vec3& x0, const Vec3& t0, const Vec3& x1, const Vec3& t1, double chord, double a) {
  const double a2 = a * a, a3 = a2 * a;
  return (2.0 * a3 - 3.0 * a2 + 1.0) * x0 + (a3 - 2.0 * a2 + a) * chord * t0 + (3.0 * a2 - 2.0 * a3) * x1 +
         (a3 - a2) * chord * t1;
}

inline double clamp_inserted(double L, const RodModel& m, bool& clamped) {
  const double lo = 2.0 * m.h, hi = m.length;
  clamped = L < lo || L > hi;
  return std::clamp(L, lo, hi);
}

/// The state's configuration (positions, angles, frames, reference twists) set to copies kept
/// elsewhere (a step's start, the line search's accepted iterate).
inline void set_configuration(RodState& s, const std::vector<Vec3>& x, const std::vector<double>& theta,
                              const std::vector<EdgeFrame>& frame, const std::vector<double>& twist) {
  s.x = x;
  s.theta = theta;
  s.frame = frame;
  s.ref_twist = twist;
}

/// Edge frames of @p frame_from parallel-transported to the edges of @p x_new, and the reference
/// twists at the vertices between them (carried on from @p twist_from); in place is allowed.
void transport_frames_to(const std::vector<Vec3>& x_new, const std::vector<EdgeFrame>& frame_from,
                         const std::vector<double>& twist_from, std::vector<EdgeFrame>& frame_to,
                         std::vector<double>& twist_to);

}  // namespace flowire::rod::detail

namespace flowire::rod {

/// The stepper's buffers, sized once for the whole wire, so that a step allocates nothing.
/// Sizes: nd = 4 nv − 1 unknowns (x_k and θ_k interleaved: q = (x_0, θ_0, x_1, θ_1, …,
/// x_{nv−1})), nv vertices, ne = nv − 1 edges.
struct TimeStepper::Work {
  explicit Work(int nvmax, int max_subdivisions);
  int max_dof = 0;

  // Step start (stepper.cpp): for velocities, the inertial target and rollback.
  std::vector<Vec3> x0, v0;                       ///< (nv)
  std::vector<double> theta0, omega0, twist0;     ///< (ne)
  std::vector<EdgeFrame> frame0;                  ///< (ne)
  Eigen::VectorXd q0;                             ///< (nd) unknowns at the step start
  Eigen::VectorXd qhat;                           ///< (nd) inertial target q₀ + h q̇₀
  std::vector<Vec3> x_end;                        ///< (nv) where the last implicit Euler step ended …
  double h_end = 0.0;                             ///< … and its step, for the next step's predictor
  double feed_end = 0.0;                          ///< … and its feed speed [m/s]
  std::vector<Vec3> path_x;                       ///< (nv) the path the last implicit Euler step started from …
  std::vector<double> path_u;                     ///< … its vertices' material coordinates …
  double path_inserted = 0.0;                     ///< … and its inserted length [m]
  double inserted0 = 0.0;                         ///< the inserted length at this step's start [m]
  std::vector<Vec3> guess_slide, guess_inertial;  ///< (free vertices) this step's two guesses (none: no slide) …
  double slide_miss = -1.0, inertial_miss = -1.0;  ///< … the last step's largest squared miss of each [m²] (< 0: none)
  std::vector<Vec3> v_guess;                       ///< (nv) velocity of Newton's initial guess
  std::vector<double> omega_guess;                 ///< (ne)
  std::vector<Vec3> x_mid;                         ///< (nv) implicit midpoint: positions at the midpoint
  struct Saved {                                   ///< a step start kept for a retry in substeps
    RodState state;
    double target_angle = 0.0, insertion_speed = 0.0;
    int first_clamped = 0;
    Vec3 base_force = Vec3::Zero(), base_torque = Vec3::Zero();
    size_t trace_size = 0;
  };
  std::vector<Saved> saved;  ///< one per subdivision level
  /// A checkpoint kept for a caller (save_checkpoint): a step start and what the next step's
  /// guess is made from.
  struct Checkpoint {
    Saved at;
    std::vector<Vec3> x_end, v0, path_x;
    std::vector<double> omega0, path_u;
    double h_end = 0.0, feed_end = 0.0, path_inserted = 0.0, slide_miss = -1.0, inertial_miss = -1.0;
    bool valid = false;
  } checkpoint;
  std::vector<Vec3> guess_x;        ///< a caller's initial guess for the next stage (restore_checkpoint) …
  std::vector<double> guess_theta;  ///< … its material angles; empty: none
  double h_newton = 0.0;            ///< the step of the last dynamic Newton solve (a substep's if halved)

  // Assembly (stepper_assembly.cpp).
  Eigen::VectorXd mass, damp;       ///< (nd) lumped mass and damping diagonals
  Eigen::VectorXd fext;             ///< (nd) loads: gravity, point forces, external forces
  Eigen::VectorXd fcons;            ///< (nd) the conservative part of fext (it has a potential)
  double ext_energy = 0.0;          ///< potential of the conservative external forces
  std::vector<EdgeGeometry> edges;  ///< (ne) tangent, length, material frame
  Mat3 moment_k = Mat3::Zero();     ///< −∂f₁/∂e of the tip couple, symmetrized
  ForceAccumulator acc;             ///< what the external forces return
  std::vector<Vec3> vel;            ///< (nv) vertex velocities at the iterate, for the externals
  std::vector<double> spin;         ///< (ne) edge spin rates at the iterate, for the externals
  std::vector<Vec3> tangent;        ///< (ne) edge tangents at the iterate, for the externals
  std::vector<Mat3> ext_k;          ///< (nv) −∂f/∂x − ∂f/∂v / h, symmetrized
  bool has_ext_k = false;
  std::vector<Eigen::Matrix<double, 6, 6>> ext_edge_k;  ///< (ne) −∂(f_j, f_j+1)/∂(x_j, x_j+1), symmetrized
  bool has_ext_edge_k = false;
  LowRankStiffness coupled;        ///< the external forces' coupled stiffness (dofs: 4·vertex)
  std::vector<double> ext_spin_k;  ///< (ne) −∂τ/∂ω / h

  // A solve (stepper_stage.cpp): its iterate, and what the line search keeps.
  Eigen::VectorXd q;     ///< (nd) unknowns at the iterate
  Eigen::VectorXd grad;  ///< (nd) gradient of the incremental potential minus the loads
  Eigen::VectorXd rhs;   ///< (nd) in the line search, the base's unknowns while a trial is evaluated
  BandedMatrix H;        ///< (nd, half-band 10) Hessian, lower band
  // The accepted iterate while the line search tries points along the direction.
  std::vector<Vec3> x_accepted;                        ///< (nv)
  std::vector<double> theta_accepted, twist_accepted;  ///< (ne), (nv)
  std::vector<EdgeFrame> frame_accepted;               ///< (ne)
  Eigen::VectorXd fext_accepted, fcons_accepted;       ///< (nd) its loads
  Eigen::VectorXd q_accepted;                          ///< (nd) its unknowns (coupled steps)
};

/// The feeder's buffers (sized once): the twist kept across a pull-back, and adaptivity's plan
/// and the old state while resampling.
struct Feeder::Scratch {
  explicit Scratch(int nvmax);
  std::vector<double> turn_angle;         ///< (nv) turning angle, or the rest shape's if larger
  std::vector<char> split_edge;           ///< (ne) edges to halve
  std::vector<char> remove_vertex;        ///< (nv) vertices to merge away
  std::vector<double> new_u;              ///< (new nv) arc positions from the tip
  std::vector<int> new_source;            ///< (new nv) the old vertex a new one copies, or −1
  std::vector<double> new_twist_density;  ///< (new nv)
  std::vector<double> old_u, old_cell, old_theta, old_omega, old_ref_twist, old_twist_density;
  std::vector<Vec3> old_x, old_v, old_tangent;
  std::vector<Vec3> tangent_now, tangent_before;  ///< (path vertices) predict_slide's paths' tangents
  std::vector<EdgeFrame> old_frame;
};

}  // namespace flowire::rod
