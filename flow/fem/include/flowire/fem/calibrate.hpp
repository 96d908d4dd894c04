#pragma once
/// @file calibrate.hpp
/// @brief The network fitted to the 3D solution (`flowire calibrate`): each branch's pressure drop
/// as Δp = a Q + K|Q|Q, the form of svZeroDSolver's blood vessel with a stenosis coefficient.
///
/// The 3D problem (the scene's `fem:` geometry, equations and mesh; a real lumen's network cut at
/// its caps, cap_cut.hpp) is solved at a few steady inlet values, the scene's scaled by each
/// factor, on one mesh (Navier–Stokes: each solve starts from the last, in increasing order).
/// From each solution every branch gets a flow and a drop: the flow from the outlets' 3D flows
/// summed over the tree downstream of it (mass conservation, exact), the drop between the 3D
/// pressures at its two end nodes (the inlet's and outlets' group pressures, elsewhere the mean
/// pressure of the section normal to the branch; at a junction the section of the branch that
/// flows into it, so that the junction's loss falls to the branches leaving it). The two coefficients are the
/// least-squares fit over the solutions, with K ≥ 0 and a ≥ a tenth of the branch's Poiseuille resistance (a bound that
/// is active is reported): a branch whose 3D drop falls below that, as where the flow decelerates into a wider lumen
/// and recovers pressure, is not represented by the law. With one solution, K = 0.
///
/// In total pressure (Navier–Stokes with a flow inlet; `CalibrateOptions::total_pressure`) the pressures fitted are
/// the 3D section's mean pressure plus the dynamic pressure ½ρ(Q/πr²)² of the flow through the
/// network's section there: the drops are then those of the energy the flow loses, which a law of
/// positive coefficients can hold, where the static pressure also rises and falls as the flow
/// slows and speeds up (it recovers downstream of a junction). The network's nodes then hold total
/// pressures, but for the outlets, whose last segment carries the dynamic pressure through the
/// outlet (½ρ/A² added to its K) so that the outlet keeps its static value.
///
/// The laws go to every segment of the branch in proportion to its Poiseuille resistance (the
/// factor a/R_P uniform, K_s = K R_P,s / R_P), on the input network (its segments beyond a cap
/// take the branch's law too). The comparison is then repeated with the calibrated network on
/// every fitted solution, and on one more not fitted (`check_factor`), beside the uncalibrated
/// comparison: the before/after table.
#include <string>
#include <vector>

#include "flowire/fem/boundary_values.hpp"
#include "flowire/fem/compare.hpp"
#include "flowire/flow/calibration.hpp"

namespace flowire::fem {

struct CalibrateOptions {
  std::vector<double> factors{0.5, 1.0, 1.5};  ///< of the inlet value, the solutions fitted (> 0)
  double check_factor = 0.75;                  ///< a solution not fitted, compared after (0: none)
  /// Fit total pressures where the inlet is a flow (see the file comment); false: static.
  bool total_pressure = true;
};

/// @brief One 3D solution and the network before and after the calibration against it.
struct CalibrationRun {
  double factor = 1.0;
  double inlet_flow = 0.0;  ///< m³/s into the 3D domain
  bool fitted = true;       ///< false: the check
  CompareResult before, after;
};

struct CalibrationResult {
  flow::Calibration calibration;  ///< the laws of the input network and the fits (calibration.hpp)
  std::vector<CalibrationRun> runs;
  double mesh_seconds = 0.0, solve_seconds = 0.0;
};

/// @brief Fit the network to the 3D solution (see the file comment). Collective under MPI.
/// @throws flowire::Error (input) for a network that is not a tree, an inlet value of 0, a
/// factor ≤ 0; as compare() does for the mesh and the solves.
CalibrationResult calibrate(const Network& net, const BoundaryValues& bv, const FemOptions& opt,
                            const CalibrateOptions& co = {});

/// @brief `calibration.md` (the before/after table per solution and the fits per branch) and
/// `calibration.csv` (every sample point of every solution, network before and after and 3D) in
/// `dir`. Rank 0 only.
void write_calibration_report(const std::string& dir, const Network& net, const CalibrationResult& r);

}  // namespace flowire::fem
