#pragma once
/// @file wall_contact.hpp
/// @brief The wall's normal force on the wire: the penalty of interaction.hpp (`wall_penalty`)
/// on the distance a `Wall` gives, at each free vertex's own radius (rod::RodView::vertex_radius),
/// stiffness per unit length (RodView::cell_weight), reported as a conservative force with its
/// energy k φ(δ) so that the rod's line search measures the contact exactly; and the entry's
/// introducer sheath, the same penalty on a plane. At the end of each step it records each
/// vertex's normal force and normal (what the friction of the next step presses with) and how
/// far outside the lumen the wire went.
#include <Eigen/Dense>
#include <limits>
#include <span>
#include <vector>

#include "flowire/coupling/compliant_wall.hpp"
#include "flowire/coupling/interaction.hpp"
#include "flowire/coupling/wall.hpp"
#include "flowire/rod/external.hpp"

namespace flowire::coupling {

class WallContact {
 public:
  /// @param wire_radius the wire's radius where the rod's view carries none [m]
  WallContact(const ContactParams& params, double wire_radius) : params_(params), wire_radius_(wire_radius) {}

  /// @brief The entry as an introducer sheath: a vertex within @p reach of the entry axis may
  /// not come back out behind the entry (point @p p, unit direction @p t into the vessel): the
  /// penalty on the signed distance (p − x)·t − a to the plane one wire radius a behind the
  /// entry (vertices fed in at the entry itself stay free).
  void set_introducer(const Vec3& p, const Vec3& t, double reach);

  /// @brief Add the normal forces on the free vertices (index < @p free) against @p wall to
  /// @p out, and each vertex's force to @p tally.
  void evaluate(const rod::RodView& rod, int free, Wall& wall, rod::ForceAccumulator& out, std::span<Vec3> tally,
                InteractionStats& stats);
  /// @brief At an accepted state: each free vertex's normal force and normal for the next step's
  /// friction, and the "outside the lumen" record of @p stats. A deformable wall is loaded with
  /// the opposites of @p tally (each vertex's wall force, normal and friction).
  void end_step(const rod::RodView& rod, Wall& wall, InteractionStats& stats, std::span<const Vec3> tally = {});
  /// @brief Contact against a wall that yields (compliant_wall.hpp; outlives this object);
  /// null: the rigid wall. The contact then takes the sharp penalty onset.
  void set_deformable(CompliantWall* wall) {
    deformable_ = wall;
    anchors_stale_ = true;
  }
  [[nodiscard]] const CompliantWall* deformable() const { return deformable_; }

  /// @brief Vertex @p i's normal force [N] and its unit direction: those of the step's start
  /// once a step has ended (lagged, as in IPC), else those of the last evaluation. (Where
  /// capsules blend, the wall distance's gradient is shorter than 1: the force is the penalty's
  /// multiplier times its length, the direction the gradient normalized, so that the friction
  /// pressed by them is Coulomb's and the gradient of its potential.)
  [[nodiscard]] double normal_force(int i) const {
    const auto k = static_cast<size_t>(i);
    return lagged() ? lag_normal_force_[k] : normal_force_[k];
  }
  [[nodiscard]] const Vec3& normal(int i) const {
    const auto k = static_cast<size_t>(i);
    return lagged() ? lag_normal_[k] : normal_[k];
  }
  /// @brief Whether the normal forces are those of a step's start (a step has ended since the
  /// vertex set last changed size).
  [[nodiscard]] bool lagged() const { return lagged_; }
  void save_checkpoint() { checkpoint_ = {lag_normal_force_, lag_normal_, lagged_}; }
  void restore_checkpoint() {
    anchors_stale_ = true;
    lag_normal_force_ = checkpoint_.normal_force;
    lag_normal_ = checkpoint_.normal;
    lagged_ = checkpoint_.lagged;
  }
  [[nodiscard]] std::uint64_t introducer_contacts() const { return intro_contacts_; }
  [[nodiscard]] const ContactParams& params() const { return params_; }
  /// @brief The wall's normal force on a vertex of radius @p a at wall distance @p d (k φ′) [N].
  [[nodiscard]] double normal_force_at(double d, double a, double cell_weight) const;
  /// @brief The wall's potential energy at the last evaluation [J]: the penalties', and with a
  /// deformable wall ½ λᵀ(K⁻¹ + C)λ, the wall's strain energy included (the introducer's not).
  [[nodiscard]] double energy() const { return energy_; }
  /// @brief The wire's vertices or its resampling changed: anchor the candidates anew.
  void invalidate_anchors() { anchors_stale_ = true; }

 private:
  /// @brief Record vertex @p k's normal force and direction from the penalty's (or the
  /// compliant solve's) multiplier and the wall distance's gradient @p grad (any length).
  static void record_normal(double multiplier, const Vec3& grad, double& force, Vec3& normal);
  void ensure_size(int n);
  /// The step's candidate contacts with a deformable wall: free vertices within reach of the
  /// rest wall at the step's first evaluation, anchored at their closest wall points, with the
  /// wall measured there (distance, normal, Hessian) for that evaluation.
  void anchor_candidates(const rod::RodView& rod, int free, Wall& wall);
  /// The candidates' normal forces λ = k·max(0, δ − C λ) (active set), applied with their
  /// energy ½ λᵀ(K⁻¹ + C)λ, the band's part of their stiffness and the coupled rest.
  void solve_compliant(rod::ForceAccumulator& out, std::span<Vec3> tally, InteractionStats& stats);
  double energy_ = 0.0;
  CompliantWall* deformable_ = nullptr;
  CompliantWall::Anchored anchored_;  ///< the step's compliance and offsets at the candidates
  bool anchors_stale_ = true;
  struct Candidate {
    int vertex = -1;
    double penetration = -1.0;  ///< into the rest wall, d + a [m]; ≤ 0 apart
    Vec3 normal = Vec3::UnitX();
    Mat3 hessian = Mat3::Zero();
    double stiffness = 0.0;  ///< the penalty's k at this vertex [N/m]
  };
  std::vector<int> candidate_of_;  ///< (vertices) index into candidates_, −1 if none
  std::vector<Candidate> candidates_;
  Eigen::VectorXd lambda_;      ///< (candidates) normal forces at the last evaluation [N]
  std::vector<char> active_;    ///< (candidates) in contact at the last evaluation; empty after an anchoring
  Eigen::VectorXd wall_shift_;  ///< (candidates) the wall's normal displacement there, C λ [m]
  double max_shift_ = 0.0;      ///< the largest such displacement at an accepted state [m]
  ContactParams params_;
  double wire_radius_;
  std::vector<double> normal_force_, lag_normal_force_;  ///< (vertices) at this evaluation / step start
  std::vector<Vec3> normal_, lag_normal_;
  std::vector<Vec3> intro_force_;  ///< (vertices) the introducer's share of the tally
  bool lagged_ = false;
  struct {
    std::vector<double> normal_force;
    std::vector<Vec3> normal;
    bool lagged = false;
  } checkpoint_;
  Vec3 intro_point_ = Vec3::Zero(), intro_dir_ = Vec3::Zero();
  double intro_reach_ = 0.0;  ///< 0: no introducer
  std::uint64_t intro_contacts_ = 0;
};

}  // namespace flowire::coupling
