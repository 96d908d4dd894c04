// The wire acts on the blood, against 3D Stokes: a tube with a 0.014" wire along it,
// coaxial and nearly touching the wall, under a pressure drop. The FEM flow against (1) the
// exact annular Poiseuille flow (flow/annulus.hpp) and (2) the network: one segment whose
// occlusion the coupling computes from a straight wire at the same offset
// (coupling::WireOcclusion), the flow then solved by the network solver. The tolerance is
// the FEM's own error (P2/P1 on straight-sided tetrahedra), measured on the empty tube.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "flowire/coupling/occlusion.hpp"
#include "flowire/flow/annulus.hpp"
#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/obstacle.hpp"
#include "flowire/flow/fem/shape_domain.hpp"
#include "flowire/flow/fem/stokes.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

using flowire::testing::tol;
constexpr double kPi = std::numbers::pi;
constexpr double kEta = 3.5e-3;
constexpr double kR = 1.5e-3, kA = 0.178e-3;  // 3 mm vessel, 0.014" wire
constexpr double kLength = 1.5e-3, kDrop = 10.0;

/// Outflow of the FEM tube (with a wire at `offset`, or none if offset < 0) for kDrop Pa.
double fem_flow(double offset, double h, double h_wire, int* tets) {
  ObstacleMesh sizes;
  sizes.mesh_size = h;
  sizes.obstacle_mesh_size = h_wire;
  sizes.growth = 0.5;
  ShapeDomain domain = wire_along_tube_domain(kR, kLength, kA, std::max(offset, 0.0), sizes);
  if (offset < 0.0) {  // the same tube, empty
    domain.holes.clear();
    domain.groups.erase(domain.groups.begin() + 1);  // wall, inlet, outlet
    domain.outer.face_group = {0, 1, 2, -1, -1, -1};
  }
  const TetMesh mesh = build_mesh(domain);
  *tets = mesh.num_tets();
  StokesOptions so;
  so.viscosity = kEta;
  std::vector<GroupCondition> cond(mesh.groups.size(), GroupCondition::at_pressure(0.0));
  cond[static_cast<size_t>(mesh.group_named("inlet"))] = GroupCondition::at_pressure(kDrop);
  const StokesSolution sol = solve_stokes(mesh, std::span<const GroupCondition>(cond), so);
  return sol.group_flow[static_cast<size_t>(mesh.group_named("outlet"))];
}

/// The network's flow through one segment of the same tube, the occlusion computed by the
/// coupling from a straight wire along y = offset over the whole length.
double network_flow(double offset) {
  const vessels::Network net =
      vessels::Network::from_graph({Vec3(0, 0, 0), Vec3(kLength, 0, 0)}, {{0, 1, kR, kLength, -1}});
  flow::FlowSpec spec = flow::default_spec(net, flow::Waveform::constant(kDrop));
  spec.viscosity = kEta;
  auto solver = flow::make_solver(net, spec);
  coupling::WireOcclusion occlusion(*solver);
  const int n = 31;
  std::vector<Eigen::Vector3d> x;
  for (int i = 0; i < n; ++i) x.emplace_back(kLength * (n - 1 - i) / (n - 1), offset, 0.0);  // tip at the outlet
  const std::vector<int> segment(n, 0);
  const std::vector<double> radius(n - 1, kA);
  solver->set_occlusion(occlusion.update(x, n, segment, radius));
  EXPECT_NEAR(solver->occlusion()[0].occupied_fraction, 1.0, 1e-12);
  solver->advance(0.0);
  return std::abs(solver->segment_flow(0));
}

TEST(FemWireOcclusion, TubeWithAWireAgainstTheAnnulusAndTheNetwork) {
#ifndef FLOWIRE_FEM_SLOW
  const double h = 0.35e-3, h_wire = 0.06e-3;
#else
  const double h = 0.2e-3, h_wire = 0.035e-3;
#endif
  const double q_tube = kPi * kDrop * std::pow(kR, 4) / (8.0 * kEta * kLength);
  int tets = 0;
  const double q_empty = fem_flow(-1.0, h, h_wire, &tets);
  const double fem_error = std::abs(q_empty / q_tube - 1.0);
  std::printf("empty tube: %d tets, FEM/Hagen-Poiseuille %.5f\n", tets, q_empty / q_tube);
  const double gap = 0.25 * kA;  // nearly touching: a quarter of the wire radius from the wall
  for (double offset : {0.0, kR - kA - gap}) {
    const double e = offset / (kR - kA);
    const double exact = q_tube * flow::annulus_flow_fraction(kA / kR, e);
    const double q_fem = fem_flow(offset, h, h_wire, &tets);
    const double q_net = network_flow(offset);
    std::printf(
        "wire at e = %.3f: %d tets, FEM/empty %.4f, exact annulus/empty %.4f, network/empty %.4f, "
        "FEM/network %.4f\n",
        e, tets, q_fem / q_tube, exact / q_tube, q_net / q_tube, q_fem / q_net);
    // The network carries the exact annulus (its only approximation here is none: a
    // straight wire at one offset over the whole segment).
    EXPECT_NEAR(q_net / exact, 1.0, 1e-9) << e;
    // The FEM agrees with both within a few times its error on the empty tube (the wire
    // adds a curved boundary, meshed with straight-sided elements).
    EXPECT_NEAR(q_fem / q_net, 1.0, std::max(5.0 * fem_error, tol(2e-3))) << e;
    // And it sees what the empty-tube model cannot: 46% less flow coaxial, 8% on the wall.
    EXPECT_LT(q_fem, (offset == 0.0 ? 0.6 : 0.95) * q_empty) << e;
  }
}

}  // namespace
}  // namespace flowire::flow::fem
