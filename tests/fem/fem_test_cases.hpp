#pragma once
// Cases shared by the fem tests: a straight tube and small Y bifurcations as networks,
// boundary values on them, a tube with a wire as a domain built in code, and Womersley's
// Bessel function.
#include <cmath>
#include <complex>

#include "flowire/flow/fem/boundary_values.hpp"
#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/shape_domain.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/vessels/generators.hpp"
#include "flowire/vessels/network.hpp"

namespace flowire::flow::fem::test {

/// Bessel function J_n of a complex argument by its power series (|z| ≤ 10 here), for
/// Womersley's exact solution.
inline std::complex<double> bessel_j(int n, std::complex<double> z) {
  std::complex<double> term = std::pow(z / 2.0, n);
  for (int k = 1; k <= n; ++k) term /= static_cast<double>(k);
  std::complex<double> sum = term;
  for (int k = 1; k < 200; ++k) {
    term *= -(z / 2.0) * (z / 2.0) / (static_cast<double>(k) * static_cast<double>(k + n));
    sum += term;
    if (std::abs(term) < 1e-17 * std::abs(sum)) break;
  }
  return sum;
}

/// Straight tube along x, radius r, length l, one segment per 5 mm.
inline vessels::Network tube(double r = 2e-3, double l = 30e-3) {
  vessels::StraightTubeParams p;
  p.radius = r;
  p.length = l;
  return vessels::Network::build(vessels::straight_tube(p));
}

/// Y bifurcation at a small scale (parent radius 1 mm) for low Reynolds numbers.
inline vessels::Network y_small(double asymmetry = 0.0) {
  vessels::YBifurcationParams p;
  p.parent_radius = 1e-3;
  p.parent_length = 10e-3;
  p.child_length = 10e-3;
  p.asymmetry = asymmetry;
  return vessels::Network::build(vessels::y_bifurcation(p));
}

/// The published section's inlet and outlet pressures on every outlet.
inline BoundaryValues paper_like() {
  BoundaryValues bv;
  bv.inlet_pressure = 12850.0;  // the published section's inlet and outlet pressures (Pa)
  bv.outlet_pressure = 12800.0;
  return bv;
}

/// The small symmetric Y (y_small(0)) with a 200 Pa inlet and outlet resistances 1 and 4
/// times a daughter's Poiseuille resistance, to a distal 10 Pa.
inline BoundaryValues y_resistances() {
  BoundaryValues bv;
  bv.inlet_pressure = 200.0;
  const auto net = test::y_small(0.0);
  // Outlet resistances 1x and 4x the Poiseuille resistance of a daughter branch.
  double r_branch = 0.0;
  const int out0 = net.ends()[1] == net.widest_end() ? net.ends()[0] : net.ends()[1];
  const auto [b, e] = net.node_segments(out0);
  r_branch = flow::poiseuille_resistance(bv.viscosity, 10e-3, net.segment(*b).radius);
  int k = 0;
  for (int end : net.ends()) {
    if (end == net.widest_end()) continue;
    bv.outlets.push_back({end, OutletValue::Type::Resistance, 10.0, (k++ == 0 ? 1.0 : 4.0) * r_branch});
  }
  return bv;
}

/// A tube along x (radius r, length l) with a coaxial wire of radius a through all of it
/// (none when a = 0): groups wall, obstacle (the wire), inlet (x = 0), outlet (x = l).
inline ShapeDomain tube_with_wire(double r, double l, double a, double h, double h_wire) {
  using Kind = BoundaryGroup::Kind;
  ShapeDomain d;
  d.name = "tube with a wire";
  d.groups = {{Kind::Wall, -1, "wall"}, {Kind::Inlet, -1, "inlet"}, {Kind::Outlet, -1, "outlet"}};
  d.outer = Solid::cylinder(Vec3(0, 0, 0), Vec3(l, 0, 0), r);
  d.outer.face_group = {0, 1, 2, -1, -1, -1};
  d.mesh_size = h;
  if (a > 0.0) {
    d.groups.push_back({Kind::Wall, -1, "obstacle"});
    Solid wire = Solid::cylinder(Vec3(-0.1 * l, 0, 0), Vec3(1.1 * l, 0, 0), a);
    wire.face_group = {3, -1, -1, -1, -1, -1};
    wire.mesh_size = h_wire;
    d.holes.push_back(wire);
  }
  return d;
}

}  // namespace flowire::flow::fem::test
