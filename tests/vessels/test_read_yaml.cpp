// flowire's YAML network file (read_yaml.cpp): branches joined and scaled by the declared
// unit, a loop, the declared unit winning over the caller's with a warning; every kind of bad
// file is one error naming the file, the line and the branch and point.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "flowire/vessels/io.hpp"
#include "reader_test_util.hpp"

namespace flowire::vessels {
namespace {

using flowire::testing::ExpectWarnings;
using flowire::testing::scratch_dir;
using namespace flowire::vessels::test;

TEST(ReadYaml, BranchesAreJoinedAndScaled) {
  const auto file = write_file(scratch_dir("io_yaml"), "y.yaml", R"(# a Y bifurcation in mm
length_unit: mm
branches:
  - name: trunk
    points: [[0, 0, 0, 5], [0, 0, -40, 5]]
  - name: left
    points: [[0, 0, -40, 3.5], [-10, 0, -60, 3.5], [-15, 0, -80, 3]]
  - name: right
    points: [[0, 0, -40.0000001, 3.5], [10, 0, -70, 3.5]]
)");
  const auto cl = read_centerlines(file);
  ASSERT_EQ(cl.branches.size(), 3u);
  EXPECT_EQ(cl.branches[1].name, "left");
  EXPECT_NEAR(cl.branches[1].points[2].x(), -0.015, 1e-15);
  EXPECT_NEAR(cl.branches[0].radii[0], 0.005, 1e-15);
  ReadOptions opt;
  opt.build.join_tolerance = 1e-6;
  const auto net = read_network(file, opt);
  const auto c = net.counts();
  EXPECT_EQ(c.branches, 3);
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
  EXPECT_EQ(net.branch(0).name, "trunk");
}

TEST(ReadYaml, TwoBranchesBetweenTheSameEndsMakeALoop) {
  const auto file = write_file(scratch_dir("io_yaml_loop"), "loop.yaml", R"(length_unit: mm
branches:
  - name: in
    points: [[0, 0, 0, 2], [10, 0, 0, 2]]
  - name: upper
    points: [[10, 0, 0, 1], [15, 5, 0, 1], [20, 0, 0, 1]]
  - name: lower
    points: [[10, 0, 0, 1], [15, -5, 0, 1], [20, 0, 0, 1]]
  - name: out
    points: [[20, 0, 0, 2], [30, 0, 0, 2]]
)");
  const auto c = read_network(file).counts();
  EXPECT_EQ(c.loops, 1);
  EXPECT_EQ(c.junctions, 2);
  EXPECT_EQ(c.ends, 2);
}

TEST(ReadYaml, DeclaredUnitWinsOverTheOptionWithAWarning) {
  const auto file = write_file(scratch_dir("io_yaml_unit"), "y.yml",
                               "length_unit: mm\nbranches:\n  - points: [[0, 0, 0, 5], [0, 0, 40, 5]]\n");
  ExpectWarnings w;
  ReadOptions opt;
  opt.length_unit = "cm";
  const auto cl = read_centerlines(file, opt);
  EXPECT_NEAR(cl.branches[0].points[1].z(), 0.04, 1e-15);
  EXPECT_TRUE(w.contains("declares length_unit mm")) << (w.warnings().empty() ? "" : w.warnings()[0]);
}

TEST(ReadBadInput, YamlErrorsNameFileLineAndPoint) {
  const auto dir = scratch_dir("io_bad_yaml");
  struct Case {
    std::string name, text, expected;
  };
  std::vector<Case> cases{
      {"empty.yaml", "", "the file is empty"},
      {"syntax.yaml", "branches:\n  - points: [[0, 0, 0, 1]\n", "syntax.yaml:"},
      {"nan.yaml", "branches:\n  - points: [[0, 0, 0, 1], [1, 0, 0, .nan]]\n",
       "nan.yaml:2: branch 0, point 1: radius is not finite"},
      {"nanx.yaml", "branches:\n  - name: a\n    points:\n      - [0, 0, 0, 1]\n      - [.nan, 0, 0, 1]\n",
       "nanx.yaml:5: branch 0 ('a'), point 1: coordinate is not finite"},
      {"zero.yaml", "branches:\n  - points:\n    - [0, 0, 0, 1]\n    - [1, 0, 0, 0]\n",
       "zero.yaml:4: branch 0, point 1: radius 0"},
      {"neg.yaml", "branches:\n  - points:\n    - [0, 0, 0, -1]\n    - [1, 0, 0, 1]\n",
       "point 0: radius -1 is not positive"},
      {"dup.yaml", "branches:\n  - points:\n    - [0, 0, 0, 1]\n    - [0, 0, 0, 1]\n",
       "dup.yaml:4: branch 0, point 1: same position as point 0 (duplicate point)"},
      {"word.yaml", "branches:\n  - points:\n    - [0, 0, zero, 1]\n    - [0, 0, 1, 1]\n", "'zero' is not a number"},
      {"unknown.yaml", "branches: []\nlenght_unit: mm\n", "unknown.yaml:2: unknown key 'lenght_unit'"},
      {"nobranches.yaml", "length_unit: mm\n", "no 'branches'"},
      {"badunit.yaml", "length_unit: parsec\nbranches:\n  - points: [[0, 0, 0, 1], [1, 0, 0, 1]]\n", "parsec"},
      {"loop.yaml", "branches:\n  - points: [[0, 0, 0, 1], [1, 0, 0, 1], [0, 0, 0, 1]]\n", "self-loop"},
      {"pieces.yaml",
       "branches:\n  - name: a\n    points: [[0, 0, 0, 1], [1, 0, 0, 1]]\n  - name: b\n    points: [[5, 0, 0, 1], [6, "
       "0, 0, 1]]\n",
       "2 disconnected pieces"},
      {"segloop.yaml", "nodes: [[0, 0, 0], [1, 0, 0]]\nsegments: [[0, 0, 1, 1, 0]]\n",
       "segloop.yaml:2: segment 0 joins node 0 to itself (self-loop)"},
      {"shape.yaml", "nodes: [[0, 0, 0], [1, 0, 0]]\nsegments:\n  - [0, 1, 1, 1, 0, 1, 1, 0.5]\n",
       "shape.yaml:3: segment 0: shape 0.5 is not finite and at least 1"},
  };
  ReadOptions opt;
  opt.build.max_segment_length = 0.0;
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const auto file = write_file(dir, c.name, c.text);
    const auto msg = error_of([&] { (void)read_network(file, opt); });
    EXPECT_CONTAINS(msg, c.expected);
    EXPECT_CONTAINS(msg, file);
  }
}

}  // namespace
}  // namespace flowire::vessels
