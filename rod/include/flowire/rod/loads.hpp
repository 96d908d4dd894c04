#pragma once
/// @file loads.hpp
/// @brief The loads a user puts on the rod, each its own object: gravity, a dead force on the
/// tip, dead forces at points of the wire, a moment on the distal edge. Each adds its
/// generalized force (4 entries per vertex: the force on x_k, the torque about edge k's
/// tangent) times the static solve's ramp factor, and where it depends on the configuration
/// (the moment, through the edge it acts on) its stiffness −∂f/∂q; and the size of its force,
/// which Newton's tolerance is relative to. They enter the line search through their work along
/// the search ray (exact for constant forces). Forces that depend on where the rod is (contact,
/// drag) come from outside through rod::ExternalForce (external.hpp) instead.
///
/// `Loads` holds one of each in the order they are summed: gravity, tip force, point forces,
/// tip moment.
#include <Eigen/Core>
#include <span>
#include <vector>

#include "flowire/rod/energies.hpp"

namespace flowire::rod {

/// @brief The rod where loads are evaluated (vertex 0 = distal tip).
struct LoadSite {
  std::span<const Vec3> positions;   ///< (vertices) [m]
  std::span<const double> material;  ///< (vertices) distance of each vertex from the tip [m]
  std::span<const double> mass;      ///< (vertices) lumped mass [kg]
  double inserted_length = 0.0;      ///< [m]
};

/// @brief What the loads add: the generalized force over the unknowns, and the stiffness
/// −∂f/∂e of a couple on the distal edge e = x₁ − x₀ (symmetrized; zero if none).
struct LoadTerms {
  Eigen::Ref<Eigen::VectorXd> force;
  Mat3& tip_edge_stiffness;
};

class Load {
 public:
  virtual ~Load() = default;
  /// @brief Add this load times @p scale.
  virtual void add(const LoadSite& rod, double scale, LoadTerms& out) const = 0;
  /// @brief Its largest force times @p scale [N] (a moment over @p length).
  [[nodiscard]] virtual double force_scale(const LoadSite& rod, double scale, double length) const = 0;
};

/// @brief m_k g on every vertex.
class Gravity final : public Load {
 public:
  Vec3 acceleration = Vec3::Zero();  ///< g [m/s²]
  void add(const LoadSite& rod, double scale, LoadTerms& out) const override;
  [[nodiscard]] double force_scale(const LoadSite& rod, double scale, double length) const override;
};

/// @brief A dead force on the distal vertex.
class TipForce final : public Load {
 public:
  Vec3 force = Vec3::Zero();  ///< [N]
  void add(const LoadSite& rod, double scale, LoadTerms& out) const override;
  [[nodiscard]] double force_scale(const LoadSite& rod, double scale, double length) const override;
};

/// @brief Dead forces at material points given by their arc length s from the entry, each
/// shared linearly by the two vertices around it; a point outside the inserted wire feels none.
class PointForces final : public Load {
 public:
  struct Point {
    double s;  ///< arc length from the entry [m]
    Vec3 f;    ///< [N]
  };
  std::vector<Point> points;
  void add(const LoadSite& rod, double scale, LoadTerms& out) const override;
  [[nodiscard]] double force_scale(const LoadSite& rod, double scale, double length) const override;
};

/// @brief A moment M on the distal edge: its component along the edge twists it (a torque on
/// θ₀), the rest acts as the couple f₁ = M⊥ × e/|e|², f₀ = −f₁ on the edge's vertices, which
/// turns with the edge (hence a stiffness).
class TipMoment final : public Load {
 public:
  Vec3 moment = Vec3::Zero();  ///< [N m]
  void add(const LoadSite& rod, double scale, LoadTerms& out) const override;
  [[nodiscard]] double force_scale(const LoadSite& rod, double scale, double length) const override;
};

/// @brief One load of each kind, summed in a fixed order.
struct Loads {
  Gravity gravity;
  TipForce tip_force;
  PointForces point_forces;
  TipMoment tip_moment;
  void add(const LoadSite& rod, double scale, LoadTerms& out) const;
  /// @brief max(@p f, every load's force_scale).
  [[nodiscard]] double force_scale(const LoadSite& rod, double scale, double length, double f) const;
};

}  // namespace flowire::rod
