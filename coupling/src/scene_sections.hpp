#pragma once
// The sections of a scene, each in one file: the declaration of its keys (declare_*_keys,
// composed in order by scene_schema(), scene_schema.cpp) next to the function that reads
// them into the settings of the part they configure. The public readers (build_scene_network,
// scene_wire_spec, scene_catheter_spec, make_vessel_forces) are declared in scene.hpp.
//
//   vessels:              config_vessels.cpp   build_scene_network
//   flow:                 flow/src/spec.cpp    flow::from_config
//   wire:, loads:         config_wire.cpp      scene_wire_spec, enter_network, apply_loads
//   catheter:             config_catheter.cpp  scene_catheter_spec
//   insertion:            config_insertion.cpp drive_wire, insertion_plan
//   contact:              config_contact.cpp   contact_settings
//   obstacles:, coupling: config_coupling.cpp  drag_model, make_vessel_forces, make_tip_forces, coupling_settings
//   solve:                config_solve.cpp     solve_settings, scene_integrator
//   fem:                  config_fem.cpp       check_fem, run_fem, run_fem_geometry
//   output:               run_output.cpp       RunRecorder
#include <filesystem>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <string_view>

#include "flowire/common/config.hpp"
#include "flowire/coupling/compliant_wall.hpp"
#include "flowire/coupling/drag.hpp"
#include "flowire/coupling/schedule.hpp"
#include "flowire/coupling/vessel_forces.hpp"
#include "flowire/flow/spec.hpp"
#include "flowire/rod/model.hpp"
#include "flowire/rod/simulator.hpp"
#include "flowire/vessels/network.hpp"

namespace flowire::flow {
class FlowSolver;
struct FlowSpec;
}  // namespace flowire::flow

namespace flowire::coupling {

class TipForces;

/// @brief The declared defaults of the top-level @p section (as a scene giving it empty has
/// them), made once. @throws flowire::Error (usage) if @p section is no top-level section.
[[nodiscard]] const config::Config& declared_scene_defaults(std::string_view section);
/// @brief @p section as @p scene gives it or, where the scene leaves it out, as its keys'
/// declared defaults state it (contact: and coupling: act on a wire in vessels unwritten).
[[nodiscard]] const config::Config& given_or_declared(const config::Config& scene, std::string_view section);

// ---- vessels: (config_vessels.cpp)
void declare_vessel_keys(config::Schema& schema);
/// @brief The flow of the scene on @p net: flow::from_config, and where vessels.file is an
/// openBF model, that model's own inlet, outlets, walls, blood and compliant model wherever
/// the scene does not state them (openbf::flow_spec).
flow::FlowSpec scene_flow(const config::Config& scene, const vessels::Network& net);

// ---- wire:, loads: (config_wire.cpp)
void declare_wire_keys(config::Schema& schema);
void declare_load_keys(config::Schema& schema);
/// @brief The network end the wire enters by (wire.entry: a node id, or auto: the end
/// farthest from the inlet). Without a wire.base: section the base is placed there, pointing
/// into the entry vessel; without an insertion: section the initially inserted length is
/// insertion.initial_length's declared default.
/// @throws flowire::Error (input) naming wire.entry if it is no end of @p net.
int enter_network(const config::Config& scene, const vessels::Network& net, rod::WireSpec& wire);
/// @brief loads: on the wire; gravity also on the @p catheter, if there is one.
void apply_loads(const config::Config& scene, rod::RodSimulator& wire, rod::RodSimulator* catheter);

// ---- catheter: (config_catheter.cpp)
void declare_catheter_keys(config::Schema& schema);

// ---- insertion: (config_insertion.cpp)
void declare_insertion_keys(config::Schema& schema);
/// @brief How the base of @p wire is driven (speeds, rotation, force limit or force feed).
/// @throws flowire::Error (input) naming the insertion key at fault.
void drive_wire(const config::Config& scene, rod::RodSimulator& wire);
/// @brief What drives the wire between steps: insertion.speed and rotation_speed (0 without
/// an insertion: section or a wire), max_length (infinity when not given), schedule (null
/// when not given).
struct InsertionPlan {
  double speed = 0.0, rotation_speed = 0.0;
  double max_length = std::numeric_limits<double>::infinity();
  std::unique_ptr<DriveSchedule> schedule;
};
/// @throws flowire::Error (input) if insertion.schedule is given with speed or rotation_speed,
/// or without a wire (@p has_wire false).
[[nodiscard]] InsertionPlan insertion_plan(const config::Config& scene, bool has_wire);

// ---- contact: (config_contact.cpp)
void declare_contact_keys(config::Schema& schema);
struct ContactSettings {
  ContactParams params;        ///< all but tip_length (the rod's) and slip_speed (the model's)
  bool settle = true;          ///< contact.settle
  bool allow_outside = false;  ///< contact.allow_outside
  bool introducer = true;      ///< contact.introducer
};
/// @brief The contact: section, or its declared defaults where the scene has none.
[[nodiscard]] ContactSettings contact_settings(const config::Config& scene);

// ---- obstacles:, coupling: (config_coupling.cpp)
void declare_obstacle_keys(config::Schema& schema);
void declare_coupling_keys(config::Schema& schema);
/// @brief The blood drag on @p wire (coupling.drag, drag_scale; flow.viscosity, density):
/// DragLaw::None without a flow (@p has_flow false).
[[nodiscard]] DragModel drag_model(const config::Config& scene, const rod::WireSpec& wire, bool has_flow);
/// @brief Obstacles (clot resistance) and steering, null if the scene has neither.
/// @throws flowire::Error (input) naming the obstacle or steering key at fault.
[[nodiscard]] std::shared_ptr<TipForces> make_tip_forces(const config::Config& scene, const vessels::Network* net);
struct CouplingSettings {
  bool occlusion = true;         ///< coupling.occlusion: annulus
  bool occlusion_given = false;  ///< coupling.occlusion in the scene (given or defaulted in its coupling:)
  int flow_every = 1;            ///< coupling.flow_every, at least 1
};
[[nodiscard]] CouplingSettings coupling_settings(const config::Config& scene);

// ---- solve: (config_solve.cpp)
void declare_solve_keys(config::Schema& schema);
struct SolveSettings {
  bool is_static = false;  ///< solve.mode: static
  double dt = 0.0;         ///< solve.dt [s]
  long steps = 0;          ///< solve.duration / dt (0 for a static scene)
};
/// @throws flowire::Error (input) naming solve.duration and solve.dt if their quotient is more
/// steps than a run may plan (kMaxSteps, steps.hpp).
[[nodiscard]] SolveSettings solve_settings(const config::Config& scene);
/// @brief solve.integrator, the rods' time integrator.
[[nodiscard]] rod::Integrator scene_integrator(const config::Config& scene);

// ---- fem: (config_fem.cpp)
void declare_fem_keys(config::Schema& schema);
/// @brief Whether the comparison is on the network's geometry (network or lumen; also
/// when the scene has no fem:).
[[nodiscard]] bool fem_on_network(const config::Config& scene);
/// @brief Input checks of the fem: section, done at setup (before the run, not after it).
void check_fem(const config::Config& scene, const flow::FlowSolver* flow, const vessels::Network* net);
/// @brief The FEM reference on the network's geometry with the flow's boundary conditions.
[[nodiscard]] nlohmann::json run_fem(const config::Config& scene, const vessels::Network& net,
                                     const flow::FlowSolver& flow, const std::filesystem::path& out);
/// @brief The DFG benchmark 3D-1Z (fem.geometry: dfg_3d_1z).
[[nodiscard]] nlohmann::json run_fem_geometry(const config::Config& scene, const std::filesystem::path& out);

// ---- wall: (config_wall.cpp)
void declare_wall_keys(config::Schema& schema);
/// @brief The vessel wall as an elastic solid (wall:), null without the section: around
/// @p surface (vessels.surface) where given, else around the network's tubes.
/// @throws flowire::Error (input) naming the key at fault, the vessels where no tube can be
/// built along the network, the surface and the place where no wall can be grown around it;
/// (input) without gmsh in the build.
/// A branch's wall is its own (wall.<branch>.youngs_modulus, .thickness, .thickness_ratio), else
/// the flow's wall of that branch (@p flow_walls: flow.wall.<branch>, or an openBF model's
/// vessels), else the wall section's.
[[nodiscard]] std::unique_ptr<CompliantWall> make_scene_wall(const config::Config& scene, const vessels::Network& net,
                                                             const vessels::LumenSurface* surface,
                                                             nlohmann::json& facts,
                                                             std::span<const flow::BranchWall> flow_walls = {});

// ---- output: (run_output.cpp)
void declare_output_keys(config::Schema& schema);
/// @brief output.every in steps of @p dt: 0 for only the final state, else at least 1.
/// @throws flowire::Error (input) naming output.every and solve.dt if their quotient is more
/// steps than a run may plan (kMaxSteps, steps.hpp).
[[nodiscard]] long output_every_steps(const config::Config& scene, double dt);

}  // namespace flowire::coupling
