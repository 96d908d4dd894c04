#pragma once
/// @file openbf.hpp
/// @brief openBF's 1D network models (its YAML: a `network:` list of vessels joined by node
/// ids `sn` → `tn`, an inlet flow table, blood properties), run as compliant lumped networks.
///
/// Each vessel is cut into segments of at most `max_segment_length`, each an svZeroDSolver
/// `BloodVessel` (svzerod/simulate.hpp) whose R, L and C are the integrals of the 1D model's per-length
/// coefficients over the segment, the radius varying linearly from `Rp` to `Rd`:
/// - friction, with openBF's velocity profile of exponent γ (`gamma_profile`, 2: Poiseuille):
///   \f$ R' = 2(\gamma + 2)\mu / (\pi r^4) \f$;
/// - inertance \f$ L' = \rho / (\pi r^2) \f$;
/// - compliance of a thin incompressible elastic wall (ν = 1/2, openBF's tube law linearized at
///   the reference area): \f$ C' = 3\pi r^3 / (2 E h) \f$, h = `h0`, or where absent Avolio's
///   law h = r (a e^{b r} + c e^{d r}), a = 0.2802, b = −505.3 m⁻¹, c = 0.1324, d = −11.14 m⁻¹.
/// The linearized 1D equations of a vessel are those of a transmission line with these
/// coefficients; the segments are its lumped approximation, converging as they shrink.
///
/// Boundary conditions as openBF reads them: the flow table (`inlet_file`, else
/// `<project_name>_inlet.dat` next to the model; time in s, flow in m³/s, one cycle, repeated)
/// into node 1; at every other end a three-element windkessel (`R1`, `Cc`, `R2`, `Pout`
/// default 0) when `R1` is given (no `R2`: openBF takes R2 = R1 − Z0, Z0 = ρc/A the
/// characteristic impedance at the vessel's end), else a resistance matching the reflection
/// coefficient `Rt` (default 0): R = Z0 (1 + Rt)/(1 − Rt). `Pext` shifts openBF's tube law
/// and does not enter the linearized flow; `M`, `Ccfl`, `jump` and `convergence_tolerance`
/// are the 1D solver's settings and are not used.
#include <filesystem>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "flowire/flow/output.hpp"
#include "flowire/flow/spec.hpp"

namespace flowire::flow::openbf {

struct Vessel {
  std::string label;
  int sn = 0, tn = 0;                               ///< source and target node ids
  double length = 0.0;                              ///< m
  double youngs_modulus = 0.0;                      ///< Pa
  double rp = 0.0, rd = 0.0;                        ///< radius at sn and at tn (m)
  double h0 = 0.0;                                  ///< wall thickness (m); 0: Avolio's law
  double gamma = 2.0;                               ///< velocity profile exponent
  double r1 = 0.0, r2 = 0.0, cc = 0.0, pout = 0.0;  ///< wk3 outlet (r1 > 0)
  double rt = 0.0;                                  ///< reflection coefficient of an outlet without wk3
  int line = 0;                                     ///< in the model file, for messages
};

struct Model {
  std::string file;
  std::string name;  ///< project_name
  double rho = 1060.0, mu = 4e-3;
  int cycles = 10;
  std::vector<double> inlet_time, inlet_flow;  ///< one cycle
  std::vector<Vessel> vessels;
  std::vector<std::string> warnings;  ///< keys read differently from openBF, said once
};

/// @brief Whether @p path is an openBF model: YAML whose top level has a `network:` list of
/// vessels with `sn` and `tn`. False for anything else (a scene), never throws.
bool is_model(const std::string& path);

/// @brief Read and check an openBF model. @throws flowire::Error (input) naming the file, the
/// line and the vessel: a missing or unknown key, a non-positive length, radius, modulus or
/// windkessel value, a network that is not one connected piece fed from node 1, an outlet
/// without a condition, an inlet table that is not increasing in time.
Model read(const std::string& path);

/// @brief Wall thickness at radius r: h0, or Avolio's law.
double wall_thickness(const Vessel& v, double r);
/// @brief Characteristic impedance ρc/A at radius r (c² = 2Eh/(3ρr)).
double characteristic_impedance(const Model& m, const Vessel& v, double r);

/// @brief The condition at the end of outlet vessel @p v as openBF reads it (node unset): its
/// windkessel (R2 = R1 − Z0 where R2 is absent), else the resistance of its reflection
/// coefficient. @throws flowire::Error (input) naming the vessel when R1 − Z0 is not positive.
flow::OutletBC outlet_condition(const Model& m, const Vessel& v);

struct Options {
  double max_segment_length = 0.02;  ///< m
  int steps_per_cycle = 500;         ///< time steps per cardiac cycle
};

/// @brief The svZeroDSolver model of @p m (one BloodVessel per segment, named
/// `<label>#<k>`, junctions at the nodes and between segments, FLOW inlet, RCR or
/// RESISTANCE outlets), simulated for the model's cycles, all cycles written.
nlohmann::json to_svzerod(const Model& m, const Options& options = {});

/// @brief Per vessel (openBF label) and output time of the last cycle: the flow and pressure
/// at its two ends; and the periodicity of the run.
struct Waveforms {
  std::vector<std::string> names;  ///< (rows)
  std::vector<double> times;       ///< (rows) from the last cycle's start
  std::vector<double> flow_in, flow_out, pressure_in, pressure_out;
  /// max over vessels of |p̄_last − p̄_previous| / p̄_last for the mean pressure at the
  /// vessel's inlet over the last two cycles
  double periodicity = 0.0;
  int cycles = 0, steps = 0, segments = 0, unknowns = 0;
  double seconds = 0.0;  ///< simulation
};

/// @brief Simulate @p m (to_svzerod) and gather the waveforms per vessel.
Waveforms simulate(const Model& m, const Options& options = {});

/// @name A model as a network in space (openbf_network.cpp)
///@{
/// @brief The model's vessels as 3D centerlines, each of its own length, its radius linear
/// from Rp to Rd, named by its label; node 1 at the origin. ADAN56's arteries (and any model
/// with labels of that anatomy) take their directions in the body (x the patient's left, y
/// anterior, z up); other models a tree spread around each parent's direction. A vessel that
/// closes a loop is a circular arc of its own length between its two placed ends.
/// @throws flowire::Error (input) naming the vessel where a loop's ends lie farther apart
/// than its length.
vessels::Centerlines layout(const Model& m);
/// @brief The network of layout(@p m).
vessels::Network network(const Model& m, const vessels::BuildOptions& options = {});
/// @brief The model's flow on @p net (its network()): the compliant model, the inlet flow
/// table at node 1's end, each outlet vessel's condition (outlet_condition) at its end, each
/// vessel's wall (E; h0, or Avolio's law at its mean radius) as its branch's own, the blood's
/// density and viscosity. A gamma_profile other than 2 is said in a warning: the network's
/// friction is Poiseuille's.
FlowSpec flow_spec(const Model& m, const vessels::Network& net);
///@}

/// @brief The waveforms of @p count vessels along the longest path from the inlet to an outlet
/// (its first and last vessel and others evenly spaced in length between), each at its inlet:
/// along the aorta to the periphery in ADAN56, as the 1D papers draw them.
std::vector<WaveformSeries> path_waveforms(const Model& m, const Waveforms& w, int count);

/// @brief vessels.csv: `name,time,flow_in,flow_out,pressure_in,pressure_out`, SI, atomically.
void write_vessels_csv(const Waveforms& w, const std::filesystem::path& path);

}  // namespace flowire::flow::openbf
