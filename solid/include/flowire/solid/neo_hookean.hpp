#pragma once
/// @file neo_hookean.hpp
/// @brief The vessel wall's material: a compressible neo-Hookean solid.
///
/// Strain energy per reference volume, with \f$ J = \det F \f$ and \f$ I_1 = \mathrm{tr}(F^TF) \f$:
/// \f[ W(F) = \tfrac{\mu}{2}(I_1 - 3) - \mu \ln J + \tfrac{\lambda}{2} (\ln J)^2, \f]
/// first Piola–Kirchhoff stress \f$ P = \mu (F - F^{-T}) + \lambda \ln J\, F^{-T} \f$ and tangent
/// \f$ \partial P_{aB} / \partial F_{cD} = \mu\,\delta_{ac}\delta_{BD} + (\mu - \lambda \ln J)
/// F^{-1}_{Bc} F^{-1}_{Da} + \lambda F^{-1}_{Ba} F^{-1}_{Dc} \f$. At \f$ F = I \f$ the tangent is
/// that of linear elasticity with Lamé's \f$ \mu, \lambda \f$, so small loads give Lamé's and
/// Timoshenko's closed forms, and large ones stay frame-indifferent with \f$ W \to \infty \f$ as
/// \f$ J \to 0 \f$ (an element cannot be turned inside out at finite energy).
///
/// Every function takes the displacement gradient \f$ H = F - I \f$, not F: the energy and
/// the stress are then evaluated without cancellation (\f$ F - F^{-T} = H + H^T F^{-T} \f$,
/// \f$ \ln J = \mathrm{log1p}(J - 1) \f$ with \f$ J - 1 \f$ from H's invariants), so a wall
/// displaced by 10⁻⁸ of its size has its stress to full precision, not to 10⁻⁸.
#include <Eigen/Dense>

namespace flowire::solid {

using Mat3 = Eigen::Matrix3d;
/// \f$ \partial P / \partial F \f$ with F and P flattened column by column: entry (a + 3B, c + 3D).
using Tangent = Eigen::Matrix<double, 9, 9>;

/// @brief Compressible neo-Hookean law (shear modulus μ, Lamé's λ).
struct NeoHookean {
  double mu = 0.0;      ///< shear modulus (Pa)
  double lambda = 0.0;  ///< Lamé's first parameter (Pa)

  /// @brief From Young's modulus E (Pa) and Poisson's ratio ν: μ = E/2(1+ν), λ = Eν/(1+ν)(1−2ν).
  /// @throws flowire::Error (usage) unless E > 0 and −1 < ν < 0.5, naming `where` (a scene key).
  static NeoHookean from_young_poisson(double young, double poisson, const char* where = "wall");

  /// @brief W(I + H); +∞ when det(I + H) ≤ 0.
  [[nodiscard]] double energy(const Mat3& H) const;
  /// @brief P(I + H), the first Piola–Kirchhoff stress (det(I + H) > 0).
  [[nodiscard]] Mat3 stress(const Mat3& H) const;
  /// @brief ∂P/∂F at F = I + H (det F > 0).
  [[nodiscard]] Tangent tangent(const Mat3& H) const;
};

}  // namespace flowire::solid
