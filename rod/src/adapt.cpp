#include "flowire/rod/feeder.hpp"

#include <algorithm>
#include <cmath>

#include "rod_internal.hpp"

namespace flowire::rod {

// -----------------------------------------------------------------------------------------
// Adaptivity
// -----------------------------------------------------------------------------------------

namespace {
/// u is a multiple of len (within round-off of the dyadic grid).
bool aligned(double u, double len) {
  const double r = u / len;
  return std::abs(r - std::round(r)) < 1e-7;
}
}  // namespace

bool Feeder::adapt(const std::function<void(const std::vector<int>&)>& on_resample) {
  const RodModel& model = body_.model;
  const Discretization& disc = body_.disc;
  if (!model.adapt.enabled) return false;
  const AdaptSpec& a = model.adapt;
  const double tol = 1e-9 * model.h;
  RodState& s = body_.state;
  Scratch& w = *scratch_;
  const int nv = s.vertex_count();
  const int fc = first_clamped_;
  // The boundary edge (fc − 1, from the last free vertex to the entry) has no level of its own:
  // its rest length follows the feed within [ℓ/2, 3ℓ/2) of its neighbour's ℓ (update_vertex_set).
  // It is refined or coarsened with that neighbour: the criteria of edge fc − 2 see the turning
  // at the entry too, and after the free part is resampled the boundary edge is cut again at
  // the neighbour's new level (boundary_vertices). The clamp's edge behind the entry is never touched.
  const int lowest = tip_clamped_ ? 3 : 0;  // a tip clamp holds vertices 0..2 as they are
  auto len = [&](int j) { return s.u[j + 1] - s.u[j]; };
  w.turn_angle.assign(nv, 0.0);
  for (int k = 1; k < nv - 1; ++k) {
    const Vec3 te = (s.x[k] - s.x[k - 1]).normalized();
    const Vec3 tf = (s.x[k + 1] - s.x[k]).normalized();
    const double phi = std::atan2(te.cross(tf).norm(), te.dot(tf));
    const double rest = 2.0 * std::atan(0.5 * std::hypot(disc.rest_kappa1[k], disc.rest_kappa2[k]));
    w.turn_angle[k] = std::max(phi, rest);
  }
  // Turning seen by edge j's criteria (the last regular edge also sees the boundary's).
  auto turning = [&](int j) {
    const double t = std::max(w.turn_angle[j], w.turn_angle[j + 1]);
    return j == fc - 2 ? std::max(t, w.turn_angle[fc]) : t;
  };
  w.split_edge.assign(nv - 1, 0);
  w.remove_vertex.assign(nv, 0);
  auto sibling_pair = [&](int k) {  // vertex k is the midpoint of an aligned parent edge
    const double l = len(k - 1);
    return std::abs(len(k) - l) <= 1e-9 * l && aligned(s.u[k - 1], 2.0 * l);
  };
  auto splittable = [&](int j) { return j >= lowest && j < fc - 1 && len(j) >= 2.0 * a.min_segment_length - tol; };
  for (int j = lowest; j < fc - 1; ++j)
    if (splittable(j) && turning(j) > a.split_angle) w.split_edge[j] = 1;
  // 2:1 balance: neighbouring rest lengths of the regular free edges differ by at most a factor 2.
  auto final_len = [&](int j) { return w.split_edge[j] ? 0.5 * len(j) : len(j); };
  for (bool again = true; again;) {
    again = false;
    for (int j = 0; j < fc - 1; ++j)
      for (int i : {j - 1, j + 1})
        if (i >= 0 && i < fc - 1 && !w.split_edge[i] && final_len(i) > 2.0 * final_len(j) + tol && splittable(i)) {
          w.split_edge[i] = 1;
          again = true;
        }
  }
  for (int k = std::max(lowest, 1); k < fc - 1; ++k) {
    if (!sibling_pair(k)) continue;
    const double l = len(k - 1);
    if (2.0 * l > a.max_segment_length + tol || w.split_edge[k - 1] || w.split_edge[k]) continue;
    if (std::max(turning(k - 1), turning(k)) >= a.merge_angle) continue;
    if (k >= 2 && final_len(k - 2) < l - tol) continue;
    if (k + 1 < fc - 1 && final_len(k + 1) < l - tol) continue;
    // Lumping the vertex's mass onto its neighbours raises the kinetic energy by
    // (m_k/8)|v_{k−1} − v_{k+1}|² (exact for a linear velocity field): merge only where
    // that is negligible, so a rod swinging through straight is not coarsened.
    const double dke = 0.125 * disc.mass[k] * (s.v[k - 1] - s.v[k + 1]).squaredNorm();
    const double ke = 0.5 * (disc.mass[k - 1] * s.v[k - 1].squaredNorm() + disc.mass[k] * s.v[k].squaredNorm() +
                             disc.mass[k + 1] * s.v[k + 1].squaredNorm());
    if (dke > 1e-4 * ke) continue;
    w.remove_vertex[k] = 1;
  }
  w.new_u.clear();
  int splits = 0, merges = 0;
  for (int k = 0; k < fc; ++k) {
    if (w.remove_vertex[k]) {
      ++merges;
    } else {
      w.new_u.push_back(s.u[k]);
    }
    if (k < fc - 1 && w.split_edge[k]) {
      w.new_u.push_back(0.5 * (s.u[k] + s.u[k + 1]));
      ++splits;
    }
  }
  if (splits == 0 && merges == 0) return false;
  const int free_before = static_cast<int>(w.new_u.size());
  boundary_vertices(s.inserted_length, w.new_u);
  const int free_after = static_cast<int>(w.new_u.size());
  w.new_u.push_back(s.u[fc]);
  w.new_u.push_back(s.u[fc + 1]);
  resample(w.new_u);
  on_resample(w.new_source);
  adapt_splits_ += splits + std::max(free_after - free_before, 0);
  adapt_merges_ += merges + std::max(free_before - free_after, 0);
  return true;
}

void Feeder::resample(const std::vector<double>& u_new) {
  RodState& s = body_.state;
  const Discretization& disc = body_.disc;
  Scratch& w = *scratch_;
  const int nv = s.vertex_count();
  const int nn = static_cast<int>(u_new.size());
  const double tol = 1e-9 * body_.model.h;
  // The old state.
  w.old_u = s.u;
  w.old_x = s.x;
  w.old_v = s.v;
  w.old_theta = s.theta;
  w.old_omega = s.omega;
  w.old_frame = s.frame;
  w.old_ref_twist = s.ref_twist;
  w.old_cell = disc.cell_length;
  const int old_clamp = first_clamped_;
  // Old twist density (twist per cell length) and vertex tangents.
  w.old_twist_density.assign(nv, 0.0);
  for (int k = 1; k < nv - 1; ++k)
    w.old_twist_density[k] = (w.old_theta[k] - w.old_theta[k - 1] + w.old_ref_twist[k]) / w.old_cell[k];
  w.old_twist_density[0] = nv > 2 ? w.old_twist_density[1] : 0.0;
  w.old_twist_density[nv - 1] = nv > 2 ? w.old_twist_density[nv - 2] : 0.0;
  w.old_tangent.resize(nv);
  for (int k = 0; k < nv; ++k) {
    const Vec3 tl = k > 0 ? Vec3((w.old_x[k] - w.old_x[k - 1]).normalized()) : Vec3::Zero();
    const Vec3 tr = k < nv - 1 ? Vec3((w.old_x[k + 1] - w.old_x[k]).normalized()) : Vec3::Zero();
    w.old_tangent[k] = (tl + tr).normalized();
  }

  // Vertices: kept ones as they were; new ones on the Hermite curve of their old edge.
  s.u = u_new;
  s.x.resize(nn);
  s.v.resize(nn);
  w.new_source.assign(nn, -1);
  w.new_twist_density.assign(nn, 0.0);  // twist density at the new vertices
  int i = 0;
  for (int m = 0; m < nn; ++m) {
    const double u = u_new[m];
    while (i < nv - 2 && w.old_u[i + 1] <= u + tol) ++i;
    if (std::abs(u - w.old_u[i]) <= tol || std::abs(u - w.old_u[i + 1]) <= tol) {
      const int k = std::abs(u - w.old_u[i]) <= tol ? i : i + 1;
      w.new_source[m] = k;
      s.x[m] = w.old_x[k];
      s.v[m] = w.old_v[k];
      w.new_twist_density[m] = w.old_twist_density[k];
      continue;
    }
    const double t = (u - w.old_u[i]) / (w.old_u[i + 1] - w.old_u[i]);
    const double chord = (w.old_x[i + 1] - w.old_x[i]).norm();
    s.x[m] = detail::hermite(w.old_x[i], w.old_tangent[i], w.old_x[i + 1], w.old_tangent[i + 1], chord, t);
    s.v[m] = (1.0 - t) * w.old_v[i] + t * w.old_v[i + 1];
    w.new_twist_density[m] = (1.0 - t) * w.old_twist_density[i] + t * w.old_twist_density[i + 1];
  }
  for (int m = 0; m < nn; ++m)
    if (w.new_source[m] == old_clamp) first_clamped_ = m;
  body_.rediscretize();

  // Edges: the old edge holding the new edge's midpoint gives the frame (transported to
  // the new tangent), the spin rate and a provisional angle.
  s.theta.resize(nn - 1);
  s.omega.resize(nn - 1);
  s.frame.resize(nn - 1);
  s.ref_twist.assign(nn, 0.0);
  i = 0;
  for (int j = 0; j < nn - 1; ++j) {
    const double mid = 0.5 * (u_new[j] + u_new[j + 1]);
    while (i < nv - 2 && w.old_u[i + 1] <= mid) ++i;
    const Vec3 t0 = w.old_frame[i].d1.cross(w.old_frame[i].d2);
    const Vec3 t1 = (s.x[j + 1] - s.x[j]).normalized();
    Vec3 d1 = parallel_transport(w.old_frame[i].d1, t0, t1);
    d1 = (d1 - t1 * t1.dot(d1)).normalized();
    s.frame[j] = EdgeFrame{d1, t1.cross(d1)};
    s.omega[j] = w.old_omega[i];
    s.theta[j] = w.old_theta[i];
  }
  for (int m = 1; m < nn - 1; ++m) {
    const int k = w.new_source[m];
    const double previous = (k > 0 && k < nv - 1) ? w.old_ref_twist[k] : 0.0;
    s.ref_twist[m] = reference_twist(s.frame[m - 1].d1, (s.x[m] - s.x[m - 1]).normalized(), s.frame[m].d1,
                                     (s.x[m + 1] - s.x[m]).normalized(), previous);
  }
  // Material angles swept from the clamp (whose edges are unchanged): each vertex carries
  // the old twist density times its new cell.
  for (int j = nn - 3; j >= 0; --j) {
    if (j >= first_clamped_) continue;  // clamp edges keep their angle
    const int m = j + 1;
    const double twist = w.new_twist_density[m] * disc.cell_length[m];
    s.theta[j] = s.theta[j + 1] + s.ref_twist[m] - twist;
  }
  refresh_arc_lengths();
}

}  // namespace flowire::rod
