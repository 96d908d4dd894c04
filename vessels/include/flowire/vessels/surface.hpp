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

/// @brief Where the closest surface point lies.
enum class Feature : std::uint8_t { Face, Edge, Vertex };

struct SurfaceDistance {
  double distance = 0.0;          ///< signed, negative inside [m]
  Vec3 gradient = Vec3::UnitX();  ///< ∇d (unit)
  Vec3 closest = Vec3::Zero();    ///< closest surface point
  int triangle = -1;              ///< triangle holding it
  Feature feature = Feature::Face;
  bool open = false;              ///< beyond an open end (closest feature on a boundary edge)
  double exact = 0.0;             ///< the unsmoothed signed distance d (smooth_distance's d_τ is `distance`)
};

/// @brief The triangles near a moving point, kept from one query to the next (one per wire
/// vertex). Built at a centre c whose nearest triangle lies at u_c, it lists every triangle
/// within u_c + 10τ + 2m of c, with their distances u_f(c). The distance is
/// 1-Lipschitz: at a point x with δ = |x − c| ≤ m, u(x) ≤ u_c + δ, and a triangle within
/// 10τ of x's nearest has u_f(c) ≤ u(x) + 10τ + δ ≤ u_c + 10τ + 2δ. A query at x checks
/// only the listed triangles within that bound (a vertex that barely moved checks just the
/// ones it needs) and walks no hierarchy; its answer is the one a fresh query gives.
struct SurfaceNeighbourhood {
  Vec3 centre = Vec3::Zero();
  double margin = -1.0;    ///< m [m]; < 0: empty, rebuilt at the next query
  double tau = 0.0;        ///< the smoothing width it was built for
  double u_centre = 0.0;   ///< u_c [m]
  int nearest = -1;        ///< nearest triangle at the last query (a hint for the rebuild)
  std::vector<int> triangles;   ///< gathered at the centre
  std::vector<double> reach;    ///< their distances u_f(c) [m]
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

  /// @brief The smoothed signed distance a contact uses: d_τ = s·u_τ with the soft minimum
  /// \f[ u_\tau = -\tau \log \sum_f e^{-u_f/\tau} \f]
  /// of the distances u_f to the triangles near x (those within u + 10τ; the rest weigh less
  /// than e⁻¹⁰) and s the sign of distance(). Unlike d, whose gradient jumps from one face
  /// normal to the next where two faces are equally near, d_τ is continuously differentiable
  /// (Newton converges on it) and 1-Lipschitz, with u − τ log k ≤ u_τ ≤ u (k: the triangles
  /// near x): inside, d ≤ d_τ ≤ d + τ log k, the wall seen slightly early. Gradient
  /// s Σ w_f e_f (softmax weights w_f, e_f the unit vector from triangle f's closest point);
  /// Hessian s [Σ w_f H_f − (Σ w_f e_f e_fᵀ − ḡ ḡᵀ)/τ] (H_f: Hessian of u_f, ḡ = Σ w_f e_f),
  /// positive semi-definite inside a convex section.
  /// τ ≤ 0 gives distance().
  SurfaceDistance smooth_distance(const Vec3& x, double tau, int hint = -1, Eigen::Matrix3d* hessian = nullptr) const;

  /// @brief smooth_distance() over the triangles of @p near, rebuilt (with margin @p margin)
  /// when x has left it or τ changed: the same answer, without a walk of the hierarchy for
  /// most queries of a vertex that moves little between them (Newton iterates, line-search
  /// trials, steps). τ ≤ 0 gives distance().
  SurfaceDistance smooth_distance(const Vec3& x, double tau, SurfaceNeighbourhood& near, double margin,
                                  Eigen::Matrix3d* hessian = nullptr) const;

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
  /// The smoothed distance over candidate triangles that hold the nearest one and every one
  /// within 10τ of it.
  SurfaceDistance smooth_over(const Vec3& x, double tau, std::span<const int> candidates,
                              Eigen::Matrix3d* hessian) const;

  std::vector<Vec3> v_;
  std::vector<std::array<int, 3>> tri_;
  std::vector<Vec3> face_normal_;
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
