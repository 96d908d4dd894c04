// The files of a comparison (flow/fem/src/compare_output.cpp): fem_compare.csv,
// fem_outlets.csv, fem_compare.md, fem.vtu and fem_compare.png written, the CSV headers and
// one row per sample.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "fem_test_cases.hpp"
#include "flowire/flow/fem/boundary_values.hpp"
#include "flowire/flow/fem/compare.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

using test::paper_like;

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
}  // namespace flowire::flow::fem
