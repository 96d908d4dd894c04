#include "flowire/vessels/surface.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <queue>
#include <unordered_map>

#include "flowire/common/error.hpp"
#include "flowire/common/union_find.hpp"

namespace flowire::vessels {

namespace {

using Mat3 = Eigen::Matrix3d;

std::uint64_t edge_key(int a, int b) {
  const auto lo = static_cast<std::uint64_t>(std::min(a, b)), hi = static_cast<std::uint64_t>(std::max(a, b));
  return (lo << 32) | hi;
}

/// Squared distance from x to a box (0 inside).
double box_distance2(const Eigen::AlignedBox3d& b, const Vec3& x) {
  const Vec3 d = (b.min() - x).cwiseMax(x - b.max()).cwiseMax(0.0);
  return d.squaredNorm();
}

}  // namespace

int clip_surface(std::vector<Vec3>& points, std::vector<std::array<int, 3>>& triangles, const Vec3& origin,
                 const Vec3& out, double reach, double eps) {
  const size_t np = points.size();
  std::vector<double> d(np, -1.0);
  for (size_t i = 0; i < np; ++i) {
    const Vec3 r = points[i] - origin;
    if (r.norm() > reach) continue;
    d[i] = r.dot(out);
    if (std::abs(d[i]) < eps) d[i] = 0.0;
  }
  std::unordered_map<std::uint64_t, int> cut;
  auto cut_point = [&](int a, int b) {  // d[a] <= 0 < d[b]
    if (d[static_cast<size_t>(a)] == 0.0) return a;
    auto [it, fresh] = cut.try_emplace(edge_key(a, b), -1);
    if (fresh) {
      const double t = d[static_cast<size_t>(a)] / (d[static_cast<size_t>(a)] - d[static_cast<size_t>(b)]);
      it->second = static_cast<int>(points.size());
      const Vec3 x =
          points[static_cast<size_t>(a)] + t * (points[static_cast<size_t>(b)] - points[static_cast<size_t>(a)]);
      points.push_back(x);
    }
    return it->second;
  };
  std::vector<std::array<int, 3>> kept;
  kept.reserve(triangles.size());
  int touched = 0;
  for (const auto& t : triangles) {
    int beyond = 0;
    for (int v : t) beyond += d[static_cast<size_t>(v)] > 0.0 ? 1 : 0;
    if (beyond == 0) {
      kept.push_back(t);
      continue;
    }
    ++touched;
    if (beyond == 3) continue;
    std::vector<int> poly;  // the kept part, in the triangle's order
    for (int k = 0; k < 3; ++k) {
      const int a = t[static_cast<size_t>(k)], b = t[static_cast<size_t>((k + 1) % 3)];
      const bool ina = d[static_cast<size_t>(a)] <= 0.0, inb = d[static_cast<size_t>(b)] <= 0.0;
      if (ina) poly.push_back(a);
      if (ina != inb) {
        const int c = ina ? cut_point(a, b) : cut_point(b, a);
        if (poly.empty() || poly.back() != c) poly.push_back(c);
      }
    }
    if (poly.size() > 1 && poly.front() == poly.back()) poly.pop_back();
    for (size_t k = 1; k + 1 < poly.size(); ++k) {
      const std::array<int, 3> tri{poly[0], poly[k], poly[k + 1]};
      if (tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2]) kept.push_back(tri);
    }
  }
  triangles = std::move(kept);
  return touched;
}

int remove_end_caps(SurfaceMesh& mesh, const std::vector<VesselEnd>& ends) {
  std::vector<std::array<int, 3>> kept;
  kept.reserve(mesh.triangles.size());
  int removed = 0;
  const double cos_max = std::cos(25.0 * 3.14159265358979323846 / 180.0);
  for (const auto& t : mesh.triangles) {
    const Vec3& a = mesh.vertices[static_cast<size_t>(t[0])];
    const Vec3& b = mesh.vertices[static_cast<size_t>(t[1])];
    const Vec3& c = mesh.vertices[static_cast<size_t>(t[2])];
    const Vec3 n = (b - a).cross(c - a);
    const double nn = n.norm();
    bool cap = false;
    for (const auto& e : ends) {
      if (cap || !(nn > 0.0)) break;
      bool near = true;
      for (const Vec3* p : {&a, &b, &c}) {
        const Vec3 r = *p - e.point;
        const double along = r.dot(e.direction);
        near = near && along >= -0.25 * e.radius && along <= 3.0 * e.radius &&
               (r - along * e.direction).norm() <= 1.6 * e.radius;
      }
      cap = near && std::abs(n.dot(e.direction)) >= cos_max * nn;
    }
    if (cap)
      ++removed;
    else
      kept.push_back(t);
  }
  if (removed > 0) {
    // A cap's rim triangles may be tilted beyond the normal test and be left as islands cut
    // off from the wall: keep only the pieces holding at least a tenth of the triangles.
    std::map<std::array<double, 3>, int> id;
    std::vector<int> vid(mesh.vertices.size());
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
      const Vec3& p = mesh.vertices[i];
      vid[i] = id.emplace(std::array<double, 3>{p.x(), p.y(), p.z()}, static_cast<int>(id.size())).first->second;
    }
    UnionFind uf(id.size());
    for (const auto& t : kept) {
      uf.unite(vid[static_cast<size_t>(t[0])], vid[static_cast<size_t>(t[1])]);
      uf.unite(vid[static_cast<size_t>(t[0])], vid[static_cast<size_t>(t[2])]);
    }
    std::unordered_map<int, size_t> size;
    for (const auto& t : kept) ++size[uf.find(vid[static_cast<size_t>(t[0])])];
    std::vector<std::array<int, 3>> big;
    for (const auto& t : kept) {
      if (10 * size[uf.find(vid[static_cast<size_t>(t[0])])] >= kept.size())
        big.push_back(t);
      else
        ++removed;
    }
    kept = std::move(big);
  }
  mesh.triangles = std::move(kept);
  return removed;
}

LumenSurface::LumenSurface(SurfaceMesh mesh, const std::vector<Vec3>& inside) : source_(mesh.source) {
  const std::string& src = source_.empty() ? std::string("surface") : source_;
  // 1) Merge coincident vertices (STL and OBJ repeat them per triangle or per normal).
  for (size_t i = 0; i < mesh.vertices.size(); ++i)
    if (!mesh.vertices[i].allFinite()) throw_input_error(src, fmt::format("vertex {} is not finite", i));
  std::map<std::array<double, 3>, int> index;
  std::vector<int> remap(mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3& p = mesh.vertices[i];
    auto [it, inserted] = index.emplace(std::array<double, 3>{p.x(), p.y(), p.z()}, static_cast<int>(v_.size()));
    if (inserted) v_.push_back(p);
    remap[i] = it->second;
  }
  counts_.merged_vertices = static_cast<int>(mesh.vertices.size() - v_.size());
  // 2) Drop degenerate triangles (repeated vertex or zero area).
  for (const auto& t : mesh.triangles) {
    for (int k : t)
      if (k < 0 || static_cast<size_t>(k) >= remap.size())
        throw_input_error(src, fmt::format("a triangle refers to vertex {} of {}", k, remap.size()));
    std::array<int, 3> m{remap[static_cast<size_t>(t[0])], remap[static_cast<size_t>(t[1])],
                         remap[static_cast<size_t>(t[2])]};
    const Vec3 n = (v_[static_cast<size_t>(m[1])] - v_[static_cast<size_t>(m[0])])
                       .cross(v_[static_cast<size_t>(m[2])] - v_[static_cast<size_t>(m[0])]);
    if (m[0] == m[1] || m[1] == m[2] || m[0] == m[2] || !(n.norm() > 0.0)) {
      ++counts_.dropped_triangles;
      continue;
    }
    tri_.push_back(m);
  }
  if (tri_.empty())
    throw_input_error(src, "the surface has no triangles (a lumen surface needs a closed or open tube of triangles)");
  order_.resize(tri_.size());
  std::iota(order_.begin(), order_.end(), 0);
  bvh_.reserve(2 * tri_.size());
  build(0, static_cast<int>(tri_.size()));
  orient(inside);  // the hierarchy depends on the triangles' vertices, not on their winding
  pseudonormals();
  counts_.vertices = static_cast<int>(v_.size());
  counts_.triangles = static_cast<int>(tri_.size());
}

void LumenSurface::orient(const std::vector<Vec3>& inside) {
  // Edge → the triangles using it, to walk each connected piece and make neighbours agree.
  std::unordered_map<std::uint64_t, std::vector<int>> edges;
  edges.reserve(3 * tri_.size());
  for (size_t f = 0; f < tri_.size(); ++f)
    for (int k = 0; k < 3; ++k)
      edges[edge_key(tri_[f][static_cast<size_t>(k)], tri_[f][static_cast<size_t>((k + 1) % 3)])].push_back(
          static_cast<int>(f));
  // Does triangle f use the directed edge a → b?
  auto uses = [&](int f, int a, int b) {
    const auto& t = tri_[static_cast<size_t>(f)];
    for (int k = 0; k < 3; ++k)
      if (t[static_cast<size_t>(k)] == a && t[static_cast<size_t>((k + 1) % 3)] == b) return true;
    return false;
  };
  std::vector<int> piece(tri_.size(), -1);
  int pieces = 0;
  for (size_t seed = 0; seed < tri_.size(); ++seed) {
    if (piece[seed] >= 0) continue;
    std::queue<int> q;
    q.push(static_cast<int>(seed));
    piece[seed] = pieces;
    while (!q.empty()) {
      const int f = q.front();
      q.pop();
      const auto t = tri_[static_cast<size_t>(f)];
      for (int k = 0; k < 3; ++k) {
        const int a = t[static_cast<size_t>(k)], b = t[static_cast<size_t>((k + 1) % 3)];
        const auto& around = edges[edge_key(a, b)];
        if (around.size() != 2) continue;  // boundary or non-manifold: no orientation to pass on
        for (int g : around) {
          if (g == f || piece[static_cast<size_t>(g)] >= 0) continue;
          piece[static_cast<size_t>(g)] = pieces;
          // A consistent neighbour runs the shared edge the other way.
          if (uses(g, a, b)) {
            std::swap(tri_[static_cast<size_t>(g)][1], tri_[static_cast<size_t>(g)][2]);
            ++counts_.flipped_triangles;
          }
          q.push(g);
        }
      }
    }
    ++pieces;
  }
  counts_.components = pieces;
  for (const auto& [key, around] : edges) {
    if (around.size() == 1) ++counts_.boundary_edges;
    if (around.size() > 2) ++counts_.nonmanifold_edges;
  }
  // Boundary loops: pieces of the graph of boundary edges.
  {
    UnionFind uf(v_.size());
    std::vector<char> on(v_.size(), 0);
    for (const auto& [key, around] : edges)
      if (around.size() == 1) {
        const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
        uf.unite(a, b);
        on[static_cast<size_t>(a)] = on[static_cast<size_t>(b)] = 1;
      }
    std::vector<char> root(v_.size(), 0);
    for (size_t i = 0; i < v_.size(); ++i)
      if (on[i] && !root[static_cast<size_t>(uf.find(static_cast<int>(i)))]) {
        root[static_cast<size_t>(uf.find(static_cast<int>(i)))] = 1;
        ++counts_.boundary_loops;
      }
  }
  // Which way is out, per piece: the side the inside points are not on (closest-triangle
  // normal test, by majority), or else the sign of the volume enclosed once each boundary
  // loop is closed by a fan around its centroid.
  std::vector<double> vote(static_cast<size_t>(pieces), 0.0);
  if (!inside.empty()) {
    for (const auto& x : inside) {
      Vec3 bc;
      Feature feat;
      int local;
      const int bf = nearest(x, -1, bc, feat, local);
      const auto& t = tri_[static_cast<size_t>(bf)];
      const Vec3 n = (v_[static_cast<size_t>(t[1])] - v_[static_cast<size_t>(t[0])])
                         .cross(v_[static_cast<size_t>(t[2])] - v_[static_cast<size_t>(t[0])]);
      // Only clear answers vote (the closest point inside the face, the point off the plane).
      const Vec3 e = x - bc;
      const double s = e.dot(n) / (n.norm() * std::max(e.norm(), 1e-300));
      if (std::abs(s) > 0.5) vote[static_cast<size_t>(piece[static_cast<size_t>(bf)])] += s > 0 ? 1.0 : -1.0;
    }
    for (auto& v : vote) v = -v;  // inside points above the faces → the normals point in: flip
  }
  {
    // Enclosed volume after closing the boundary loops (used where no point voted).
    std::vector<double> volume(static_cast<size_t>(pieces), 0.0);
    for (size_t f = 0; f < tri_.size(); ++f) {
      const auto& t = tri_[f];
      volume[static_cast<size_t>(piece[f])] +=
          v_[static_cast<size_t>(t[0])].dot(v_[static_cast<size_t>(t[1])].cross(v_[static_cast<size_t>(t[2])])) / 6.0;
    }
    // Fans: directed boundary edges a → b (as their triangle runs them) closed by (centroid, b, a).
    UnionFind uf(v_.size());
    std::vector<std::array<int, 3>> rims;  // a, b, piece
    for (size_t f = 0; f < tri_.size(); ++f)
      for (int k = 0; k < 3; ++k) {
        const int a = tri_[f][static_cast<size_t>(k)], b = tri_[f][static_cast<size_t>((k + 1) % 3)];
        if (edges[edge_key(a, b)].size() == 1) {
          rims.push_back({a, b, piece[f]});
          uf.unite(a, b);
        }
      }
    std::unordered_map<int, std::pair<Vec3, int>> centroid;
    for (const auto& r : rims) {
      auto& c = centroid[uf.find(r[0])];
      if (c.second == 0) c.first.setZero();
      c.first += v_[static_cast<size_t>(r[0])];
      ++c.second;
    }
    for (const auto& r : rims) {
      const auto& c = centroid[uf.find(r[0])];
      const Vec3 m = c.first / c.second;
      volume[static_cast<size_t>(r[2])] +=
          m.dot(v_[static_cast<size_t>(r[1])].cross(v_[static_cast<size_t>(r[0])])) / 6.0;
    }
    for (int p = 0; p < pieces; ++p)
      if (vote[static_cast<size_t>(p)] == 0.0) vote[static_cast<size_t>(p)] = volume[static_cast<size_t>(p)];
  }
  for (size_t f = 0; f < tri_.size(); ++f)
    if (vote[static_cast<size_t>(piece[f])] < 0.0) std::swap(tri_[f][1], tri_[f][2]);
}

void LumenSurface::pseudonormals() {
  const size_t nf = tri_.size();
  face_normal_.resize(nf);
  plane_.resize(nf);
  edge_normal_.assign(nf, {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()});
  edge_open_.assign(nf, {false, false, false});
  vertex_normal_.assign(v_.size(), Vec3::Zero());
  vertex_open_.assign(v_.size(), 0);
  std::unordered_map<std::uint64_t, Vec3> edge_sum;
  std::unordered_map<std::uint64_t, int> edge_count;
  double emin = std::numeric_limits<double>::infinity(), emax = 0.0, esum = 0.0;
  for (size_t f = 0; f < nf; ++f) {
    const auto& t = tri_[f];
    const Vec3 area_vector = 0.5 * (v_[static_cast<size_t>(t[1])] - v_[static_cast<size_t>(t[0])])
                                       .cross(v_[static_cast<size_t>(t[2])] - v_[static_cast<size_t>(t[0])]);
    const Vec3 n = area_vector.normalized();
    const Vec3 centroid =
        (v_[static_cast<size_t>(t[0])] + v_[static_cast<size_t>(t[1])] + v_[static_cast<size_t>(t[2])]) / 3.0;
    face_normal_[f] = n;
    for (int k : t) max_vertex_reach_ = std::max(max_vertex_reach_, (v_[static_cast<size_t>(k)] - centroid).norm());
    plane_[f] = {centroid, n, area_vector.norm()};
    for (int k = 0; k < 3; ++k) {
      const int a = t[static_cast<size_t>(k)], b = t[static_cast<size_t>((k + 1) % 3)],
                c = t[static_cast<size_t>((k + 2) % 3)];
      const auto key = edge_key(a, b);
      auto [it, ins] = edge_sum.emplace(key, Vec3::Zero());
      it->second += n;
      ++edge_count[key];
      // Angle of the triangle at vertex a.
      const Vec3 u = (v_[static_cast<size_t>(b)] - v_[static_cast<size_t>(a)]).normalized();
      const Vec3 w = (v_[static_cast<size_t>(c)] - v_[static_cast<size_t>(a)]).normalized();
      vertex_normal_[static_cast<size_t>(a)] += std::acos(std::clamp(u.dot(w), -1.0, 1.0)) * n;
      const double len = (v_[static_cast<size_t>(b)] - v_[static_cast<size_t>(a)]).norm();
      emin = std::min(emin, len), emax = std::max(emax, len), esum += len;
    }
  }
  counts_.min_edge = emin, counts_.max_edge = emax, counts_.mean_edge = esum / (3.0 * static_cast<double>(nf));
  for (size_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = tri_[f][static_cast<size_t>(k)], b = tri_[f][static_cast<size_t>((k + 1) % 3)];
      const auto key = edge_key(a, b);
      edge_normal_[f][static_cast<size_t>(k)] = edge_sum[key];
      if (edge_count[key] == 1) {
        edge_open_[f][static_cast<size_t>(k)] = true;
        vertex_open_[static_cast<size_t>(a)] = vertex_open_[static_cast<size_t>(b)] = 1;
      }
    }
}

int LumenSurface::build(int first, int count) {
  const int id = static_cast<int>(bvh_.size());
  bvh_.emplace_back();
  Eigen::AlignedBox3d box, centres;
  for (int i = first; i < first + count; ++i) {
    const auto& t = tri_[static_cast<size_t>(order_[static_cast<size_t>(i)])];
    Vec3 c = Vec3::Zero();
    for (int k : t) box.extend(v_[static_cast<size_t>(k)]), c += v_[static_cast<size_t>(k)];
    centres.extend(c / 3.0);
  }
  bvh_[static_cast<size_t>(id)].box = box;
  if (count <= 4) {
    bvh_[static_cast<size_t>(id)].first = first;
    bvh_[static_cast<size_t>(id)].count = count;
    return id;
  }
  int axis = 0;
  centres.sizes().maxCoeff(&axis);
  auto centre = [&](int f) {
    const auto& t = tri_[static_cast<size_t>(f)];
    return v_[static_cast<size_t>(t[0])][axis] + v_[static_cast<size_t>(t[1])][axis] +
           v_[static_cast<size_t>(t[2])][axis];
  };
  const int mid = first + count / 2;
  std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + first + count,
                   [&](int a, int b) { return centre(a) < centre(b); });
  const int l = build(first, mid - first);
  const int r = build(mid, first + count - mid);
  bvh_[static_cast<size_t>(id)].left = l;
  bvh_[static_cast<size_t>(id)].right = r;
  return id;
}

double LumenSurface::closest_on(int f, const Vec3& p, Vec3& out, Feature& feat, int& local) const {
  // Closest point on triangle abc by the Voronoi regions of its features (Ericson, Real-Time
  // Collision Detection, 5.1.5), telling which feature holds it.
  const auto& t = tri_[static_cast<size_t>(f)];
  const Vec3& a = v_[static_cast<size_t>(t[0])];
  const Vec3& b = v_[static_cast<size_t>(t[1])];
  const Vec3& c = v_[static_cast<size_t>(t[2])];
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    out = a, feat = Feature::Vertex, local = 0;
    return (p - out).squaredNorm();
  }
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) {
    out = b, feat = Feature::Vertex, local = 1;
    return (p - out).squaredNorm();
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    out = a + (d1 / (d1 - d3)) * ab, feat = Feature::Edge, local = 0;
    return (p - out).squaredNorm();
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) {
    out = c, feat = Feature::Vertex, local = 2;
    return (p - out).squaredNorm();
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    out = a + (d2 / (d2 - d6)) * ac, feat = Feature::Edge, local = 2;  // edge c → a
    return (p - out).squaredNorm();
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    out = b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b), feat = Feature::Edge, local = 1;
    return (p - out).squaredNorm();
  }
  const double denom = 1.0 / (va + vb + vc);
  out = a + ab * (vb * denom) + ac * (vc * denom), feat = Feature::Face, local = 0;
  return (p - out).squaredNorm();
}

SurfaceDistance LumenSurface::finish(const Vec3& x, int f, const Vec3& c, Feature feat, int local,
                                     Mat3* hessian) const {
  SurfaceDistance r;
  r.triangle = f;
  r.closest = c;
  r.feature = feat;
  const auto& t = tri_[static_cast<size_t>(f)];
  Vec3 N = Vec3::Zero();
  switch (feat) {
    case Feature::Face:
      N = face_normal_[static_cast<size_t>(f)];
      break;
    case Feature::Edge:
      N = edge_normal_[static_cast<size_t>(f)][static_cast<size_t>(local)];
      r.open = edge_open_[static_cast<size_t>(f)][static_cast<size_t>(local)];
      break;
    case Feature::Vertex:
      N = vertex_normal_[static_cast<size_t>(t[static_cast<size_t>(local)])];
      r.open = vertex_open_[static_cast<size_t>(t[static_cast<size_t>(local)])] != 0;
      break;
  }
  const Vec3 e = x - c;
  const double u = e.norm();
  double s = e.dot(N) > 0.0 ? 1.0 : -1.0;
  if (r.open) s = -1.0;  // beyond an open end: not outside
  r.distance = s * u;
  r.gradient = u > 0.0 ? Vec3(s * e / u) : face_normal_[static_cast<size_t>(f)];
  if (hessian) {
    hessian->setZero();
    if (u > 0.0 && feat != Feature::Face) {
      const Vec3 n = e / u;
      Mat3 P = Mat3::Identity() - n * n.transpose();
      if (feat == Feature::Edge) {
        const Vec3 tan = (v_[static_cast<size_t>(t[static_cast<size_t>((local + 1) % 3)])] -
                          v_[static_cast<size_t>(t[static_cast<size_t>(local)])])
                             .normalized();
        P -= tan * tan.transpose();
      }
      *hessian = (s / u) * P;
    }
  }
  return r;
}

int LumenSurface::nearest(const Vec3& x, int hint, Vec3& bc, Feature& bfeat, int& bl) const {
  double best = std::numeric_limits<double>::infinity();
  int bf = -1;
  bl = 0;
  bc.setZero();
  bfeat = Feature::Face;
  if (hint >= 0 && hint < static_cast<int>(tri_.size())) {
    best = closest_on(hint, x, bc, bfeat, bl);
    bf = hint;
  }
  // Depth-first, nearer child first, pruned by the best squared distance so far.
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = bvh_[static_cast<size_t>(stack[--top])];
    if (box_distance2(n.box, x) > best) continue;
    if (n.left < 0) {
      for (int i = n.first; i < n.first + n.count; ++i) {
        const int f = order_[static_cast<size_t>(i)];
        Vec3 c;
        Feature feat;
        int local;
        const double d2 = closest_on(f, x, c, feat, local);
        // Ties (a shared edge or vertex): the lower index, whatever the traversal order.
        if (d2 < best || (d2 == best && f < bf)) best = d2, bf = f, bc = c, bfeat = feat, bl = local;
      }
      continue;
    }
    const double dl = box_distance2(bvh_[static_cast<size_t>(n.left)].box, x);
    const double dr = box_distance2(bvh_[static_cast<size_t>(n.right)].box, x);
    if (top + 2 > 128) continue;  // depth ≤ log2(triangles) + 1: cannot happen
    if (dl < dr) {
      stack[top++] = n.right;
      stack[top++] = n.left;
    } else {
      stack[top++] = n.left;
      stack[top++] = n.right;
    }
  }
  return bf;
}

SurfaceDistance LumenSurface::distance(const Vec3& x, int hint, Mat3* hessian) const {
  Vec3 c;
  Feature feat;
  int local;
  const int f = nearest(x, hint, c, feat, local);
  return finish(x, f, c, feat, local, hessian);
}

SurfaceDistance LumenSurface::distance(const Vec3& x, const SurfaceNeighbourhood& near) const {
  // The listed triangles hold x's nearest ones if every triangle within u(x) of x has its
  // centroid within R of c: u(x) ≤ u_c + δ, and such a triangle's centroid lies within
  // u(x) + (its farthest vertex from its centroid) of x.
  const double delta = (x - near.centre).norm();
  if (!near.gathered || near.margin < 0.0 || near.u_centre + 2.0 * delta + max_vertex_reach_ > near.radius)
    return distance(x, near.nearest);
  return closest_among(x, near.triangles);
}

SurfaceDistance LumenSurface::closest_among(const Vec3& x, std::span<const int> candidates) const {
  double best = std::numeric_limits<double>::infinity();
  int bf = -1, bl = 0;
  Vec3 bc = Vec3::Zero();
  Feature bfeat = Feature::Face;
  for (int f : candidates) {
    Vec3 c;
    Feature feat;
    int local;
    const double d2 = closest_on(f, x, c, feat, local);
    // Ties (a shared edge or vertex): the lower index, as nearest() decides them.
    if (d2 < best || (d2 == best && f < bf)) best = d2, bf = f, bc = c, bfeat = feat, bl = local;
  }
  return finish(x, bf, bc, bfeat, bl, nullptr);
}

void LumenSurface::gather(const Vec3& x, double radius, std::vector<int>& out) const {
  out.clear();
  const double r2 = radius * radius;
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = bvh_[static_cast<size_t>(stack[--top])];
    if (box_distance2(n.box, x) > r2) continue;
    if (n.left < 0) {
      for (int i = n.first; i < n.first + n.count; ++i) out.push_back(order_[static_cast<size_t>(i)]);
    } else if (top + 2 <= 128) {
      stack[top++] = n.left;
      stack[top++] = n.right;
    }
  }
}

namespace {
/// Weights below e^−K of the largest are dropped (w_f ∝ e^{−|x − g_f|²/σ²}): near a wall
/// the dropped triangles' planes lie within a few σ²κ of the kept ones', so d_σ jumps by less
/// than e^−10 of that (about 1e-9 m on the real anatomies).
constexpr double kWeightCut = 10.0;
}  // namespace

SmoothDistance LumenSurface::smooth_distance(const Vec3& x, double sigma, Mat3* hessian) const {
  SurfaceNeighbourhood near;
  return smooth_distance(x, sigma, near, 0.0, hessian);
}

SmoothDistance LumenSurface::smooth_distance(const Vec3& x, double sigma, SurfaceNeighbourhood& near, double margin,
                                             Mat3* hessian, double skip_deeper_than) const {
  const double s = std::max(sigma, 0.0);
  double delta = (x - near.centre).norm();
  // A point provably deeper than skip_deeper_than keeps its centre however far it moves. One
  // whose centre was that deep but which has moved too far to tell is centred again (an exact
  // query costs less than d_σ).
  const bool deep = near.margin >= 0.0 && near.inside && near.u_centre - delta > skip_deeper_than;
  const bool unsure = near.inside && near.u_centre > skip_deeper_than && delta > 0.0;
  if (!deep && (near.margin < 0.0 || near.sigma != s || delta > near.margin || unsure)) {
    const SurfaceDistance r = distance(x, near.nearest, nullptr);
    near.centre = x;
    near.margin = std::max(margin, 0.0);
    near.sigma = s;
    near.u_centre = std::abs(r.distance);
    near.inside = r.distance < 0.0;
    near.nearest = r.triangle;
    near.gathered = false;
    delta = 0.0;
  }
  SmoothDistance out;
  // The exact distance is 1-Lipschitz, and x cannot have crossed the wall since c while it
  // stays farther from it than it moved.
  if (near.inside && near.u_centre - delta > skip_deeper_than) {
    out.skipped = true;
    out.distance = -(near.u_centre - delta);
    return out;
  }
  if (!(s > 0.0)) {
    const SurfaceDistance r = distance(x, near.nearest, hessian);
    out.distance = r.distance;
    out.gradient = r.gradient;
    return out;
  }
  if (!near.gathered) {
    const double rho = (near.centre - plane_[static_cast<size_t>(near.nearest)].centroid).norm();
    const double m = near.margin;
    const double radius = std::sqrt((rho + m) * (rho + m) + kWeightCut * s * s) + m;
    near.radius = radius;
    thread_local std::vector<int> boxes;
    gather(near.centre, radius, boxes);  // a triangle's box holds its centroid
    near.triangles.clear();
    for (int f : boxes)
      if ((plane_[static_cast<size_t>(f)].centroid - near.centre).norm() <= radius) near.triangles.push_back(f);
    near.gathered = true;
  }
  return implicit_over(x, s, near.triangles, hessian);
}

SmoothDistance LumenSurface::implicit_over(const Vec3& x, double sigma, const std::vector<int>& listed,
                                           Mat3* hessian) const {
  // Pass 1: squared distances to the listed centroids, and the least (the weights' scale).
  thread_local std::vector<double> r2;
  r2.resize(listed.size());
  double r2_min = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < listed.size(); ++i) {
    r2[i] = (x - plane_[static_cast<size_t>(listed[i])].centroid).squaredNorm();
    r2_min = std::min(r2_min, r2[i]);
  }
  // Pass 2: the weights relative to the nearest centroid's Gaussian (the common factor
  // cancels) and the moments of d_f, n_f and a_f = −2(x − g_f)/σ² they weigh.
  const double inv_s2 = 1.0 / (sigma * sigma);
  const double r2_cut = r2_min + kWeightCut * sigma * sigma;
  double W = 0.0, D = 0.0;
  Vec3 Sn = Vec3::Zero(), Sa = Vec3::Zero(), Sda = Vec3::Zero();
  Mat3 Sna = Mat3::Zero(), Saa = Mat3::Zero(), Sdaa = Mat3::Zero();
  for (size_t i = 0; i < listed.size(); ++i) {
    if (r2[i] > r2_cut) continue;
    const Plane& p = plane_[static_cast<size_t>(listed[i])];
    const Vec3 rel = x - p.centroid;
    const double w = p.area * std::exp(-(r2[i] - r2_min) * inv_s2);
    const double d = rel.dot(p.normal);
    const Vec3 a = (-2.0 * inv_s2) * rel;
    W += w;
    D += w * d;
    Sn += w * p.normal;
    Sa += w * a;
    Sda += (w * d) * a;
    if (hessian) {
      const Vec3 wa = w * a;
      Sna.noalias() += p.normal * wa.transpose();
      Saa.noalias() += a * wa.transpose();
      Sdaa.noalias() += d * a * wa.transpose();
    }
  }
  // Centred: Σ w (d_f − d_σ) a_f = Sda − d_σ Sa (the d_f of a query's planes differ by far
  // less than they are, so the difference keeps all but a few digits).
  SmoothDistance out;
  out.distance = D / W;
  out.gradient = (Sn + Sda - out.distance * Sa) / W;
  if (hessian) {
    const Vec3 abar = Sa / W;
    const Mat3 na = Sna / W;
    *hessian = na + na.transpose() + (Sdaa - out.distance * Saa) / W - abar * out.gradient.transpose() -
               out.gradient * abar.transpose();
  }
  return out;
}

SurfaceDistance LumenSurface::distance_brute_force(const Vec3& x) const {
  std::vector<int> all(tri_.size());
  std::iota(all.begin(), all.end(), 0);
  return closest_among(x, all);
}

}  // namespace flowire::vessels
