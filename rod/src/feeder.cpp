#include "flowire/rod/feeder.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/kernel_clones.hpp"
#include "rod_internal.hpp"

namespace flowire::rod {

// -----------------------------------------------------------------------------------------
// Feeding: the inserted length decides which vertices are free, which are held by the
// clamp, and where the prescribed ones are.
// -----------------------------------------------------------------------------------------

Feeder::Scratch::Scratch(int nvmax) {
  for (auto* v : {&turn_angle, &new_u, &new_twist_density, &old_u, &old_twist_density, &old_cell, &old_theta,
                  &old_omega, &old_ref_twist})
    v->reserve(static_cast<size_t>(nvmax));
  for (auto* v : {&old_x, &old_v, &old_tangent, &tangent_now, &tangent_before}) v->reserve(static_cast<size_t>(nvmax));
  old_frame.reserve(static_cast<size_t>(nvmax));
  new_source.reserve(static_cast<size_t>(nvmax));
  split_edge.reserve(static_cast<size_t>(nvmax));
  remove_vertex.reserve(static_cast<size_t>(nvmax));
}

Feeder::Feeder(RodBody& body) : body_(body), scratch_(std::make_unique<Scratch>(body.max_vertices())) {
  arc_length_.reserve(static_cast<size_t>(body.max_vertices()));
  const Vec3 t = -body.model.base_direction;  // clamped edges point from tip side to holder
  base_d2_ = body.model.base_normal;
  base_d1_ = base_d2_.cross(t);
}

Feeder::~Feeder() = default;

void Feeder::build(double inserted) {
  const RodModel& model = body_.model;
  const double h = model.h;
  // Free grid points 0 … m, the last within [h/2, 3h/2) of the entry; then the boundary vertex
  // at the entry (u = inserted) and one more, a segment behind it.
  const int m = std::max(1, static_cast<int>(std::floor((inserted - 0.5 * h) / h + 1e-9)));
  const int nv = m + 3;
  RodState& s = body_.state;
  s.x.assign(nv, Vec3::Zero());
  s.v.assign(nv, Vec3::Zero());
  s.theta.assign(nv - 1, 0.0);
  s.omega.assign(nv - 1, 0.0);
  s.frame.assign(nv - 1, EdgeFrame{});
  s.ref_twist.assign(nv, 0.0);
  s.u.resize(nv);
  for (int k = 0; k <= m; ++k) s.u[k] = model.u(k);
  s.u[m + 1] = inserted;
  s.u[m + 2] = inserted + h;
  body_.rediscretize();
  s.inserted_length = inserted;
  s.base_angle = 0.0;
  s.time = 0.0;
  first_clamped_ = m + 1;
  drive_.set_base_angle(0.0);
  layout_rest_shape();
}

void Feeder::layout_rest_shape() {
  RodState& s = body_.state;
  const RodModel& model = body_.model;
  const Discretization& d = body_.disc;
  const int nv = s.vertex_count();
  const int kc = first_clamped_;
  const double inserted = s.inserted_length;
  const Vec3& pb = model.base_position;
  const Vec3& db = model.base_direction;
  const Vec3 a = model.base_normal;
  for (int k = kc; k < nv; ++k) s.x[k] = pb - db * (s.u[k] - inserted);
  // Lay out the rest shape from the clamp to the tip (planar bends about the base normal).
  Vec3 tf = -db;
  for (int k = kc; k >= 1; --k) {
    const double kappa = d.rest_kappa1[k];
    const double phi = 2.0 * std::atan(0.5 * kappa);
    const Eigen::AngleAxisd rot(-phi, a);
    const Vec3 te = k == kc && k == nv - 1 ? tf : (rot * tf).normalized();
    s.x[k - 1] = s.x[k] - d.rest_length[k - 1] * te;
    tf = te;
  }
  for (auto& v : s.v) v.setZero();
  for (int j = 0; j < nv - 1; ++j) {
    s.theta[j] = 0.0;
    s.omega[j] = 0.0;
  }
  for (int j = 0; j < nv - 1; ++j) {
    const Vec3 t = (s.x[j + 1] - s.x[j]).normalized();
    s.frame[j].d2 = (a - t * t.dot(a)).normalized();
    s.frame[j].d1 = s.frame[j].d2.cross(t);
  }
  for (int k = 1; k < nv - 1; ++k)
    s.ref_twist[k] = reference_twist(s.frame[k - 1].d1, (s.x[k] - s.x[k - 1]).normalized(), s.frame[k].d1,
                                     (s.x[k + 1] - s.x[k]).normalized(), 0.0);
  refresh_arc_lengths();
}

void Feeder::lay_along(const std::function<Vec3(double)>& along) {
  RodState& s = body_.state;
  const int nv = s.vertex_count();
  const int kc = first_clamped_;
  for (int k = 0; k < kc; ++k) s.x[k] = along(arc_length_[k]);
  for (auto& v : s.v) v.setZero();
  for (int j = 0; j < nv - 1; ++j) s.theta[j] = s.omega[j] = 0.0;
  // Frames from the clamp towards the tip, each transported from its neighbour.
  for (int j = std::min(kc, nv - 2) - 1; j >= 0; --j) {
    const Vec3 tn = (s.x[j + 2] - s.x[j + 1]).normalized();
    const Vec3 t = (s.x[j + 1] - s.x[j]).normalized();
    Vec3 d1 = parallel_transport(s.frame[j + 1].d1, tn, t);
    d1 = (d1 - t * t.dot(d1)).normalized();
    s.frame[j].d1 = d1;
    s.frame[j].d2 = t.cross(d1);
  }
  for (int k = 1; k < nv - 1; ++k)
    s.ref_twist[k] = reference_twist(s.frame[k - 1].d1, (s.x[k] - s.x[k - 1]).normalized(), s.frame[k].d1,
                                     (s.x[k + 1] - s.x[k]).normalized(), 0.0);
}

// The stepper's frame transport (rod_internal.hpp), beside the feeder's own transports of frames.
FLOWIRE_KERNEL_CLONES
void detail::transport_frames_to(const std::vector<Vec3>& x_new, const std::vector<EdgeFrame>& frame_from,
                                 const std::vector<double>& twist_from, std::vector<EdgeFrame>& frame_to,
                                 std::vector<double>& twist_to) {
  // One pass: edge j's frame, then the reference twist at the vertex before it from the
  // two new frames (their tangents kept, not re-derived as d1 × d2). In place is allowed.
  const int nv = static_cast<int>(x_new.size());
  Vec3 t_prev = Vec3::Zero(), d1_prev = Vec3::Zero();
  for (int j = 0; j < nv - 1; ++j) {
    const EdgeFrame& from = frame_from[j];
    const Vec3 t0 = from.d1.cross(from.d2);
    const Vec3 t1 = (x_new[j + 1] - x_new[j]).normalized();
    Vec3 d1 = parallel_transport(from.d1, t0, t1);
    d1 = (d1 - t1 * t1.dot(d1)).normalized();
    frame_to[j].d1 = d1;
    frame_to[j].d2 = t1.cross(d1);
    if (j > 0) twist_to[j] = reference_twist(d1_prev, t_prev, d1, t1, twist_from[j]);
    t_prev = t1;
    d1_prev = d1;
  }
}

void Feeder::refresh_arc_lengths() {
  const RodState& s = body_.state;
  arc_length_.resize(s.x.size());
  for (size_t k = 0; k < s.x.size(); ++k) arc_length_[k] = s.inserted_length - s.u[k];
}

namespace {
/// Vertex @p k's tangent of the path through @p x: inside, the mean of the unit edges on either
/// side; at an end, the edge reflected about the next vertex's tangent. Both exact on a circular
/// arc sampled evenly, O(ℓ²) off elsewhere, so that the cubic through them is O(ℓ³) from the curve.
Vec3 path_tangent(std::span<const Vec3> x, int k) {
  const int n = static_cast<int>(x.size());
  auto edge = [&](int j) { return Vec3((x[j + 1] - x[j]).normalized()); };
  auto inner = [&](int i) { return Vec3((edge(i - 1) + edge(i)).normalized()); };
  if (n < 3) return edge(0);
  if (k == 0) return Vec3(2.0 * edge(0).dot(inner(1)) * edge(0) - inner(1));
  if (k == n - 1) return Vec3(2.0 * edge(n - 2).dot(inner(n - 2)) * edge(n - 2) - inner(n - 2));
  return inner(k);
}
}  // namespace

int Feeder::boundary_change(double inserted, double u_prev, double u_last, bool removable) const {
  const double l = u_last - u_prev, b = inserted - u_last, tol = 1e-9 * body_.model.h;
  if (b >= 1.5 * l - tol) return 1;
  if (b < 0.5 * l - tol && removable) return -1;
  return 0;
}

double Feeder::next_boundary_point(double u_prev, double u_last) const {
  const double h = body_.model.h, l = u_last - u_prev;
  if (std::abs(l - h) <= 1e-9 * h) return body_.model.u(static_cast<int>(std::lround(u_last / h)) + 1);
  return u_last + l;
}

void Feeder::boundary_vertices(double inserted, std::vector<double>& u) const {
  for (int guard = 0; guard < 64; ++guard) {
    const size_t n = u.size();
    const int change = boundary_change(inserted, u[n - 2], u[n - 1], n > 2);
    if (change > 0) {
      u.push_back(next_boundary_point(u[n - 2], u[n - 1]));
    } else if (change < 0) {
      u.pop_back();
    } else {
      return;
    }
  }
}

void Feeder::update_vertex_set(double new_inserted) {
  // The clamp's boundary stays at the entry: vertex first_clamped_ is the material point at the
  // entry (u = inserted), the next one a segment behind it, both held on the insertion line. The
  // last free edge (the boundary edge) has no rest length of its own: it stays within [ℓ/2, 3ℓ/2)
  // of the edge before it (ℓ: a segment unless adaptivity refined or coarsened it). When it would
  // pass 3ℓ/2 the next point of that edge's level is inserted on it (where that material lay at
  // the step's start), when it would fall below ℓ/2 its last free vertex is removed (the two
  // edges merged, their twist kept). The support of the free wire is then continuous in the
  // inserted length (a grid clamp vertex would jump back by a segment each time one is freed).
  const RodModel& model = body_.model;
  RodState& s = body_.state;
  const double h = model.h;
  const double L = s.inserted_length;
  const Vec3& pb = model.base_position;
  const Vec3& db = model.base_direction;
  const Vec3 v_entry = db * feed_speed_;  // the material's velocity at the entry
  const int nv_old = s.vertex_count();
  int kc = first_clamped_;
  auto at = [](auto& vec, int i) { return vec.begin() + i; };
  for (int guard = 0; guard < 1 << 20; ++guard) {
    const int change = boundary_change(new_inserted, s.u[kc - 2], s.u[kc - 1], kc >= 3);
    if (change < 0) {
      // Pulled back: the last free vertex leaves; the edge before it reaches the entry, keeping
      // its frame and angle; the boundary's reference twist keeps the sum of the two, so the
      // material twist is continuous.
      const int j = kc - 1;  // the vertex leaving, and the edge from it to the boundary
      s.ref_twist[kc] += s.ref_twist[j];
      s.u.erase(at(s.u, j));
      s.x.erase(at(s.x, j));
      s.v.erase(at(s.v, j));
      s.ref_twist.erase(at(s.ref_twist, j));
      s.theta.erase(at(s.theta, j));
      s.omega.erase(at(s.omega, j));
      s.frame.erase(at(s.frame, j));
      --kc;
    } else if (change > 0 && kc + 2 < model.grid_vertices) {
      // Fed: the new vertex on the wire's path at the step's start. Inside the entry it splits
      // the boundary edge (both halves keep its frame, angle and spin; velocity interpolated
      // between its neighbours' material velocities); behind it, the new edge to the boundary is
      // material the clamp held (its frame, angle and spin; the twist that was at the boundary
      // moves to the new vertex).
      const double u_last = s.u[kc - 1];
      const double u_new = next_boundary_point(s.u[kc - 2], u_last);
      const bool inside = u_new < L && L - u_last > 0.0;
      const int source = inside ? kc - 1 : kc;  // the edge the new edge copies
      Vec3 x_new = pb - db * (u_new - L), v_new = v_entry;
      if (inside) {
        // On the cubic Hermite curve from the last free vertex (its tangent the mean of its
        // edges') to the entry (the clamp's direction): a chord would put the vertex off the
        // bent wire by the edge's sagitta, and the step after would give that offset to its
        // velocity (a kick the next steps' guesses carry on).
        // (The boundary vertex is still at the entry here: the last free vertex's tangent is
        // the path's.)
        const double a = (u_new - u_last) / (L - u_last);
        const Vec3& x0 = s.x[kc - 1];
        x_new = detail::hermite(x0, path_tangent(s.x, kc - 1), pb, -db, (pb - x0).norm(), a);
        v_new = (1.0 - a) * s.v[kc - 1] + a * v_entry;
      }
      const double theta = s.theta[source], omega = s.omega[source];
      const EdgeFrame frame = s.frame[source];
      const double twist = inside ? 0.0 : s.ref_twist[kc];
      if (!inside) s.ref_twist[kc] = 0.0;
      s.u.insert(at(s.u, kc), u_new);
      s.x.insert(at(s.x, kc), x_new);
      s.v.insert(at(s.v, kc), v_new);
      s.ref_twist.insert(at(s.ref_twist, kc), twist);
      s.theta.insert(at(s.theta, kc), theta);
      s.omega.insert(at(s.omega, kc), omega);
      s.frame.insert(at(s.frame, kc), frame);
      ++kc;
    } else {
      break;
    }
  }
  // The boundary and the vertex behind it: the material at the new entry, where it lay at the
  // step's start (set_prescribed moves them to the step's end).
  s.u[kc] = new_inserted;
  s.u[kc + 1] = new_inserted + h;
  for (int k = kc; k < kc + 2; ++k) {
    s.x[k] = pb - db * (s.u[k] - L);
    s.v[k] = v_entry;
  }
  first_clamped_ = kc;
  if (s.vertex_count() != nv_old || new_inserted != L) body_.rediscretize();
}

void Feeder::set_prescribed(double inserted, double angle, std::vector<Vec3>& x, std::vector<double>& theta) const {
  const RodModel& model = body_.model;
  const Vec3& pb = model.base_position;
  const Vec3& db = model.base_direction;
  const int nv = static_cast<int>(x.size());
  for (int k = first_clamped_; k < nv; ++k) x[k] = pb - db * (body_.state.u[k] - inserted);
  // Clamped edges point from the tip side to the holder (−base_direction); the base angle
  // is right-handed about +base_direction, hence the sign.
  for (int j = first_clamped_; j < nv - 1; ++j) theta[j] = -angle;
  if (tip_clamped_) {
    x[0] = tip_clamp_x0_;
    x[1] = tip_clamp_x1_;
    theta[0] = tip_clamp_theta_;
  }
}

void Feeder::clamp_tip(const Vec3& tip, const Vec3& next) {
  if (first_clamped_ < 3) throw_usage_error("Feeder::clamp_tip: the wire is too short");
  if ((next - tip).norm() <= 0.0) throw_usage_error("Feeder::clamp_tip: tip and next coincide");
  tip_clamped_ = true;
  tip_clamp_x0_ = tip;
  tip_clamp_x1_ = next;
  tip_clamp_theta_ = body_.state.theta[0];
}

Vec3 Feeder::path_point(const WirePath& path, double sigma) const {
  const Vec3& pb = body_.model.base_position;
  const Vec3& db = body_.model.base_direction;
  if (sigma <= 0.0) return pb + db * sigma;  // the insertion line, behind the entry
  const auto& x = path.x;
  const auto& u = path.u;
  const int n = static_cast<int>(x.size());
  const double m = path.inserted - sigma;  // the material coordinate that lay there
  if (m >= u[n - 1]) return pb + db * sigma;
  auto tangent = [&](int k) {
    return path.tangent.empty() ? path_tangent(x, k) : path.tangent[static_cast<size_t>(k)];
  };
  const int j = std::clamp(static_cast<int>(std::upper_bound(u.begin(), u.end(), m) - u.begin()) - 1, 0, n - 2);
  const double chord = (x[j + 1] - x[j]).norm();
  const Vec3 t0 = tangent(j), t1 = tangent(j + 1);
  auto cubic = [&](double a) { return detail::hermite(x[j], t0, x[j + 1], t1, chord, a); };
  const double a = (m - u[j]) / (u[j + 1] - u[j]);
  if (a >= -1.0) return cubic(a);  // (past the tip: the first edge's cubic, up to one edge on)
  // Farther past the tip: straight on from there.
  const Vec3 end_tangent = 12.0 * (x[j] - x[j + 1]) + chord * (8.0 * t0 + 5.0 * t1);  // the cubic's slope at a = −1
  return cubic(-1.0) + (a + 1.0) * end_tangent;
}

void Feeder::predict_feed(double fed, double h, std::span<const Vec3> x0, std::span<const Vec3> v0) {
  // Initial Newton guess while feeding: each free vertex follows the wire — it moves to
  // where material u_k − fed lay at the step start (on the old polyline, on the insertion
  // line behind the entry, or past the tip along the tip edge) — plus its velocity across
  // the wire. The plain inertial guess x + h v can fold the wire at the entry when the feed
  // per step exceeds a segment. (On the polyline, not on predict_slide's cubic: at the start
  // of a feed a pre-shaped tip's hook, bent by half a radian a segment, would carry the
  // cubic's overshoot past its end; the first step of the J-tipped push of
  // CoSim.AnAdaptiveJTipWirePushedThroughTheArchStaysInside then fails at dt/8.)
  if (fed == 0.0) return;
  RodState& s = body_.state;
  const Vec3& pb = body_.model.base_position;
  const Vec3& db = body_.model.base_direction;
  const int nv = static_cast<int>(x0.size());
  const double L_old = s.inserted_length;
  const std::vector<double>& uk = s.u;
  int i = 0;  // old edge holding material u (u increases with k: a forward walk)
  for (int k = 0; k < first_clamped_; ++k) {
    const double u = uk[k] - fed;
    Vec3 p;
    if (u >= L_old) {
      p = pb + db * (L_old - u);
    } else if (u < 0.0) {
      p = x0[0] + (x0[0] - x0[1]) * (-u / (uk[1] - uk[0]));
    } else {
      while (i < nv - 2 && uk[i + 1] <= u) ++i;
      const double a = (u - uk[i]) / (uk[i + 1] - uk[i]);
      p = (1.0 - a) * x0[i] + a * x0[i + 1];
    }
    const Vec3 t = k + 1 < nv ? Vec3((x0[k + 1] - x0[k]).normalized()) : db;
    const Vec3 v = v0[k];
    s.x[k] = p + h * (v - t * t.dot(v));
  }
}

void Feeder::predict_slide(double inserted, const WirePath& now, const WirePath& before) {
  RodState& s = body_.state;
  const Discretization& d = body_.disc;
  // The tip: up to the last free vertex with a rest curvature (a pre-shaped tip), else the
  // tip vertex itself.
  double u_tip = s.u[0];
  for (int k = 1; k < first_clamped_; ++k)
    if (d.rest_kappa1[k] != 0.0 || d.rest_kappa2[k] != 0.0) u_tip = s.u[k];
  // Both paths' vertex tangents once, not two for each point asked for.
  Scratch& sc = *scratch_;
  WirePath paths[2] = {now, before};
  std::vector<Vec3>* tangents[2] = {&sc.tangent_now, &sc.tangent_before};
  for (int p = 0; p < 2; ++p) {
    tangents[p]->resize(paths[p].x.size());
    for (size_t k = 0; k < paths[p].x.size(); ++k) (*tangents[p])[k] = path_tangent(paths[p].x, static_cast<int>(k));
    paths[p].tangent = *tangents[p];
  }
  for (int k = 0; k < first_clamped_; ++k) {
    // C² smoothstep from the tip's own guess to the slide: a kink in the blend would bend or
    // stretch the stiff wire (a jump of 6 µm along one 1 mm edge is 50 N of stretching).
    const double t = std::clamp((s.u[k] - u_tip) / kSlideBlend, 0.0, 1.0);
    const double w = t * t * t * (10.0 - 15.0 * t + 6.0 * t * t);
    if (w == 0.0) continue;
    const double sigma = inserted - s.u[k];
    const Vec3 slid = 2.0 * path_point(paths[0], sigma) - path_point(paths[1], sigma);
    s.x[k] = w * slid + (1.0 - w) * s.x[k];
  }
}

double Feeder::feed_vertex_set(double dt) {
  RodState& s = body_.state;
  bool clamped = false;
  const double L_new = detail::clamp_inserted(s.inserted_length + feed_speed_ * dt, body_.model, clamped);
  if (clamped && feed_speed_ != 0.0) {
    warn(fmt::format("rod: inserted length held at {:.6g} m (wire end reached)", L_new));
    drive_.set_insertion_speed(0.0);
    feed_speed_ = 0.0;
  }
  s.base_angle = drive_.base_angle();
  update_vertex_set(L_new);
  return L_new;
}

void Feeder::vertex_params(int k, VertexParams& p) const {
  // A clamp vertex owns only the half cell on its free side: the wire behind it is
  // held rigid, so its bending and twisting act over h/2 (this keeps the clamp exactly at
  // the entry and the scheme second-order; a full cell would move the clamp back by h/2).
  const Discretization& d = body_.disc;
  double cell = 1.0;
  if (k == first_clamped_) cell = 0.5 * d.rest_length[k - 1] / d.cell_length[k];
  if (tip_clamped_ && k == 1) cell = 0.5;
  p.bend_stiffness1 = p.bend_stiffness2 = d.bend_stiffness[k];
  p.rest_kappa1 = cell * d.rest_kappa1[k];
  p.rest_kappa2 = cell * d.rest_kappa2[k];
  p.twist_stiffness = d.twist_stiffness[k];
  p.rest_twist = 0.0;
  p.voronoi_length = cell * d.cell_length[k];
}
}  // namespace flowire::rod
