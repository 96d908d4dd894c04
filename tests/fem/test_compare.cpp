// The network model against the FEM on Y bifurcations at low Reynolds number: outlet
// flow split, pressures along the centerlines away from and near the junction, and the
// comparison files.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "fem_test_cases.hpp"
#include "flowire/fem/boundary_values.hpp"
#include "flowire/fem/compare.hpp"
#include "flowire_test.hpp"

namespace flowire::fem {
namespace {

BoundaryValues paper_like() {
  BoundaryValues bv;
  bv.inlet_pressure = 12850.0;  // the published section's inlet and outlet pressures (Pa)
  bv.outlet_pressure = 12800.0;
  return bv;
}

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

TEST(FemCompare, WritesTheComparisonFiles) {
  const auto dir = testing::scratch_dir("fem_compare");
  const auto net = test::y_small(0.2);
  FemOptions opt;
  opt.size_factor = 0.5;
  opt.samples_per_branch = 6;
  const CompareResult r = compare(net, paper_like(), opt, dir.string());
  for (const char* f : {"fem_compare.csv", "fem_outlets.csv", "fem_compare.md", "fem.vtu", "fem_compare.png"})
    EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
  std::ifstream csv(dir / "fem_compare.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("branch,s,x,y,z,pressure_network,pressure_fem,rel_diff", 0), 0u) << header;
  int rows = 0;
  for (std::string line; std::getline(csv, line);) ++rows;
  EXPECT_EQ(rows, static_cast<int>(r.samples.size()));
  EXPECT_EQ(rows, 3 * 6);
  std::ifstream outlets(dir / "fem_outlets.csv");
  std::getline(outlets, header);
  EXPECT_EQ(header.rfind("outlet,flow_network,flow_fem", 0), 0u);
}

}  // namespace
}  // namespace flowire::fem
