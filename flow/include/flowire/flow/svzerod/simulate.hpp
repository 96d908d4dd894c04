#pragma once
/// @file simulate.hpp
/// @brief svZeroDSolver interop: read its JSON model, simulate it as svZeroDSolver does,
/// write `svzerod_result.csv` in its format.
///
/// Supported blocks (others are refused naming the block and its type):
/// - `BloodVessel` (R_poiseuille, C, L, stenosis_coefficient), unknowns P, Q at both ends:
///   \f$ P_{in} - P_{out} - (R + S|Q_{in}|) Q_{in} - L \dot Q_{out} = 0 \f$,
///   \f$ Q_{in} - Q_{out} - C \frac{d}{dt}\left(P_{in} - (R + S|Q_{in}|)Q_{in}\right) = 0 \f$;
/// - `BloodVesselCRL` (C at the inlet, then R and L): \f$ P_{in} - P_{out} - (R + S|Q_{out}|)Q_{out}
///   - L\dot Q_{out} = 0 \f$, \f$ Q_{in} - Q_{out} - C\dot P_{in} = 0 \f$;
/// - `NORMAL_JUNCTION`: equal pressures, conserved flow; `BloodVesselJunction`: one inlet,
///   lists R_poiseuille, L, stenosis_coefficient per outlet, \f$ P_{in} - P_i - (R_i + S_i|Q_i|)Q_i
///   - L_i\dot Q_i = 0 \f$;
/// - boundary conditions `FLOW` (Q, t), `PRESSURE` (P, t), `RESISTANCE` (R, Pd):
///   P − R Q − Pd = 0, and `RCR` (Rp, C, Rd, Pd): P − Rp Q − P_c = 0,
///   \f$ R_d Q - P_c - R_d C \dot P_c + P_d = 0 \f$, and the open-loop `CORONARY` (Ra1, Ca,
///   Ra2, Cc with intramyocardial pressure Pim(t), Rv1 to P_v; unknown V_im; in the steady
///   initial phase V_im = 0 and P = (Ra1 + Ra2 + Rv1) Q + P_v), also as `CORONARY_VAR_RES`
///   whose Ra2 varies over the cycle between Ra2_min and Ra2_max (ramps T_vc, T_vr).
/// A parameter is a number or a periodic table over `t` (linear interpolation).
///
/// Time integration as svZeroDSolver: generalized-α (`rho_infty`, default 0.5; Jansen,
/// Whiting & Hulbert 2000, Comput. Methods Appl. Mech. Engrg. 190, 305–319) on
/// \f$ E\dot y + F y + c(y, \dot y, t) = 0 \f$ (svzerod/integrator.hpp): one factorization per
/// phase for a linear model, Newton iterations to `absolute_tolerance` where a block is
/// nonlinear. Blocks by name: svzerod/blocks.hpp;
/// a steady initial state (time tables replaced by their mean, RCR capacitors removed,
/// 31 steps of one tenth of the period) unless `steady_initial: false`; the number of
/// cycles from the largest RCR time constant when `use_cycle_to_cycle_error` is set (without
/// RCR: extra cycles until the mean cap flows and pressures change by less than the tolerance);
/// output of the last cycle (times from 0) or of all cycles, vessel- or variable-based,
/// mean only, with derivatives, as its `simulation_parameters` ask.
#include <filesystem>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

namespace flowire::flow::svzerod {

/// @brief A result table, one row per (vessel or variable, time), as svZeroDSolver writes it.
struct Result {
  std::vector<std::string> columns;       ///< e.g. name,time,flow_in,flow_out,pressure_in,pressure_out
  std::vector<std::string> names;         ///< (rows) vessel or variable name
  std::vector<double> times;              ///< (rows) NaN for mean-only rows (empty time field)
  std::vector<std::vector<double>> data;  ///< (rows x columns−2) the numeric columns after name,time
  bool variable_based = false;
};

/// @brief What a run did, for the CLI's summary.json.
struct Summary {
  std::string model;        ///< input file
  std::string result_file;  ///< path of svzerod_result.csv
  int vessels = 0, junctions = 0, boundary_conditions = 0, unknowns = 0;
  int cycles = 0, steps = 0, rows = 0;
  double period = 0.0, dt = 0.0;
  double newton_iterations_per_step = 0.0;  ///< linear solves per step (1 for a linear model)
  long factorizations = 0;                  ///< numeric factorizations (2 for a linear model: steady, pulsatile)
  double seconds = 0.0;
};

/// @brief How a model's equations are set up (the solution is the same either way).
struct Options {
  /// The connections of a `NORMAL_JUNCTION` share one pressure unknown instead of each
  /// carrying its own and the junction the equations \f$ P_0 - P_i = 0 \f$: a smaller system
  /// (on a binary tree 25% fewer unknowns) with the same solution up to rounding. Output and
  /// `initial_condition` still name each connection's pressure; an initial condition that
  /// gives a junction's connections different pressures sets the shared one to the last.
  bool share_junction_pressures = true;
  /// Without `output_all_cycles`, the output covers this many cycles at the end (1: the last,
  /// as svZeroDSolver writes it; 2 lets a caller measure how periodic the run became), times
  /// from the first of them.
  int last_cycles = 1;
};

/// @brief Simulate an svZeroDSolver JSON model file.
/// @throws flowire::Error: input (unreadable JSON, unsupported block, missing parameter,
/// inconsistent period, naming the file and block), numerical (singular system, Newton
/// not converging).
Result simulate(const std::string& json_path, Summary* summary = nullptr, const Options& options = {});
/// @brief Simulate a model given as JSON in memory (e.g. built from an openBF network, openbf.hpp);
/// @p name stands for its file in messages and the summary.
Result simulate(const nlohmann::json& model, const std::string& name, Summary* summary = nullptr,
                const Options& options = {});

/// @brief Write a result as svZeroDSolver's CSV (scientific, 16 digits), atomically.
void write_result_csv(const Result& result, const std::filesystem::path& path);

/// @brief Simulate `json_path` and write `out_dir/svzerod_result.csv`; for `flowire run model.json`.
Summary run(const std::string& json_path, const std::filesystem::path& out_dir);

}  // namespace flowire::flow::svzerod
