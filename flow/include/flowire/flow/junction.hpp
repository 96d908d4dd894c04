#pragma once
/// @file junction.hpp
/// @brief The static pressure change where branches meet: Mynard & Valen-Sendstad's unified
/// junction loss model (IJNMBE 31:e02717, 2015), `flow.losses.junction: unified`.
///
/// At a junction the flow of the supplying branches (flow into the junction) is shared among
/// the collecting ones (flow out of it). The static pressure of every supplier's end is the
/// junction's pressure p_J; that of each collector c is lower by
/// \f[ p_J - p_c = C_c\,\rho\,U_c^2, \qquad
///     C_c = \big(1 - e^{-\lambda_c/0.02}\big)\Big(1 - \frac{\cos\big(\tfrac34(\pi - \psi_c)\big)}
///           {\lambda_c\,A'_c/A_c}\Big), \f]
/// U_c = Q_c/A_c its mean velocity, λ_c = Q_c/Q_tot its share of the total supplied flow, ψ_c the
/// angle between it and the pseudo-supplier (the suppliers merged: the direction of their
/// flow-weighted unit vectors), and A'_c the pseudo-supplier's effective area,
/// \f[ A'_c = \frac{Q_{tot}}{(1-\eta_c)\,\bar U}, \quad \bar U = \frac{\sum_s U_s Q_s}{Q_{tot}}, \quad
///     \eta_c = \big(0.8(\pi - \theta)\,\sigma_c - 0.2\big)(1 - \lambda_c), \f]
/// η_c the share of the supplied energy the collector takes over (θ the angle between the
/// pseudo-supplier and the pseudo-collector, the collectors merged; σ_c = +1 where the collector
/// lies on the pseudo-supplier's side of the pseudo-collector, −1 on the other). C can be
/// negative: the static pressure recovers where the flow slows into a wider collector. With one
/// supplier and one collector in line it is Borda–Carnot's sudden expansion,
/// p_J − p_c = ρU_c(U_c − U_s), and nothing for equal areas. The factor 1 − e^{−λ/0.02} keeps C
/// finite as a collector's flow vanishes (the authors' published implementation; it is 1 to 10⁻²
/// above λ = 0.1).
///
/// The model is planar: the authors give every branch an angle in the junction's plane. Here the
/// branches are directions in space (from the junction along each branch's centerline over about
/// two radii), ψ and θ the angles between them and σ the side of the plane through the
/// pseudo-collector's axis, which reduces to the planar model where the branches are coplanar.
/// The merged collector direction is the mean of the collectors' unit vectors (the authors take
/// the mean of their angles, the same wherever the collectors span less than π).
#include <array>
#include <vector>

#include "flowire/vessels/network.hpp"

namespace flowire::flow {

using vessels::Network;
using vessels::Vec3;

/// @brief One branch meeting a junction: the segment that touches it.
struct JunctionBranch {
  int segment = -1;
  double outward = 1.0;  ///< +1: the segment starts at the junction (its flow leaves it); −1: it ends there
  double area = 0.0;  ///< m², the branch's section: its length-weighted median radius's, away from a flared junction
  Vec3 direction{1.0, 0.0, 0.0};  ///< unit, from the junction along the branch
};

/// @brief A node where three segments or more meet.
struct Junction {
  int node = -1;
  std::vector<JunctionBranch> branches;
};

/// @brief Every junction of @p net (nodes of degree ≥ 3), each branch's direction taken over
/// about two of its radii along its centerline.
[[nodiscard]] std::vector<Junction> find_junctions(const Network& net);

/// @brief The unified model's static pressure drops p_J − p_i (Pa) of every branch of @p j for blood
/// of @p density, given each branch's flow out of the junction @p outward (m³/s; negative: it
/// supplies). @p drop gets one value per branch (0 for the suppliers). Where @p jacobian is given
/// it gets ∂drop_i/∂outward_k, row-major (n × n); within one pattern of suppliers and collectors
/// the drops are smooth in the flows and the derivatives exact (forward automatic differentiation).
void unified_junction_drops(const Junction& j, double density, const double* outward, double* drop,
                            double* jacobian = nullptr);

/// @brief Every segment's static pressure below its nodes' at its start ([0]) and its end ([1]) at
/// the segment flows @p q (m³/s, node_from → node_to): the unified model's drop where that end
/// meets one of @p junctions, 0 elsewhere. @p drops is resized to the network's segments; where
/// @p jacobians is given it gets each junction's ∂drop/∂outward (unified_junction_drops).
void segment_end_drops(const Network& net, const std::vector<Junction>& junctions, double density, const double* q,
                       std::vector<std::array<double, 2>>& drops,
                       std::vector<std::vector<double>>* jacobians = nullptr);

/// @brief The unified model's coefficient C of every branch (0 for the suppliers), as the authors
/// tabulate it: p_J − p_c = C_c ρ U_c².
[[nodiscard]] std::vector<double> unified_junction_coefficients(const Junction& j, const double* outward);

}  // namespace flowire::flow
