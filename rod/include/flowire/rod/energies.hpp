#pragma once
/// @file energies.hpp
/// @brief Discrete elastic rod energies as pure functions (value / gradient / Hessian).
///
/// The rod is a polyline x_0..x_n with one twist angle θ_j per edge e^j = x_{j+1} − x_j.
/// Each edge carries a *reference frame* (d1, d2, t) with t = e/|e|, kept by time-parallel
/// transport, and a *material frame* rotated from it by θ about t:
/// \f[ m_1 = \cos\theta\, d_1 + \sin\theta\, d_2, \qquad m_2 = -\sin\theta\, d_1 + \cos\theta\, d_2. \f]
///
/// **Chart.** The energies are functions of positions and angles *given* the reference
/// frames of the last update: when an edge moves from tangent t⁰ (the frame's own tangent
/// d1 × d2) to t, its reference frame is carried by the minimal rotation P(t⁰→t)
/// (time-parallel transport). The value functions evaluate this for any configuration;
/// the gradient and Hessian functions are the exact derivatives of that same function at
/// the *base point*, i.e. when the frames are up to date (t⁰ = t), which is how the
/// simulator calls them (it re-transports the frames after every Newton update).
///
/// Stencils and variable order (matching the interleaved global unknowns
/// x_0, θ_0, x_1, θ_1, …, x_n):
/// - stretching: one edge, variables (x_0, x_1) — 6 unknowns;
/// - bending and twisting: one interior vertex with its two edges e (before) and f
///   (after), variables (x_0, θ_e, x_1, θ_f, x_2) — 11 unknowns, contiguous in the global
///   vector.
#include <cmath>
#include <numbers>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace flowire::rod {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec11 = Eigen::Matrix<double, 11, 1>;
using Mat11 = Eigen::Matrix<double, 11, 11>;

/// @brief Minimal rotation taking unit vector @p from to unit vector @p to, applied to @p u.
/// \f[ P u = (a\cdot b)\,u + (a\times b)\times u + \frac{(a\times b)\,((a\times b)\cdot u)}{1+a\cdot b} \f]
/// For antiparallel inputs (1 + a·b < 1e-14) it rotates by π about an axis ⊥ @p from.
/// Inline: the simulator transports every edge's frame at each Newton trial.
[[nodiscard]] inline Vec3 parallel_transport(const Vec3& u, const Vec3& from, const Vec3& to) {
  const Vec3 b = from.cross(to);
  const double c = from.dot(to);
  if (1.0 + c < 1e-14) [[unlikely]] {
    // Rotation by π about an axis ⊥ from.
    const Vec3 trial = std::abs(from.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    const Vec3 axis = (trial - from * from.dot(trial)).normalized();
    return 2.0 * axis * axis.dot(u) - u;
  }
  return c * u + b.cross(u) + b * (b.dot(u) / (1.0 + c));
}

/// @brief Signed angle from @p a to @p b about axis @p axis (a, b ⊥ axis), in (−π, π].
[[nodiscard]] inline double signed_angle(const Vec3& a, const Vec3& b, const Vec3& axis) {
  return std::atan2(a.cross(b).dot(axis), a.dot(b));
}

/// @brief Curvature binormal of two consecutive edge tangents:
/// \f[ (\kappa b) = \frac{2\, t_e \times t_f}{1 + t_e\cdot t_f}, \quad |\kappa b| = 2\tan(\varphi/2) \f]
/// with φ the turning angle (an integrated, dimensionless curvature).
[[nodiscard]] Vec3 curvature_binormal(const Vec3& te, const Vec3& tf);

/// @brief Reference twist at the vertex between edges e and f: the signed angle about
/// t_f from the space-parallel transport of d1_e to d1_f. The result is taken on the
/// branch closest to @p previous (2π jumps removed).
[[nodiscard]] inline double reference_twist(const Vec3& d1e, const Vec3& te, const Vec3& d1f, const Vec3& tf,
                                            double previous) {
  const double a = signed_angle(parallel_transport(d1e, te, tf), d1f, tf);
  constexpr double two_pi = 2.0 * std::numbers::pi;
  return a + two_pi * std::round((previous - a) / two_pi);
}

// ---------------------------------------------------------------------------------------
// Stretching
// ---------------------------------------------------------------------------------------

/// @brief Stretching energy of one edge.
/// \f[ E_s = \tfrac12\, k_s\, \bar\ell\, \Big(\frac{\ell}{\bar\ell} - 1\Big)^2, \qquad \ell = |x_1 - x_0| \f]
/// @param ks axial stiffness EA [N]
/// @param rest_length \f$\bar\ell\f$ [m]
[[nodiscard]] double stretch_energy(const Vec3& x0, const Vec3& x1, double ks, double rest_length);
/// @brief Gradient of stretch_energy w.r.t. (x0, x1): \f$ \pm k_s (\ell/\bar\ell - 1)\, t \f$.
[[nodiscard]] Vec6 stretch_gradient(const Vec3& x0, const Vec3& x1, double ks, double rest_length);
/// @brief Hessian of stretch_energy: blocks ±H_e with
/// \f[ H_e = \frac{k_s}{\bar\ell}\, t t^T + k_s\Big(\frac{1}{\bar\ell} - \frac{1}{\ell}\Big)(I - t t^T). \f]
/// Indefinite under compression (ℓ < ℓ̄), as the exact Hessian must be; with
/// @p clamp_compression the transverse term is floored at 0 (positive semi-definite).
[[nodiscard]] Mat6 stretch_hessian(const Vec3& x0, const Vec3& x1, double ks, double rest_length,
                                   bool clamp_compression = false);

// ---------------------------------------------------------------------------------------
// Bending and twisting at an interior vertex
// ---------------------------------------------------------------------------------------

/// @brief Reference frame of one edge: d1, d2 orthonormal; its tangent is d1 × d2.
struct EdgeFrame {
  Vec3 d1 = Vec3::UnitY();
  Vec3 d2 = Vec3::UnitZ();
};

/// @brief Unknowns and frames of one bend/twist stencil (vertices x0, x1, x2; edges e, f).
struct VertexStencil {
  Vec3 x0 = Vec3::Zero(), x1 = Vec3::Zero(), x2 = Vec3::Zero();
  double theta_e = 0.0, theta_f = 0.0;
  EdgeFrame frame_e, frame_f;  ///< reference frames at the last update
  double ref_twist = 0.0;      ///< reference twist of those frames (radians, unwrapped)
};

/// @brief Material constants of one interior vertex.
struct VertexParams {
  double bend_stiffness1 = 1.0;  ///< B₁ = E·I₁ [N m²] (bending about m₁... curvature κ₁)
  double bend_stiffness2 = 1.0;  ///< B₂ = E·I₂ [N m²]; equal to B₁ for a round wire
  double rest_kappa1 = 0.0;      ///< \f$\bar\kappa_1\f$ (integrated, dimensionless)
  double rest_kappa2 = 0.0;      ///< \f$\bar\kappa_2\f$
  double twist_stiffness = 1.0;  ///< G·J [N m²]
  double rest_twist = 0.0;       ///< \f$\bar m\f$ (integrated, radians)
  double voronoi_length = 1.0;   ///< \f$\bar\ell_i = (\bar\ell_e + \bar\ell_f)/2\f$ [m]
};

/// @brief Material curvatures (κ₁, κ₂) of a stencil, with frames transported to the
/// current tangents:
/// \f[ \kappa_1 = \tfrac12 (m_2^e + m_2^f)\cdot(\kappa b), \qquad
///     \kappa_2 = -\tfrac12 (m_1^e + m_1^f)\cdot(\kappa b). \f]
[[nodiscard]] Eigen::Vector2d material_curvature(const VertexStencil& s);

/// @brief Bending energy
/// \f[ E_b = \frac{1}{2\bar\ell_i}\Big(B_1(\kappa_1-\bar\kappa_1)^2 + B_2(\kappa_2-\bar\kappa_2)^2\Big). \f]
[[nodiscard]] double bend_energy(const VertexStencil& s, const VertexParams& p);
/// @brief Gradient of bend_energy w.r.t. (x0, θe, x1, θf, x2) at the base point.
[[nodiscard]] Vec11 bend_gradient(const VertexStencil& s, const VertexParams& p);
/// @brief Hessian of bend_energy at the base point (exact, including the second-order
/// terms of the time-parallel transport of the frames).
[[nodiscard]] Mat11 bend_hessian(const VertexStencil& s, const VertexParams& p);

/// @brief Integrated twist \f$ m = \theta_f - \theta_e + m_{ref} \f$.
[[nodiscard]] double twist(const VertexStencil& s);
/// @brief Twisting energy \f[ E_t = \frac{GJ}{2\bar\ell_i}\,(m - \bar m)^2. \f]
[[nodiscard]] double twist_energy(const VertexStencil& s, const VertexParams& p);
/// @brief Gradient of twist_energy at the base point. The reference twist varies as
/// \f$ \partial m/\partial t_e = \partial m/\partial t_f = (\kappa b)/2 \f$.
[[nodiscard]] Vec11 twist_gradient(const VertexStencil& s, const VertexParams& p);
/// @brief Hessian of twist_energy at the base point. The reference twist is written as
/// the holonomy of the quadrilateral t_e⁰ → t_e → t_f → t_f⁰ on the unit sphere,
/// \f$ m_{ref} = m_{ref}^0 - \Omega(t_e^0, t_e, t_f) - \Omega(t_e^0, t_f, t_f^0) \f$ with
/// \f$ \tan(\Omega/2) = a\cdot(b\times c)/(1 + a\cdot b + b\cdot c + c\cdot a) \f$, and
/// differentiated twice.
[[nodiscard]] Mat11 twist_hessian(const VertexStencil& s, const VertexParams& p);

/// @brief Bending plus twisting, value, gradient and Hessian in one pass (what the
/// simulator uses; same results as the separate functions).
///
/// With @p gauss_newton the Hessian keeps only the first-derivative products
/// \f$ \sum_k c_k \nabla\kappa_k \nabla\kappa_k^T + c_t \nabla m \nabla m^T \f$ — positive
/// semi-definite by construction, used by Newton when the exact Hessian is indefinite.
double bend_twist(const VertexStencil& s, const VertexParams& p, Vec11* gradient, Mat11* hessian,
                  bool gauss_newton = false);

/// @brief Geometry of one edge at the base point, shared by the two stencils around it.
struct EdgeGeometry {
  Vec3 t = Vec3::UnitX();                       ///< unit tangent
  double length = 1.0;                          ///< |e|
  Vec3 m1 = Vec3::UnitY(), m2 = Vec3::UnitZ();  ///< material directors
};

/// @brief Edge geometry from its end points, reference frame (at this tangent) and angle.
[[nodiscard]] EdgeGeometry edge_geometry(const Vec3& x0, const Vec3& x1, const EdgeFrame& frame, double theta);

/// @brief bend_twist at the base point from precomputed edge geometry (the simulator's
/// path: frames are up to date, each edge's tangent and material frame computed once).
/// Same results as bend_twist(VertexStencil) when the stencil's frames are at the base.
double bend_twist(const EdgeGeometry& e, const EdgeGeometry& f, double theta_e, double theta_f, double ref_twist,
                  const VertexParams& p, Vec11* gradient, Mat11* hessian, bool gauss_newton = false);

namespace detail {
/// @brief The same function as bend_twist(EdgeGeometry, …), evaluated the straightforward
/// way: dense 8×8 Hessian in y = (t_e, t_f, θ_e, θ_f), then the chain rule with dense
/// projector products. Kept as the reference for tests and benchmarks of the fast kernel.
double bend_twist_reference(const EdgeGeometry& e, const EdgeGeometry& f, double theta_e, double theta_f,
                            double ref_twist, const VertexParams& p, Vec11* gradient, Mat11* hessian,
                            bool gauss_newton = false);
}  // namespace detail

}  // namespace flowire::rod
