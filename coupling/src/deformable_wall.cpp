// The wall around a network's lumen, or around an image's lumen surface, as an elastic solid:
// meshed by solid::mesh_network_wall or solid::mesh_surface_wall,
// ends held, supported outside, linearized at rest; the step's contacts anchored on its lumen
// and their compliance condensed; loaded at the end of a step.
#include "flowire/coupling/deformable_wall.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/mesh/vtu.hpp"
#include "flowire/solid/elastic_solid.hpp"
#include "flowire/solid/lumen_compliance.hpp"
#include "flowire/solid/surface_wall.hpp"
#include "flowire/solid/tube_wall.hpp"

namespace flowire::coupling {
namespace {
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// The segment of @p net nearest to @p x (by its axis), the parameter t ∈ [0, 1] of the nearest
/// axis point along it, and x less that point.
struct NearestSegment {
  int segment = 0;
  double t = 0.0;
  Vec3 offset = Vec3::Zero();
};
NearestSegment nearest_segment(const vessels::Network& net, const Vec3& x) {
  NearestSegment best;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < net.num_segments(); ++k) {
    const auto& seg = net.segment(k);
    const Vec3 a = net.node(seg.node_from), ab = net.node(seg.node_to) - a;
    const double t = std::clamp((x - a).dot(ab) / std::max(ab.squaredNorm(), 1e-300), 0.0, 1.0);
    const Vec3 r = x - a - t * ab;
    if (r.squaredNorm() < best_d2) best_d2 = r.squaredNorm(), best = {k, t, r};
  }
  return best;
}
}  // namespace

DeformableWall::DeformableWall(const vessels::Network& net, const WallSpec& spec, const vessels::LumenSurface* surface)
    : net_(net) {
  const auto t0 = Clock::now();
  const solid::NeoHookean law = solid::NeoHookean::from_young_poisson(spec.youngs_modulus, spec.poisson_ratio,
                                                                      "wall.youngs_modulus / wall.poisson_ratio");
  if (!(spec.thickness > 0.0) && !(spec.thickness_ratio > 0.0))
    throw_usage_error(fmt::format("wall.thickness: must be > 0, got {} m", spec.thickness));
  if (!(spec.mesh_size > 0.0) && !surface)
    throw_usage_error(fmt::format("wall.mesh_size: must be > 0, got {} m", spec.mesh_size));
  if (!(spec.support >= 0.0)) throw_usage_error(fmt::format("wall.support: must be >= 0, got {} Pa/m", spec.support));
  if (!(spec.relinearize >= 0.0))
    throw_usage_error(fmt::format("wall.relinearize: must be >= 0, got {}", spec.relinearize));
  relinearize_ = spec.relinearize;
  mesh::TetMesh m;
  if (surface) {
    solid::SurfaceWall sw;
    sw.thickness = spec.thickness;
    sw.thickness_ratio = spec.thickness_ratio;
    sw.mesh_size = spec.mesh_size;
    sw.branches = spec.branch_thickness;
    solid::SurfaceWallStats stats;
    m = solid::mesh_surface_wall(*surface, net, sw, &stats);
    thinnest_ = stats.min_thickness;
    lumen_facts_ = {{"lumen", "surface"},
                    {"lumen_vertices", stats.lumen_vertices},
                    {"thinned_vertices", stats.thinned_vertices},
                    {"min_thickness", stats.min_thickness},
                    {"max_thickness", stats.max_thickness}};
  } else {
    thinnest_ = std::numeric_limits<double>::infinity();
    for (int k = 0; k < net.num_segments(); ++k)
      thinnest_ = std::min(thinnest_, spec.thickness_at(net.segment(k).branch, net.segment(k).radius));
    m = solid::mesh_network_wall(net, {spec.thickness, spec.thickness_ratio, spec.mesh_size, spec.branch_thickness});
    lumen_facts_ = {{"lumen", "network"}};
  }
  mesh_seconds_ = m.mesh_seconds;
  solid_ = std::make_unique<solid::ElasticSolid>(std::move(m), law);
  if (!spec.branch_youngs_modulus.empty()) assign_branch_laws(spec);
  for (size_t g = 0; g < solid_->mesh().groups.size(); ++g)  // every end held
    if (solid_->mesh().groups[g].name.rfind("end_", 0) == 0) solid_->hold(static_cast<int>(g));
  if (spec.support > 0.0) solid_->support(solid_->mesh().group_named("outer"), spec.support);
  solid_->linearize();
  lumen_ = std::make_unique<solid::LumenCompliance>(*solid_, solid_->mesh().group_named("lumen"));
  measure_thickness();
  displacement_ = Eigen::VectorXd::Zero(solid_->num_dofs());
  load_ = displacement_;
  base_ = displacement_;
  base_u_ = displacement_;
  base_load_ = displacement_;
  seconds_ += since(t0);
}

void DeformableWall::assign_branch_laws(const WallSpec& spec) {
  // One law per branch given; each tetrahedron the branch of the segment nearest its centroid
  // (a junction's tetrahedra split between its branches where their axes are equally near).
  std::vector<solid::NeoHookean> laws{solid_->law()};
  std::vector<int> law_of_branch(static_cast<size_t>(net_.num_branches()), 0);
  for (const auto& [branch, modulus] : spec.branch_youngs_modulus) {
    if (branch < 0 || branch >= net_.num_branches())
      throw_usage_error(fmt::format("wall: no branch {} in a network of {}", branch, net_.num_branches()));
    law_of_branch[static_cast<size_t>(branch)] = static_cast<int>(laws.size());
    laws.push_back(solid::NeoHookean::from_young_poisson(modulus, spec.poisson_ratio,
                                                         "wall.<branch>.youngs_modulus / wall.poisson_ratio"));
  }
  const auto& m = solid_->mesh();
  std::vector<int> tet_law(m.tets.size(), 0);
  for (size_t t = 0; t < m.tets.size(); ++t) {
    Vec3 c = Vec3::Zero();
    for (int k = 0; k < 4; ++k) c += 0.25 * m.nodes[static_cast<size_t>(m.tets[t][static_cast<size_t>(k)])];
    tet_law[t] = law_of_branch[static_cast<size_t>(net_.segment(nearest_segment(net_, c).segment).branch)];
  }
  solid_->set_laws(std::move(laws), std::move(tet_law));
}

namespace {
vessels::Network straight_vessel(const Vec3& p0, const Vec3& p1, double radius) {
  vessels::Centerlines c;
  c.branches.push_back({"vessel", {p0, p1}, {radius, radius}});
  return vessels::Network::build(c, {.max_segment_length = (p1 - p0).norm()});
}
}  // namespace

DeformableWall::DeformableWall(const Vec3& p0, const Vec3& p1, double radius, const WallSpec& spec)
    : DeformableWall(straight_vessel(p0, p1, radius), spec) {}

DeformableWall::~DeformableWall() = default;

const mesh::TetMesh& DeformableWall::mesh() const { return solid_->mesh(); }

int DeformableWall::compliance_columns() const { return lumen_->solved_nodes(); }

CompliantWall::Anchored DeformableWall::anchor(const void* body, std::span<const Vec3> points,
                                               std::span<const Vec3> normals, std::span<const double> radii) {
  const auto t0 = Clock::now();
  std::vector<solid::LumenPoint> at;
  at.reserve(points.size());
  for (size_t j = 0; j < points.size(); ++j)
    at.push_back(lumen_->locate_patch(points[j], j < radii.size() ? radii[j] : 0.0));
  Anchored a;
  // Each body its own kept blocks (cache 0 is the loads' check): its anchorings follow each other
  // at nearly the same nodes, another body's lie elsewhere.
  auto cache = std::find(cache_bodies_.begin(), cache_bodies_.end(), body);
  if (cache == cache_bodies_.end()) cache = cache_bodies_.insert(cache_bodies_.end(), body);
  a.compliance = lumen_->compliance(at, normals, 1 + static_cast<int>(cache - cache_bodies_.begin()));
  anticipate(points, radii);
  const bool pressed = pressure_response_.size() > 0 && last_pressure_.size() > 0, based = relinearizations_ > 0;
  bool others = false;
  for (const auto& [who, l] : loads_) others = others || (who != body && !l->points.empty());
  if (pressed || others || based) {
    Eigen::VectorXd other_response;  // the other bodies' loads
    for (const auto& [who, l] : loads_)
      if (who != body && !l->points.empty())
        other_response = other_response.size() ? Eigen::VectorXd(other_response + response(*l)) : response(*l);
    a.offsets = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(at.size()));
    for (size_t j = 0; j < at.size(); ++j) {
      Vec3 u = pressed ? pressure_displacement(at[j]) : Vec3::Zero();
      if (based) u += lumen_->interpolate(at[j], base_);  // the state the wall is linear about
      if (other_response.size()) u += lumen_->displacement(at[j], other_response);
      a.offsets[static_cast<Eigen::Index>(j)] = normals[j].dot(u);
    }
  }
  seconds_ += since(t0);
  return a;
}

void DeformableWall::load(const void* body, std::span<const Vec3> points, std::span<const Vec3> forces,
                          std::span<const double> radii) {
  const auto t0 = Clock::now();
  auto it = std::find_if(loads_.begin(), loads_.end(), [&](const auto& e) { return e.first == body; });
  if (it == loads_.end()) it = loads_.insert(loads_.end(), {body, std::make_unique<BodyLoad>()});
  BodyLoad& l = *it->second;
  l.points.clear();
  l.forces.assign(forces.begin(), forces.end());
  l.total.setZero();
  for (size_t j = 0; j < points.size(); ++j) {
    l.points.push_back(lumen_->locate_patch(points[j], j < radii.size() ? radii[j] : 0.0));
    l.total += forces[j];
  }
  l.response.resize(0);  // formed when another body's anchoring asks for it
  load_.setZero();
  load_total_.setZero();
  load_dofs_.clear();
  for (const auto& [who, b] : loads_) {
    if (!b->points.empty()) load_ += lumen_->nodal_forces(b->points, b->forces);
    load_total_ += b->total;
    for (const auto& at : b->points)
      for (const auto& [node, w] : at.weights)
        for (int c = 0; c < 3; ++c) load_dofs_.push_back(3 * node + c);
  }
  std::sort(load_dofs_.begin(), load_dofs_.end());
  load_dofs_.erase(std::unique(load_dofs_.begin(), load_dofs_.end()), load_dofs_.end());
  field_current_ = false;
  seconds_ += since(t0);
  if (relinearize_ > 0.0 && moved_beyond_linearization()) relinearize();
  anticipate(points, radii);
}

void DeformableWall::anticipate(std::span<const Vec3> points, std::span<const double> radii) {
  // The next step's footprints lie a little further along from these: their columns are solved on
  // the second thread meanwhile, the faces within a footprint and kAnticipation of each point.
  double radius = 0.0;
  for (double r : radii) radius = std::max(radius, r);
  lumen_->anticipate(points, radius + kAnticipation);
}

const Eigen::VectorXd& DeformableWall::response(BodyLoad& l) {
  if (l.response.size() == 0 && !l.points.empty()) l.response = lumen_->response(l.points, l.forces);
  return l.response;
}

bool DeformableWall::moved_beyond_linearization() {
  const auto t0 = Clock::now();
  // Each loaded point's displacement now (the base state's, the pressure's, every body's
  // loads through the kept node blocks) against the state the wall was linearized about.
  std::vector<solid::LumenPoint> points;
  std::vector<Vec3> forces;
  for (const auto& [who, l] : loads_) {
    (void)who;
    points.insert(points.end(), l->points.begin(), l->points.end());
    forces.insert(forces.end(), l->forces.begin(), l->forces.end());
  }
  const std::vector<Vec3> moved = lumen_->displacements(points, forces);
  bool beyond = false;
  for (size_t j = 0; j < points.size() && !beyond; ++j) {
    const solid::LumenPoint& at = points[j];
    Vec3 u = lumen_->interpolate(at, base_) + moved[j];
    if (pressure_response_.size() > 0 && last_pressure_.size() > 0) u += pressure_displacement(at);
    // (the thickness at the face's vertices, weighted by their shape functions' magnitudes: a
    // quadratic face's vertex weights are negative near its middle)
    double t = 0.0, w_sum = 0.0;
    for (const auto& [node, w] : at.weights)
      if (node_thickness_[static_cast<size_t>(node)] > 0.0)
        t += std::abs(w) * node_thickness_[static_cast<size_t>(node)], w_sum += std::abs(w);
    if (!(w_sum > 0.0)) continue;
    if ((u - lumen_->interpolate(at, base_u_)).norm() > relinearize_ * t / w_sum) beyond = true;
  }
  seconds_ += since(t0);
  return beyond;
}

void DeformableWall::relinearize() {
  const auto t0 = Clock::now();
  // The columns of the last tangent dropped, and their second thread stopped: it reads the factor
  // this solve replaces.
  lumen_->clear();
  Eigen::VectorXd f = load_;
  if (last_pressure_.size() > 0) f += pressure_basis_ * last_pressure_;
  // Newton on the neo-Hookean solid under the loads as they stand (dead loads), then its tangent
  // there. The loads are reached from the last linearization's, f_b + t (f − f_b): in one go from
  // the linear estimate about the last state; where that fails (an element turned inside out, a
  // tangent that is not positive definite, no convergence: loads large for the wall, as a stiff
  // wire's on a thin wall), in increments of t, halved until each converges from the state
  // before it and doubled after.
  Eigen::MatrixXd x = f;
  solid_->tangent_solve(x);
  const Eigen::VectorXd estimate = base_ + x.col(0);
  Eigen::VectorXd from = base_u_;
  double done = 0.0, step = 1.0;
  int increments = 0;
  std::string why;
  while (done < 1.0) {
    const double t = std::min(1.0, done + step);
    solid_->set_displacement(done == 0.0 && t == 1.0 ? estimate : from);
    solid_->nodal_forces() = base_load_ + t * (f - base_load_);
    bool converged = false;
    try {
      const solid::SolveReport report = solid_->solve({.tolerance = 1e-6, .max_iterations = 30, .keep_tangent = true});
      converged = report.converged;
      if (!converged) why = fmt::format("{} Newton iterations, residual {:.3g} N", report.iterations, report.residual);
    } catch (const Error& e) {
      if (e.kind() != ErrorKind::Numerical) throw;
      why = e.what();
    }
    if (converged) {
      done = t;
      from = solid_->displacement();
      step *= 2.0;
      ++increments;
      continue;
    }
    step *= 0.5;
    if (step < 1.0 / 1024.0)
      throw_numerical_error(
          fmt::format("wall: solving the wall under its loads to linearize it again did not converge "
                      "beyond {:.4g} of the way from the last linearization's loads ({}): the wall cannot "
                      "carry these loads (a stiffer or thicker wall, wall.support_stiffness, or less force on it)",
                      done, why));
  }
  if (increments > 1) load_increments_ += increments;
  base_load_ = f;
  if (!solid_->linearized()) solid_->linearize();  // (else the last iteration's tangent is kept)
  base_u_ = solid_->displacement();
  x = f;
  solid_->tangent_solve(x);
  base_ = base_u_ - x.col(0);
  for (auto& [who, l] : loads_) l->response.resize(0);  // (about the new tangent when asked)
  if (pressure_response_.size() > 0) {
    pressure_response_.resize(0, 0);
    ++pressure_generation_;
    solve_pressure_response();
  }
  widening_.resize(0, 0);
  widening_pressure_.resize(0, 0);
  if (radial_.size() > 0) base_widening_ = radial_.transpose() * base_;
  ++relinearizations_;
  field_current_ = false;
  const double spent = since(t0);
  relinearize_seconds_ += spent;
  seconds_ += spent;
}

void DeformableWall::set_blood_pressure(std::span<const double> node_pressures, double reference) {
  if (static_cast<int>(node_pressures.size()) != net_.num_nodes())
    throw_usage_error(
        fmt::format("wall: {} node pressures for a network of {} nodes", node_pressures.size(), net_.num_nodes()));
  // Unchanged pressures (a steady flow) leave the wall as it is.
  double largest = std::abs(reference),
         change = node_pressures_.empty() ? 1.0 : std::abs(reference - reference_pressure_);
  for (size_t k = 0; k < node_pressures.size(); ++k) {
    largest = std::max(largest, std::abs(node_pressures[k]));
    if (!node_pressures_.empty()) change = std::max(change, std::abs(node_pressures[k] - node_pressures_[k]));
  }
  if (!node_pressures_.empty() && change <= 1e-12 * largest) return;
  const auto t0 = Clock::now();
  node_pressures_.assign(node_pressures.begin(), node_pressures.end());
  reference_pressure_ = reference;
  if (pressure_basis_.size() == 0) {
    // The pressure at a lumen point: along the nearest segment, between its nodes' pressures,
    // so the load is linear in them, f = B p: B once, then K⁻¹B on the lumen once a linearization.
    pressure_basis_ = solid_->pressure_basis(solid_->mesh().group_named("lumen"), net_.num_nodes(),
                                             [this](const Vec3& x, std::vector<std::pair<int, double>>& w) {
                                               const NearestSegment near = nearest_segment(net_, x);
                                               const auto& seg = net_.segment(near.segment);
                                               w.emplace_back(seg.node_from, 1.0 - near.t);
                                               w.emplace_back(seg.node_to, near.t);
                                             });
  }
  Eigen::VectorXd p(net_.num_nodes());
  for (int k = 0; k < net_.num_nodes(); ++k) p[k] = node_pressures_[static_cast<size_t>(k)] - reference;
  last_pressure_ = p;  // its nodal forces B p formed only where the whole field is solved
  ++pressure_generation_;
  solve_pressure_response();
  field_current_ = false;
  seconds_ += since(t0);
}

void DeformableWall::solve_pressure_response() {
  if (pressure_response_.size() == 0) {
    // The lumen's response to each unit node pressure, K⁻¹B on the lumen's nodes, solved once
    // a linearization: the wall then follows a pulsatile pressure by a few rows of it a contact,
    // and its full field is solved only for an output frame.
    if (lumen_nodes_.empty()) {
      for (size_t f = 0; f < solid_->mesh().faces.size(); ++f)
        if (solid_->mesh().face_group[f] == solid_->mesh().group_named("lumen"))
          for (int node : solid_->mesh().faces[f]) lumen_nodes_.push_back(node);
      std::sort(lumen_nodes_.begin(), lumen_nodes_.end());
      lumen_nodes_.erase(std::unique(lumen_nodes_.begin(), lumen_nodes_.end()), lumen_nodes_.end());
    }
    Eigen::MatrixXd x = Eigen::MatrixXd(pressure_basis_);
    solid_->tangent_solve(x);
    pressure_response_.resize(3 * static_cast<Eigen::Index>(lumen_nodes_.size()), x.cols());
    lumen_row_.assign(static_cast<size_t>(solid_->mesh().num_nodes()), -1);
    for (size_t a = 0; a < lumen_nodes_.size(); ++a) {
      pressure_response_.middleRows<3>(3 * static_cast<Eigen::Index>(a)) = x.middleRows<3>(3 * lumen_nodes_[a]);
      lumen_row_[static_cast<size_t>(lumen_nodes_[a])] = static_cast<int>(a);
    }
  }
  // The lumen's displacement under the pressure is read where a contact needs it
  // (pressure_displacement), not formed over the whole lumen each frame.
}

Vec3 DeformableWall::pressure_displacement(const solid::LumenPoint& at) const {
  Vec3 u = Vec3::Zero();
  for (const auto& [node, w] : at.weights) {
    const int a = lumen_row_[static_cast<size_t>(node)];
    if (a < 0) continue;
    // Each node's displacement computed once a pressure (points share their nodes).
    if (pressure_node_u_.size() != lumen_nodes_.size()) {
      pressure_node_u_.assign(lumen_nodes_.size(), Vec3::Zero());
      pressure_node_stamp_.assign(lumen_nodes_.size(), 0);
    }
    const auto k = static_cast<size_t>(a);
    if (pressure_node_stamp_[k] != pressure_generation_) {
      pressure_node_u_[k] = pressure_response_.middleRows<3>(3 * static_cast<Eigen::Index>(a)) * last_pressure_;
      pressure_node_stamp_[k] = pressure_generation_;
    }
    u += w * pressure_node_u_[k];
  }
  return u;
}

double DeformableWall::max_pressure_displacement() const {
  if (pressure_response_.size() == 0 || last_pressure_.size() == 0) return 0.0;
  const Eigen::VectorXd lumen = pressure_response_ * last_pressure_;
  double largest = 0.0;
  for (Eigen::Index a = 0; a < lumen.size() / 3; ++a) largest = std::max(largest, lumen.segment<3>(3 * a).norm());
  return largest;
}

void DeformableWall::measure_thickness() {
  // Each lumen vertex's wall thickness: its distance to the nearest vertex of the outer surface
  // (within the outer surface's element size of the true thickness).
  const mesh::TetMesh& m = solid_->mesh();
  const int lumen = m.group_named("lumen"), outer = m.group_named("outer");
  std::vector<int> in, out;
  for (size_t f = 0; f < m.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      if (m.face_group[f] == lumen) in.push_back(m.faces[f][static_cast<size_t>(k)]);
      if (m.face_group[f] == outer) out.push_back(m.faces[f][static_cast<size_t>(k)]);
    }
  for (auto* v : {&in, &out}) {
    std::sort(v->begin(), v->end());
    v->erase(std::unique(v->begin(), v->end()), v->end());
  }
  local_thickness_.clear();
  node_thickness_.assign(static_cast<size_t>(m.num_nodes()), 0.0);
  for (int a : in) {
    double best = std::numeric_limits<double>::infinity();
    for (int b : out)
      best = std::min(best, (m.nodes[static_cast<size_t>(a)] - m.nodes[static_cast<size_t>(b)]).squaredNorm());
    local_thickness_.emplace_back(a, std::sqrt(best));
    node_thickness_[static_cast<size_t>(a)] = std::sqrt(best);
  }
}

std::vector<double> DeformableWall::segment_widening() {
  const auto t0 = Clock::now();
  const int segments = net_.num_segments();
  if (radial_.size() == 0) {
    // w_s: each lumen vertex's radial direction about its nearest segment's axis, averaged.
    const mesh::TetMesh& m = solid_->mesh();
    std::vector<std::vector<std::pair<int, Vec3>>> of(static_cast<size_t>(segments));
    for (const auto& [node, thickness] : local_thickness_) {
      (void)thickness;
      const NearestSegment near = nearest_segment(net_, m.nodes[static_cast<size_t>(node)]);
      of[static_cast<size_t>(near.segment)].emplace_back(node, near.offset.normalized());
    }
    std::vector<Eigen::Triplet<double>> entries;
    segment_has_nodes_.assign(static_cast<size_t>(segments), 0);
    for (int k = 0; k < segments; ++k) {
      const auto& nodes = of[static_cast<size_t>(k)];
      segment_has_nodes_[static_cast<size_t>(k)] = nodes.empty() ? 0 : 1;
      for (const auto& [node, radial] : nodes)
        for (int c = 0; c < 3; ++c)
          entries.emplace_back(3 * node + c, k, radial[c] / static_cast<double>(nodes.size()));
    }
    radial_.resize(solid_->num_dofs(), segments);
    radial_.setFromTriplets(entries.begin(), entries.end());
    base_widening_ = radial_.transpose() * base_;
  }
  if (widening_.size() == 0) {  // K⁻¹W, again after each linearization
    Eigen::MatrixXd x = Eigen::MatrixXd(radial_);
    solid_->tangent_solve(x);
    widening_ = x;
  }
  if (widening_pressure_.size() == 0 && pressure_basis_.size() > 0)  // (the pressure may come later)
    widening_pressure_ = widening_.transpose() * pressure_basis_;
  Eigen::VectorXd u = base_widening_;
  for (int i : load_dofs_)  // the bodies' forces: a few nonzero entries
    if (load_[i] != 0.0) u += load_[i] * widening_.row(i).transpose();
  if (last_pressure_.size() > 0) u += widening_pressure_ * last_pressure_;
  // Segments without vertices of their own: their neighbours' mean (a few passes).
  std::vector<double> out(u.data(), u.data() + segments);
  std::vector<char> known = segment_has_nodes_;
  for (int pass = 0; pass < 8; ++pass) {
    bool filled = false;
    for (int k = 0; k < segments; ++k) {
      if (known[static_cast<size_t>(k)]) continue;
      double sum = 0.0;
      int n = 0;
      for (int end : {net_.segment(k).node_from, net_.segment(k).node_to}) {
        const auto [b, e] = net_.node_segments(end);
        for (auto it = b; it != e; ++it)
          if (*it != k && known[static_cast<size_t>(*it)] == 1) sum += out[static_cast<size_t>(*it)], ++n;
      }
      if (n > 0) out[static_cast<size_t>(k)] = sum / n, known[static_cast<size_t>(k)] = 2, filled = true;
    }
    for (char& c : known)
      if (c == 2) c = 1;
    if (!filled) break;
  }
  seconds_ += since(t0);
  return out;
}

void DeformableWall::solve_field() const {
  if (field_current_) return;
  const auto t0 = Clock::now();
  Eigen::MatrixXd u = load_;
  if (last_pressure_.size() > 0) u.col(0) += pressure_basis_ * last_pressure_;
  solid_->tangent_solve(u);
  displacement_ = base_ + u.col(0);
  max_displacement_ = 0.0;
  for (int n = 0; n < solid_->mesh().num_nodes(); ++n)
    max_displacement_ = std::max(max_displacement_, displacement_.segment<3>(3 * n).norm());
  max_ever_ = std::max(max_ever_, max_displacement_);
  for (const auto& [node, t] : local_thickness_) {
    max_ratio_ever_ = std::max(max_ratio_ever_, displacement_.segment<3>(3 * node).norm() / t);
    max_increment_ratio_ =
        std::max(max_increment_ratio_, (displacement_.segment<3>(3 * node) - base_u_.segment<3>(3 * node)).norm() / t);
  }
  field_current_ = true;
  // The linear wall's field as a deformation: an element turned inside out is no wall any more.
  if (!std::isfinite(solid_->energy(displacement_)))
    throw_numerical_error(
        fmt::format("wall: the wall's displacement (largest {:.3g} mm, {:.3g} times its thickness where it moved "
                    "most relative to it) turns an element inside out: the wall linear about rest cannot carry "
                    "these loads (a stiffer or thicker wall, wall.support_stiffness, or less force on it)",
                    max_displacement_ * 1e3, max_ratio_ever_));
  seconds_ += since(t0);
}

const Eigen::VectorXd& DeformableWall::displacement() const {
  solve_field();
  return displacement_;
}

double DeformableWall::max_displacement() const {
  solve_field();
  return max_displacement_;
}

nlohmann::json DeformableWall::summary() const {
  solve_field();
  // The wall is linear about the state it was last linearized about (rest, unless
  // wall.relinearize solved it again under its loads): 6% off the nonlinear solid at half its
  // thickness (docs/deformable-wall.md), more beyond. Say so when a run went beyond the
  // thickness from that state where it moved (each lumen vertex against its own thickness).
  const bool beyond = max_increment_ratio_ > 1.0;
  if (beyond && !warned_range_) {
    warned_range_ = true;
    warn(fmt::format(
        "wall: it moved {:.3g} times its thickness from the state it is linear about where it moved most relative "
        "to it (largest displacement {:.3g} mm): its displacements and forces are approximate beyond its thickness{}",
        max_increment_ratio_, max_ever_ * 1e3,
        relinearize_ > 0.0 ? "" : " (wall.relinearize solves the wall again about its loaded state)"));
  }
  nlohmann::json j = lumen_facts_;
  j.update({{"max_displacement", max_ever_},  // over the output frames and the end
            {"beyond_linear_range", beyond},
            {"max_displacement_over_thickness", max_ratio_ever_},
            {"max_increment_over_thickness", max_increment_ratio_},
            {"relinearizations", relinearizations_},
            {"relinearize_seconds", relinearize_seconds_},
            {"relinearize_load_increments", load_increments_},
            {"final_max_displacement", max_displacement_},
            {"final_load", {load_total_.x(), load_total_.y(), load_total_.z()}},
            {"compliance_columns", compliance_columns()},
            {"compliance_columns_ahead", lumen_->anticipated_nodes()},
            {"seconds_ahead", lumen_->anticipated_seconds()},
            {"compliance_columns_dropped", lumen_->dropped_nodes()},
            {"blood_pressure_max_lumen_displacement", pressure_response_.size() > 0 && last_pressure_.size() > 0
                                                          ? nlohmann::json(max_pressure_displacement())
                                                          : nlohmann::json(nullptr)},
            {"seconds", seconds_}});
  return j;
}

void DeformableWall::write_vtu(const std::filesystem::path& path, const Eigen::VectorXd& state) const {
  const auto n = static_cast<size_t>(mesh().num_nodes());
  mesh::PointField displacement{"displacement", 3, std::vector<double>(state.data(), state.data() + 3 * n)};
  mesh::PointField magnitude{"displacement_magnitude", 1, {}};
  for (size_t k = 0; k < n; ++k) magnitude.values.push_back(state.segment<3>(3 * static_cast<Eigen::Index>(k)).norm());
  // The Cauchy stress (a 3 × 3 tensor a node, row by row) and its von Mises equivalent.
  mesh::PointField stress{"stress", 9, {}}, von_mises{"von_mises_stress", 1, {}};
  for (const Eigen::Matrix3d& sigma : solid_->nodal_stress(state)) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) stress.values.push_back(sigma(r, c));
    const Eigen::Matrix3d dev = sigma - sigma.trace() / 3.0 * Eigen::Matrix3d::Identity();
    von_mises.values.push_back(std::sqrt(1.5 * dev.cwiseProduct(dev).sum()));
  }
  mesh::write_vtu(path, mesh(), {displacement, magnitude, stress, von_mises});
}

}  // namespace flowire::coupling
