#pragma once
/// @file occlusion.hpp
/// @brief The wire acts on the blood (`coupling.occlusion: annulus`): the part of each
/// vessel segment a wire occupies, and what the annular flow around it (flow/annulus.hpp)
/// does to the segment's resistance, inertance and pressure gradient.
///
/// Each free vertex i stands for half of each of its two edges. The part of that length
/// along the axis e_s of the segment s_i the vertex lies in, \f$ \ell_i = \tfrac12\sum
/// |\Delta x\cdot e_s| \f$, is occupied by a wire of radius a_i at the vertex's distance d_i
/// from the axis, in a vessel of local radius r_i (linear between the segment's end radii).
/// Per segment, with length-weighted means \f$\bar a, \bar r, \bar d\f$:
/// - occupied length \f$ L = \sum\ell_i \f$, fraction L/l (a wire looping inside one segment
///   is scaled down to l);
/// - \f$ F = 1/q(\bar a/\bar r,\ \bar d/(\bar r - \bar a)) \f$, q the annulus' flow fraction
///   (concentric to touching, Piercy, Hooper & Winny 1933);
/// - the occupied part's empty resistance \f$ R_{occ} = \sum 8\eta\ell_i/(\pi r_i^4) \f$ rises
///   by the factor F: resistance_factor = 1 + (F − 1) R_occ / R_s, R_s the segment's own
///   (frustum) resistance;
/// - the inertance ρ∫dx/A with the wire's area taken out of A: inertance_factor =
///   \f$ 1 + \sum \rho\ell_i\,[1/(\pi(r_i^2 - a_i^2)) - 1/(\pi r_i^2)] / L_s \f$;
/// - gradient_factor = F: where the wire lies, the pressure gradient is F times the empty
///   tube's at the same flow. The flow solver scales the velocity profile there by it, so the
///   drag law's annular shear (drag.hpp), which takes the empty tube's velocity under the
///   local gradient, and the annulus flow come from one solution: exact for a coaxial wire.
/// Limits (stated, not hidden): one mean eccentricity per segment; the Womersley profile of
/// an occupied segment is the empty tube's scaled by F (the oscillatory annulus is not
/// solved); a wire wider than kMaxOcclusionRadiusRatio of the vessel is taken at that ratio
/// (counted in `radius_ratio_clamped`).
#include <initializer_list>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "flowire/flow/solver.hpp"

namespace flowire::coupling {

/// @brief Largest wire/vessel radius ratio evaluated (the annulus' flow is then 0.13% of
/// the empty tube's; a wire filling more of the lumen is outside the model's range).
inline constexpr double kMaxOcclusionRadiusRatio = 0.9;

/// @brief What a run's occlusion did, for summary.json.
struct OcclusionStats {
  int occupied_segments = 0;           ///< at the last update
  double max_resistance_factor = 1.0;  ///< over the run
  long radius_ratio_clamped = 0;       ///< segment updates with a/r above the model's range
};

/// @brief Computes every segment's occlusion from a wire; allocation-free after the first
/// update (only the segments the wire touched are reset).
class WireOcclusion {
 public:
  /// @param flow the solver whose network, viscosity, density and resistances are used
  explicit WireOcclusion(const flow::FlowSolver& flow);

  /// @brief Occlusion of every segment for a wire with vertices `x` (index 0 the tip),
  /// the first `free` of them in the vessels, vertex i in segment `segment[i]` (−1: none),
  /// edge i (x_i → x_{i+1}) of radius `edge_radius[i]`.
  std::span<const flow::SegmentOcclusion> update(std::span<const Eigen::Vector3d> x, int free,
                                                 std::span<const int> segment, std::span<const double> edge_radius);
  /// @brief One instrument in the vessels, as update()'s arguments.
  struct Body {
    std::span<const Eigen::Vector3d> x;
    int free = 0;
    std::span<const int> segment;
    std::span<const double> edge_radius;
  };
  /// @brief Occlusion by several instruments that do not overlap (a catheter, and the part of
  /// the wire beyond its tip): each segment's sums run over all of them.
  std::span<const flow::SegmentOcclusion> update(std::initializer_list<Body> bodies);

  [[nodiscard]] std::span<const flow::SegmentOcclusion> occlusion() const { return occ_; }
  [[nodiscard]] const OcclusionStats& stats() const { return stats_; }

 private:
  void add(std::span<const Eigen::Vector3d> x, int free, std::span<const int> segment,
           std::span<const double> edge_radius);
  std::span<const flow::SegmentOcclusion> finish();
  struct Sum {
    double length = 0.0;      // Σ ℓ
    double offset = 0.0;      // Σ ℓ d
    double wire = 0.0;        // Σ ℓ a
    double radius = 0.0;      // Σ ℓ r
    double resistance = 0.0;  // Σ 8ηℓ/(π r⁴)
    double inertance = 0.0;   // Σ ρℓ [1/(π(r² − a²)) − 1/(πr²)]
  };
  const flow::FlowSolver& flow_;
  std::vector<Eigen::Vector3d> axis_;        // (num_segments) unit axis
  std::vector<double> inertance_;            // (num_segments) ρ l/(π r_from r_to)
  std::vector<Sum> sum_;                     // (num_segments)
  std::vector<flow::SegmentOcclusion> occ_;  // (num_segments)
  std::vector<int> touched_;                 // segments with a nonzero sum
  OcclusionStats stats_;
};

}  // namespace flowire::coupling
