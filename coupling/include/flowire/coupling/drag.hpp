#pragma once
/// @file drag.hpp
/// @brief Blood drag on a guidewire segment: the force per unit length that the blood
/// flowing at velocity u exerts on a wire of radius a, unit tangent t and velocity v lying
/// in a vessel of radius R, with its exact Jacobian in v. Pure functions, checked in
/// tests/coupling/test_drag.cpp against finite differences, the exact annular Poiseuille
/// solution and published cylinder drag measurements and solutions.
///
/// The default law (`DragLaw::Cylinder`) splits the relative velocity into the part
/// normal to the wire and the part along it (the independence principle for a yawed
/// cylinder, Sears 1948; it holds for laminar flow past a long cylinder) and treats each
/// with the fluid mechanics that governs it at arterial Reynolds numbers:
///
/// **Normal (cross-flow) force**, with \f$ w_n = (I - tt^T)(u - v) \f$ and the normal
/// Reynolds number \f$ Re_n = \rho |w_n| d/\eta \f$ (d = 2a):
/// \f[ f_n = \tfrac12 \rho\, C_D(Re_n)\, d\, |w_n|\, w_n = \eta\, g(Re_n)\, w_n,
///     \qquad g(Re) = \tfrac12 Re\, C_D(Re), \f]
/// with the cylinder drag curve C_D of cylinder_drag_coefficient(). The vessel's wall raises
/// g above the curve (confinement); how depends on how the wire's cross-section plane cuts
/// the vessel (docs/blood-drag.md, "Confinement", has the derivation):
///
/// - *Wire along the vessel* (tangent t ∥ axis A): the cross-section plane cuts the vessel in
///   a circle of radius R. In creeping flow an unbounded cylinder's drag vanishes like
///   1/ln(1/Re) (Stokes' paradox: the Oseen length d/Re sets the logarithm); in the vessel the
///   wall cuts the logarithm off first, so g is never below that of a cylinder translating in
///   a coaxial tube (the concentric two-dimensional Stokes solution, stream function
///   sin θ (A r³ + B r + C r ln r + D/r); Happel & Brenner 1965, Low Reynolds Number
///   Hydrodynamics): \f$ g_\circ = \max\bigl(g_{conf}(a/R),\, g(Re_n)\bigr) \f$,
///   \f$ g_{conf} = 4\pi/(\ln(R/a) - (R^2 - a^2)/(R^2 + a^2)) \f$.
/// - *Wire across the vessel* (t ⊥ A): the plane contains the axis and cuts the vessel in
///   a channel of half-width h (the distance from the wire to the wall along
///   \f$ n = t \times A \f$, perpendicular to both wire and flow; \f$ h = \sqrt{R^2 - y^2} \f$ at
///   distance y from the axis along a diameter), and the wire stands across it like a
///   cylinder midway between two plane walls (strip theory). With k = a/h,
///   \f$ g_= = \max\bigl(g_F(k),\ (1 + \varepsilon)\, g(Re_n (1 + \varepsilon))\bigr) \f$:
///   Faxén's confined Stokes drag (faxen_channel_coefficient()) until the inertial law is
///   larger, and the inertial law in the stream that the wall images of the wire's own far
///   field accelerate by the fraction
///   \f$ \varepsilon = \tfrac{\pi^2}{12} k^2 + g(Re_n)\, W(s)/(4\pi) \f$,
///   \f$ s = Re_n/(4k) = U h/(2\nu) \f$. W is the wall images' velocity at the wire per unit
///   force/η of a two-dimensional Oseen point force in the channel (channel_oseen_wall());
///   the first term is the images of the potential doublet. For s → ∞ this is Glauert's
///   blockage correction of wind-tunnel practice (solid blockage π²k²/12, wake blockage
///   C_D k/4); for s → 0, with Lamb's Oseen g, 1/g − W/(4π) tends to Faxén's value.
/// - In between, \f$ g = c^2 g_\circ + (1 - c^2) g_= \f$ with c = t·A: exact at both ends,
///   an interpolation for oblique wires. Without the axis (DragInput::axis zero) the law
///   takes the wire along the vessel on its axis.
///
/// Range: k ≤ 0.4 (the wall at least 1.5 wire radii from the wire's surface along n;
/// closer, k is held at 0.4, where the last term of Faxén's truncated series is 1.3% of the
/// sum); the wire midway in the chord (its eccentricity there ignored); a wire translating
/// between walls at rest in still fluid (Faxén's and the Oseen problem), which stands for a
/// wire held in the local Poiseuille flow (the two differ by O(k²) in creeping flow); strip
/// theory, with the gap varying slowly along the span. Against the 3D Navier–Stokes force
/// on a 0.014" wire across a 3 mm vessel (docs/drag-verification.md): 1.12 times the law
/// at Re_d = 1, 1.07–1.08 at Re_d = 10, 0.73–0.75 at Re_d = 100 (steady, no shedding).
///
/// **Tangential force**: fully developed axial flow in a straight vessel is unidirectional,
/// so the convective term vanishes and the annular Poiseuille solution between a coaxial
/// wire and the wall is exact at any laminar Reynolds number. For a pressure gradient G and
/// a wire sliding at v_t it gives (superposition of the pressure-driven and the Couette
/// annulus)
/// \f[ f_t = c_\parallel\,(\kappa\, u_0 - v_t), \quad c_\parallel = \frac{2\pi\eta}{\ln(R/a)},
///     \quad \kappa = 1 - \frac{a^2}{R^2}\Bigl(1 + 2\ln\frac{R}{a}\Bigr), \f]
/// with \f$ u_0 = G R^2/(4\eta) \f$ the centreline velocity of the same vessel without the
/// wire. The law evaluates this with u_0 replaced by the undisturbed velocity at the wire's
/// centre, t·u: exact for a coaxial wire (the Poiseuille profile's centre value is u_0), the
/// local velocity for a thin wire (κ → 1 as a/R → 0), and an approximation for an
/// off-axis wire (its exact coefficient is that of the eccentric annulus). c_∥ is the
/// slender-body coefficient 2πη/ln(L/a) with the wall, not the wire length, as cut-off.
///
/// R is the radius of the vessel segment the wire's vertex lies in, taken as at least 2a
/// (a wire filling more than half the radius leaves the model's range).
#include <Eigen/Core>

namespace flowire::coupling {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

/// @brief Which law turns the blood velocity into a force on the wire.
enum class DragLaw {
  None,
  Cylinder,     ///< Reynolds-aware cross-flow drag + annular Poiseuille shear (this file)
  SlenderBody,  ///< resistive-force (Stokes) drag, valid for Re ≪ 1 (slender_body_drag: Gazzola et al. 2018, eq. 4.13)
  VelocityOffset,  ///< the published form: the blood velocity added to the velocity update (eq. 10 of the published
                   ///< method)
};

/// @brief Largest Reynolds number of the drag curve's published range (Sucker & Brauer 1975).
inline constexpr double kCylinderDragMaxReynolds = 2e5;

/// @brief A value of the cylinder drag curve and its derivative in Re.
struct DragCurvePoint {
  double cd = 0.0;   ///< C_D(Re)
  double dcd = 0.0;  ///< dC_D/dRe
};

/// @brief Drag coefficient of a long circular cylinder in a uniform cross-flow,
/// \f$ C_D = F'/(\tfrac12\rho U^2 d) \f$, with Re = ρUd/η (d the diameter):
/// - Re ≤ 0.4: Kaplun's matched-asymptotic creeping-flow result (Kaplun 1957; its leading
///   term is Lamb's 1911 Oseen solution)
///   \f[ C_D = \frac{8\pi}{Re}\,(\varepsilon - 0.87\,\varepsilon^3),\quad
///       \varepsilon = \frac{1}{\ln(7.406/Re)}; \f]
/// - Re ≥ 1: the correlation of Sucker & Brauer (1975, Wärme- und Stoffübertragung 8,
///   149–158), fitted to measurements for 10⁻⁴ < Re < 2·10⁵,
///   \f[ C_D = 1.18 + \frac{6.8}{Re^{0.89}} + \frac{1.96}{Re^{1/2}}
///       - \frac{4\cdot10^{-4}\,Re}{1 + 3.64\cdot10^{-7} Re^2}; \f]
/// - in between a cubic smoothstep in ln Re (the two differ by less than 1% there), so
///   C_D is continuously differentiable.
/// Re must be > 0; the curve is evaluated beyond 2·10⁵ as well (callers warn).
DragCurvePoint cylinder_drag_curve(double reynolds);
/// @brief C_D(Re) alone (see cylinder_drag_curve).
double cylinder_drag_coefficient(double reynolds);

/// @brief Constant parameters of a drag law for one wire in one blood.
struct DragModel {
  DragLaw law = DragLaw::Cylinder;
  double viscosity = 3.5e-3;     ///< η [Pa s]
  double density = 1060.0;       ///< ρ [kg/m³]
  double wire_radius = 0.0;      ///< a [m]
  double scale = 1.0;            ///< multiplies the force (sensitivity studies)
  double wire_length = 1.0;      ///< slender_body: L in c⊥ = 4πη/ln(L/a) [m]
  double mass_per_length = 0.0;  ///< velocity_offset: ρ_wire·A [kg/m]
  /// Evaluate the law once a step, at Newton's initial guess, and take it into the step
  /// linearized in the wire velocity, f(v) = f* + (∂f/∂v)*(v − v*) (linearly implicit, as
  /// in Rosenbrock methods); false: the law again at every Newton iterate and trial.
  bool once_per_step = true;
};

/// @brief What one vertex sees: blood and wire velocity, tangent, the length it stands for.
struct DragInput {
  Vec3 u = Vec3::Zero();       ///< undisturbed blood velocity at the vertex [m/s]
  Vec3 v = Vec3::Zero();       ///< wire velocity [m/s]
  Vec3 t = Vec3::UnitX();      ///< unit tangent of the wire
  double ell = 0.0;            ///< length of wire the vertex represents [m]
  double vessel_radius = 0.0;  ///< R of the segment the vertex lies in [m] (Cylinder)
  double dt = 0.0;             ///< time step [s] (VelocityOffset)
  /// Unit direction of the vessel's axis at the vertex (Cylinder); zero: unknown, the law
  /// then takes the wire along the vessel on its axis.
  Vec3 axis = Vec3::Zero();
  /// The vertex minus its nearest point on the vessel's axis [m] (Cylinder, with `axis`).
  Vec3 axis_offset = Vec3::Zero();
  double wire_radius = 0.0;  ///< the wire's radius at the vertex [m]; 0: the model's wire_radius
};

/// @brief Force on the vertex (per vertex, i.e. per unit length times ell) and its exact
/// Jacobian with respect to the wire velocity v (symmetric, negative semi-definite for
/// Cylinder and SlenderBody; zero for VelocityOffset, which does not depend on v).
struct DragForce {
  Vec3 force = Vec3::Zero();
  Mat3 dfdv = Mat3::Zero();
  double reynolds_normal = 0.0;  ///< Re_n = ρ|w_n|d/η (Cylinder)
};

/// @brief Evaluate `model.law` at one vertex. @throws flowire::Error (usage) for a
/// slender-body length not above the wire radius.
DragForce blood_drag(const DragModel& model, const DragInput& in);

/// @brief c⊥ = 4πη/ln(L/r) of the resistive-force law (per unit length).
/// @throws flowire::Error (usage) if L ≤ r or r ≤ 0.
double slender_body_normal_coefficient(double eta, double L, double r);

/// @brief Resistive-force (slender-body) drag per unit length on a thin cylinder with unit
/// tangent t moving at v through fluid moving at u (Stokes flow, Gazzola et al. 2018, eq. 4.13):
/// \f[ f = c_\perp (I - t t^T)(u - v) + c_\parallel\, t t^T (u - v),\quad
///     c_\perp = \frac{4\pi\eta}{\ln(L/r)},\ c_\parallel = c_\perp/2 \f]
/// (leading order in 1/ln(L/r) of Cox's slender-body theory). The force returned is f·ell.
DragForce slender_body_drag(const Vec3& u, const Vec3& v, const Vec3& t, double eta, double L, double r, double ell);

/// @brief Faxén's drag of a cylinder of radius a translating midway between two plane
/// walls a distance 2h apart, parallel to them, in Stokes flow, per unit length and η U
/// (Faxén 1946; the coefficients as quoted by Happel & Brenner 1965), k = a/h:
/// \f[ g_F = \frac{4\pi}{\ln(1/k) - 0.9157 + 1.7244 k^2 - 1.7302 k^4 + 2.4056 k^6 - 4.5913 k^8}. \f]
/// @throws flowire::Error (usage) unless 0 < k ≤ 0.5 (beyond, the truncated series fails).
double faxen_channel_coefficient(double k);

/// @brief The wall term of a two-dimensional Oseen point force midway in a channel of
/// half-width h, with the stream U along it: the velocity the wall images induce at the
/// force, per unit force/η, as a function of s = U h/(2ν), and its derivative. Computed
/// (Fourier transform along the channel, no-slip at both walls) and tabulated. Limits:
/// \f$ W \to \ln(2/s) - \gamma + \tfrac12 + 0.91569 \f$ (s → 0: with Lamb's Oseen drag,
/// Faxén's constant) and \f$ W s \to \pi/2 \f$ (s → ∞: Glauert's wake blockage).
struct ChannelOseenWall {
  double w = 0.0;   ///< W(s)
  double dw = 0.0;  ///< dW/ds
};
ChannelOseenWall channel_oseen_wall(double s);

/// @brief g = F'/(ηU) of a wire across a channel of half-width h = a/k at Re = ρUd/η (the
/// "across" law of the file comment) and dg/dRe. Re > 0, 0 < k ≤ 0.4 (larger k is held at 0.4).
struct ChannelDrag {
  double g = 0.0, dg = 0.0;
  bool stokes = false;  ///< Faxén's confined Stokes value is the larger
};
ChannelDrag channel_drag_coefficient(double reynolds, double k);

/// @brief The annulus factor κ(a/R) and coefficient c_∥ = 2πη/ln(R/a) of the tangential law.
struct AnnulusShear {
  double kappa = 1.0;
  double coefficient = 0.0;  ///< c_∥ [Pa s]
};
AnnulusShear annulus_shear(double eta, double wire_radius, double vessel_radius);

}  // namespace flowire::coupling
