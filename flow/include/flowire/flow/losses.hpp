#pragma once
/// @file losses.hpp
/// @brief Losses beyond Poiseuille's law that the network takes from its own geometry
/// (`flow.losses`), each a published model added to the segments' laws (FlowSpec::segment_laws).
///
/// **Stenosis: Young & Tsai's expansion loss.** The jet that leaves a narrowing loses the kinetic
/// energy of its excess velocity where it spreads again (Borda–Carnot), measured on model stenoses
/// by Young & Tsai (J. Biomech. 6:395–410, 1973) as
/// \f[ \Delta p_t = \frac{K_t\rho}{2}\Big(\frac{A_0}{A_s}-1\Big)^2 |U_0| U_0, \quad K_t = 1.52, \f]
/// with U₀ = Q/A₀ the mean velocity in the unobstructed vessel, A₀ its area and A_s the throat's:
/// a quadratic coefficient \f$ K = \frac{K_t\rho}{2A_0^2}(A_0/A_s-1)^2 \f$ (Pa·s²/m⁶), the form
/// svZeroDSolver's `stenosis_coefficient` takes. With K_t = 1 it is the Borda–Carnot loss of a
/// sudden expansion from A_s to A₀, ½ρ(U_s − U₀)² (`borda_carnot`), which the project's 3D
/// Navier–Stokes on smooth stenoses follows more closely at laminar Reynolds numbers
/// (docs/flow-losses.md). The viscous part of their law (K_v) is not added:
/// the network's segments already carry the Poiseuille resistance of the narrowed lumen, segment
/// by segment. Young & Tsai's inertial term (K_u) is the rlc model's own inertance of those
/// segments.
///
/// A stenosis is a local minimum of the radius along a branch whose narrowing, measured against
/// the lower of the two shoulders that enclose it (the largest radius on each side before the
/// lumen becomes narrower than the throat again: the minimum's prominence), reduces the area by at
/// least a threshold. Its K is spread over the segments from the throat to where the lumen has
/// widened 90% of the way to that shoulder (in the branch's own direction), in proportion to their
/// lengths: there the jet expands.
/// **Curvature: White's law for a bend.** In a curved vessel the centrifugal force drives a
/// secondary (Dean) flow that steepens the axial profile against the outer wall and raises the
/// wall shear. For fully developed laminar flow White (Proc. R. Soc. Lond. A 123:645–663, 1929)
/// measured the resistance of coiled pipes against the straight pipe's as a function of the Dean
/// number De = Re √(a/R) alone (Re on the diameter and the mean velocity, a the radius, R the
/// bend's radius of curvature):
/// \f[ \phi(De) = \Big[1 - \big(1 - (11.6/De)^{0.45}\big)^{2.2}\Big]^{-1},\quad De > 11.6, \f]
/// 1 below; Dean's own perturbation series (1928) gives φ − 1 = O(De⁴) for small De. The network
/// takes each segment's curvature from its centerline (the turning angle at each node of a branch
/// over the mean length of its two segments; a segment the mean of its two nodes'), and its law
/// becomes Δp = f R_P Q φ(De(|Q|)) + K|Q|Q. Bends in arteries are short: the secondary flow needs
/// a length of the order of the bend's own to develop, so a short bend loses less than φ says.
///
/// **Entrance: Shah's developing flow.** Where a branch leaves a junction its flow starts again with
/// a nearly uniform core and a thin boundary layer, and reaches Poiseuille's profile only after
/// x ≈ 0.056 D Re (several centimetres in an iliac at Re 400): the wall shear is higher on the way
/// and the profile's kinetic energy grows from ½ρū² to twice that, both paid by the static
/// pressure. For a uniform entering profile Shah (J. Fluids Eng. 100:177–179, 1978) correlated the
/// solutions of the entrance problem (within ±2.4% of them, his statement) as an apparent Fanning
/// friction factor
/// \f[ f_{app} Re = \frac{3.44}{\sqrt{x^+}} + \frac{1.25/(4x^+) + 16 - 3.44/\sqrt{x^+}}{1 + 0.00021\,(x^+)^{-2}}, \quad
///     x^+ = \frac{x}{D\,Re}, \f]
/// the drop from the entrance to x being 4 f_app Re x⁺ ½ρū²: Poiseuille's 64 x⁺ ½ρū² plus the
/// incremental drop K(x⁺)½ρū², 0 at the entrance and 1.25 far downstream. Each segment of a branch
/// that starts (or ends) at an entrance carries the increment of K between its two ends at its own
/// mean velocity (SegmentLaw's E(Q); x⁺ = x μπ/(4ρQ) needs no radius). What the model leaves out:
/// the junction itself (the parent's kinetic energy and its turning loss, Mynard & Valen's kind of
/// model, need the parent's flow in the daughter's law), and the real entering profile, skewed by
/// the turn rather than uniform.
#include <vector>

#include "flowire/flow/spec.hpp"
#include "flowire/vessels/network.hpp"

namespace flowire::flow {

/// @brief Young & Tsai's expansion-loss coefficient K for a throat of radius @p throat_radius in a
/// vessel of radius @p reference_radius (Pa·s²/m⁶; 0 where the throat is not narrower).
[[nodiscard]] double young_tsai_coefficient(double density, double reference_radius, double throat_radius,
                                            double expansion_coefficient = 1.52);

/// @brief The stenoses of @p net: every local minimum of a branch's radius whose area reduction
/// against its lower shoulder is at least @p min_area_reduction (in [0, 1)), with K for blood of
/// @p density.
[[nodiscard]] std::vector<Stenosis> find_stenoses(const Network& net, double density, double min_area_reduction,
                                                  double expansion_coefficient = 1.52);

/// @brief Each segment's curvature (1/m) from its branch's centerline (0 on a straight one).
[[nodiscard]] std::vector<double> segment_curvatures(const Network& net);

/// @brief Give every curved segment White's law (SegmentLaw::dean) for blood of @p density and
/// @p viscosity; @p laws made one per segment if empty and a segment is curved. The number of
/// curved segments.
int add_curvature_losses(const Network& net, double density, double viscosity, std::vector<SegmentLaw>& laws);

/// @brief Give every segment of a branch one of whose end nodes is marked in @p entrance (one
/// flag per node) Shah's developing flow from that end (SegmentLaw::entry, entry_forward or
/// entry_backward), for blood of @p density and @p viscosity. The number of branch ends marked.
int add_entrance_losses(const Network& net, double density, double viscosity, const std::vector<char>& entrance,
                        std::vector<SegmentLaw>& laws);

/// @brief Add the stenoses' coefficients to @p laws (made one per segment if empty).
void add_stenosis_losses(const Network& net, const std::vector<Stenosis>& stenoses, std::vector<SegmentLaw>& laws);

}  // namespace flowire::flow
