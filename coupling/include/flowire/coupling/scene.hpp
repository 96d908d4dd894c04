#pragma once
/// @file scene.hpp
/// @brief Scenes: the declaration of every scene key, and the runner that executes only the
/// sections a scene has (no `flow:` → no flow assembly, no `wire:` → no rod, no output → no I/O).
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "flowire/common/config.hpp"
#include "flowire/coupling/catheter.hpp"
#include "flowire/rod/model.hpp"
#include "flowire/vessels/network.hpp"
#include "flowire/vessels/surface.hpp"

namespace flowire::flow {
class FlowSolver;
}
namespace flowire::vessels {
class SpatialIndex;
}

namespace flowire::coupling {

/// @brief The one declaration of every scene key (type, default, unit, range, doc).
const config::Schema& scene_schema();

/// @brief Load a scene file with `--set` overrides (and `--out` as output.dir).
config::Config load_scene(const std::string& file, const std::vector<std::string>& overrides,
                          const std::string& out_dir = {});

/// @brief The parts of a scene this build of the library cannot run, each named by the key that
/// asks for it: `wall` (an elastic wall, meshed with gmsh), `fem` (gmsh and PETSc),
/// `flow.solver: petsc`. Empty where the library was built with all of them. The scene runner
/// (flowire-run, built without gmsh and PETSc so that it starts in a tenth of the time) hands a
/// scene that needs one to the full program before it reads or writes anything else.
std::vector<std::string> unbuilt_scene_parts(const config::Config& scene);

/// @brief Build the vessel network a scene describes (`vessels.file` or `vessels.generator`),
/// with its radii from the sections of `vessels.surface` where the scene has one
/// (`vessels.radius`, vessels/sections.hpp).
vessels::Network build_scene_network(const config::Config& scene);

/// @brief The network with what building it read and measured: the lumen surface when the
/// radii came from it (kept for the wall contact), and the radii's source for summary.json.
struct SceneNetwork {
  vessels::Network network;
  std::unique_ptr<vessels::LumenSurface> surface;  ///< read for the radii; null otherwise
  nlohmann::json surface_info;                     ///< make_scene_surface's facts
  double surface_smoothing = 0.0;
  nlohmann::json radius;  ///< {"source": "surface" | "inscribed", ...}
};
SceneNetwork build_scene_network_and_radii(const config::Config& scene);

/// @brief The wire a scene describes (`wire:` and `insertion.initial_length`), before the
/// vessel network places its base.
rod::WireSpec scene_wire_spec(const config::Config& scene);

/// @brief The scene's `catheter:` section, checked against its @p wire (the lumen must hold
/// it). @throws flowire::Error (input) naming the offending key.
CatheterSpec scene_catheter_spec(const config::Config& scene, const rod::WireSpec& wire);

class VesselForces;
/// @brief Wall contact and blood drag on the wire as the scene's `contact:` and `coupling:`
/// sections configure them (drag only with a @p flow solver); null when the scene needs
/// neither (`contact.enabled: false` and no drag), so nothing is looked up. The rod's
/// distal `tip.length` takes `contact.tip_friction` (a catheter's rod has none: the same
/// Coulomb friction, `contact.friction`, all along it).
std::shared_ptr<VesselForces> make_vessel_forces(const config::Config& scene, const vessels::SpatialIndex& index,
                                                 const rod::WireSpec& wire, flow::FlowSolver* flow);

/// @brief Result of a run; `summary` is what `summary.json` holds.
struct RunResult {
  nlohmann::json summary;
  std::string out_dir;
};

/// @brief Where a run stands, reported after every time step.
struct Progress {
  long step = 0;              ///< steps done
  long steps = 0;             ///< steps in the run
  double time = 0.0;          ///< simulated time reached [s]
  double duration = 0.0;      ///< simulated time of the whole run [s]
  double wall_seconds = 0.0;  ///< since the run started
};

/// @brief How a caller follows a run (a terminal's progress line, a GUI, a script).
struct RunOptions {
  /// Called after every step; keep it cheap (the command line redraws at most 5× a second).
  std::function<void(const Progress&)> progress;
};

/// @brief Run a validated scene and write its outputs (summary.json always).
/// @throws flowire::Error; a numerical error still leaves summary.json with status "error".
RunResult run_scene(const config::Config& scene, const RunOptions& options = {});

/// @brief What `flowire calibrate` fits: the 3D solutions at the scene's inlet value times each
/// factor, and one more not fitted to check the calibrated network against.
struct CalibrateOptions {
  std::vector<double> factors{0.5, 1.0, 1.5};
  double check_factor = 0.75;  ///< 0: no check
};

/// @brief Fit the scene's network to the 3D solution of its `fem:` section (fem/calibrate.hpp,
/// docs/fem-real-lumens.md): writes calibration.json (for `vessels.calibration`),
/// calibration.md (the before/after table), calibration.csv and summary.json in output.dir.
/// @throws flowire::Error: input (no fem: or flow: section, a built-in fem geometry, a network
/// that is not a tree, the FEM not built), numerical (a 3D solve that fails).
nlohmann::json calibrate_scene(const config::Config& scene, const CalibrateOptions& options = {});

/// @brief A network's counts as summary.json and `flowire info --json` write them.
nlohmann::json counts_json(const vessels::NetworkCounts& counts);

}  // namespace flowire::coupling
