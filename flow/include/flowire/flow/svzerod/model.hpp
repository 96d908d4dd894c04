#pragma once
/// @file model.hpp
/// @brief An svZeroDSolver JSON model read into blocks (through the Registry), connection
/// nodes, unknowns and simulation parameters.
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "flowire/flow/svzerod/block.hpp"
#include "flowire/flow/svzerod/integrator.hpp"
#include "flowire/flow/svzerod/simulate.hpp"

namespace flowire::flow::svzerod {

/// @brief `simulation_parameters` of the model, with svZeroDSolver's defaults.
struct SimulationParameters {
  int cycles = 1;                   ///< number_of_cardiac_cycles
  int pts = 2;                      ///< number_of_time_pts_per_cardiac_cycle
  double atol = 1e-8;               ///< absolute_tolerance
  int max_iter = 30;                ///< maximum_nonlinear_iterations
  bool steady_initial = true;       ///< steady_initial
  double rho = 0.5;                 ///< rho_infty
  bool variable_based = false;      ///< output_variable_based
  bool mean_only = false;           ///< output_mean_only
  bool derivative = false;          ///< output_derivative
  bool all_cycles = false;          ///< output_all_cycles
  int output_interval = 1;          ///< output_interval
  int last_cycles = 1;              ///< cycles output without output_all_cycles (Options::last_cycles)
  double period = -1.0;             ///< cardiac_period (-1: from the tables)
  bool cycle_error = false;         ///< use_cycle_to_cycle_error
  double cycle_error_value = 0.01;  ///< sim_cycle_to_cycle_percent_error / 100
};

/// @brief A vessel as the output lists it; `cap`: 1 inlet vessel, 2 outlet vessel, 3 both, 0 inside.
struct Vessel {
  const Block* block = nullptr;
  int cap = 0;
};

struct Model {
  std::string file;
  std::vector<std::unique_ptr<Block>> blocks;  ///< vessels, boundary conditions, junctions, in input order
  std::vector<Node> nodes;                     ///< one per connection, in connection order
  /// The peer's variables in its order: flow:A:B, pressure:A:B per connection, then the blocks'
  /// own (pressure_c:X, ...); with shared junction pressures several name one unknown.
  std::vector<std::string> dofs;
  std::vector<int> dof_unknown;  ///< (dofs) the unknown each variable is
  std::vector<Vessel> vessels;   ///< in input order
  int unknowns = 0, junctions = 0, boundary_conditions = 0;
  double period = 1.0;  ///< cardiac period
  bool has_rcr = false;
  double max_tau = 0.0;  ///< largest RCR time constant Rd·C
  SimulationParameters sim;
  State initial;  ///< from `initial_condition` (zero elsewhere)

  [[nodiscard]] std::vector<Block*> block_pointers() const;
};

/// @brief Read a model file. @throws flowire::Error (input) naming the file and the block, or
/// the key of simulation_parameters out of its range.
Model read_model(const std::string& json_path, const Options& options = {});
/// @brief The same from a model already in memory (e.g. one built from an openBF network);
/// @p json_path names it in messages.
Model read_model(const nlohmann::json& cfg, const std::string& json_path, const Options& options = {});

/// @brief Refuse a run of more time steps than a run may plan (kMaxSteps, steps.hpp):
/// (@p pts - 1) x @p cycles, the cycles from @p cycles_from (a key, or what set them).
/// @throws flowire::Error (input) naming @p file and the keys.
void check_time_steps(const std::string& file, double pts, double cycles, std::string_view cycles_from);

}  // namespace flowire::flow::svzerod
