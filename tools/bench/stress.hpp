#pragma once
/// @file stress.hpp
/// @brief The stability stress matrix of the aortic-arch co-simulation scene.
///
/// Each point of the matrix (time step × shaft stiffness × wire length × insertion speed ×
/// base rotation × flow amplitude × friction) loads `examples/aortic_arch/scene.yaml`,
/// applies the point as `--set` overrides, and steps the scene with the library's public
/// pieces (network, flow solver, rod, vessel forces — what `coupling::run_scene` does)
/// while watching every accepted step. A run passes when, at every step,
/// - the state is finite (the rod step did not report NaN/Inf or a singular matrix),
/// - no vertex is outside the lumen by more than 10% of the wire radius,
/// - the length drift |Σℓ − Σℓ̄|/Σℓ̄ stays below 0.1%,
/// - the energy stays bounded: the kinetic energy stays below ½·m·(10 m/s)² (m: mass of the
///   simulated wire; 10 m/s is a hundred times the fastest insertion and ten times the peak
///   blood velocity) and the elastic energy below that of the whole simulated wire bent to a
///   1 mm radius at the largest bending stiffness, ½·EI_max·(1/1 mm)²·ℓ.
/// The first step that breaks a criterion is recorded with the reason.
#include <string>
#include <vector>

namespace flowire::bench {

struct StressPoint {
  double dt = 0.01;              ///< [s]
  double youngs_modulus = 60e9;  ///< [Pa] shaft
  double wire_length = 0.8;      ///< [m]
  double speed = 0.01;           ///< [m/s] insertion speed
  double rotation = 0.0;         ///< [turns/s] base rotation speed
  double flow_scale = 1.0;       ///< multiplies the blood drag (coupling.drag_scale)
  double friction = 0.2;         ///< Coulomb coefficient, shaft and tip
  double duration = 1.0;         ///< [s] simulated time
};

struct StressResult {
  StressPoint point;
  bool pass = false;
  std::string reason;         ///< empty when passing
  long held_steps = 0;        ///< steps in which the force limit held the feed
  long first_bad_step = -1;   ///< 1-based step where a criterion first failed (−1: none)
  long steps = 0;             ///< steps taken
  int unconverged_steps = 0;  ///< Newton steps reported as not converged (warnings)
  double max_outside_over_radius = 0.0;
  double max_length_drift = 0.0;
  double max_energy_ratio = 0.0;  ///< max over steps of energy / its cap (kinetic or elastic)
  double max_rms_speed = 0.0;     ///< [m/s] max over steps of √(2 KE / m)
  double inserted_length = 0.0;   ///< [m] at the end
  double planned_feed = 0.0;      ///< [m] what the drive asked for: speed × duration, up to insertion.max_length
  double fed = 0.0;               ///< [m] what went in: the inserted length's change
  /// The force limit held the feed to under half of what was asked: the point tests a held
  /// wire, not a fed one (reported as such, not counted as a feeding run).
  [[nodiscard]] bool stalled() const { return planned_feed > 0.0 && fed < 0.5 * planned_feed; }
  double seconds = 0.0;  ///< wall-clock time of the run
};

/// @brief Run one point of the matrix on the scene file `scene`.
StressResult run_stress_point(const std::string& scene, const StressPoint& p);

/// @brief The matrix: `reduced` is the CI size (a handful of runs, well under a minute).
std::vector<StressPoint> stress_matrix(bool reduced);

/// @brief CSV header and one row.
std::string stress_csv_header();
std::string stress_csv_row(const StressResult& r);

/// @brief Stable identifier of a point (used by the known-failures list).
std::string stress_point_id(const StressPoint& p);

}  // namespace flowire::bench
