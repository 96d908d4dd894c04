// SimVascular ROM centerlines (read_simvascular_rom.cpp): one branch per BranchId, the
// bifurcation region collapsed into one junction at its branching point; the real SimVascular
// demo aorta's ROM centerlines (skipped, saying so, where ../shared is absent).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "flowire/vessels/io.hpp"
#include "reader_test_util.hpp"

namespace flowire::vessels {
namespace {

using flowire::testing::scratch_dir;
using namespace flowire::vessels::test;

TEST_F(ReadersWithVtk, SimVascularRomCenterlinesJoinAtTheBifurcation) {
  // Branch 0 (trunk) -> bifurcation region (BranchId -1) with a branching point -> branches 1, 2,
  // as two-point line cells sharing point ids.
  TestPoly p;
  std::vector<double> branch, bif, path_s, area;
  auto add = [&](const Vec3& x, int b, int f, double s, double r) {
    p.points.push_back(x);
    branch.push_back(b), bif.push_back(f), path_s.push_back(s);
    area.push_back(std::numbers::pi * r * r);
    return static_cast<long long>(p.points.size() - 1);
  };
  std::vector<long long> trunk, region, left, right;
  for (int i = 0; i <= 10; ++i) trunk.push_back(add(Vec3(0, 0, -i), 0, -1, i, 1.2));
  const Vec3 hub(0, 0, -12);
  region.push_back(add(Vec3(0, 0, -11), -1, 0, 0, 1.1));
  const long long hub_id = add(hub, -1, 0, 0, 1.0);
  const long long rl = add(Vec3(-0.5, 0, -12.5), -1, 0, 0, 0.9);
  const long long rr = add(Vec3(0.5, 0, -12.5), -1, 0, 0, 0.9);
  for (int i = 1; i <= 8; ++i) left.push_back(add(Vec3(-0.5 - i, 0, -12.5 - i), 1, -1, i, 0.6));
  for (int i = 1; i <= 6; ++i) right.push_back(add(Vec3(0.5 + i, 0, -12.5 - i), 2, -1, i, 0.5));
  auto chain = [&](const std::vector<long long>& ids) {
    for (size_t k = 0; k + 1 < ids.size(); ++k) p.lines.push_back({ids[k], ids[k + 1]});
  };
  chain(trunk);
  p.lines.push_back({trunk.back(), region[0]});
  p.lines.push_back({region[0], hub_id});
  p.lines.push_back({hub_id, rl});
  p.lines.push_back({hub_id, rr});
  p.lines.push_back({rl, left.front()});
  p.lines.push_back({rr, right.front()});
  chain(left);
  chain(right);
  std::vector<double> misr;
  for (const double a : area) misr.push_back(std::sqrt(a / std::numbers::pi));
  p.point_data.push_back({"BranchId", branch, 1, "Int64"});
  p.point_data.push_back({"BifurcationId", bif, 1, "Int64"});
  p.point_data.push_back({"Path", path_s});
  p.point_data.push_back({"CenterlineSectionArea", area});
  p.point_data.push_back({"MaximumInscribedSphereRadius", misr});
  const auto dir = scratch_dir("io_rom");
  const auto file = write_file(dir, "rom.vtp", vtp_text(p));
  ReadOptions opt;
  opt.length_unit = "cm";
  const auto cl = read_centerlines(file, opt);
  ASSERT_EQ(cl.branches.size(), 3u);
  // Trunk: its 11 points + the junction; daughters: junction + their points.
  EXPECT_EQ(cl.branches[0].points.size(), 12u);
  EXPECT_EQ(cl.branches[1].points.size(), 9u);
  EXPECT_EQ(cl.branches[2].points.size(), 7u);
  EXPECT_LT((cl.branches[0].points.back() - hub * 1e-2).norm(), 1e-12);
  EXPECT_LT((cl.branches[1].points.front() - hub * 1e-2).norm(), 1e-12);
  EXPECT_LT((cl.branches[2].points.front() - hub * 1e-2).norm(), 1e-12);
  EXPECT_NEAR(cl.branches[1].radii.back(), 0.6e-2, 1e-12);
  const auto net = read_network(file, opt);
  const auto c = net.counts();
  EXPECT_EQ(c.branches, 3);
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
  EXPECT_NEAR(c.radius_max, 1.2e-2, 1e-9);
}

#ifdef FLOWIRE_HAVE_VTK

TEST(RealData, SimVascularRomCenterlinesGiveAortaAndIliac) {
  FLOWIRE_REQUIRE_SHARED("data/real/simvascular-demo-aorta-iliac/rom-centerlines.vtp");
  const auto net = read_real("simvascular-demo-aorta-iliac/rom-centerlines.vtp", "cm");
  const auto c = net.counts();
  RecordProperty("counts", describe(c));
  EXPECT_EQ(c.branches, 3);   // BranchId 0, 1, 2
  EXPECT_EQ(c.junctions, 1);  // BifurcationId 0
  EXPECT_EQ(c.ends, 3);
  EXPECT_EQ(c.loops, 0);
  // Per-branch paths 20.3 + 20.2 + 22.2 cm, plus the bifurcation region.
  EXPECT_GT(c.total_length, 0.60);
  EXPECT_LT(c.total_length, 0.70);
  EXPECT_GE(c.radius_min, 4.4e-3);
  EXPECT_LE(c.radius_max, 12.8e-3);
  expect_physiological(c);
}

#endif  // FLOWIRE_HAVE_VTK

}  // namespace
}  // namespace flowire::vessels
