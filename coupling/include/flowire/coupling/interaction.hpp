#pragma once
/// @file interaction.hpp
/// @brief Wire–vessel interaction laws (wall penalty, friction) as pure functions, each with
/// its derivatives (value / gradient / Hessian or force / Jacobian), checked against finite
/// differences in tests/coupling/test_interaction.cpp. The wire–blood laws are in drag.hpp.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

#include "flowire/coupling/drag.hpp"  // the blood drag laws

namespace flowire::coupling {

/// @brief φ(g) = ½ g² for g ≥ δ/2, u³/(6δ) with u = g + δ/2 for |g| < δ/2, 0 below, plus
/// δ²/24 on the quadratic part so that φ, φ′ and φ″ are continuous (φ″ ramps from 0 to 1 over the
/// band): the penalty's force k φ′ is that of ½ k g₊² beyond the band, and its stiffness k φ″ has
/// no jump. δ = 0: the plain ½ g₊². @p d1, @p d2: φ′ and φ″.
[[nodiscard]] double onset_quadratic(double g, double delta, double* d1 = nullptr, double* d2 = nullptr);

/// @brief Wall penalty on a wire vertex of radius a.
///
/// With d(x) the signed distance from the vertex to the wall (negative inside the lumen),
/// n = ∇d and H_d = ∇²d, the penetration is δ = d + a and, with φ = onset_quadratic(·, w),
/// \f[ E = k\,\varphi(\delta), \quad \nabla E = k\,\varphi'(\delta)\,n, \quad
///     \nabla^2 E = k\,(\varphi''(\delta)\, n n^T + \varphi'(\delta)\, H_d) \f]
/// (zero where δ ≤ −w/2): k/2 δ₊² beyond the onset band |δ| < w/2, where the force ramps in
/// smoothly (w = 0: the sharp k/2 δ₊², whose stiffness jumps from 0 to k at first touch). The
/// Hessian is positive semi-definite for a convex lumen section (H_d ⪰ 0 for the distance to a
/// cylinder's axis), so the implicit step stays a minimisation.
struct PenaltyResult {
  double energy = 0.0;
  Vec3 gradient = Vec3::Zero();
  Mat3 hessian = Mat3::Zero();
  double penetration = 0.0;   ///< δ₊ (m)
  double normal_force = 0.0;  ///< k φ′(δ) = |∇E| (N)
};
PenaltyResult wall_penalty(double d, const Vec3& n, const Mat3& hess_d, double a, double k, double onset = 0.0);

/// @brief Signed distance to a capsule's wall and its derivatives (exact): d = |x − q(x)| − r
/// with q the closest axis point; on the cylinder part
/// H_d = (I − t tᵀ − n nᵀ)/ρ, on the end caps H_d = (I − n nᵀ)/ρ (ρ = distance to the axis).
double capsule_distance(const Vec3& x, const Vec3& a, const Vec3& b, double r, Vec3* grad, Mat3* hess);

/// @brief Smooth Coulomb friction: the dissipation potential
/// \f[ D(v) = \mu N\,(\sqrt{|v_t|^2 + \varepsilon^2} - \varepsilon),\quad v_t = (I - n n^T) v \f]
/// gives f = −∇_v D = −μN v_t/√(|v_t|² + ε²): viscous below the slip speed ε (sticking),
/// saturating at μN when sliding. ∂f/∂v = −∇²_v D is symmetric negative semi-definite. @p n
/// must be a unit vector (else I − n nᵀ is no projector and f is not −∇D).
struct FrictionResult {
  double dissipation = 0.0;  ///< D(v)
  Vec3 force = Vec3::Zero();
  Mat3 dfdv = Mat3::Zero();
};
FrictionResult coulomb_friction(const Vec3& v, const Vec3& n, double normal_force, double mu, double eps);

/// @brief The wall contact and friction settings of a scene's `contact:` section.
struct ContactParams {
  bool enabled = true;
  double stiffness = 0.0;  ///< penalty stiffness per vertex [N/m]
  /// [m] width of the penalty's smoothed onset around first touch (wall_penalty): the force
  /// ramps in over |δ| < onset/2, so that Newton sees a wall before it reaches it
  double onset = 0.0;
  double friction = 0.1;      ///< Coulomb coefficient, shaft (wire on vessel wall: 0.1–1.0, Tang et al. 2010, §3.3)
  double tip_friction = 0.1;  ///< Coulomb coefficient, tip region
  double tip_length = 0.03;   ///< [m] distal length using tip_friction
  double slip_speed = 1e-4;   ///< [m/s] smooth stick/slip transition width ε
  double viscous_friction = 0.0;  ///< [N s/m²] tangential viscous wall friction per unit length
};

/// @brief What the interaction of the wire with the vessels and the blood did, summed over a run.
struct InteractionStats {
  std::uint64_t evaluations = 0;
  std::uint64_t lookups = 0;
  std::uint64_t contacts = 0;          ///< vertex evaluations in contact
  std::uint64_t wall_queries = 0;      ///< wall distances asked of the network or the lumen surface
  std::uint64_t drag_evaluations = 0;  ///< vertex evaluations of the blood drag
  double max_penetration = 0.0;        ///< over accepted steps [m]
  double max_outside = 0.0;            ///< max over accepted steps of (wall distance of a vertex centre) [m]
  /// Where and when a vertex centre was first more than a wire radius outside the lumen
  /// (outside_time < 0: never).
  double outside_time = -1.0;       ///< [s]
  double outside_arc_length = 0.0;  ///< of that vertex, from the entry [m]
  double outside_distance = 0.0;    ///< its distance outside the wall [m]
  Eigen::Vector3d outside_position = Eigen::Vector3d::Zero();
  double seconds_lookup = 0.0, seconds_contact = 0.0, seconds_drag = 0.0;
  double max_reynolds = 0.0;  ///< largest normal Reynolds number of the drag law over accepted steps [-]
};

}  // namespace flowire::coupling
