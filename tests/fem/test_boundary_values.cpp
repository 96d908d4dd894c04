// The network's boundary conditions on both models (flow/fem/src/boundary_values.cpp):
// boundary values from a flow spec (a flow inlet, RCR outlets as Rp + Rd), and unequal
// outlet resistances on a Y bifurcation, each outlet obeying its resistance law in the
// network and in the FEM, the split like the network's.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "fem_test_cases.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/fem/boundary_values.hpp"
#include "flowire/flow/fem/compare.hpp"
#include "flowire/flow/spec.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

using test::y_resistances;

TEST(FemBoundary, YWithUnequalOutletResistancesSplitsLikeTheNetwork) {
  const auto net = test::y_small(0.0);
  FemOptions opt;
  opt.write_png = false;
  const BoundaryValues bv = y_resistances();
  const CompareResult r = compare(net, bv, opt, "");
  ASSERT_EQ(r.outlets.size(), 2u);
  const double qn = r.outlets[0].flow_network + r.outlets[1].flow_network;
  const double qf = r.outlets[0].flow_fem + r.outlets[1].flow_fem;
  std::printf(
      "Y, outlet resistances 1:4: network split %.4f / %.4f, FEM %.4f / %.4f, split error %.3e, flow error "
      "%.3e; outlet pressures network %.3f / %.3f Pa, FEM %.3f / %.3f Pa\n",
      r.outlets[0].flow_network / qn, r.outlets[1].flow_network / qn, r.outlets[0].flow_fem / qf,
      r.outlets[1].flow_fem / qf, r.max_flow_split_error, r.max_flow_error, r.outlets[0].pressure_network,
      r.outlets[1].pressure_network, r.outlets[0].pressure_fem, r.outlets[1].pressure_fem);
  EXPECT_GT(std::abs(r.outlets[0].flow_network / qn - 0.5), 0.1);  // the resistances do change the split
  EXPECT_LT(r.max_flow_split_error, testing::tol(1e-2));
  EXPECT_LT(r.max_rel_diff_drop_away, testing::tol(2e-2));
  for (const auto& o : r.outlets) {  // each outlet obeys its resistance law in both models
    const auto& ov = bv.outlets[o.node == bv.outlets[0].node ? 0 : 1];
    EXPECT_NEAR(o.pressure_fem, ov.pressure + ov.resistance * o.flow_fem, 1e-9 * 200.0);
    EXPECT_NEAR(o.pressure_network, ov.pressure + ov.resistance * o.flow_network, 1e-9 * 200.0);
  }
}

TEST(FemBoundary, NetworkBoundaryValuesFromAFlowSpec) {
  const auto net = test::y_small(0.0);
  flow::FlowSpec spec;
  flow::InletBC in;
  in.type = flow::InletBC::Type::Flow;
  in.waveform = flow::Waveform::sine(2e-6, 1e-6, 0.8);
  spec.inlets.push_back(in);
  flow::OutletBC o;
  o.type = flow::OutletBC::Type::Rcr;
  o.rp = 1e8;
  o.rd = 3e8;
  o.c = 1e-9;
  o.distal_pressure = 50.0;
  spec.outlets.push_back(o);
  flow::resolve_nodes(spec, net);
  const BoundaryValues bv = boundary_values(spec, net, 0.2);  // a quarter period: the systolic value
  EXPECT_EQ(bv.inlet_type, BoundaryValues::Inlet::Flow);
  EXPECT_NEAR(bv.inlet_flow, 2e-6, 1e-18);
  ASSERT_EQ(bv.outlets.size(), 2u);
  for (const auto& v : bv.outlets) {
    EXPECT_EQ(v.type, OutletValue::Type::Resistance);
    EXPECT_DOUBLE_EQ(v.resistance, 4e8);
    EXPECT_DOUBLE_EQ(v.pressure, 50.0);
  }
  spec.inlets.push_back(spec.inlets.front());
  EXPECT_THROW((void)boundary_values(spec, net, 0.0), Error);
}

}  // namespace
}  // namespace flowire::flow::fem
