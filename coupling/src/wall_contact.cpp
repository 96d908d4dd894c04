#include "flowire/coupling/wall_contact.hpp"

#include <algorithm>
#include <vector>

namespace flowire::coupling {

void WallContact::set_introducer(const Vec3& p, const Vec3& t, double reach) {
  intro_point_ = p;
  intro_dir_ = t.normalized();
  intro_reach_ = reach;
}

void WallContact::ensure_size(int n) {
  if (static_cast<int>(normal_force_.size()) >= n) return;
  normal_force_.resize(static_cast<size_t>(n), 0.0);
  normal_.resize(static_cast<size_t>(n), Vec3::UnitX());
  lag_normal_force_.resize(static_cast<size_t>(n), 0.0);
  lag_normal_.resize(static_cast<size_t>(n), Vec3::UnitX());
  intro_force_.resize(static_cast<size_t>(n), Vec3::Zero());
}

double WallContact::normal_force_at(double d, double a, double cell_weight) const {
  double d1 = 0.0;
  (void)onset_quadratic(d + a, params_.onset, &d1);
  return params_.stiffness * cell_weight * d1;
}

void WallContact::evaluate(const rod::RodView& rod, int free, Wall& wall, rod::ForceAccumulator& out,
                           std::span<Vec3> tally, InteractionStats& stats) {
  ensure_size(rod.vertex_count());
  wall.ensure_size(rod.vertex_count());
  energy_ = 0.0;
  // Anchoring measures every free vertex's wall (Hessian included): this evaluation reads the
  // candidates' from it, and the others are out of the contact's reach.
  bool anchored_now = false;
  if (deformable_) {
    if (anchors_stale_ || static_cast<int>(candidate_of_.size()) != rod.vertex_count()) {
      anchor_candidates(rod, free, wall);
      anchored_now = true;
    } else {
      for (auto& c : candidates_) c.penetration = -1.0;
    }
  }
  for (int i = 0; i < free; ++i) {
    const auto k = static_cast<size_t>(i);
    normal_force_[k] = 0.0;
    intro_force_[k].setZero();
    const Vec3& x = rod.position(i);
    const double a = rod.vertex_radius(i, wire_radius_);
    // Stiffness per vertex of the feeding grid, scaled with the vertex's edges where the
    // rod is resampled (so the wall stays equally stiff per unit length).
    const double k_wall = params_.stiffness * rod.cell_weight(i);
    if (intro_reach_ > 0.0) {
      // The introducer: no way back out behind the entry plane near the entry axis.
      const Vec3 r = x - intro_point_;
      const double along = r.dot(intro_dir_);
      if ((r - along * intro_dir_).norm() < intro_reach_) {
        // The plane lies one wire radius behind the entry, so that vertices fed in at the
        // entry itself are free: δ = −along − a + a > 0 once a vertex is behind it.
        const auto pen = wall_penalty(-along - 2.0 * a, -intro_dir_, Mat3::Zero(), a, k_wall, params_.onset);
        if (pen.energy > 0.0) {
          ++intro_contacts_;
          out.add_conservative_force(i, -pen.gradient);
          out.add_energy(pen.energy);
          out.add_position_jacobian(i, -pen.hessian);
          tally[k] -= pen.gradient;
          intro_force_[k] = -pen.gradient;
        }
      }
    }
    ++stats.wall_queries;
    if (anchored_now) continue;
    double d = 0.0;
    Vec3 n_wall;
    Mat3 H_wall;  // exact, blends included: Newton stays quadratic near junctions and bends
    if (!wall.at(i, x, a, 0.5 * params_.onset, &d, &n_wall, &H_wall)) continue;
    if (deformable_ && candidate_of_[k] >= 0) {  // solved with the others below
      Candidate& c = candidates_[static_cast<size_t>(candidate_of_[k])];
      c.penetration = d + a;
      c.normal = n_wall;
      c.hessian = H_wall;
      c.stiffness = k_wall;
      continue;
    }
    const auto pen = wall_penalty(d, n_wall, H_wall, a, k_wall, params_.onset);
    if (!(pen.energy > 0.0)) continue;
    if (deformable_) anchors_stale_ = true;  // a contact outside the candidates
    ++stats.contacts;
    // The penalty has a potential (k φ(δ)): reported, the rod's line search measures the
    // contact exactly instead of by the work along its search ray.
    const Vec3 f = -pen.gradient;
    out.add_conservative_force(i, f);
    out.add_energy(pen.energy);
    energy_ += pen.energy;
    out.add_position_jacobian(i, -pen.hessian);
    record_normal(pen.normal_force, n_wall, normal_force_[k], normal_[k]);
    tally[k] += f;
  }
  if (deformable_) solve_compliant(out, tally, stats);
}

void WallContact::anchor_candidates(const rod::RodView& rod, int free, Wall& wall) {
  anchors_stale_ = false;
  candidate_of_.assign(static_cast<size_t>(rod.vertex_count()), -1);
  candidates_.clear();
  std::vector<Vec3> points, normals;
  std::vector<double> radii;
  // Within reach: four wire radii, the wall's largest displacement at a contact so far twice, and 1 mm of
  // motion within the step (a vertex that comes into contact from farther during a solve
  // meets the rest wall there, and the candidates are anchored again at the next evaluation).
  const double reach = 4.0 * wire_radius_ + 2.0 * max_shift_ + 1e-3;
  for (int i = 0; i < free; ++i) {
    const double a = rod.vertex_radius(i, wire_radius_);
    double d = 0.0;
    Vec3 n;
    Mat3 h;
    if (!wall.at(i, rod.position(i), a, reach, &d, &n, &h) || d + a < -reach) continue;
    candidate_of_[static_cast<size_t>(i)] = static_cast<int>(candidates_.size());
    candidates_.push_back({i, d + a, n, h, params_.stiffness * rod.cell_weight(i)});
    points.push_back(rod.position(i) - d * n);  // the rest wall's closest point
    normals.push_back(n);
    radii.push_back(a);  // the wire presses on the wall over its own width
  }
  anchored_ = deformable_->anchor(this, points, normals, radii);
  active_.clear();
  lambda_.setZero(static_cast<Eigen::Index>(candidates_.size()));
  wall_shift_.setZero(static_cast<Eigen::Index>(candidates_.size()));
}

void WallContact::solve_compliant(rod::ForceAccumulator& out, std::span<Vec3> tally, InteractionStats& stats) {
  const auto m = static_cast<Eigen::Index>(candidates_.size());
  lambda_.setZero(m);
  wall_shift_.setZero(m);
  if (m == 0) return;
  const Eigen::MatrixXd& c = anchored_.compliance;
  // The wall's normal displacement before this body's contact forces (the blood pressure's and
  // the other bodies' last forces'), o: the contacts meet the wall there, their penetration δ − o.
  const Eigen::VectorXd& o = anchored_.offsets;
  auto gap = [&](Eigen::Index j) {
    return candidates_[static_cast<size_t>(j)].penetration - (o.size() == m ? o[j] : 0.0);
  };
  // λ = k·max(0, δ − o − C λ): an LCP with the P-matrix K⁻¹ + C, whose solution is unique; active
  // sets from the last evaluation's contacts (at an anchoring, those pressed into the pressed-out
  // rest wall), dropping negative forces and adding the contacts the wall's motion still leaves
  // penetrated, until none changes.
  std::vector<char>& active = active_;
  if (static_cast<Eigen::Index>(active.size()) != m) {
    active.assign(static_cast<size_t>(m), 0);
    for (Eigen::Index j = 0; j < m; ++j) active[static_cast<size_t>(j)] = gap(j) > 0.0;
  }
  std::vector<Eigen::Index> idx;
  Eigen::MatrixXd a;
  Eigen::LLT<Eigen::MatrixXd> llt;
  for (Eigen::Index pass = 0; pass < 2 * m + 2; ++pass) {
    idx.clear();
    for (Eigen::Index j = 0; j < m; ++j)
      if (active[static_cast<size_t>(j)]) idx.push_back(j);
    const auto na = static_cast<Eigen::Index>(idx.size());
    lambda_.setZero();
    if (na > 0) {
      a = c(idx, idx);
      Eigen::VectorXd b(na);
      for (Eigen::Index r = 0; r < na; ++r) {
        const Candidate& cr = candidates_[static_cast<size_t>(idx[static_cast<size_t>(r)])];
        a(r, r) += 1.0 / cr.stiffness;
        b[r] = gap(idx[static_cast<size_t>(r)]);
      }
      llt.compute(a);
      const Eigen::VectorXd l = llt.solve(b);
      for (Eigen::Index r = 0; r < na; ++r) lambda_[idx[static_cast<size_t>(r)]] = l[r];
    }
    bool changed = false;
    for (Eigen::Index j : idx)
      if (lambda_[j] < 0.0) active[static_cast<size_t>(j)] = 0, changed = true;
    if (!changed) {
      wall_shift_ = c * lambda_;
      for (Eigen::Index j = 0; j < m; ++j)
        if (!active[static_cast<size_t>(j)] && gap(j) - wall_shift_[j] > 0.0)
          active[static_cast<size_t>(j)] = 1, changed = true;
    }
    if (!changed) break;
  }
  lambda_ = lambda_.cwiseMax(0.0);
  for (Eigen::Index j = 0; j < m; ++j) active[static_cast<size_t>(j)] = lambda_[j] > 0.0;
  wall_shift_ = c * lambda_;
  if (o.size() == m) wall_shift_ += o;  // the wall's whole normal displacement there
  idx.clear();
  for (Eigen::Index j = 0; j < m; ++j)
    if (lambda_[j] > 0.0) idx.push_back(j);
  const auto na = static_cast<Eigen::Index>(idx.size());
  if (na == 0) return;
  // The contacts' stiffness S = (K⁻¹ + C)⁻¹ on the active set: its diagonal in the band, the
  // rest coupled (a low-rank term for the rod's Newton).
  a = c(idx, idx);
  double energy = 0.0;
  for (Eigen::Index r = 0; r < na; ++r)
    a(r, r) += 1.0 / candidates_[static_cast<size_t>(idx[static_cast<size_t>(r)])].stiffness;
  const Eigen::MatrixXd s = a.llt().solve(Eigen::MatrixXd::Identity(na, na));
  std::vector<int> vertices;
  std::vector<Vec3> directions;
  for (Eigen::Index r = 0; r < na; ++r) {
    const Eigen::Index j = idx[static_cast<size_t>(r)];
    const Candidate& cj = candidates_[static_cast<size_t>(j)];
    const double l = lambda_[j];
    const auto k = static_cast<size_t>(cj.vertex);
    energy += 0.5 * l * gap(j);  // ½ λᵀ(K⁻¹ + C)λ = ½ λ·(δ − o)
    const Vec3 f = -l * cj.normal;
    out.add_conservative_force(cj.vertex, f);
    out.add_position_jacobian(cj.vertex, -(s(r, r) * cj.normal * cj.normal.transpose() + l * cj.hessian));
    record_normal(l, cj.normal, normal_force_[k], normal_[k]);
    tally[k] += f;
    ++stats.contacts;
    vertices.push_back(cj.vertex);
    directions.push_back(cj.normal);
  }
  out.add_energy(energy);
  energy_ += energy;
  if (na > 1) {
    Eigen::MatrixXd off = s;
    off.diagonal().setZero();
    out.add_coupled_stiffness(vertices, directions, off);
  }
}

void WallContact::record_normal(double multiplier, const Vec3& grad, double& force, Vec3& normal) {
  const double length = grad.norm();
  force = multiplier * length;
  normal = length > 0.0 ? Vec3(grad / length) : grad;
}

void WallContact::end_step(const rod::RodView& rod, Wall& wall, InteractionStats& stats, std::span<const Vec3> tally) {
  const int n = rod.vertex_count();
  const int free = std::min(rod.first_clamped_vertex, n);
  ensure_size(n);
  wall.ensure_size(n);
  lagged_ = params_.enabled;
  for (int i = 0; i < n; ++i) lag_normal_force_[static_cast<size_t>(i)] = 0.0;
  std::vector<Vec3> wall_points, wall_forces;
  std::vector<double> wall_radii;
  for (int i = 0; i < free; ++i) {
    const auto k = static_cast<size_t>(i);
    const double a = rod.vertex_radius(i, wire_radius_);
    const double s = rod.arc_length.empty() ? std::numeric_limits<double>::infinity() : rod.arc_length[k];
    AcceptedWall w;
    if (!wall.accepted(i, rod.position(i), a, 0.5 * params_.onset, s, &w)) continue;
    // Against a deformable wall a candidate's force and distance are those of the wall where
    // it has moved (its normal displacement C λ), not of the rest wall.
    const int j = deformable_ && k < candidate_of_.size() ? candidate_of_[k] : -1;
    const double shift = j >= 0 && j < wall_shift_.size() ? wall_shift_[j] : 0.0;
    const double fn =
        j >= 0 ? (j < lambda_.size() ? lambda_[j] : 0.0) : normal_force_at(w.contact_distance, a, rod.cell_weight(i));
    if (fn > 0.0) record_normal(fn, w.normal, lag_normal_force_[k], lag_normal_[k]);
    if (deformable_ && k < tally.size() && (tally[k] - intro_force_[k]).squaredNorm() > 0.0) {
      wall_points.push_back(rod.position(i) - w.contact_distance * w.normal);
      wall_forces.push_back(-(tally[k] - intro_force_[k]));  // the wall's share, opposite
      wall_radii.push_back(a);
    }
    if (!w.measured) continue;
    const double d = w.distance - shift;
    stats.max_outside = std::max(stats.max_outside, d);
    if (d > a && stats.outside_time < 0.0) {
      stats.outside_time = rod.time;
      stats.outside_arc_length = rod.arc_length.empty() ? 0.0 : rod.arc_length[k];
      stats.outside_distance = d;
      stats.outside_position = rod.position(i);
    }
    stats.max_penetration = std::max(stats.max_penetration, d + a);
  }
  if (deformable_) {
    if (wall_shift_.size() > 0) max_shift_ = std::max(max_shift_, wall_shift_.maxCoeff());
    deformable_->load(this, wall_points, wall_forces, wall_radii);
    anchors_stale_ = true;
  }
}

}  // namespace flowire::coupling
