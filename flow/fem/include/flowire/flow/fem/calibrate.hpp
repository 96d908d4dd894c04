#pragma once
/// @file calibrate.hpp
/// @brief The network fitted to the 3D solution (`flowire calibrate`): each branch's pressure drop
/// as Δp = a Q + K|Q|Q, the form of svZeroDSolver's blood vessel with a stenosis coefficient.
///
/// The 3D problem (the scene's `fem:` geometry, equations and mesh; a real lumen's network cut at
/// its caps, cap_cut.hpp) is solved at a few steady inlet values, the scene's scaled by each
/// factor, on one mesh (Navier–Stokes: each solve starts from the last, in increasing order).
/// From each solution every branch gets a flow, the outlets' 3D flows summed over the tree
/// downstream of it (mass conservation, exact), and every node a pressure: the inlet's and the
/// outlets' group pressures, elsewhere the mean pressure of the section normal to the branch (at a
/// junction the section of the branch that flows into it, so that the junction's loss falls to the
/// branches leaving it). The branches are fitted from the inlet down, each piece by piece: a piece
/// runs to the next node with a 3D pressure, and is merged with the following one while a bound of
/// its fit is active; its two coefficients are the least-squares fit over the solutions relative
/// to each drop, with K ≥ 0 and a ≥ a tenth of its Poiseuille resistance; and its drop is taken
/// from the pressure the fitted network will have at its start, so that what one fit misses the
/// next takes up and the drops along every path from the inlet to an outlet stay the 3D
/// solution's. A branch whose 3D drop is negative (a pressure that recovers over it) gets the floor
/// and is reported as bounded. With one solution, K = 0.
///
/// In total pressure (Navier–Stokes with a flow inlet; `CalibrateOptions::total_pressure`) the
/// pressures fitted are the energy each section carries per unit flow, ∫(p + ½ρ|u|²) u·n dA / Q
/// over the disk of the network's radius (section_total_pressure: the kinetic energy of the real
/// velocity profile included), at the inlet too; at an outlet its static value plus α½ρ(Q/A)²
/// (α that of the 3D profile through the outlet's section), which the outlet's last segment carries in its
/// law so that the outlet node keeps the static value. The drops are then those of the energy the flow loses, which a
/// law of positive coefficients holds, where the static pressure rises and falls as the flow slows and speeds up (it
/// recovers downstream of a junction, and the arch's jet stagnates at the branch ostia). The calibrated network's nodes
/// hold total pressures, and it is compared in total pressure.
///
/// Each segment takes its piece's law in proportion to its Poiseuille resistance (the factor a/R_P
/// uniform over the piece, K_s = K R_P,s / R_P), on the input network too (its segments beyond a
/// cap take their branch's law as a whole). The comparison is then repeated with the calibrated network on
/// every fitted solution, and on one more not fitted (`check_factor`), beside the uncalibrated
/// comparison: the before/after table.
#include <string>
#include <vector>

#include "flowire/flow/calibration.hpp"
#include "flowire/flow/fem/boundary_values.hpp"
#include "flowire/flow/fem/compare.hpp"

namespace flowire::flow::fem {

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
/// `calibration.csv` (every sample point of every solution: the 3D static pressure and the
/// network's before; the 3D pressure the calibrated network is compared with, total in total
/// pressure, and the network's after) in `dir`. Rank 0 only.
void write_calibration_report(const std::string& dir, const Network& net, const CalibrationResult& r);

}  // namespace flowire::flow::fem
