#pragma once
/// @file rlc.hpp
/// @brief The `flow.model: rlc` network model: resistance, inertance and compliance.
///
/// Governing equations (unknowns: node pressures p, segment flows Q, and the capacitor
/// pressure p_c of every RCR outlet):
/// - segment s: \f$ L_s \dot Q_s + R_s Q_s = p_{from} - p_{to} \f$ with
///   \f$ R_s = 8\eta l/(\pi r^4) \f$ and \f$ L_s = \rho l/(\pi r^2) \f$ (Inertance::Poiseuille)
///   or the Womersley-corrected \f$ L_s = 4\rho l/(3\pi r^2) \f$ (Inertance::Womersley: the
///   low-α limit of the impedance of Womersley's 1955 solution, Z = R(1 + iα²/6 + O(α⁴));
///   with R in series this reproduces the Womersley amplitude and phase within 1–4 % up to
///   α ≈ 4);
/// - node i: \f$ C_i \dot p_i = \sum Q_{in} - \sum Q_{out} + Q_{bc} \f$ with
///   \f$ C_i = \sum_{s \ni i} C_s / 2 \f$, \f$ C_s = 3\pi r^3 l / (2 E h) \f$ (thin elastic wall,
///   h = `wall_thickness_ratio`·r; `wall_youngs_modulus` ≤ 0 gives rigid walls, C = 0);
/// - pressure BC: p_i = p(t); resistance outlet: Q_bc = −(p_i − P_d)/R;
/// - RCR outlet: Q_bc = −(p_i − p_c)/R_p, \f$ C \dot p_c = (p_i - p_c)/R_p - (p_c - P_d)/R_d \f$
///   (the three-element windkessel; Westerhof, Lankhaar & Westerhof 2009, Med. Biol. Eng.
///   Comput. 47, 131–141).
///
/// Time stepping: generalized-α (second order, spectral radius `rho_infinity` at infinite
/// step; Jansen, Whiting & Hulbert 2000, Comput. Methods Appl. Mech. Engrg. 190, 305–319),
/// the one of svzerod::GeneralizedAlpha: the network is two blocks of an
/// svzerod::System, E and F (written again only when an occlusion changes a segment) and the
/// boundary values c(t), so the matrix \f$ \alpha_m E + \alpha_f\gamma\Delta t F \f$ is factored
/// (KLU) once for the fixed step `dt` and again only after an occlusion change. The initial state is the steady
/// solution at t = 0. With a periodic inlet, setup runs whole cycles (the period after which every periodic inlet
/// repeats: T for inlets of periods T and T/2) until two consecutive cycle starts differ by less
/// than `periodic_tolerance` (relative), at most `max_cycles`, and that periodic state becomes t = 0. `advance(t)`
/// steps the grid k·dt to t and interpolates linearly between steps.
#include "flowire/flow/solver.hpp"

namespace flowire::flow {

/// @brief Cycles run during setup to reach the periodic state (0 for a steady inlet or
/// another model), and whether the tolerance was met.
struct PeriodicInfo {
  int cycles = 0;
  bool converged = true;
  double last_change = 0.0;  ///< relative change between the last two cycle starts
};
[[nodiscard]] PeriodicInfo periodic_info(const FlowSolver& solver);
/// @brief Numeric factorizations of the rlc model's system so far: one for the steady
/// initial state, one for the time step, one more per occlusion change (0 for another model).
[[nodiscard]] long rlc_factorizations(const FlowSolver& solver);

/// @brief Inertance of a cylindrical segment (kg/m⁴): ρl/(πr²), times 4/3 for `Womersley`.
[[nodiscard]] double segment_inertance(Inertance kind, double density, double length, double radius);
/// @brief Inertance of a linearly tapered segment, ∫ρ/(π r(x)²) dx = ρl/(π r1 r2) (times 4/3 for `Womersley`).
[[nodiscard]] double segment_inertance(Inertance kind, double density, double length, double r1, double r2);
/// @brief Compliance of a cylindrical segment (m³/Pa), 3πr²l/(2E h/r) with h/r = `thickness_ratio`;
/// 0 when `youngs_modulus` ≤ 0.
[[nodiscard]] double segment_compliance(double youngs_modulus, double thickness_ratio, double length, double radius);
/// @brief Compliance of a linearly tapered segment, ∫3π r(x)²/(2E h/r) dx = π l (r1² + r1 r2 + r2²)/(2E h/r).
[[nodiscard]] double segment_compliance(double youngs_modulus, double thickness_ratio, double length, double r1,
                                        double r2);

}  // namespace flowire::flow
