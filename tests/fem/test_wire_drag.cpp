// The blood-drag law on a guidewire against 3D Navier–Stokes: a wire across a tube (a
// cylinder spanning the diameter, perpendicular to the axis) at wire Reynolds numbers
// 1, 10 and 100. The FEM force per unit length against the unconfined cylinder drag curve
// (cylinder_drag_coefficient), against the law without the vessel's axis (which holds the
// normal coefficient at or above the coaxial-tube Stokes value: the law before its
// confinement across the vessel) at the span-averaged undisturbed velocity, and against
// the law as the co-simulation evaluates it: at each point of the span with the local
// undisturbed velocity and the vertex's offset from the vessel's axis (strip theory: the
// wire stands across a channel of half-width √(R² − y²)). The figures and the tolerances
// are discussed in docs/drag-verification.md.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "flowire/coupling/drag.hpp"
#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/obstacle.hpp"
#include "flowire/flow/fem/shape_domain.hpp"
#include "flowire/flow/fem/stokes.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kEta = 3.5e-3, kRho = 1060.0;
constexpr double kR = 1.5e-3, kA = 0.178e-3;  // 3 mm vessel, 0.014" wire

struct CrossWire {
  double re_d = 0.0;                 ///< ρ U d/η with U the mean axial velocity
  double force_per_length = 0.0;     ///< FEM, N/m
  double curve = 0.0;                ///< ½ρ C_D(Re_w) d U_w², U_w the span-averaged velocity
  double curve_local = 0.0;          ///< the same law integrated along the span with the local u(y)
  double law_before = 0.0;           ///< blood_drag at U_w without the vessel's axis (coaxial-tube floor)
  double law = 0.0;                  ///< blood_drag along the span: local velocity, offset and axis
  double g_fem = 0.0, g_conf = 0.0;  ///< F'/(η U_w) of the FEM; the coaxial-tube Stokes floor
  int tets = 0, unknowns = 0, newton = 0;
};

/// The law per unit length of a wire across the tube, evaluated like the co-simulation
/// does at its vertices: at n points of the span, each with its undisturbed Poiseuille
/// velocity u(y) = 2U(1 − y²/R²), the tube's axis and the point's offset from it.
double law_along_span(double u_mean, int n = 400) {
  coupling::DragModel model;
  model.viscosity = kEta;
  model.density = kRho;
  model.wire_radius = kA;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double y = -kR + (i + 0.5) * 2.0 * kR / n;
    coupling::DragInput in;
    in.u = Vec3(2.0 * u_mean * (1.0 - y * y / (kR * kR)), 0, 0);
    in.t = Vec3::UnitY();
    in.ell = 2.0 * kR / n;
    in.vessel_radius = kR;
    in.axis = Vec3::UnitX();
    in.axis_offset = Vec3(0, y, 0);
    sum += coupling::blood_drag(model, in).force.x();
  }
  return sum / (2.0 * kR);
}

CrossWire cross_wire(double re_d, double h, double h_wire, double growth, Equations equations, Vec3& f) {
  const double d = 2.0 * kA;
  const double u_mean = re_d * kEta / (kRho * d);
  ObstacleMesh sizes;
  sizes.mesh_size = h;
  sizes.obstacle_mesh_size = h_wire;
  sizes.growth = growth;
  const double up = 2.0 * kR, down = 4.0 * kR;
  const TetMesh mesh = build_mesh(wire_in_tube_domain(kR, up + down, kA, true, up, sizes));
  StokesOptions so;
  so.viscosity = kEta;
  so.density = kRho;
  so.equations = equations;
  std::vector<GroupCondition> cond(mesh.groups.size(), GroupCondition::at_pressure(0.0));
  cond[static_cast<size_t>(mesh.group_named("inlet"))] = GroupCondition::with_flow(-u_mean * kPi * kR * kR);
  const StokesSolution sol = solve_stokes(mesh, std::span<const GroupCondition>(cond), so);
  f = boundary_forces(mesh, sol, so)[static_cast<size_t>(mesh.group_named("obstacle"))];
  CrossWire r;
  r.re_d = re_d;
  r.tets = mesh.num_tets();
  r.unknowns = sol.unknowns;
  r.newton = sol.newton_iterations;
  r.force_per_length = f.x() / (2.0 * kR);
  // Poiseuille u(y) = 2U(1 − y²/R²) along the wire: span average 4U/3.
  const double uw = 4.0 * u_mean / 3.0;
  const double re_w = kRho * uw * d / kEta;
  r.curve = 0.5 * kRho * coupling::cylinder_drag_coefficient(re_w) * d * uw * uw;
  const int n = 400;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double y = -kR + (i + 0.5) * 2.0 * kR / n;
    const double u = 2.0 * u_mean * (1.0 - y * y / (kR * kR));
    if (u > 0.0) sum += 0.5 * kRho * coupling::cylinder_drag_coefficient(kRho * u * d / kEta) * d * u * u;
  }
  r.curve_local = sum / n;
  coupling::DragModel model;
  model.viscosity = kEta;
  model.density = kRho;
  model.wire_radius = kA;
  coupling::DragInput in;
  in.u = Vec3(uw, 0, 0);
  in.t = Vec3::UnitY();
  in.ell = 1.0;
  in.vessel_radius = kR;
  r.law_before = coupling::blood_drag(model, in).force.x();
  r.law = law_along_span(u_mean);
  r.g_fem = r.force_per_length / (kEta * uw);
  r.g_conf = 4.0 * kPi / (std::log(kR / kA) - (kR * kR - kA * kA) / (kR * kR + kA * kA));
  std::printf(
      "cross wire Re_d %5.1f%s: %d tets, %d unknowns, %d Newton steps; F' FEM %.4e N/m, curve %.4e (ratio %.3f), "
      "curve local %.4e (ratio %.3f), law without the axis %.4e (ratio %.3f), law along the span %.4e (ratio "
      "%.3f); g FEM %.2f, g_conf %.2f; sideways %.1e of F_x\n",
      re_d, equations == Equations::Stokes ? " (Stokes)" : "", r.tets, r.unknowns, r.newton, r.force_per_length,
      r.curve, r.force_per_length / r.curve, r.curve_local, r.force_per_length / r.curve_local, r.law_before,
      r.force_per_length / r.law_before, r.law, r.force_per_length / r.law, r.g_fem, r.g_conf,
      std::hypot(f.y(), f.z()) / f.x());
  return r;
}

/// What docs/drag-verification.md states for the law along the span (FEM/law): 1.11–1.12 at
/// Re_d = 1 (strip theory misses the tube's three-dimensional confinement of the middle of
/// the span and the inertia at Re_d = 1), 1.07–1.08 at Re_d = 10, 0.73–0.75 at Re_d = 100
/// (a steady solution against a law for the time-mean drag of the shedding wake).
void expect_documented(const CrossWire& r) {
  const double ratio = r.force_per_length / r.law;
  if (r.re_d <= 1.0) {
    EXPECT_GT(ratio, 1.0) << "Re_d " << r.re_d;
    EXPECT_LT(ratio, 1.15) << "Re_d " << r.re_d;
  } else if (r.re_d <= 10.0) {
    EXPECT_GT(ratio, 0.9) << "Re_d " << r.re_d;
    EXPECT_LT(ratio, 1.1) << "Re_d " << r.re_d;
  } else {
    EXPECT_GT(ratio, 0.65) << "Re_d " << r.re_d;
    EXPECT_LT(ratio, 0.85) << "Re_d " << r.re_d;
  }
  if (r.re_d <= 10.0) {
    // Confined: above the unbounded-stream curve, and closer to the FEM than the law
    // without the confinement across the vessel.
    EXPECT_GT(r.force_per_length, r.curve) << "Re_d " << r.re_d;
    EXPECT_LT(std::abs(ratio - 1.0), std::abs(r.force_per_length / r.law_before - 1.0)) << "Re_d " << r.re_d;
  }
}

#ifndef FLOWIRE_FEM_SLOW
// Coarse mesh (6.2k tets, 21k unknowns; at this Reynolds number the force per length is
// within 0.33% of a mesh with 1.7 times the tetrahedra).
TEST(FemWireDrag, CrossWireAtReynoldsOneAgainstTheLaw) {
  Vec3 f;
  const CrossWire r = cross_wire(1.0, 0.6e-3, 0.1e-3, 0.4, Equations::NavierStokes, f);
  expect_documented(r);
  // The geometry is symmetric: no sideways force (up to the mesh's asymmetry).
  EXPECT_LT(std::hypot(f.y(), f.z()), 1e-2 * f.x());
  // In creeping flow the vessel wall, not the Oseen length, bounds the disturbance: the
  // 3D drag is above the two-dimensional coaxial-tube Stokes value.
  EXPECT_GT(r.g_fem, r.g_conf);
}

TEST(FemWireDrag, CrossWireInStokesFlowAgainstFaxenStripTheory) {
  // The law's creeping-flow limit across the vessel is Faxén's channel drag at each point
  // of the span; the 3D Stokes force is 7–8% above it (the tube's wall closes in along the
  // span, which strip theory leaves out).
  Vec3 f;
  const CrossWire r = cross_wire(1e-3, 0.6e-3, 0.1e-3, 0.4, Equations::Stokes, f);
  const double ratio = r.force_per_length / r.law;
  EXPECT_GT(ratio, 1.0);
  EXPECT_LT(ratio, 1.1);
}
#else
TEST(FemWireDragSlow, CrossWireAtReynolds1To100) {
  for (double re : {1.0, 10.0, 100.0}) {
    Vec3 f;
    const CrossWire r = cross_wire(re, 0.45e-3, 0.09e-3, 0.3, Equations::NavierStokes, f);
    expect_documented(r);
  }
}
#endif

}  // namespace
}  // namespace flowire::flow::fem
