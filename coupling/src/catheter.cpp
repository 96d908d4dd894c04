// The catheter over the wire: its tube rod and the penalty that keeps the wire in its lumen
// (catheter.hpp; derivation in docs/catheter.md).
#include "flowire/coupling/catheter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <Eigen/Dense>

namespace flowire::coupling {

rod::WireSpec catheter_rod_spec(const CatheterSpec& cat, const rod::WireSpec& wire) {
  rod::WireSpec s;
  s.length = cat.length;
  s.radius = cat.outer_radius;
  s.youngs_modulus = cat.youngs_modulus;
  s.poisson_ratio = cat.poisson_ratio;
  s.density = cat.density;
  s.segments = 0;
  s.segment_length = wire.segments > 0 ? wire.length / wire.segments : wire.segment_length;
  s.base_position = wire.base_position;
  s.base_direction = wire.base_direction;
  s.base_normal = wire.base_normal;
  s.inserted_length = cat.initial_length;
  s.tip.length = 0.0;  // one section over the whole tube (and contact.friction all along it)
  s.damping = wire.damping;
  s.mass_damping = wire.mass_damping;
  // The tube's section (thick-walled, exact).
  const double ro = cat.outer_radius, ri = cat.inner_radius, pi = std::numbers::pi;
  const double i4 = pi * (std::pow(ro, 4) - std::pow(ri, 4)) / 4.0;
  const double area = pi * (ro * ro - ri * ri);
  const double g = cat.youngs_modulus / (2.0 * (1.0 + cat.poisson_ratio));
  s.bending_stiffness = cat.youngs_modulus * i4;
  s.twist_stiffness = g * 2.0 * i4;
  s.stretch_stiffness = cat.youngs_modulus * area;
  s.mass_per_length = cat.density * area;
  return s;
}

std::vector<double> cell_weights(const rod::RodSimulator& r) {
  rod::RodView view;  // RodView::cell_weight reads only the rest lengths and the grid's segment length
  view.rest_lengths = r.discretization().rest_length;
  view.segment_length = r.model().h;
  std::vector<double> w(static_cast<size_t>(r.vertex_count()));
  for (int i = 0; i < r.vertex_count(); ++i) w[static_cast<size_t>(i)] = view.cell_weight(i);
  return w;
}

double tip_weight(double alpha, double* dw, double* d2w) {
  // The share of the vertex's cell (one edge, centred on it) inside the lumen, α + ½ for
  // α ∈ [−½, ½], smoothed by the quintic smoothstep so that w, w′ and w″ are continuous.
  const double t = std::clamp(alpha + 0.5, 0.0, 1.0);
  const bool ramp = t > 0.0 && t < 1.0;
  if (dw) *dw = ramp ? 30.0 * t * t * (1.0 - t) * (1.0 - t) : 0.0;
  if (d2w) *d2w = ramp ? 60.0 * t * (1.0 - t) * (1.0 - 2.0 * t) : 0.0;
  return t * t * t * (10.0 - 15.0 * t + 6.0 * t * t);
}

LumenPenalty lumen_penalty(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double c,
                           double k, bool open_before_a, double onset) {
  using M = Eigen::Matrix3d;
  LumenPenalty p;
  p.grad_x.setZero(), p.grad_a.setZero(), p.grad_b.setZero();
  p.hess_xx.setZero(), p.hess_aa.setZero(), p.hess_bb.setZero(), p.hess_ab.setZero();
  p.hess_xa.setZero(), p.hess_xb.setZero();
  const Eigen::Vector3d e = b - a;
  const double l2 = e.squaredNorm();
  const double raw = l2 > 0.0 ? (x - a).dot(e) / l2 : 0.0;
  const M I = M::Identity();
  // r = x − nearest point; R_y = ∂r/∂y; S_y = Σ_m n_m ∂²r_m/∂y² (symmetric).
  Eigen::Vector3d r;
  M rx = I, ra = M::Zero(), rb = M::Zero();
  Eigen::Vector3d da = Eigen::Vector3d::Zero(), db = Eigen::Vector3d::Zero();
  bool interior = false;
  if (raw <= 0.0 && !open_before_a) {
    p.alpha = 0.0, r = x - a, ra = -I;
  } else if (raw >= 1.0) {
    p.alpha = 1.0, r = x - b, rb = -I;
  } else {
    interior = true;
    p.alpha = raw;
    r = x - a - raw * e;
    rx = I - e * e.transpose() / l2;
    da = (-(e + (x - a)) + 2.0 * raw * e) / l2;  // ∂α/∂a
    db = ((x - a) - 2.0 * raw * e) / l2;         // ∂α/∂b
    ra = -(1.0 - raw) * I - e * da.transpose();
    rb = -raw * I - e * db.transpose();
  }
  const double d = r.norm();
  p.distance = d;
  double dphi = 0.0, d2phi = 0.0;
  const double phi = onset_quadratic(d - c, onset, &dphi, &d2phi);
  // The open tip end: the penalty weighted by the vertex's share inside the lumen, w(α),
  // which falls smoothly from 1 at half an edge inside the tip to 0 at half an edge beyond.
  double dw = 0.0, d2w = 0.0;
  const double w = open_before_a && interior ? tip_weight(p.alpha, &dw, &d2w) : 1.0;
  p.weight = w;
  if (!(phi > 0.0) || !(d > 0.0) || !(w > 0.0)) return p;
  const Eigen::Vector3d n = r / d;
  const double energy = k * phi;
  const M pn = I - n * n.transpose();
  auto block = [&](const M& R, const M& S, Eigen::Vector3d& grad, M& hess) {
    const Eigen::Vector3d rn = R.transpose() * n;
    grad = k * dphi * rn;
    hess = k * (d2phi * rn * rn.transpose() + dphi * (R.transpose() * pn * R / d + S));
  };
  const M sa = interior ? M(da * n.transpose() + n * da.transpose()) : M::Zero();
  const M sb = interior ? M(-(db * n.transpose() + n * db.transpose())) : M::Zero();
  block(rx, M::Zero(), p.grad_x, p.hess_xx);
  block(ra, sa, p.grad_a, p.hess_aa);
  block(rb, sb, p.grad_b, p.hess_bb);
  // ∂²r/∂a_i∂b_j · n = n_i ∂α/∂b_j − ∂α/∂a_i n_j (n ⊥ e).
  const M sab = interior ? M(n * db.transpose() - da * n.transpose()) : M::Zero();
  p.hess_ab = k * (d2phi * (ra.transpose() * n) * (rb.transpose() * n).transpose() +
                   dphi * (ra.transpose() * pn * rb / d + sab));
  // ∂²r/∂x_i∂a_j · n = n_j e_i/|e|² and ∂²r/∂x_i∂b_j · n = −n_j e_i/|e|² (interior; n ⊥ e).
  const M sxa = interior ? M(e * n.transpose() / l2) : M::Zero();
  const Eigen::Vector3d rxn = rx.transpose() * n;
  p.hess_xa = k * (d2phi * rxn * (ra.transpose() * n).transpose() + dphi * (rx.transpose() * pn * ra / d + sxa));
  p.hess_xb = k * (d2phi * rxn * (rb.transpose() * n).transpose() + dphi * (rx.transpose() * pn * rb / d - sxa));
  p.energy = energy;
  if (w < 1.0) {
    // E_w = w(α) E: ∂_y E_w = w ∂_y E + E w′ α_y,
    // ∂²_yz E_w = w ∂²_yz E + w′ (∂_y E α_zᵀ + α_y ∂_z Eᵀ) + E (w″ α_y α_zᵀ + w′ α_yz),
    // α_x = e/|e|², α_a = da, α_b = db, and the second derivatives of α = (x − a)·e/|e|²:
    // α_xx = 0, α_aa = 2 ((1 − α) I + e daᵀ + da eᵀ)/|e|², α_bb = −2 (α I + e dbᵀ + db eᵀ)/|e|²,
    // α_ab = ((2α − 1) I + 2 e dbᵀ − 2 da eᵀ)/|e|² (rows a, columns b).
    const Eigen::Vector3d ax = e / l2;
    const double al = p.alpha;
    const M aaa = 2.0 * ((1.0 - al) * I + e * da.transpose() + da * e.transpose()) / l2;
    const M abb = -2.0 * (al * I + e * db.transpose() + db * e.transpose()) / l2;
    const M aab = ((2.0 * al - 1.0) * I + 2.0 * e * db.transpose() - 2.0 * da * e.transpose()) / l2;
    auto hess = [&](const M& h, const Eigen::Vector3d& gy, const Eigen::Vector3d& gz, const Eigen::Vector3d& ay,
                    const Eigen::Vector3d& az, const M& ayz) {
      return M(w * h + dw * (gy * az.transpose() + ay * gz.transpose()) +
               energy * (d2w * ay * az.transpose() + dw * ayz));
    };
    p.hess_xx = hess(p.hess_xx, p.grad_x, p.grad_x, ax, ax, M::Zero());
    p.hess_aa = hess(p.hess_aa, p.grad_a, p.grad_a, da, da, aaa);
    p.hess_bb = hess(p.hess_bb, p.grad_b, p.grad_b, db, db, abb);
    p.hess_ab = hess(p.hess_ab, p.grad_a, p.grad_b, da, db, aab);
    // α_xa = (−I + 2 e eᵀ/|e|²)/|e|², α_xb = −α_xa.
    const M axa = (-I + 2.0 * e * e.transpose() / l2) / l2;
    p.hess_xa = hess(p.hess_xa, p.grad_x, p.grad_a, ax, da, axa);
    p.hess_xb = hess(p.hess_xb, p.grad_x, p.grad_b, ax, db, M(-axa));
    p.grad_x = w * p.grad_x + energy * dw * ax;
    p.grad_a = w * p.grad_a + energy * dw * da;
    p.grad_b = w * p.grad_b + energy * dw * db;
    p.energy = w * energy;
  }
  return p;
}

namespace {
/// The reaction −f of a vertex's friction f (at relative velocity v_vertex − v_point) on the
/// point (1 − α) x_j + α x_{j+1} of an edge, split between its ends, with the incremental
/// potential Δt·D and its Jacobian: v_point enters v with −1, so ∂F_j/∂v_j = (1 − α)² ∂f/∂v,
/// ∂F_j/∂v_{j+1} = (1 − α) α ∂f/∂v, ∂F_{j+1}/∂v_{j+1} = α² ∂f/∂v, entered as the edge's position
/// Jacobian over Δt (the rod's ∂v/∂x).
void add_edge_point_friction(rod::ForceAccumulator& out, int j, double alpha, const FrictionResult& fr, double dt) {
  const double w0 = 1.0 - alpha, w1 = alpha;
  out.add_conservative_force(j, -w0 * fr.force);
  out.add_conservative_force(j + 1, -w1 * fr.force);
  out.add_energy(dt * fr.dissipation);
  Eigen::Matrix<double, 6, 6> jac;
  jac << w0 * w0 * fr.dfdv, w0 * w1 * fr.dfdv, w0 * w1 * fr.dfdv, w1 * w1 * fr.dfdv;
  out.add_edge_jacobian(j, jac / dt);
}
}  // namespace

int LumenContact::nearest_edge(const Eigen::Vector3d& x, double s, const std::vector<Eigen::Vector3d>& cath,
                               const std::vector<double>& arc) const {
  const int nv = static_cast<int>(cath.size());
  if (nv < 2 || !(s > 0.0)) return -1;
  // Both rods enter at the same point, so inside the lumen a wire vertex lies near the
  // catheter vertices of about its own arc length: search a window around it.
  const double window = 4.0 * std::abs(arc.front() - arc[1]) + 2.0 * clearance_ + 1e-9;
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (int j = 0; j + 1 < nv; ++j) {
    if (arc[j] < s - window || arc[j + 1] > s + window) continue;
    const Eigen::Vector3d e = cath[j + 1] - cath[j];
    const double l2 = e.squaredNorm();
    const double t = l2 > 0.0 ? std::clamp((x - cath[j]).dot(e) / l2, 0.0, 1.0) : 0.0;
    const double d = (x - cath[j] - t * e).squaredNorm();
    if (d < best_d) best_d = d, best = j;
  }
  if (best == 0) {  // more than half an edge beyond the catheter's tip: out of the lumen
    const Eigen::Vector3d e = cath[1] - cath[0];
    if ((x - cath[0]).dot(e) < -0.5 * e.squaredNorm()) return -1;
  }
  return best;
}

void LumenContact::evaluate_wire(const rod::RodView& rod, rod::ForceAccumulator& out) const {
  for (int i = 0; i < rod.first_clamped_vertex; ++i) {
    const int j = i < static_cast<int>(wire_edge.size())
                      ? wire_edge[static_cast<size_t>(i)]
                      : nearest_edge(rod.position(i), rod.arc_length[i], catheter_snapshot, catheter_arc);
    if (j < 0 || j + 1 >= static_cast<int>(catheter_snapshot.size())) continue;
    const double k = stiffness_ * rod.cell_weight(i);
    const LumenPenalty p =
        lumen_penalty(rod.position(i), catheter_snapshot[j], catheter_snapshot[j + 1], clearance_, k, j == 0, onset_);
    if (!(p.energy > 0.0)) continue;
    out.add_conservative_force(i, -p.grad_x);
    out.add_energy(p.energy);
    out.add_position_jacobian(i, -p.hess_xx);
  }
  if (!(friction_ > 0.0) || !(rod.dt > 0.0)) return;
  // With N, the normal and the other rod held, f = −∇_v D(v) and v = (x − x₀)/Δt − v_other: the
  // gradient in x of Δt·D, reported as a potential for the line search (as on the walls).
  for (int i = 0; i < rod.first_clamped_vertex && i < static_cast<int>(friction_contact.size()); ++i) {
    const FrictionContact& fc = friction_contact[static_cast<size_t>(i)];
    if (fc.edge < 0 || static_cast<size_t>(fc.edge) + 1 >= catheter_velocity.size()) continue;
    const auto j = static_cast<size_t>(fc.edge);
    const FrictionResult fr = friction_at(fc, rod.velocity(i), catheter_velocity[j], catheter_velocity[j + 1]);
    out.add_conservative_force(i, fr.force);
    out.add_energy(rod.dt * fr.dissipation);
    out.add_velocity_jacobian(i, fr.dfdv);
  }
}

FrictionResult LumenContact::friction_at(const FrictionContact& fc, const Eigen::Vector3d& vp,
                                         const Eigen::Vector3d& va, const Eigen::Vector3d& vb) const {
  if (fc.edge < 0 || !(fc.normal > 0.0)) return FrictionResult{};
  const Eigen::Vector3d v_edge = (1.0 - fc.alpha) * va + fc.alpha * vb;
  return coulomb_friction(vp - v_edge, fc.direction, fc.normal, friction_, slip_speed_);
}

void LumenContact::lag_friction() {
  friction_contact.assign(wire_snapshot.size(), FrictionContact{});
  if (!(friction_ > 0.0)) return;
  // N = |∂E/∂x| of the penalty at the held states, the normal along x − (the edge's point).
  for (size_t i = 0; i < wire_snapshot.size() && i < wire_edge.size(); ++i) {
    const int j = wire_edge[i];
    if (j < 0 || j + 1 >= static_cast<int>(catheter_snapshot.size())) continue;
    const Eigen::Vector3d& x = wire_snapshot[i];
    const Eigen::Vector3d& a = catheter_snapshot[static_cast<size_t>(j)];
    const Eigen::Vector3d& b = catheter_snapshot[static_cast<size_t>(j) + 1];
    const LumenPenalty p = lumen_penalty(x, a, b, clearance_, stiffness_ * weight(i), j == 0, onset_);
    const Eigen::Vector3d r = x - (a + p.alpha * (b - a));
    if (!(p.energy > 0.0) || !(r.norm() > 0.0)) continue;
    FrictionContact& fc = friction_contact[i];
    fc.edge = j;
    fc.alpha = std::clamp(p.alpha, 0.0, 1.0);
    fc.normal = p.grad_x.norm();
    fc.direction = r.normalized();
  }
}

void LumenContact::evaluate_catheter(const rod::RodView& rod, rod::ForceAccumulator& out) const {
  const std::vector<Eigen::Vector3d> cath(rod.positions.begin(), rod.positions.end());
  const std::vector<double> arc(rod.arc_length.begin(), rod.arc_length.end());
  for (size_t i = 0; i < wire_snapshot.size(); ++i) {
    const int j = i < wire_edge.size() ? wire_edge[i] : nearest_edge(wire_snapshot[i], wire_arc[i], cath, arc);
    if (j < 0 || j + 1 >= static_cast<int>(cath.size())) continue;
    const LumenPenalty p =
        lumen_penalty(wire_snapshot[i], cath[j], cath[j + 1], clearance_, stiffness_ * weight(i), j == 0, onset_);
    if (!(p.energy > 0.0)) continue;
    out.add_conservative_force(j, -p.grad_a);
    out.add_conservative_force(j + 1, -p.grad_b);
    if (catheter_reports_energy) out.add_energy(p.energy);
    Eigen::Matrix<double, 6, 6> hess;
    hess << p.hess_aa, p.hess_ab, p.hess_ab.transpose(), p.hess_bb;
    out.add_edge_jacobian(j, -hess);
  }
  if (!(friction_ > 0.0) || !(rod.dt > 0.0)) return;
  for (size_t i = 0; i < friction_contact.size() && i < wire_velocity.size(); ++i) {
    const FrictionContact& fc = friction_contact[i];
    if (fc.edge < 0 || fc.edge + 1 >= rod.vertex_count()) continue;
    FrictionResult fr = friction_at(fc, wire_velocity[i], rod.velocity(fc.edge), rod.velocity(fc.edge + 1));
    if (!catheter_reports_energy) fr.dissipation = 0.0;
    add_edge_point_friction(out, fc.edge, fc.alpha, fr, rod.dt);
  }
}

double LumenContact::energy() const {
  double e = 0.0;
  for (size_t i = 0; i < wire_snapshot.size(); ++i) {
    const int j = i < wire_edge.size() ? wire_edge[i] : -1;
    if (j >= 0 && j + 1 < static_cast<int>(catheter_snapshot.size()))
      e += lumen_penalty(wire_snapshot[i], catheter_snapshot[j], catheter_snapshot[j + 1], clearance_,
                         stiffness_ * weight(i), j == 0, onset_)
               .energy;
  }
  return e;
}

void LumenContact::assign_edges() {
  wire_edge.assign(wire_snapshot.size(), -1);
  for (size_t i = 0; i < wire_snapshot.size() && i < wire_arc.size(); ++i)
    wire_edge[i] = nearest_edge(wire_snapshot[i], wire_arc[i], catheter_snapshot, catheter_arc);
}

std::vector<char> LumenContact::inside() const {
  std::vector<char> in(wire_snapshot.size(), 0);
  if (catheter_snapshot.size() < 2) return in;
  const Eigen::Vector3d& a0 = catheter_snapshot[0];
  const Eigen::Vector3d into = catheter_snapshot[1] - a0;
  for (size_t i = 0; i < in.size() && i < wire_edge.size(); ++i)
    in[i] = wire_edge[i] > 0 || (wire_edge[i] == 0 && (wire_snapshot[i] - a0).dot(into) >= 0.0);
  return in;
}

void LumenContact::hold_catheter(const rod::RodSimulator& catheter) {
  catheter_snapshot.assign(catheter.positions().begin(), catheter.positions().end());
  catheter_velocity.assign(catheter.velocities().begin(), catheter.velocities().end());
  catheter_arc.assign(catheter.arc_lengths().begin(), catheter.arc_lengths().end());
  assign_edges();
}

void LumenContact::hold_wire(const rod::RodSimulator& wire) {
  wire_snapshot.assign(wire.positions().begin(), wire.positions().end());
  wire_velocity.assign(wire.velocities().begin(), wire.velocities().end());
  wire_arc.assign(wire.arc_lengths().begin(), wire.arc_lengths().end());
  wire_weight = cell_weights(wire);
  assign_edges();
}

PairStaticReport solve_static_pair(rod::RodSimulator& wire, rod::RodSimulator& catheter, LumenContact& contact,
                                   int max_sweeps, double tol) {
  // Fixed point c = H(c): the catheter after solving the wire against c and the catheter
  // against that wire. IQN-ILS: with the differences V of residuals r = H(c) − c and W of
  // H(c) over the sweeps so far, c ← H(c) + W γ, γ = argmin |V γ + r|.
  PairStaticReport rep;
  auto flat = [](const std::vector<Eigen::Vector3d>& v) {
    Eigen::VectorXd f(3 * static_cast<Eigen::Index>(v.size()));
    for (size_t i = 0; i < v.size(); ++i) f.segment<3>(3 * static_cast<Eigen::Index>(i)) = v[i];
    return f;
  };
  contact.hold_catheter(catheter);
  Eigen::VectorXd c = flat(contact.catheter_snapshot);
  std::vector<Eigen::VectorXd> rs, hs;
  for (rep.sweeps = 1; rep.sweeps <= max_sweeps; ++rep.sweeps) {
    (void)wire.solve_static();
    contact.hold_wire(wire);
    (void)catheter.solve_static();
    const Eigen::VectorXd h =
        flat(std::vector<Eigen::Vector3d>(catheter.positions().begin(), catheter.positions().end()));
    if (h.size() != c.size()) {  // the vertex set changed: restart the history
      rs.clear(), hs.clear();
      c = h;
    }
    const Eigen::VectorXd r = h - c;
    rep.correction = r.size() ? r.cwiseAbs().maxCoeff() : 0.0;
    // Converged when both rods balance together: the catheter was just solved against this
    // wire, and the wire must balance against the catheter as it now is. A small change of
    // the catheter alone says nothing: under a stiff lumen penalty a sweep moves it by little
    // however far the pair is from equilibrium (the wire bent alone, pressing on the lumen).
    contact.hold_catheter(catheter);
    rep.imbalance = wire.static_imbalance();
    if (rep.correction < tol && rep.imbalance <= 1.0) {
      rep.converged = true;
      break;
    }
    Eigen::VectorXd next = h;
    if (!rs.empty()) {
      const Eigen::Index m = static_cast<Eigen::Index>(rs.size());
      Eigen::MatrixXd V(r.size(), m), W(r.size(), m);
      for (Eigen::Index q = 0; q < m; ++q) V.col(q) = r - rs[q], W.col(q) = h - hs[q];
      const Eigen::VectorXd gamma = V.colPivHouseholderQr().solve(-r);
      next = h + W * gamma;
    }
    rs.push_back(r), hs.push_back(h);
    if (rs.size() > 20) rs.erase(rs.begin()), hs.erase(hs.begin());
    c = next;
    for (size_t i = 0; i < contact.catheter_snapshot.size(); ++i)
      contact.catheter_snapshot[i] = c.segment<3>(3 * static_cast<Eigen::Index>(i));
    contact.assign_edges();
  }
  if (rep.sweeps > max_sweeps) rep.sweeps = max_sweeps;
  contact.hold_catheter(catheter);
  return rep;
}

PairStepReport step_pair(rod::RodSimulator& wire, rod::RodSimulator& catheter, LumenContact& contact, double dt,
                         int max_sweeps) {
  PairStepReport rep;
  const bool iterate = wire.settings().integrator == rod::Integrator::ImplicitEuler && max_sweeps > 1;
  // Friction in the lumen takes the normal forces of the step's start, the same in every sweep.
  contact.lag_friction();
  if (iterate) wire.save_checkpoint(), catheter.save_checkpoint();
  auto flat = [](std::span<const Eigen::Vector3d> v) {
    Eigen::VectorXd f(3 * static_cast<Eigen::Index>(v.size()));
    for (size_t i = 0; i < v.size(); ++i) f.segment<3>(3 * static_cast<Eigen::Index>(i)) = v[i];
    return f;
  };
  // The columns of the least-squares update come from this step's sweeps only: columns kept
  // from earlier steps (IQN-ILS "with reuse") sent the pair far off whenever the contact set
  // changed between steps.
  Eigen::VectorXd c = flat(contact.catheter_snapshot);
  std::vector<Eigen::VectorXd> rs, hs;
  double best_imbalance = std::numeric_limits<double>::infinity();
  int best_sweep = 0;
  for (rep.sweeps = 1;; ++rep.sweeps) {
    rep.wire = wire.step(dt);
    contact.hold_wire(wire);
    rep.catheter = catheter.step(dt);
    contact.hold_catheter(catheter);
    if (!iterate || !rep.wire.converged() || !rep.catheter.converged()) break;
    rep.imbalance = wire.step_imbalance();
    if (rep.imbalance * wire.settings().force_tolerance <= kPairForceTolerance) {
      rep.converged = true;
      break;
    }
    // Stop where the sweeps stop gaining (the imbalance not halved in three sweeps): the contact
    // set changing between sweeps (a wire sliding out of the catheter's tip, friction turning
    // from stick to slip) leaves the fixed point no smooth map to converge on, and more sweeps
    // only cost.
    if (rep.imbalance < 0.5 * best_imbalance) best_imbalance = rep.imbalance, best_sweep = rep.sweeps;
    if (rep.sweeps >= max_sweeps || rep.sweeps - best_sweep >= 3) break;
    const Eigen::VectorXd h = flat(catheter.positions());
    if (h.size() != c.size()) rs.clear(), hs.clear(), c = h;  // the catheter's vertex set changed
    const Eigen::VectorXd r = h - c;
    Eigen::VectorXd next = h;
    if (!rs.empty()) {
      const Eigen::Index m = static_cast<Eigen::Index>(rs.size());
      Eigen::MatrixXd V(r.size(), m), W(r.size(), m);
      for (Eigen::Index q = 0; q < m; ++q)
        V.col(q) = r - rs[static_cast<size_t>(q)], W.col(q) = h - hs[static_cast<size_t>(q)];
      // The least-squares correction, each vertex's part held within the lumen's clearance:
      // an estimate farther off than the wire can be from the catheter is no estimate, and it
      // pushed the wire through the vessel wall on the first step of a pair laid in an arch.
      Eigen::VectorXd dc = W * V.colPivHouseholderQr().solve(-r);
      for (Eigen::Index k = 0; k + 2 < dc.size(); k += 3)
        if (const double n = dc.segment<3>(k).norm(); n > contact.clearance())
          dc.segment<3>(k) *= contact.clearance() / n;
      next = h + dc;
    }
    rs.push_back(r), hs.push_back(h);
    if (rs.size() > 20) rs.erase(rs.begin()), hs.erase(hs.begin());
    c = next;
    // Both again from the step's start, the wire against the new estimate of the catheter.
    wire.restore_checkpoint(true), catheter.restore_checkpoint(true);
    for (size_t i = 0; i < contact.catheter_snapshot.size(); ++i)
      contact.catheter_snapshot[i] = c.segment<3>(3 * static_cast<Eigen::Index>(i));
    contact.assign_edges();
  }
  if (!iterate) rep.converged = rep.wire.converged() && rep.catheter.converged();
  return rep;
}

}  // namespace flowire::coupling
