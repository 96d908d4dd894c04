#pragma once
/// @file pulsatile.hpp
/// @brief The network model against the FEM over a period: a series of comparisons
/// (compare.hpp) at frame times, from quasi-steady FEM frames or from a time integration
/// of the FEM side with windkessel (RCR) outlets.
///
/// Quasi-steady Stokes frames cost one factorization and one unit solve per open boundary
/// (StokesBasis); every frame is then a linear combination. With DynamicOptions both sides
/// integrate the windkessels over the period until the frames repeat (BDF2; quasi-steady
/// 3D fields, or time-dependent Stokes, UnsteadyStokes). The files are those of
/// compare_output.hpp.
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "flowire/flow/fem/boundary_values.hpp"
#include "flowire/flow/fem/compare.hpp"
#include "flowire/flow/spec.hpp"

namespace flowire::flow::fem {

/// @brief Time integration of a pulsatile FEM series (see compare_pulsatile).
struct DynamicOptions {
  /// Boundary values at any time of the period (inlet waveform; the outlets listed in
  /// `windkessels` are replaced by their windkessels).
  std::function<BoundaryValues(double)> values_at;
  /// The network solution at a time of the period, in its periodic state (e.g. the rlc
  /// model run over enough periods); empty: the quasi-steady Poiseuille network of the
  /// frame's boundary values.
  std::function<NetworkFlow(double)> network_at;
  /// RCR outlets of the catalogue (flow::OutletBC::Type::Rcr, with C > 0) at their ends:
  /// C dP_c/dt = Q − (P_c − P_d)/R_d, outlet pressure P_c + R_p·Q (Q the flow out).
  std::vector<flow::OutletBC> windkessels;
  double period = 0.0;          ///< s, > 0; the frame times are k·period/N
  bool time_dependent = false;  ///< time-dependent Stokes (UnsteadyStokes) instead of quasi-steady frames
  int steps_per_period = 200;   ///< at least; rounded up to a multiple of the frames
  int max_periods = 40;
  double periodic_tolerance = 1e-5;  ///< max change of the frames' outlet flows over a period / max flow
};

/// @brief A pulsatile series of quasi-steady comparisons.
struct PulsatileResult {
  CompareResult steady;               ///< the comparison at `steady_time` (the fem_compare.* files)
  std::vector<CompareResult> frames;  ///< one per time
  double max_rel_diff_drop_away = 0.0, max_rel_diff_drop_junction = 0.0;  ///< over all frames
  double max_flow_split_error = 0.0, max_flow_error = 0.0;                ///< over all frames
  int factorizations = 0;                                                 ///< FEM matrix factorizations (1 for Stokes)
  double basis_seconds = 0.0;                                             ///< assembly, factorization and unit solves
  double frames_seconds = 0.0;                                            ///< combining the frames and comparing them
  int periods = 0;               ///< dynamic: periods integrated until periodic
  int steps_per_period = 0;      ///< dynamic: time steps per period
  double periodic_change = 0.0;  ///< dynamic: the last period's change (see DynamicOptions)
};

/// @brief Quasi-steady FEM frames at `times` with the boundary values `frames[i]`, and the
/// steady comparison `steady` (at time `steady_time`), all compared with the network.
/// Stokes: one factorization and one unit solve per open boundary (StokesBasis); every
/// frame is a linear combination. Navier–Stokes: every frame is solved on its own.
/// Every frame must have the same inlet node and the same kinds of conditions.
/// Writes, besides the steady files of `compare`: fem_pulsatile.csv (`time`, then the
/// columns of fem_compare.csv), fem_pulsatile_outlets.csv (`time`, then the columns of
/// fem_outlets.csv), and with `write_vtu` fem.pvd + fem_NNNN.vtu.
/// @throws flowire::Error (usage) for inconsistent frames, and as `compare`.
/// With `dyn` (Stokes only), the frames come from a time integration instead: BDF2 with
/// `steps_per_period` steps, each outlet in `dyn->windkessels` carrying its capacitor
/// (BDF2 too: at each step a resistance R_p + 1/(C·D) to a pressure set by the history,
/// D = 3/(2Δt) + 1/(R_d C)), quasi-steady 3D fields or, with `time_dependent`,
/// UnsteadyStokes; period after period until the frames' outlet flows change by less than
/// `periodic_tolerance` (else a numerical error). The frames are those of the last period.
PulsatileResult compare_pulsatile(const Network& net, std::span<const double> times,
                                  std::span<const BoundaryValues> frames, const BoundaryValues& steady,
                                  double steady_time, const FemOptions& opt, const std::string& out_dir,
                                  const DynamicOptions* dyn = nullptr);

}  // namespace flowire::flow::fem
