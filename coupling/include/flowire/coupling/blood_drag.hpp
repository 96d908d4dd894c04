#pragma once
/// @file blood_drag.hpp
/// @brief The blood's drag on the wire: at each free vertex, the law of drag.hpp (`blood_drag`)
/// from the blood velocity where the vertex lies (a `VelocityField`, e.g.
/// FlowSolver::velocity_at, in the segment WireLocation found), the vertex's own radius
/// (rod::RodView::vertex_radius), the length of wire it stands for and the vessel's axis there,
/// with its exact velocity Jacobian (implicit in the wire velocity). Once a step
/// (DragModel::once_per_step) the law is evaluated at Newton's initial guess and taken
/// linearized in the wire velocity for the rest of the step. Vertices inside a catheter are
/// shielded (no drag).
#include <functional>
#include <limits>
#include <span>
#include <vector>

#include "flowire/coupling/drag.hpp"
#include "flowire/coupling/interaction.hpp"
#include "flowire/coupling/wire_location.hpp"
#include "flowire/rod/external.hpp"

namespace flowire::coupling {

/// @brief Blood velocity at a point located in a segment (e.g. FlowSolver::velocity_at).
using VelocityField = std::function<vessels::Vec3(int segment, const vessels::Vec3& p)>;

class BloodDrag {
 public:
  /// @param model the law and the blood (its wire_radius is set to @p wire_radius)
  /// @param wire_radius the wire's largest radius [m], where the rod's view carries none
  /// @throws flowire::Error (usage) for a slender-body length not above the wire radius
  BloodDrag(DragModel model, double wire_radius, VelocityField velocity);

  /// @brief Whether there is a law and a blood velocity to drag with.
  [[nodiscard]] bool active() const { return model_.law != DragLaw::None && velocity_; }
  /// @brief Add the drag on the free vertices (index < @p free), located by @p where, to @p out,
  /// and each vertex's force to @p tally (which it sets: the drag is the vertex's only one there).
  void evaluate(const rod::RodView& rod, int free, const WireLocation& where, rod::ForceAccumulator& out,
                std::span<Vec3> tally, InteractionStats& stats);
  /// @brief At an accepted state: the largest normal Reynolds number into @p stats; the next
  /// step linearizes anew.
  void end_step(int free, InteractionStats& stats);
  /// @brief Forget the step's linearization (a step retaken, another vertex set).
  void invalidate() { step_time_ = std::numeric_limits<double>::quiet_NaN(); }

  /// @brief Vertices the blood does not reach (a wire inside a catheter): shielded[i] != 0
  /// has no drag. Empty: none.
  void set_shielded(std::vector<char> shielded) { shielded_ = std::move(shielded); }
  [[nodiscard]] const std::vector<char>& shielded() const { return shielded_; }
  void set_velocity_field(VelocityField v) { velocity_ = std::move(v); }
  [[nodiscard]] const DragModel& model() const { return model_; }
  /// @brief (vertices) blood velocity at each vertex at the last evaluation of the law.
  [[nodiscard]] const std::vector<Vec3>& fluid_velocity() const { return fluid_; }

 private:
  void ensure_size(int n);
  DragModel model_;
  double wire_radius_;
  VelocityField velocity_;
  std::vector<char> shielded_;
  std::vector<Vec3> fluid_;
  std::vector<double> reynolds_;  ///< (vertices) normal Reynolds number at the last evaluation
  /// The drag of the step linearized at Newton's initial guess: per vertex the force, its
  /// velocity Jacobian and the velocity and tangent they were taken at, valid for the solve
  /// step_serial_ (RodView::solve_serial) of the step that ends at step_time_ with step_dt_.
  struct Linearization {
    Vec3 force = Vec3::Zero(), v = Vec3::Zero(), t = Vec3::UnitX();
    Mat3 dfdv = Mat3::Zero();
    bool valid = false;
  };
  std::vector<Linearization> lin_;
  double step_time_ = std::numeric_limits<double>::quiet_NaN();
  double step_dt_ = 0.0;
  long step_serial_ = -1;
};

}  // namespace flowire::coupling
