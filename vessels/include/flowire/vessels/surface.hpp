#pragma once
/// @file surface.hpp
/// @brief A triangulated lumen surface and the signed distance to it.
///
/// The surface is read from `.vtp`, `.stl` or `.obj` (VTK's readers), duplicate vertices are
/// merged and degenerate triangles dropped; a bounding-volume hierarchy over the triangles
/// answers closest-point queries.
///
/// Signed distance. With c the closest surface point to x and u = |x − c|, the distance is
/// d = s·u, negative inside the lumen. The sign s comes from the angle-weighted pseudonormal
/// N of the feature holding c (Bærentzen & Aanæs 2005): the face normal on a face, the sum of
/// the two face normals on an edge, the sum of the incident face normals weighted by their
/// angles at a vertex; s = sign((x − c)·N), exact for a closed, consistently oriented mesh.
/// Away from the surface and the medial axis d is differentiable with
/// \f[ \nabla d = s\,e,\quad e = (x - c)/u, \f]
/// and its Hessian is 0 in a face's region, s(I − t tᵀ − e eᵀ)/u in an edge's (t the edge
/// direction), s(I − e eᵀ)/u at a vertex.
///
/// Open ends. A boundary edge (one triangle) belongs to an open end (inlet/outlet rim). A point
/// whose closest feature is a boundary edge or vertex lies beyond an open end: it is not
/// outside, d = −u (the distance to the rim, as a wall seen from inside).
///
/// Orientation. The triangles' winding is made consistent over each connected piece and turned
/// so that the normals point out of the lumen (see the constructor).
#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "flowire/vessels/network.hpp"

namespace flowire::vessels {

/// @brief Raw triangles (metres).
struct SurfaceMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;
  std::string source;  ///< file name (for messages)
};

/// @brief Read a triangulated surface: `.vtp` (VTK XML poly data, polygons triangulated),
/// `.stl`, `.obj`; coordinates multiplied by @p length_factor (file unit → m).
/// @throws flowire::Error (input) naming the file: missing or unreadable file, no triangles,
/// non-finite coordinates.
SurfaceMesh read_surface(const std::string& path, double length_factor = 1.0);

/// @brief Remove the planar caps that close a surface at the ends of its centerlines (a capped
/// VMTK or SimVascular model), so that the surface is open there as the vessel is.
///
/// At an end with point p, unit direction t out of the vessel and radius r, a triangle is
/// part of the cap when its vertices lie ahead of p (from 0.25 r behind to 3 r ahead along
/// t, a centerline may stop short of its cap) within 1.6 r of the axis, and its normal is
/// within 25° of ±t (the wall's normals are across t).
/// @return the number of triangles removed.
struct VesselEnd {
  Vec3 point;
  Vec3 direction;  ///< out of the vessel, unit
  double radius = 0.0;
};
int remove_end_caps(SurfaceMesh& mesh, const std::vector<VesselEnd>& ends);

/// @brief Cut a triangulated surface by the plane through @p origin normal to @p out near
/// @p origin: triangles with a vertex within @p reach of it lose their part beyond the plane (on
/// the side @p out points to), split where they cross it; the cut points are shared, so the
/// result stays conforming. Vertices within @p eps of the plane count as on it.
/// @return the number of triangles touched.
int clip_surface(std::vector<Vec3>& points, std::vector<std::array<int, 3>>& triangles, const Vec3& origin,
                 const Vec3& out, double reach, double eps);

/// @brief Where the closest surface point lies.
enum class Feature : std::uint8_t { Face, Edge, Vertex };

struct SurfaceDistance {
  double distance = 0.0;          ///< signed, negative inside [m]
  Vec3 gradient = Vec3::UnitX();  ///< ∇d (unit)
  Vec3 closest = Vec3::Zero();    ///< closest surface point
  int triangle = -1;              ///< triangle holding it
  Feature feature = Feature::Face;
  bool open = false;  ///< beyond an open end (closest feature on a boundary edge)
};

/// @brief The smooth signed distance of a contact (LumenSurface::smooth_distance).
struct SmoothDistance {
  double distance = 0.0;          ///< d_σ, negative inside [m]; if skipped, an upper bound of d
  Vec3 gradient = Vec3::UnitX();  ///< ∇d_σ
  bool skipped = false;           ///< the point lies deeper inside than asked: nothing computed
};

/// @brief The triangles near a moving point, kept from one query to the next (one per wire
/// vertex). Built at a centre c, it holds the exact distance u_c from c to the surface and, once
/// a query needs them, the triangles whose centroids lie within
/// R = √((ρ_c + m)² + Kσ²) + m of c (ρ_c: the distance from c to the centroid of its nearest
/// triangle, m the margin, K the weights' cut-off below). For a point x with δ = |x − c| ≤ m,
/// every centroid that weighs at x lies within R of c: its nearest centroid lies within
/// ρ_c + δ, and a weighing one within √((ρ_c + δ)² + Kσ²) of x. A query at x uses the listed
/// triangles and walks no hierarchy; its answer is the one a fresh query gives.
struct SurfaceNeighbourhood {
  Vec3 centre = Vec3::Zero();
  double margin = -1.0;        ///< m [m]; < 0: empty, rebuilt at the next query
  double sigma = 0.0;          ///< the smoothing width it was built for
  double u_centre = 0.0;       ///< u_c: exact (unsigned) distance from c to the surface [m]
  bool inside = true;          ///< c lies inside the lumen (or beyond an open end)
  int nearest = -1;            ///< nearest triangle at c (a hint for the next rebuild)
  bool gathered = false;       ///< the triangles below are listed
  double radius = 0.0;         ///< R [m]
  std::vector<int> triangles;  ///< centroids within R of c
  void clear() { margin = -1.0; }
};

struct SurfaceCounts {
  int vertices = 0, triangles = 0, boundary_edges = 0, boundary_loops = 0, nonmanifold_edges = 0;
  int components = 0, merged_vertices = 0, dropped_triangles = 0, flipped_triangles = 0;
  double min_edge = 0.0, max_edge = 0.0, mean_edge = 0.0;
};

class LumenSurface {
 public:
  /// @brief Build from raw triangles: merges coincident vertices, drops degenerate triangles,
  /// orients each connected piece consistently with its normals out of the lumen (the side
  /// the enclosed or, for open tubes, the swept volume lies on: the orientation for which the
  /// points @p inside, e.g. the centerline's points, have negative distance; without them, the
  /// one with positive enclosed volume after closing each boundary loop by a fan around its
  /// centroid), and builds the hierarchy.
  /// @throws flowire::Error (input) naming mesh.source if no triangle is left.
  explicit LumenSurface(SurfaceMesh mesh, const std::vector<Vec3>& inside = {});

  /// @brief Signed distance from @p x, its gradient and (if asked) Hessian.
  /// @param hint a triangle near the answer (e.g. the previous query's), or −1: it bounds the
  /// search from the start, the answer does not depend on it.
  SurfaceDistance distance(const Vec3& x, int hint = -1, Eigen::Matrix3d* hessian = nullptr) const;

  /// @brief The smooth signed distance a contact uses: the implicit moving-least-squares
  /// surface of the triangles' planes (Shen, O'Brien & Shewchuk 2004; Kolluri 2008, point form),
  /// \f[ d_\sigma(x) = \frac{\sum_f w_f(x)\,(x - g_f)\cdot n_f}{\sum_f w_f(x)},\qquad
  ///     w_f(x) = A_f\,e^{-|x - g_f|^2/\sigma^2}, \f]
  /// with g_f, n_f, A_f triangle f's centroid, outward unit normal and area. Each term is the
  /// signed distance to one triangle's plane; d_σ is their Gaussian-weighted mean, C∞ in x.
  /// On a plane it is the exact distance at any height. Near a facet edge it blends the two
  /// planes over a width ~σ²/ℓ (ℓ the edge length) instead of the exact distance's jump of
  /// gradient; on a faceted tube of radius R it is within O(σ²/R) of the exact distance (a
  /// second-order error, tested). Unlike a soft minimum over triangles it does not see the
  /// wall earlier the farther the point is: the weights compare squared distances, which on a
  /// plane differ by the lateral offsets alone. Weights below e⁻¹⁰ of the largest are dropped.
  /// Gradient (1/W) Σ w_f [n_f + (d_f − d_σ) a_f] with a_f = −2(x − g_f)/σ²; Hessian
  /// (1/W) Σ w_f [n_f a_fᵀ + a_f n_fᵀ + (d_f − d_σ) a_f a_fᵀ] − ā ∇d_σᵀ − ∇d_σ āᵀ, ā = Σ w_f a_f / W.
  /// Beyond an open end the last ring of planes continues: the wire may leave through it as
  /// through a tube of the vessel's own width.
  /// The neighbourhood @p near (kept between queries of one moving point, see
  /// SurfaceNeighbourhood) is rebuilt, with margin @p margin, when x has left it or σ changed.
  /// If x lies provably deeper inside than @p skip_deeper_than (by the exact distance at the
  /// neighbourhood's centre, which is 1-Lipschitz), nothing is computed: `skipped`, and
  /// `distance` = −(u_c − δ), an upper bound of the exact signed distance d. Such a point keeps
  /// its neighbourhood's centre beyond the margin, as long as it stays that deep.
  /// σ ≤ 0 gives the exact signed distance (distance()).
  SmoothDistance smooth_distance(const Vec3& x, double sigma, SurfaceNeighbourhood& near, double margin,
                                 Eigen::Matrix3d* hessian = nullptr,
                                 double skip_deeper_than = std::numeric_limits<double>::infinity()) const;

  /// @brief The same without a kept neighbourhood (a fresh one for this query).
  SmoothDistance smooth_distance(const Vec3& x, double sigma, Eigen::Matrix3d* hessian = nullptr) const;

  /// @brief distance() at a point near @p near's centre: over its listed triangles where they
  /// provably hold the nearest one (R ≥ u_c + 2δ + the largest centroid-to-vertex distance of
  /// any triangle), else by the hierarchy. The same answer either way.
  SurfaceDistance distance(const Vec3& x, const SurfaceNeighbourhood& near) const;

  /// @brief The triangles whose bounding boxes lie within @p radius of @p x (into @p out).
  void triangles_within(const Vec3& x, double radius, std::vector<int>& out) const { gather(x, radius, out); }

  /// @brief Reference answer by checking every triangle (tests and benchmarks).
  SurfaceDistance distance_brute_force(const Vec3& x) const;

  [[nodiscard]] const SurfaceCounts& counts() const { return counts_; }
  [[nodiscard]] const std::vector<Vec3>& vertices() const { return v_; }
  [[nodiscard]] const std::vector<std::array<int, 3>>& triangles() const { return tri_; }
  [[nodiscard]] const std::string& source() const { return source_; }
  [[nodiscard]] const Eigen::AlignedBox3d& bounds() const { return bvh_.front().box; }

 private:
  struct Node {
    Eigen::AlignedBox3d box;
    int left = -1, right = -1;
    int first = 0, count = 0;
  };
  int build(int first, int count);
  /// Triangles whose box lies within `radius` of x.
  void gather(const Vec3& x, double radius, std::vector<int>& out) const;
  void orient(const std::vector<Vec3>& inside);
  void pseudonormals();
  /// Closest point on triangle f: squared distance, point, feature and its local index.
  /// The closest triangle to x (ties: the lower index), its closest point and feature.
  int nearest(const Vec3& x, int hint, Vec3& c, Feature& feat, int& local) const;
  double closest_on(int f, const Vec3& x, Vec3& c, Feature& feat, int& local) const;
  SurfaceDistance finish(const Vec3& x, int f, const Vec3& c, Feature feat, int local, Eigen::Matrix3d* hessian) const;
  /// The exact signed distance over @p candidates (which must hold the nearest triangle).
  SurfaceDistance closest_among(const Vec3& x, std::span<const int> candidates) const;
  /// d_σ over the triangles of a gathered neighbourhood (those that weigh at x among them).
  SmoothDistance implicit_over(const Vec3& x, double sigma, const std::vector<int>& listed,
                               Eigen::Matrix3d* hessian) const;

  std::vector<Vec3> v_;
  std::vector<std::array<int, 3>> tri_;
  std::vector<Vec3> face_normal_;
  struct Plane {
    Vec3 centroid, normal;
    double area;
  };
  std::vector<Plane> plane_;                      ///< (triangles) what d_σ weighs, packed for its loop
  double max_vertex_reach_ = 0.0;                 ///< the largest distance from a triangle's centroid to its vertices
  std::vector<std::array<Vec3, 3>> edge_normal_;  ///< (triangles x 3) edge k = (v[k], v[k+1]), pseudonormal
  std::vector<std::array<bool, 3>> edge_open_;    ///< boundary edge
  std::vector<Vec3> vertex_normal_;
  std::vector<char> vertex_open_;
  std::vector<int> order_;
  std::vector<Node> bvh_;
  SurfaceCounts counts_;
  std::string source_;
};

}  // namespace flowire::vessels
