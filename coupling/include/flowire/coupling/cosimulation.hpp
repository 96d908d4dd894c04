#pragma once
/// @file cosimulation.hpp
/// @brief A scene's co-simulation, one step at a time: what `run_scene` steps, for a caller
/// that steers it between steps (the insertion speed, a script, a GUI) and reads the wire
/// and the flow as it goes. It writes nothing; `run_scene` adds the outputs around it.
///
/// Usage:
/// @code
/// auto scene = load_scene("scene.yaml", {});
/// CoSimulation sim(scene);
/// sim.start();                       // flow at t = 0, the wire settled against the walls
/// while (sim.step_count() < sim.planned_steps()) {
///   sim.set_insertion_speed(0.01);   // [m/s], before any step
///   sim.step();                      // solve.dt of simulated time
///   auto frame = sim.wire_frame();   // vertices base → tip, forces per vertex
/// }
/// @endcode
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "flowire/common/config.hpp"
#include "flowire/coupling/catheter.hpp"
#include "flowire/coupling/compliant_wall.hpp"
#include "flowire/coupling/schedule.hpp"
#include "flowire/coupling/wire_output.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire/vessels/network.hpp"
#include "flowire/vessels/spatial.hpp"

namespace flowire::flow {
class FlowSolver;
struct SegmentOcclusion;
}  // namespace flowire::flow
namespace flowire::rod {
class RodSimulator;
}
namespace flowire::vessels {
class LumenSurface;
}

namespace flowire::coupling {

class VesselForces;
class TipForces;
class WireOcclusion;
class LumenContact;

class CoSimulation {
 public:
  /// @brief Build what the scene has (vessels, flow, wire, contact, drag) and check its
  /// solve: and output: values. @p facts (optional) receives the summary entries known at
  /// setup (`network` counts, `flow` solver and model, `wire_entry_node`) as soon as each
  /// is known, so a run that fails later still reports them.
  /// @throws flowire::Error (input) naming the scene file and key at fault.
  explicit CoSimulation(const config::Config& scene, nlohmann::json* facts = nullptr);
  ~CoSimulation();
  CoSimulation(const CoSimulation&) = delete;
  CoSimulation& operator=(const CoSimulation&) = delete;

  /// @brief The flow at t = 0; a static scene's equilibrium, or a dynamic wire's initial
  /// shape settled against the walls (`contact.settle`). Call once, before step().
  /// @throws flowire::Error (numerical) if the static solve fails.
  void start();
  /// @brief Advance by solve.dt: the flow (every coupling.flow_every steps), then the rod.
  /// @throws flowire::Error (numerical) if the rod step fails (NaN, singular matrix).
  void step();

  // --- controls (take effect at the next step) ---------------------------------------------
  /// @brief Feeding speed [m/s] (> 0 pushes in); insertion.max_length still stops it. With
  /// insertion.schedule, the schedule sets both speeds again at every step.
  void set_insertion_speed(double speed);
  /// @brief Clamp rotation speed about the insertion direction [rad/s].
  void set_rotation_speed(double omega);
  /// @brief The feeding and rotation speeds of the next step (insertion.speed and
  /// rotation_speed until set; 0 once insertion.max_length is reached).
  [[nodiscard]] double insertion_speed() const { return insertion_speed_; }
  /// @brief insertion.schedule, or null.
  [[nodiscard]] const DriveSchedule* schedule() const { return schedule_.get(); }
  [[nodiscard]] double rotation_speed() const { return rotation_speed_; }

  // --- the run ----------------------------------------------------------------------------
  [[nodiscard]] const config::Config& scene() const { return scene_; }
  [[nodiscard]] double dt() const { return dt_; }
  /// @brief Steps of solve.duration (0 for a static scene).
  [[nodiscard]] long planned_steps() const { return steps_; }
  /// @brief Steps taken so far.
  [[nodiscard]] long step_count() const { return step_; }
  /// @brief Simulated time reached [s].
  [[nodiscard]] double time() const { return static_cast<double>(step_) * dt_; }
  /// @brief Rod steps (and the static solve) that did not converge.
  [[nodiscard]] int unconverged_steps() const { return failures_; }
  /// @brief The settling solve's report (`converged`, `newton_iterations`); null if none.
  [[nodiscard]] const nlohmann::json& settle() const { return settle_; }
  /// @brief How the wire was laid out at the start: "straight" or "vessel_path".
  [[nodiscard]] const std::string& initial_layout() const { return initial_layout_; }
  /// @brief Seconds spent in the flow and in the rod (contact and drag included) so far.
  [[nodiscard]] double flow_seconds() const { return t_flow_; }
  [[nodiscard]] double rod_seconds() const { return t_rod_; }

  // --- the parts (null when the scene has none) ----------------------------------------------
  [[nodiscard]] const vessels::Network* network() const { return net_ ? &*net_ : nullptr; }
  [[nodiscard]] flow::FlowSolver* flow() const { return fsolver_.get(); }
  [[nodiscard]] rod::RodSimulator* rod() const { return sim_.get(); }
  [[nodiscard]] const VesselForces* forces() const { return forces_.get(); }
  [[nodiscard]] const TipForces* tip_forces() const { return tip_forces_.get(); }
  [[nodiscard]] const vessels::SpatialIndex* index() const { return index_ ? &*index_ : nullptr; }
  /// @brief The wire's occlusion of the flow (coupling.occlusion: annulus), null if none.
  [[nodiscard]] const WireOcclusion* occlusion() const { return occlusion_.get(); }

  /// @brief The wire now, as the outputs write it: free vertices from the base (s = 0) to the
  /// tip, with the interaction, drag, contact forces and blood velocity at each (zero without
  /// contact and drag). Empty without a wire.
  [[nodiscard]] WireFrame wire_frame() const;
  /// @brief The catheter (`catheter:`), null if none; its wall forces; its frame as wire_frame().
  [[nodiscard]] rod::RodSimulator* catheter() const { return cath_.get(); }
  [[nodiscard]] const VesselForces* catheter_forces() const { return cath_forces_.get(); }
  [[nodiscard]] WireFrame catheter_frame() const;
  /// @brief The wire–catheter lumen contact, null without a catheter.
  [[nodiscard]] const LumenContact* lumen_contact() const { return lumen_.get(); }
  /// @brief The deformable vessel wall (wall:), null without.
  [[nodiscard]] const CompliantWall* wall() const { return wall_.get(); }
  /// @brief With wall.flow_radii, the largest relative widening |u|/r a segment of the flow took.
  [[nodiscard]] double max_flow_widening() const { return max_widening_; }
  [[nodiscard]] bool wall_widens_flow() const { return wall_flow_radii_; }
  /// @brief Catheter steps that did not converge; coupled static solves that did not.
  [[nodiscard]] int catheter_unconverged_steps() const { return cath_failures_; }
  /// @brief The last coupled static solve of wire and catheter (sweeps, imbalance).
  [[nodiscard]] const PairStaticReport& pair_static_report() const { return pair_static_; }
  /// @brief Sweeps (wire + catheter steps) of the coupled steps so far, and the steps whose
  /// sweeps ended with the pair out of balance.
  [[nodiscard]] long pair_sweeps() const { return pair_sweeps_; }
  [[nodiscard]] long pair_unconverged_steps() const { return pair_unconverged_; }

 private:
  // The set-up steps of the constructor, in order; each reads its own sections.
  void build_network(nlohmann::json& facts);  ///< vessels:
  void build_flow(nlohmann::json& facts);     ///< flow:
  /// wire: (placed at its entry), catheter:, loads:, insertion:, and what acts on them.
  void build_wire(nlohmann::json& facts);
  void build_catheter(const rod::WireSpec& wire);
  /// Lays the inserted wire (and catheter) along the vessel path from the entry.
  void lay_along_vessels(int entry);
  /// Wall contact and blood drag (contact:, coupling:, vessels.surface), on the catheter too.
  void add_wall_forces(const rod::WireSpec& wire, int entry, nlohmann::json& facts);
  void couple_catheter(nlohmann::json& facts);  ///< the wire in the catheter's lumen
  void plan_steps();                            ///< solve:, coupling.flow_every, insertion: speeds, limit, schedule
  void couple_occlusion();                      ///< coupling.occlusion
  /// Sets the flow's segment occlusion from the wire of the last accepted step.
  void occlude();
  void shield_wire();
  config::Config scene_;
  /// The flow's node pressures onto the wall (wall.blood_pressure), after each flow solve.
  void press_wall();
  std::optional<vessels::Network> net_;
  std::unique_ptr<flow::FlowSolver> fsolver_;
  std::unique_ptr<rod::RodSimulator> sim_;
  std::optional<vessels::SpatialIndex> index_;
  std::unique_ptr<vessels::LumenSurface> surface_;  // vessels.surface, null without
  nlohmann::json surface_info_;                     // what reading it found (summary.json)
  double surface_smoothing_ = 0.0;
  std::shared_ptr<VesselForces> forces_;
  std::unique_ptr<CompliantWall> wall_;  // wall:, null without
  bool wall_blood_pressure_ = false;     // wall.blood_pressure: the flow's pressure loads the wall
  double wall_reference_pressure_ = 0.0;
  bool wall_flow_radii_ = false;                         // wall.flow_radii: the flow's segments widen with the wall
  double max_widening_ = 0.0;                            // the largest |u|/r a segment took
  std::vector<flow::SegmentOcclusion> segment_factors_;  // the occlusion and widening of each segment
  std::shared_ptr<TipForces> tip_forces_;
  std::unique_ptr<WireOcclusion> occlusion_;
  // catheter: (catheter.hpp): its rod, wall forces and the contact with the wire in its lumen
  std::unique_ptr<rod::RodSimulator> cath_;
  std::optional<CatheterSpec> cath_spec_;
  std::shared_ptr<VesselForces> cath_forces_;
  std::shared_ptr<LumenContact> lumen_;
  int cath_failures_ = 0;
  PairStaticReport pair_static_;
  long pair_sweeps_ = 0;       ///< wire + catheter steps taken by the coupled steps
  long pair_unconverged_ = 0;  ///< coupled steps whose sweeps ended with the pair out of balance
  /// Static equilibrium of what the scene has (the pair with a catheter).
  rod::StepReport solve_static_all();
  std::string initial_layout_ = "straight";
  nlohmann::json settle_;
  double dt_ = 0.0, max_length_ = 0.0;
  double insertion_speed_ = 0.0, rotation_speed_ = 0.0;
  std::unique_ptr<DriveSchedule> schedule_;  ///< insertion.schedule, if given
  long steps_ = 0, step_ = 0;
  int flow_every_ = 1;
  bool is_static_ = false;
  int failures_ = 0;
  double t_flow_ = 0.0, t_rod_ = 0.0;
};

}  // namespace flowire::coupling
