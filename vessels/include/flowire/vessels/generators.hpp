#pragma once
/// @file generators.hpp
/// @brief Synthetic anatomies, each documented with its parameters (SI units).
#include <string>

#include "flowire/vessels/network.hpp"

namespace flowire::vessels {

struct StraightTubeParams {
  double length = 0.1;   ///< m
  double radius = 2e-3;  ///< m
  Vec3 origin = Vec3::Zero();
  Vec3 direction = Vec3::UnitX();
};
/// @brief One straight branch from `origin` along `direction`.
Centerlines straight_tube(const StraightTubeParams& p);

struct YBifurcationParams {
  double parent_radius = 5e-3;   ///< m
  double parent_length = 40e-3;  ///< m
  double child_length = 40e-3;   ///< m
  double angle = 0.6;            ///< half-angle between the daughters (rad)
  double asymmetry = 0.0;        ///< 0: equal daughters (Murray: r_d = r_p / 2^(1/3)); in (-1, 1) skews the flow split
};
/// @brief Parent along +x from the origin, two daughters in the xy-plane; Murray's law
/// r_p³ = r_1³ + r_2³ (C. D. Murray 1926, "The physiological principle of minimum work",
/// Proc. Natl. Acad. Sci. USA 12, 207–214) with r_1³ = (1 + a)/2·r_p³, r_2³ = (1 − a)/2·r_p³.
Centerlines y_bifurcation(const YBifurcationParams& p);

struct AorticArchParams {
  double scale = 1.0;     ///< multiplies every length and radius (1: adult)
  int points_per_cm = 4;  ///< centerline sampling of the curved parts
};
/// @brief Adult aorta from the aortic root: ascending aorta, arch with brachiocephalic,
/// left common carotid and left subclavian arteries, descending thoracic and abdominal
/// aorta to the iliac bifurcation, common/external iliac to the femoral arteries.
/// Branch names: "ascending_aorta", "arch_1", "arch_2", "descending_aorta",
/// "brachiocephalic", "left_common_carotid", "left_subclavian", "right_iliac_femoral",
/// "left_iliac_femoral". Root at the origin; +z is cranial, +y anterior.
/// The aortic root (widest end) is the flow inlet; "right_iliac_femoral" ends at the
/// femoral entry used for wire insertion (`aortic_arch_entry`).
Centerlines aortic_arch(const AorticArchParams& p = {});
/// @brief Position of the right femoral entry of `aortic_arch(p)`.
Vec3 aortic_arch_entry(const AorticArchParams& p = {});

struct BinaryTreeParams {
  int depth = 5;                             ///< generations 0..depth, 2^(depth+1) − 1 vessels
  double root_radius = 2e-3;                 ///< m
  double root_length = 20e-3;                ///< m
  double radius_ratio = 0.7937005259840998;  ///< r_{k+1}/r_k (Murray 1926 for equal daughters: 2^(−1/3))
  double length_ratio = 0.7937005259840998;  ///< L_{k+1}/L_k
  double angle = 0.5;                        ///< branching half-angle (rad)
};
/// @brief Binary tree, one segment per vessel, built directly as a graph (10⁶ vessels in
/// about a second). Node 0 is the root inlet; vessels are numbered breadth-first.
Network binary_tree(const BinaryTreeParams& p);

struct ArterialTreeParams {
  double scale = 1.0;
};
/// @brief The 33-artery network of Alastruey et al. 2007 (J. Biomech. 40:1794–1805) with
/// the circle of Willis (loops), published lengths and radii, laid out in 3D.
Centerlines arterial_tree(const ArterialTreeParams& p = {});

}  // namespace flowire::vessels
