// The steady comparison (flow/fem/src/compare.cpp): the network model against the FEM on Y
// bifurcations and a bent tube at low Reynolds number: outlet flow split, pressures along
// the centerlines away from and near the junction.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "fem_test_cases.hpp"
#include "flowire/flow/fem/boundary_values.hpp"
#include "flowire/flow/fem/compare.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

using test::paper_like;

void report(const char* name, const CompareResult& r) {
  std::printf(
      "%s: %d tets, %d unknowns; flow split error %.3e, flow error %.3e; pressure difference "
      "(fraction of the drop) away from the junction %.3e, near it %.3e; mesh %.2f s, assembly "
      "%.2f s, solve %.2f s\n",
      name, r.tets, r.unknowns, r.max_flow_split_error, r.max_flow_error, r.max_rel_diff_drop_away,
      r.max_rel_diff_drop_junction, r.mesh_seconds, r.assemble_seconds, r.solve_seconds);
}

TEST(FemCompare, SymmetricYSplitsFiftyFiftyLikeTheNetwork) {
  const auto net = test::y_small(0.0);
  FemOptions opt;
  opt.write_png = false;
  const CompareResult r = compare(net, paper_like(), opt, "");
  report("symmetric Y", r);
  ASSERT_EQ(r.outlets.size(), 2u);
  const double total = r.outlets[0].flow_fem + r.outlets[1].flow_fem;
  EXPECT_NEAR(r.outlets[0].flow_fem / total, 0.5, 1e-3);
  EXPECT_LT(r.max_flow_split_error, testing::tol(1e-2));
  EXPECT_LT(r.max_rel_diff_drop_away, testing::tol(2e-2));
}

TEST(FemCompare, AsymmetricYFlowSplitWithinOnePercent) {
  const auto net = test::y_small(0.4);
  FemOptions opt;
  opt.write_png = false;
  const CompareResult r = compare(net, paper_like(), opt, "");
  report("asymmetric Y (a = 0.4)", r);
  EXPECT_LT(r.max_flow_split_error, testing::tol(1e-2));
  EXPECT_LT(r.max_rel_diff_drop_away, testing::tol(2e-2));
}

TEST(FemCompare, BentTubeWithASphereAtTheBendMatchesTheNetwork) {
  vessels::Centerlines c;
  c.branches.push_back({"bent",
                        {vessels::Vec3(0, 0, 0), vessels::Vec3(10e-3, 0, 0),
                         vessels::Vec3(10e-3 + 10e-3 * std::cos(0.8), 10e-3 * std::sin(0.8), 0)},
                        {1e-3, 1e-3, 1e-3}});
  const auto net = vessels::Network::build(c);
  FemOptions opt;
  opt.size_factor = 0.4;
  const CompareResult r = compare(net, paper_like(), opt, "");
  report("bent tube (46 deg)", r);
  EXPECT_LT(r.max_flow_error, testing::tol(1e-2));
  EXPECT_LT(r.max_rel_diff_drop_away, testing::tol(1e-2));
}

}  // namespace
}  // namespace flowire::flow::fem
