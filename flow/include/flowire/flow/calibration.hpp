#pragma once
/// @file calibration.hpp
/// @brief A network's calibration to the 3D solution: each branch's pressure drop fitted as
/// Δp = a Q + K|Q|Q to the finite-element solution at a few steady flows (`flowire calibrate`,
/// fem/calibrate.hpp), stored per segment (FlowSpec::segment_laws) in a JSON file that a scene
/// reads back (`vessels.calibration`).
///
/// File (`calibration.json`): `format: "flowire-calibration"`, `version: 1`, `network` (the source
/// file and the counts and total length that identify it), `fem` (the equations, the inlet flows of
/// the fit and the check), `branches` (per branch: name, a and K, the Poiseuille resistance they
/// are relative to, the fitted data and the fit's residual), `segments` (per segment of the
/// network: `resistance_factor`, `quadratic` in Pa·s²/m⁶), in SI units.
#include <string>
#include <vector>

#include "flowire/flow/spec.hpp"
#include "flowire/vessels/network.hpp"

namespace flowire::flow {

/// @brief One branch's fit.
struct BranchFit {
  int branch = -1;
  std::string name;
  double poiseuille_resistance = 0.0;  ///< R_P of the branch as the 3D domain has it (Pa·s/m³)
  double linear = 0.0;                 ///< a (Pa·s/m³)
  double quadratic = 0.0;              ///< K (Pa·s²/m⁶)
  std::vector<double> flows, drops;    ///< the 3D solution's: branch flow (m³/s) and drop (Pa) per fitted flow
  double residual = 0.0;               ///< rms over the flows of (fit − drop) / drop
  bool bounded = false;                ///< a bound was active (a at its floor, or K at 0)
  int pieces = 1;                      ///< the pieces of the branch fitted each on its own (its segments' laws)
};

struct Calibration {
  std::string network_source;  ///< the network's file, for messages
  int nodes = 0, segments = 0, branches = 0;
  double total_length = 0.0;  ///< m
  /// Σ of the segments' Poiseuille resistances at unit viscosity (m⁻³): the radii's share of the identity
  double resistance_sum = 0.0;
  std::string equations;  ///< of the 3D solution: "stokes" or "navier_stokes"
  /// "total": the calibrated network's nodes hold total pressures p + ½ρū² (its outlets their
  /// static values); "static": static pressures (fem/calibrate.hpp)
  std::string pressure = "static";
  std::vector<double> inlet_flows;  ///< m³/s of the fitted solutions
  double check_inlet_flow = 0.0;    ///< m³/s of the solution not fitted (0: none)
  std::vector<BranchFit> fits;
  std::vector<SegmentLaw> laws;  ///< (segments)
  /// (nodes, or empty) in total pressure, the kinetic energy factor α of each outlet's 3D profile
  /// (the outlet's total pressure is its static value plus α½ρ(Q/A)²); 1 elsewhere
  std::vector<double> end_alpha;
};

/// @brief Fill the identification of `net` (source, counts, total length) into `c`.
void identify(Calibration& c, const Network& net);

/// @brief Write the calibration file (atomically).
/// @throws flowire::Error (input) when the file cannot be written.
void write_calibration(const std::string& path, const Calibration& c);

/// @brief Read a calibration file and check that it was made for `net` (same numbers of nodes,
/// segments and branches, total length and resistance sum within 10⁻⁹); `where` names the scene
/// key for messages.
/// @throws flowire::Error (input) naming the file and the place: unreadable, not a calibration, a
/// value out of range, or made for another network.
Calibration read_calibration(const std::string& path, const Network& net, const std::string& where = {});

}  // namespace flowire::flow
