// The wall around a network's lumen as an elastic solid: meshed by solid::mesh_network_wall,
// ends held, supported outside, linearized at rest; the step's contacts anchored on its lumen
// and their compliance condensed; loaded at the end of a step.
#include "flowire/coupling/deformable_wall.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>

#include "flowire/common/error.hpp"
#include "flowire/mesh/vtu.hpp"
#include "flowire/solid/elastic_solid.hpp"
#include "flowire/solid/lumen_compliance.hpp"
#include "flowire/solid/tube_wall.hpp"

namespace flowire::coupling {
namespace {
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
}  // namespace

DeformableWall::DeformableWall(const vessels::Network& net, const WallSpec& spec) {
  const auto t0 = Clock::now();
  const solid::NeoHookean law = solid::NeoHookean::from_young_poisson(spec.youngs_modulus, spec.poisson_ratio,
                                                                      "wall.youngs_modulus / wall.poisson_ratio");
  if (!(spec.thickness > 0.0) && !(spec.thickness_ratio > 0.0))
    throw_usage_error(fmt::format("wall.thickness: must be > 0, got {} m", spec.thickness));
  if (!(spec.mesh_size > 0.0)) throw_usage_error(fmt::format("wall.mesh_size: must be > 0, got {} m", spec.mesh_size));
  if (!(spec.support >= 0.0)) throw_usage_error(fmt::format("wall.support: must be >= 0, got {} Pa/m", spec.support));
  mesh::TetMesh m = solid::mesh_network_wall(net, {spec.thickness, spec.thickness_ratio, spec.mesh_size});
  mesh_seconds_ = m.mesh_seconds;
  solid_ = std::make_unique<solid::ElasticSolid>(std::move(m), law);
  for (int e : net.ends()) solid_->hold(solid_->mesh().group_named(fmt::format("end_{}", e)));
  if (spec.support > 0.0) solid_->support(solid_->mesh().group_named("outer"), spec.support);
  solid_->linearize();
  lumen_ = std::make_unique<solid::LumenCompliance>(*solid_, solid_->mesh().group_named("lumen"));
  displacement_ = Eigen::VectorXd::Zero(solid_->num_dofs());
  load_ = displacement_;
  seconds_ += since(t0);
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

void DeformableWall::anchor(std::span<const Vec3> points, std::span<const Vec3> normals) {
  const auto t0 = Clock::now();
  std::vector<solid::LumenPoint> at;
  at.reserve(points.size());
  for (const Vec3& p : points) at.push_back(lumen_->locate(p));
  compliance_ = lumen_->compliance(at, normals);
  seconds_ += since(t0);
}

void DeformableWall::load(std::span<const Vec3> points, std::span<const Vec3> forces) {
  const auto t0 = Clock::now();
  std::vector<solid::LumenPoint> at;
  at.reserve(points.size());
  load_total_.setZero();
  for (size_t j = 0; j < points.size(); ++j) {
    at.push_back(lumen_->locate(points[j]));
    load_total_ += forces[j];
  }
  load_ = lumen_->nodal_forces(at, forces);
  field_current_ = false;
  seconds_ += since(t0);
}

void DeformableWall::solve_field() const {
  if (field_current_) return;
  const auto t0 = Clock::now();
  Eigen::MatrixXd u = load_;
  solid_->tangent_solve(u);
  displacement_ = u.col(0);
  max_displacement_ = 0.0;
  for (int n = 0; n < solid_->mesh().num_nodes(); ++n)
    max_displacement_ = std::max(max_displacement_, displacement_.segment<3>(3 * n).norm());
  max_ever_ = std::max(max_ever_, max_displacement_);
  field_current_ = true;
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
  return {{"max_displacement", max_ever_},  // over the output frames and the end
          {"final_max_displacement", max_displacement_},
          {"final_load", {load_total_.x(), load_total_.y(), load_total_.z()}},
          {"compliance_columns", compliance_columns()},
          {"seconds", seconds_}};
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
