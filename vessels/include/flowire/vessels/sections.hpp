#pragma once
/// @file sections.hpp
/// @brief Cross-sections of a lumen surface normal to the centerline, and a network whose radii
/// are the sections' area-equivalent radii instead of the centerline's inscribed-sphere radii.
///
/// A centerline's radius is the largest sphere inscribed in the lumen (VMTK's
/// MaximumInscribedSphereRadius): the smallest half-width of the section, not its size. The
/// Poiseuille resistance 8ηL/(πr⁴) of a section of area A is closest to that of the circle of the
/// same area, r = √(A/π) (exact for a circle; for an ellipse of axes a ≥ b the exact resistance
/// is 8ηL (a² + b²)/(2πa³b³) against 8ηL/(π a² b²) from √(ab): the two differ by
/// (a² + b²)/(2ab) − 1, 1.25% at a/b = 1.17, which each segment carries as its shape factor,
/// Segment::shape), while the inscribed radius b overestimates it by (a/b)² (37% at 1.17). On the real lumens the
/// network's pressure drop stood 20–30% above the 3D solution by that mismatch (docs/fem-real-lumens.md).
#include <optional>
#include <string>

#include "flowire/vessels/network.hpp"
#include "flowire/vessels/surface.hpp"

namespace flowire::vessels {

/// @brief The lumen's cross-section through a centerline point.
struct Section {
  double area = 0.0;          ///< [m²] of the contour around the point
  double perimeter = 0.0;     ///< [m]
  double min_distance = 0.0;  ///< the contour's nearest point from the centerline point [m]
  double max_distance = 0.0;  ///< its farthest [m]
  int contours = 0;           ///< closed contours the plane cut within reach
  /// (a² + b²)/(2ab) of the ellipse with the contour's area and the ratio of its principal second
  /// moments of area (a/b = √(I₁/I₂)): Poiseuille's resistance of that ellipse over the circle's of
  /// the same area (Boussinesq's exact solution for elliptic pipes). 1 for a circle; for a
  /// non-elliptic contour an estimate by its equivalent ellipse.
  double shape_factor = 1.0;
  /// @brief √(A/π).
  [[nodiscard]] double equivalent_radius() const;
};

/// @brief The section of @p surface by the plane through @p p normal to @p t: the triangles within
/// @p reach of p are cut by the plane, the pieces chained into contours through the triangle
/// edges they cross (each edge shared by two triangles), and the smallest closed contour that
/// winds around p is the section. None where no closed contour within reach winds around p (the
/// plane leaves the surface through an open end, a branch's section reaches beyond @p reach, or
/// p lies outside the lumen).
std::optional<Section> cut_section(const LumenSurface& surface, const Vec3& p, const Vec3& t, double reach);

/// @brief Which sections are taken (section_radii).
struct SectionRadiiOptions {
  double reach = 4.0;       ///< cut the triangles within reach × the inscribed radius
  double max_ratio = 1.6;   ///< √(A/π) at most this × the inscribed radius ...
  double max_extent = 3.0;  ///< ... and the contour within this × the inscribed radius of the point
};

/// @brief A network with its radii from the lumen's sections.
struct SectionRadii {
  Network network;              ///< the input network, each segment's end radii from the sections
  int points = 0;               ///< (branch, node) points cut
  int measured = 0;             ///< of which a section was taken
  int filled = 0;               ///< the rest: the ratio of the nearest measured point of the branch
  int branches_unmeasured = 0;  ///< branches with no section taken (their inscribed radii kept)
  double median_ratio = 1.0;    ///< median over the measured points of √(A/π) / inscribed radius
  double median_shape = 1.0;    ///< median over the measured points of Section::shape_factor
  double max_shape = 1.0;       ///< the largest of them
};

/// @brief Each branch's radius at each of its nodes from the section there (normal to the branch:
/// the direction between its neighbouring nodes), as the ratio s = √(A/π) / r_inscribed applied
/// to the segment ends at that node; a section is taken where the plane cuts a closed contour
/// around the node no larger than the options allow (junctions, where the plane crosses into the
/// other branches, and open ends are not), elsewhere the ratio of the nearest measured node of the
/// same branch (by arc length), or 1 for a branch with none. The segments, nodes and branches are
/// the input's; only radius_from, radius_to and radius change.
SectionRadii section_radii(const Network& net, const LumenSurface& surface, const SectionRadiiOptions& options = {});

}  // namespace flowire::vessels
