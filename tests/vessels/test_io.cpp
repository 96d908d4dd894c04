// The network readers and writers on files the tests write themselves: VMTK paths,
// VMTK branch-split, SimVascular ROM, plain and legacy VTK polylines, YAML, svOneDSolver
// decks; the .vtp / .yaml round trips; and every kind of bad input.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <string>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/vessels/io.hpp"
#include "flowire_test.hpp"

namespace flowire::vessels {
namespace {

namespace fs = std::filesystem;
using flowire::testing::ExpectWarnings;
using flowire::testing::scratch_dir;

// ---------------------------------------------------------------------------------------
// Writing test files

struct TestArray {
  std::string name;
  std::vector<double> values;
  int components = 1;
  std::string type = "Float64";
};

struct TestPoly {
  std::vector<Vec3> points;
  std::vector<std::vector<long long>> lines;
  std::vector<TestArray> point_data, cell_data;
};

std::string numbers(const std::vector<double>& v) {
  std::string s;
  for (const double x : v) s += fmt::format(" {}", x);
  return s;
}

std::string data_array(const TestArray& a) {
  std::string s = fmt::format(R"(<DataArray type="{}" Name="{}" NumberOfComponents="{}" format="ascii">)", a.type,
                              a.name, a.components);
  if (a.type == "Float64" || a.type == "Float32") {
    s += numbers(a.values);
  } else {
    for (const double x : a.values) s += fmt::format(" {}", static_cast<long long>(x));
  }
  return s + "</DataArray>\n";
}

/// ASCII VTK XML poly data, as VTK writes it with SetDataModeToAscii.
std::string vtp_text(const TestPoly& p) {
  std::string s = "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n";
  s += fmt::format(
      "<PolyData>\n<Piece NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"{}\" NumberOfStrips=\"0\" "
      "NumberOfPolys=\"0\">\n",
      p.points.size(), p.lines.size());
  s += "<PointData>\n";
  for (const auto& a : p.point_data) s += data_array(a);
  s += "</PointData>\n<CellData>\n";
  for (const auto& a : p.cell_data) s += data_array(a);
  s += "</CellData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">";
  for (const auto& x : p.points) s += fmt::format(" {} {} {}", x.x(), x.y(), x.z());
  s += "</DataArray>\n</Points>\n<Lines>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">";
  long long end = 0;
  std::string offsets;
  for (const auto& l : p.lines) {
    for (const long long id : l) s += fmt::format(" {}", id);
    end += static_cast<long long>(l.size());
    offsets += fmt::format(" {}", end);
  }
  s += "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">" + offsets + "</DataArray>\n";
  s += "</Lines>\n</Piece>\n</PolyData>\n</VTKFile>\n";
  return s;
}

/// Legacy ASCII VTK poly data with one point scalar per array.
std::string legacy_text(const TestPoly& p) {
  std::string s = "# vtk DataFile Version 3.0\nvtk output\nASCII\nDATASET POLYDATA\n";
  s += fmt::format("POINTS {} double\n", p.points.size());
  for (const auto& x : p.points) s += fmt::format("{} {} {}\n", x.x(), x.y(), x.z());
  size_t size = 0;
  for (const auto& l : p.lines) size += l.size() + 1;
  s += fmt::format("LINES {} {}\n", p.lines.size(), size);
  for (const auto& l : p.lines) {
    s += fmt::format("{}", l.size());
    for (const long long id : l) s += fmt::format(" {}", id);
    s += "\n";
  }
  s += fmt::format("POINT_DATA {}\n", p.points.size());
  for (const auto& a : p.point_data)
    s += fmt::format("SCALARS {} double\nLOOKUP_TABLE default\n{}\n", a.name, numbers(a.values));
  return s;
}

std::string write_file(const fs::path& dir, const std::string& name, const std::string& text) {
  const auto path = (dir / name).string();
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

/// Points from a to b (inclusive) every `step`.
std::vector<Vec3> line_points(const Vec3& a, const Vec3& b, double step, bool include_first = true) {
  const int n = std::max(1, static_cast<int>(std::round((b - a).norm() / step)));
  std::vector<Vec3> out;
  for (int i = include_first ? 0 : 1; i <= n; ++i) out.push_back(a + (b - a) * (static_cast<double>(i) / n));
  return out;
}

/// The message of the flowire::Error `f` throws (fails the test if it throws nothing else).
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a flowire::Error: " << e.what();
    return {};
  }
  ADD_FAILURE() << "no error";
  return {};
}

#define EXPECT_CONTAINS(text, fragment) \
  EXPECT_NE(std::string(text).find(fragment), std::string::npos) << "message: " << (text)

// ---------------------------------------------------------------------------------------
// A VMTK-style three-outlet aorta: one path per outlet, each repeating the shared trunk.

struct Aorta {
  Vec3 inlet{0, 0, 0}, j1{0, 0, -60}, j2{0, 0, -120};
  Vec3 out_a{30, 0, -100}, out_b{20, 0, -160}, out_c{-20, 0, -160};
  double r_trunk = 10, r_a = 4, r_b = 6, r_c = 5;
  /// Exact total length (mm) of the tree.
  [[nodiscard]] double length() const {
    return (j1 - inlet).norm() + (out_a - j1).norm() + (j2 - j1).norm() + (out_b - j2).norm() + (out_c - j2).norm();
  }
  [[nodiscard]] TestPoly vmtk() const {
    TestPoly p;
    std::vector<double> radius, edge;
    auto add_path = [&](std::vector<std::pair<Vec3, double>> knots) {
      std::vector<long long> ids;
      for (size_t k = 0; k + 1 < knots.size(); ++k) {
        const auto pts = line_points(knots[k].first, knots[k + 1].first, 1.0, k == 0);
        for (const auto& x : pts) {
          ids.push_back(static_cast<long long>(p.points.size()));
          p.points.push_back(x);
          radius.push_back(knots[k + 1].second);
          edge.insert(edge.end(), {1.0, 2.0});
        }
      }
      radius[static_cast<size_t>(ids.front())] = r_trunk;
      // vmtkcenterlines repeats a point at the end of a path
      ids.push_back(ids.back());
      p.lines.push_back(ids);
    };
    add_path({{inlet, r_trunk}, {j1, r_trunk}, {out_a, r_a}});
    add_path({{inlet, r_trunk}, {j1, r_trunk}, {j2, r_trunk}, {out_b, r_b}});
    add_path({{inlet, r_trunk}, {j1, r_trunk}, {j2, r_trunk}, {out_c, r_c}});
    p.point_data.push_back({"MaximumInscribedSphereRadius", radius});
    p.point_data.push_back({"EdgeArray", edge, 2});
    return p;
  }
};

class ReadersWithVtk : public ::testing::Test {
 protected:
  void SetUp() override {
#ifndef FLOWIRE_HAVE_VTK
    GTEST_SKIP() << "built without VTK: .vtp/.vtk readers are off";
#endif
  }
};

TEST_F(ReadersWithVtk, VmtkThreeOutletAortaMergesIntoOneTree) {
  const auto dir = scratch_dir("io_vmtk");
  const Aorta a;
  const auto path = write_file(dir, "aorta.vtp", vtp_text(a.vmtk()));
  ReadOptions opt;
  opt.length_unit = "mm";
  opt.build.max_segment_length = 0.01;
  const auto net = read_network(path, opt);
  const auto c = net.counts();
  EXPECT_EQ(c.ends, 4);  // 1 inlet + 3 outlets
  EXPECT_EQ(c.junctions, 2);
  EXPECT_EQ(c.branches, 5);
  EXPECT_EQ(c.loops, 0);
  EXPECT_EQ(c.components, 1);
  EXPECT_NEAR(c.total_length, a.length() * 1e-3, 0.02 * a.length() * 1e-3);
  EXPECT_NEAR(c.radius_max, 10e-3, 1e-9);
  // The inlet is the widest end, at the origin.
  EXPECT_LT(net.node(net.widest_end()).norm(), 1e-12);
  const auto ends = net.ends();
  EXPECT_EQ(ends.size(), 4u);
  int outlets_found = 0;
  for (const Vec3& o : {a.out_a, a.out_b, a.out_c})
    for (const int e : ends) outlets_found += (net.node(e) - o * 1e-3).norm() < 1e-12;
  EXPECT_EQ(outlets_found, 3);
}

TEST_F(ReadersWithVtk, VmtkPathsWithTightToleranceJoinExactlyAtTheJunctions) {
  const auto dir = scratch_dir("io_vmtk_exact");
  const Aorta a;
  const auto path = write_file(dir, "aorta.vtp", vtp_text(a.vmtk()));
  ReadOptions opt;
  opt.length_unit = "mm";
  opt.merge_tolerance = 0.01;
  opt.build.max_segment_length = 0.01;
  const auto net = read_network(path, opt);
  const auto c = net.counts();
  EXPECT_EQ(c.ends, 4);
  EXPECT_EQ(c.junctions, 2);
  EXPECT_NEAR(c.total_length, a.length() * 1e-3, 1e-9);
  std::vector<Vec3> junctions;
  for (int i = 0; i < net.num_nodes(); ++i)
    if (net.degree(i) == 3) junctions.push_back(net.node(i) * 1e3);
  ASSERT_EQ(junctions.size(), 2u);
  for (const Vec3& j : {a.j1, a.j2}) {
    const bool found = (junctions[0] - j).norm() < 1e-9 || (junctions[1] - j).norm() < 1e-9;
    EXPECT_TRUE(found) << "junction at " << j.transpose() << " mm";
  }
}

TEST(ReadLegacyVtk, VmtkPathsAsLegacyVtkGiveTheSameTree) {
  const auto dir = scratch_dir("io_vmtk_legacy");
  const Aorta a;
  auto poly = a.vmtk();
  poly.point_data.pop_back();  // legacy SCALARS: one component
  const auto path = write_file(dir, "aorta.vtk", legacy_text(poly));
  ReadOptions opt;
  opt.length_unit = "mm";
  const auto c = read_network(path, opt).counts();
  EXPECT_EQ(c.ends, 4);
  EXPECT_EQ(c.junctions, 2);
}

TEST_F(ReadersWithVtk, VmtkPathsOfADeepTreeMergeLevelByLevel) {
  // A planar binary tree of depth 6 (64 outlets), one VMTK-style path per outlet.
  constexpr int depth = 6;
  TestPoly p;
  std::vector<double> radius;
  for (int leaf = 0; leaf < (1 << depth); ++leaf) {
    std::vector<long long> ids;
    Vec3 x(0, 0, 0);
    double angle = -std::numbers::pi / 2;
    for (int level = 0; level <= depth; ++level) {
      if (level > 0) angle += ((leaf >> (depth - level)) & 1 ? 1.0 : -1.0) * std::numbers::pi / 6;
      const double len = 40.0 * std::pow(0.8, level), r = 5.0 * std::pow(0.8, level);
      const Vec3 y = x + len * Vec3(std::cos(angle), std::sin(angle), 0);
      for (const auto& q : line_points(x, y, 0.5, level == 0)) {
        ids.push_back(static_cast<long long>(p.points.size()));
        p.points.push_back(q);
        radius.push_back(r);
      }
      x = y;
    }
    p.lines.push_back(ids);
  }
  p.point_data.push_back({"MaximumInscribedSphereRadius", radius});
  const auto file = write_file(scratch_dir("io_vmtk_deep"), "tree.vtp", vtp_text(p));
  ReadOptions opt;
  opt.length_unit = "mm";
  const auto c = read_network(file, opt).counts();
  EXPECT_EQ(c.ends, (1 << depth) + 1);
  EXPECT_EQ(c.junctions, (1 << depth) - 1);
  EXPECT_EQ(c.branches, (1 << (depth + 1)) - 1);
  EXPECT_EQ(c.loops, 0);
}

TEST_F(ReadersWithVtk, VmtkBranchSplitCenterlinesJoinAtTheBlankedRegion) {
  // Two centerlines: trunk (group 0), bifurcation region (group 1, blanked), daughters 2 and 3.
  TestPoly p;
  std::vector<double> radius;
  std::vector<double> line_ids, tract_ids, blanking, groups;
  auto cell = [&](const std::vector<Vec3>& pts, double r, int line, int tract, int blank, int group) {
    std::vector<long long> ids;
    for (const auto& x : pts) {
      ids.push_back(static_cast<long long>(p.points.size()));
      p.points.push_back(x);
      radius.push_back(r);
    }
    p.lines.push_back(ids);
    line_ids.push_back(line), tract_ids.push_back(tract), blanking.push_back(blank), groups.push_back(group);
  };
  const Vec3 in(0, 0, 0), end_trunk(0, 0, -50), fork(0, 0, -58), left(-20, 0, -100), right(20, 0, -100);
  const Vec3 l0 = fork + (left - fork).normalized() * 5.0, r0 = fork + (right - fork).normalized() * 5.0;
  for (int line = 0; line < 2; ++line) {
    const Vec3 jitter(0, line * 0.01, 0);  // the second centerline's trunk is a slightly different copy
    auto trunk = line_points(in + jitter, end_trunk + jitter, 2.0);
    cell(trunk, 8.0, line, 0, 0, 0);
    const Vec3 d0 = line == 0 ? l0 : r0;
    std::vector<Vec3> blank{end_trunk + jitter, fork, d0};
    cell(blank, 7.0, line, 1, 1, 1);
    cell(line_points(d0, line == 0 ? left : right, 2.0), line == 0 ? 4.0 : 3.0, line, 2, 0, line == 0 ? 2 : 3);
  }
  p.point_data.push_back({"MaximumInscribedSphereRadius", radius});
  p.cell_data.push_back({"CenterlineIds", line_ids, 1, "Int32"});
  p.cell_data.push_back({"TractIds", tract_ids, 1, "Int32"});
  p.cell_data.push_back({"Blanking", blanking, 1, "Int32"});
  p.cell_data.push_back({"GroupIds", groups, 1, "Int32"});
  const auto dir = scratch_dir("io_branch_split");
  const auto path = write_file(dir, "split.vtp", vtp_text(p));
  ReadOptions opt;
  opt.length_unit = "mm";
  const auto cl = read_centerlines(path, opt);
  ASSERT_EQ(cl.branches.size(), 3u);
  EXPECT_EQ(cl.branches[0].name, "group_0");
  EXPECT_EQ(cl.branches[1].name, "group_2");
  EXPECT_EQ(cl.branches[2].name, "group_3");
  // Both daughters start where the (first centerline's) trunk ends, then run through the region.
  for (int b : {1, 2}) {
    EXPECT_LT((cl.branches[static_cast<size_t>(b)].points.front() - end_trunk * 1e-3).norm(), 1e-12);
    EXPECT_LT((cl.branches[static_cast<size_t>(b)].points[1] - fork * 1e-3).norm(), 1e-12);
  }
  EXPECT_LT((cl.branches[1].points.back() - left * 1e-3).norm(), 1e-12);
  EXPECT_LT((cl.branches[2].points.back() - right * 1e-3).norm(), 1e-12);
  EXPECT_DOUBLE_EQ(cl.branches[1].radii.back(), 4e-3);
  const auto c = read_network(path, opt).counts();
  EXPECT_EQ(c.branches, 3);
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
}

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

TEST_F(ReadersWithVtk, PlainPolylinesWithRadiusAreJoinedAtSharedPoints) {
  // A tree of three polylines: cell 1 shares the end point id of cell 0, cell 2 repeats its
  // coordinates under a new id. Array named "Radius" (any case is accepted).
  TestPoly p;
  std::vector<double> r;
  auto pts = [&](const std::vector<Vec3>& xs, double radius) {
    std::vector<long long> ids;
    for (const auto& x : xs) {
      ids.push_back(static_cast<long long>(p.points.size()));
      p.points.push_back(x);
      r.push_back(radius);
    }
    return ids;
  };
  auto c0 = pts(line_points(Vec3(0, 0, 0), Vec3(0.05, 0, 0), 0.01), 0.004);
  auto c1 = pts(line_points(Vec3(0.05, 0, 0), Vec3(0.08, 0.03, 0), 0.01, false), 0.003);
  c1.insert(c1.begin(), c0.back());
  auto c2 = pts(line_points(Vec3(0.05, 0, 0), Vec3(0.08, -0.03, 0), 0.01), 0.002);
  p.lines = {c0, c1, c2};
  p.point_data.push_back({"Radius", r});
  const auto dir = scratch_dir("io_plain");
  const auto file = write_file(dir, "plain.vtp", vtp_text(p));
  const auto net = read_network(file);
  const auto c = net.counts();
  EXPECT_EQ(c.branches, 3);
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
  EXPECT_NEAR(c.total_length, 0.05 + 2 * std::sqrt(2.0) * 0.03, 1e-12);
  EXPECT_NEAR(c.radius_min, 0.002, 1e-15);
  EXPECT_NEAR(c.radius_max, 0.004, 1e-15);
}

TEST_F(ReadersWithVtk, TwoPointLineCellsAreChainedIntoBranches) {
  TestPoly p;
  std::vector<double> r;
  for (int i = 0; i <= 20; ++i) {
    p.points.emplace_back(0.001 * i, 0, 0);
    r.push_back(0.002);
  }
  for (long long i = 0; i < 20; ++i) p.lines.push_back({i, i + 1});
  p.point_data.push_back({"radii", r});
  const auto file = write_file(scratch_dir("io_soup"), "soup.vtp", vtp_text(p));
  ReadOptions opt;
  opt.build.max_segment_length = 0.0;
  const auto cl = read_centerlines(file, opt);
  ASSERT_EQ(cl.branches.size(), 1u);
  EXPECT_EQ(cl.branches[0].points.size(), 21u);
  const auto c = read_network(file, opt).counts();
  EXPECT_EQ(c.segments, 1);
  EXPECT_NEAR(c.total_length, 0.02, 1e-15);
}

TEST(ReadLegacyVtk, TreeWithRadii) {
  // Like the BlueFern coronary files: lines between bifurcations sharing end-point ids, mm.
  TestPoly p;
  std::vector<double> r;
  auto add = [&](const Vec3& x, double radius) {
    p.points.push_back(x);
    r.push_back(radius);
    return static_cast<long long>(p.points.size() - 1);
  };
  std::vector<long long> l0, l1, l2;
  for (int i = 0; i <= 10; ++i) l0.push_back(add(Vec3(i, 0, 0), 2.0));
  l1.push_back(l0.back());
  l2.push_back(l0.back());
  for (int i = 1; i <= 5; ++i) l1.push_back(add(Vec3(10 + i, i, 0), 1.5));
  for (int i = 1; i <= 7; ++i) l2.push_back(add(Vec3(10 + i, -i, 0.5 * i), 1.0));
  p.lines = {l0, l1, l2};
  p.point_data.push_back({"radii", r});
  const auto file = write_file(scratch_dir("io_legacy"), "tree.vtk", legacy_text(p));
  ReadOptions opt;
  opt.length_unit = "mm";
  opt.build.max_segment_length = 0.0;
  opt.build.radius_change = 0.0;
  const auto net = read_network(file, opt);
  const auto c = net.counts();
  EXPECT_EQ(c.branches, 3);
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
  EXPECT_EQ(c.segments, 3);
  EXPECT_NEAR(c.total_length, (10 + 5 * std::sqrt(2.0) + 7 * 1.5) * 1e-3, 1e-12);
  EXPECT_NEAR(c.radius_max, 2e-3, 1e-15);
  EXPECT_NEAR(c.radius_min, (1.0 * 7 + 2.0 * 0) / 7 * 1e-3, 0.2e-3);
}

TEST_F(ReadersWithVtk, ClosedRingIsALoopOfTwoBranches) {
  // One closed polyline cell (last id = first id) plus a feeding vessel: one loop.
  TestPoly p;
  std::vector<double> r;
  for (int i = 0; i < 12; ++i) {
    const double a = 2 * std::numbers::pi * i / 12;
    p.points.emplace_back(0.01 * std::cos(a), 0.01 * std::sin(a), 0);
    r.push_back(0.001);
  }
  p.points.emplace_back(0.03, 0, 0);
  r.push_back(0.002);
  std::vector<long long> ring;
  for (long long i = 0; i < 12; ++i) ring.push_back(i);
  ring.push_back(0);
  p.lines = {ring, {12, 0}};
  p.point_data.push_back({"radius", r});
  const auto file = write_file(scratch_dir("io_ring"), "ring.vtp", vtp_text(p));
  const auto c = read_network(file).counts();
  EXPECT_EQ(c.loops, 1);
  EXPECT_EQ(c.ends, 1);
  EXPECT_EQ(c.branches, 3);
  EXPECT_EQ(c.components, 1);
}

TEST_F(ReadersWithVtk, LengthUnitScalesCoordinatesAndRadii) {
  TestPoly p;
  p.points = {Vec3(0, 0, 0), Vec3(10, 0, 0)};
  p.lines = {{0, 1}};
  p.point_data.push_back({"radius", {2.0, 2.0}});
  const auto file = write_file(scratch_dir("io_units"), "tube.vtp", vtp_text(p));
  for (const auto& [unit, f] : std::vector<std::pair<std::string, double>>{{"mm", 1e-3}, {"cm", 1e-2}}) {
    ReadOptions opt;
    opt.length_unit = unit;
    const auto cl = read_centerlines(file, opt);
    EXPECT_NEAR(cl.branches[0].points[1].x(), 10 * f, 1e-15) << unit;
    EXPECT_NEAR(cl.branches[0].radii[0], 2 * f, 1e-15) << unit;
  }
  ReadOptions opt;
  opt.length_factor = 0.5;
  EXPECT_NEAR(read_centerlines(file, opt).branches[0].points[1].x(), 5.0, 1e-15);
  opt = {};
  opt.length_unit = "furlong";
  EXPECT_CONTAINS(error_of([&] { (void)read_centerlines(file, opt); }), "furlong");
}

// ---------------------------------------------------------------------------------------
// YAML and svOneDSolver

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

/// A small deck: parent 0 -> 1 -> 2 (vessel "main", two segments) and a daughter starting 0.3 cm
/// off node 1 (node 5), joined to node 1 by a JOINT whose node field names the daughter's node.
std::string small_deck(const std::string& daughter_in_area = "0.2") {
  return "# svOneDSolver deck written by the test\n"
         "MODEL test_\n"
         "NODE 0 0.0 0.0 0.0\nNODE 1 0.0 0.0 -2.0\nNODE 2 0.0 0.0 -5.0\n"
         "NODE 5 0.3 0.0 -2.0\nNODE 6 2.0 0.0 -4.0\nNODE 9 9.0 9.0 9.0\n"
         "SEGMENT main_0 0 2.0 10 0 1 1.0 0.8 0.0 MAT1 NONE 0.0 0 0 NOBOUND NONE\n"
         "SEGMENT main_1 1 3.0 10 1 2 0.8 0.5 0.0 MAT1 NONE 0.0 0 0 RESISTANCE R1\n"
         "SEGMENT side_0 2 2.7 10 5 6 " +
         daughter_in_area +
         " 0.1 0.0 MAT1 NONE 0.0 0 0 RESISTANCE R2\n"
         "JOINT J1 5 IN1 OUT1\nJOINTINLET IN1 1 0\nJOINTOUTLET OUT1 2 1 2\n"
         "DATATABLE R1 LIST\n0.0 100.0\nENDDATATABLE\n"
         "DATATABLE R2 LIST\n0.0 200.0\nENDDATATABLE\n"
         "MATERIAL MAT1 OLUFSEN 1.06 0.04 0.0 1.0 2.0e7 -22.5267 8.65e5\n";
}

TEST(ReadSvOneD, DeckSegmentsJoinedAtTheJoint) {
  const auto file = write_file(scratch_dir("io_oned"), "deck.in", small_deck());
  ReadOptions opt;
  opt.build.max_segment_length = 0.0;
  opt.build.radius_change = 0.0;
  const auto net = read_network(file, opt);
  const auto c = net.counts();
  EXPECT_EQ(c.segments, 3);
  EXPECT_EQ(c.nodes, 4);  // node 5 is merged into node 1, node 9 is unused
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
  EXPECT_NEAR(c.total_length, (2.0 + 3.0 + 2.7) * 1e-2, 1e-15);  // deck lengths, cm -> m
  const auto r = [](double area_cm2) { return std::sqrt(area_cm2 / std::numbers::pi) * 1e-2; };
  // Each segment's radius is the mean of its end radii.
  EXPECT_NEAR(net.segment(0).radius, 0.5 * (r(1.0) + r(0.8)), 1e-15);
  EXPECT_NEAR(net.segment(2).radius, 0.5 * (r(0.2) + r(0.1)), 1e-15);
  EXPECT_EQ(net.branch(0).name, "main.1");  // main is cut at the junction
  EXPECT_EQ(net.branch(1).name, "main.2");
  EXPECT_EQ(net.branch(2).name, "side");
  // The daughter starts at the parent's node 1.
  EXPECT_EQ(net.segment(2).node_from, net.segment(0).node_to);
  EXPECT_LT((net.node(net.segment(2).node_from) - Vec3(0, 0, -0.02)).norm(), 1e-15);
  // Split further by max_segment_length (1 cm): 2 + 3 + 3 pieces, same total length.
  opt.build.max_segment_length = 0.01;
  const auto fine = read_network(file, opt).counts();
  EXPECT_EQ(fine.segments, 8);
  EXPECT_NEAR(fine.total_length, c.total_length, 1e-15);
  const auto cl = read_centerlines(file);
  ASSERT_EQ(cl.branches.size(), 3u);
  EXPECT_NEAR(cl.branches[0].radii[0], r(1.0), 1e-15);
}

// ---------------------------------------------------------------------------------------
// Writers

Network sample_network() {
  Centerlines c;
  c.source = "sample";
  c.branches.push_back({"aorta", {Vec3(0, 0, 0), Vec3(0, 0, -0.03), Vec3(0.001, 0, -0.06)}, {0.012, 0.011, 0.010}});
  c.branches.push_back({"left <iliac>", {Vec3(0.001, 0, -0.06), Vec3(-0.02, 0, -0.09)}, {0.005, 0.004}});
  c.branches.push_back(
      {"right \"iliac\"\n\\2", {Vec3(0.001, 0, -0.06), Vec3(0.0234567891234, 1e-7, -0.0912)}, {0.0051, 0.0037}});
  BuildOptions b;
  b.max_segment_length = 7e-3;
  return Network::build(c, b);
}

void expect_identical(const Network& a, const Network& b) {
  ASSERT_EQ(a.num_nodes(), b.num_nodes());
  ASSERT_EQ(a.num_segments(), b.num_segments());
  ASSERT_EQ(a.num_branches(), b.num_branches());
  for (int i = 0; i < a.num_nodes(); ++i) EXPECT_EQ(a.node(i), b.node(i)) << "node " << i;
  for (int s = 0; s < a.num_segments(); ++s) {
    EXPECT_EQ(a.segment(s).node_from, b.segment(s).node_from);
    EXPECT_EQ(a.segment(s).node_to, b.segment(s).node_to);
    EXPECT_EQ(a.segment(s).radius, b.segment(s).radius);
    EXPECT_EQ(a.segment(s).radius_from, b.segment(s).radius_from) << "segment " << s;  // the taper
    EXPECT_EQ(a.segment(s).radius_to, b.segment(s).radius_to) << "segment " << s;
    EXPECT_EQ(a.segment(s).length, b.segment(s).length);
    EXPECT_EQ(a.segment(s).branch, b.segment(s).branch);
  }
  for (int k = 0; k < a.num_branches(); ++k) {
    EXPECT_EQ(a.branch(k).name, b.branch(k).name);
    EXPECT_EQ(a.branch(k).nodes, b.branch(k).nodes);
    EXPECT_EQ(a.branch(k).segments, b.branch(k).segments);
  }
}

TEST_F(ReadersWithVtk, VtpRoundTripIsExact) {
  const auto net = sample_network();
  const auto dir = scratch_dir("io_vtp_roundtrip");
  const auto file = (dir / "net.vtp").string();
  std::vector<double> pressure(static_cast<size_t>(net.num_nodes()));
  for (size_t i = 0; i < pressure.size(); ++i) pressure[i] = 1000.0 + static_cast<double>(i);
  std::vector<double> flow(static_cast<size_t>(net.num_segments()), 1e-6);
  std::vector<double> velocity(3 * static_cast<size_t>(net.num_segments()), 0.1);
  write_network_vtp(net, file, {{"pressure", pressure, 1}}, {{"flow_rate", flow, 1}, {"velocity", velocity, 3}});
  EXPECT_FALSE(fs::exists(file + ".partial"));
  const auto back = read_network(file);
  expect_identical(net, back);
  // Reading our own file as centerlines gives the branches back.
  const auto cl = read_centerlines(file);
  ASSERT_EQ(cl.branches.size(), 3u);
  EXPECT_EQ(cl.branches[1].name, "left <iliac>");
  // A length unit given for a file in metres is ignored, with a warning.
  ExpectWarnings w;
  ReadOptions opt;
  opt.length_unit = "mm";
  expect_identical(net, read_network(file, opt));
  EXPECT_TRUE(w.contains("declares length_unit m"));
}

TEST(WriteNetwork, YamlRoundTripIsExact) {
  const auto net = sample_network();
  const auto file = (scratch_dir("io_yaml_roundtrip") / "net.yaml").string();
  write_network_yaml(net, file);
  expect_identical(net, read_network(file));
  const auto cl = read_centerlines(file);  // the branches alone are a valid network file too
  ASSERT_EQ(cl.branches.size(), 3u);
  EXPECT_EQ(cl.branches[2].name, "right \"iliac\"\n\\2");
  EXPECT_EQ(cl.branches[0].points.size(), net.branch(0).nodes.size());
}

TEST(WriteNetwork, BadArrayLeavesNoFile) {
  const auto net = sample_network();
  const auto file = (scratch_dir("io_write_bad") / "net.vtp").string();
  EXPECT_THROW(write_network_vtp(net, file, {{"pressure", {1.0, 2.0}, 1}}), Error);
  EXPECT_THROW(
      write_network_vtp(net, file, {}, {{"radius", std::vector<double>(static_cast<size_t>(net.num_segments())), 1}}),
      Error);
  EXPECT_FALSE(fs::exists(file));
  EXPECT_FALSE(fs::exists(file + ".partial"));
  EXPECT_THROW(write_network(net, (scratch_dir("io_write_bad") / "net.obj").string()), Error);
}

// ---------------------------------------------------------------------------------------
// Bad input: one flowire::Error naming the file and the place, nothing printed by VTK.

TestPoly tube(std::vector<double> radii, std::string radius_name = "radius") {
  TestPoly p;
  for (size_t i = 0; i < radii.size(); ++i) p.points.emplace_back(0.01 * static_cast<double>(i), 0, 0);
  std::vector<long long> ids;
  for (size_t i = 0; i < radii.size(); ++i) ids.push_back(static_cast<long long>(i));
  p.lines = {ids};
  p.point_data.push_back({std::move(radius_name), std::move(radii)});
  return p;
}

TEST_F(ReadersWithVtk, BadVtkInputGivesOneErrorNamingFileAndPoint) {
  const auto dir = scratch_dir("io_bad_vtk");
  struct Case {
    std::string name, text, expected;
  };
  auto dup = tube({1, 1, 1, 1});
  dup.points[2] = dup.points[1];
  auto loop = tube({1, 1, 1});
  loop.lines.push_back({2, 2});
  auto out_of_range = tube({1, 1, 1});
  out_of_range.lines[0].push_back(7);
  auto nan_point = tube({1, 1, 1});
  nan_point.points[2].y() = std::nan("");
  const std::string valid = vtp_text(tube({1, 1, 1}));
  std::vector<Case> cases{
      {"noradius.vtp", vtp_text(tube({1, 1, 1}, "Scalars_")), "no radius array"},
      {"zero.vtp", vtp_text(tube({1, 0, 1})), "point 1 (line cell 0): radius 0 is not positive"},
      {"negative.vtp", vtp_text(tube({1, 1, -2})), "point 2 (line cell 0): radius -2 is not positive"},
      {"nan.vtp", vtp_text(tube({1, std::nan(""), 1})), "point 1 (line cell 0): radius is not finite"},
      {"nanx.vtk", legacy_text(nan_point), "point 2 (line cell 0): coordinate is not finite"},
      {"empty.vtp", "", "the file is empty"},
      {"empty.vtk", "", "the file is empty"},
      {"truncated.vtp", valid.substr(0, valid.size() / 2), "truncated"},
      {"duplicate.vtp", vtp_text(dup), "line cell 0: points 1 and 2 (ids 1 and 2) coincide (duplicate point)"},
      {"selfloop.vtp", vtp_text(loop), "line cell 1 joins point 2 to itself (self-loop)"},
      {"range.vtp", vtp_text(out_of_range), "line cell 0: point id 7 is out of range"},
      {"garbage.vtp", "<VTKFile type=\"PolyData\"><PolyData><Piece NumberOfPoints=\"2\">&&&<<</VTKFile>",
       "cannot read"},
      {"notvtk.vtp", "hello", "not a VTK file"},
      {"huge.vtp",
       "<VTKFile type=\"PolyData\"><PolyData><Piece NumberOfPoints=\"99999999999\"></Piece></PolyData></VTKFile>",
       "NumberOfPoints=\"99999999999\" does not fit"},
      {"legacy_bad.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 99999999999 float\n",
       "POINTS"},
      {"surface.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 1 float\n0 0 0\n",
       "POLYDATA"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const auto file = write_file(dir, c.name, c.text);
    ::testing::internal::CaptureStderr();
    const auto msg = error_of([&] { (void)read_network(file); });
    const auto printed = ::testing::internal::GetCapturedStderr();
    EXPECT_CONTAINS(msg, c.expected);
    EXPECT_CONTAINS(msg, file);
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    EXPECT_EQ(printed, "") << "VTK printed: " << printed;
  }
}

TEST_F(ReadersWithVtk, DisconnectedPiecesAreAnErrorOrTheInletPieceIsKept) {
  TestPoly p;
  p.points = {Vec3(0, 0, 0), Vec3(0.05, 0, 0), Vec3(0, 0.1, 0), Vec3(0.02, 0.1, 0), Vec3(0.04, 0.1, 0)};
  p.lines = {{0, 1}, {2, 3, 4}};
  p.point_data.push_back({"radius", {0.008, 0.008, 0.003, 0.003, 0.003}});
  const auto file = write_file(scratch_dir("io_pieces"), "pieces.vtp", vtp_text(p));
  const auto msg = error_of([&] { (void)read_network(file); });
  EXPECT_CONTAINS(msg, "2 disconnected pieces");
  EXPECT_CONTAINS(msg, "piece 1");
  EXPECT_CONTAINS(msg, "branch_1");
  ExpectWarnings w;
  ReadOptions opt;
  opt.keep_inlet_piece = true;
  const auto net = read_network(file, opt);
  EXPECT_EQ(net.counts().components, 1);
  EXPECT_NEAR(net.counts().radius_max, 0.008, 1e-15);  // the piece with the widest end
  EXPECT_NEAR(net.counts().total_length, 0.05, 1e-15);
  ASSERT_EQ(w.warnings().size(), 1u);
  EXPECT_TRUE(w.contains("disconnected pieces"));
}

// ---------------------------------------------------------------------------------------
// Trees written one polyline per branch, as a VTK writer or VMTK's branch export does: every
// branch carries its own radius, the junction point is repeated at the start of each daughter.

struct SplitTree {
  TestPoly poly;
  std::vector<double> branch_radius;  // per line cell
};

/// A Y (parent r0, daughters r1 and r2) as three polylines with their own point ids. The
/// parent's points are a + (b − a)·i/n, as writers compute them; `gap` moves each daughter's
/// first point away from b by that vector.
SplitTree split_y(double r0, double r1, double r2, const Vec3& gap = Vec3::Zero()) {
  SplitTree t;
  std::vector<double> r;
  const Vec3 a(0.0, 0.0, 0.0), b(0.0137, 0.0011, -0.0023);
  auto branch = [&](const Vec3& from, const Vec3& to, double radius, int n) {
    std::vector<long long> ids;
    for (int i = 0; i <= n; ++i) {
      ids.push_back(static_cast<long long>(t.poly.points.size()));
      t.poly.points.push_back(from + (to - from) * (static_cast<double>(i) / n));
      r.push_back(radius);
    }
    t.poly.lines.push_back(ids);
    t.branch_radius.push_back(radius);
  };
  branch(a, b, r0, 7);
  branch(b + gap, b + Vec3(0.011, 0.007, 0.001), r1, 5);
  branch(b + gap, b + Vec3(0.009, -0.006, 0.002), r2, 3);
  t.poly.point_data.push_back({"radius", r});
  return t;
}

TEST(ReadSplitPolylines, EverySegmentTakesTheRadiusOfItsOwnBranch) {
  const auto t = split_y(2e-3, 1.6e-3, 1.1e-3);
  const auto file = write_file(scratch_dir("io_split_radius"), "y.vtk", legacy_text(t.poly));
  ReadOptions opt;
  opt.build.max_segment_length = 2e-3;
  const auto net = read_network(file, opt);
  const auto c = net.counts();
  ASSERT_EQ(c.branches, 3);
  EXPECT_EQ(c.junctions, 1);
  EXPECT_EQ(c.ends, 3);
  for (int s = 0; s < net.num_segments(); ++s) {
    const auto& seg = net.segment(s);
    // The branch of a segment: the line cell whose straight line holds its midpoint.
    const Vec3 mid = 0.5 * (net.node(seg.node_from) + net.node(seg.node_to));
    int cell = -1;
    for (size_t k = 0; k < t.poly.lines.size(); ++k) {
      const Vec3 p = t.poly.points[static_cast<size_t>(t.poly.lines[k].front())];
      const Vec3 q = t.poly.points[static_cast<size_t>(t.poly.lines[k].back())];
      if ((mid - p).cross(q - p).norm() <= 1e-12 * (q - p).norm() * (q - p).norm()) cell = static_cast<int>(k);
    }
    ASSERT_GE(cell, 0) << "segment " << s;
    const double r = t.branch_radius[static_cast<size_t>(cell)];
    EXPECT_DOUBLE_EQ(seg.radius, r) << "segment " << s;
    EXPECT_DOUBLE_EQ(seg.radius_from, r) << "segment " << s;
    EXPECT_DOUBLE_EQ(seg.radius_to, r) << "segment " << s;
  }
}

TEST(ReadSplitPolylines, EndsThatDifferByRoundingAreOneNode) {
  // The daughters start one unit in the last place away from the parent's end, on every
  // axis: what two writers computing the same point in different orders produce.
  const Vec3 b(0.0137, 0.0011, -0.0023);
  const Vec3 ulp(std::nextafter(b.x(), 1.0) - b.x(), std::nextafter(b.y(), 1.0) - b.y(),
                 std::nextafter(b.z(), 1.0) - b.z());
  for (const Vec3& gap : {ulp, Vec3(-ulp), Vec3(3.0 * ulp)}) {
    const auto t = split_y(2e-3, 1.6e-3, 1.1e-3, gap);
    const auto file = write_file(scratch_dir("io_split_rounding"), "y.vtk", legacy_text(t.poly));
    const auto c = read_network(file).counts();
    EXPECT_EQ(c.components, 1);
    EXPECT_EQ(c.junctions, 1);
    EXPECT_EQ(c.ends, 3);
    EXPECT_EQ(c.branches, 3);
  }
}

TEST(ReadSplitPolylines, ARealGapIsStillAnError) {
  // 1% of the smaller daughter's radius is a gap, not rounding: one clear error naming the pieces.
  const auto t = split_y(2e-3, 1.6e-3, 1.1e-3, Vec3(0.0, 1.1e-5, 0.0));
  const auto file = write_file(scratch_dir("io_split_gap"), "y.vtk", legacy_text(t.poly));
  const auto msg = error_of([&] { (void)read_network(file); });
  EXPECT_CONTAINS(msg, "y.vtk");
  EXPECT_CONTAINS(msg, "disconnected pieces");
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

TEST(ReadBadInput, SvOneDErrorsNameFileAndLine) {
  const auto dir = scratch_dir("io_bad_oned");
  const auto deck = small_deck();
  struct Case {
    std::string name, text, expected;
  };
  auto replace = [&](const std::string& from, const std::string& to) {
    auto s = deck;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  std::vector<Case> cases{
      {"empty.in", "", "the file is empty"},
      {"zero_area.in", small_deck("0.0"), "deck.in"},
      {"nan_node.in", replace("NODE 6 2.0", "NODE 6 nan"), "NODE 6: coordinate is not finite"},
      {"missing_node.in", replace("0 1 1.0 0.8", "0 7 1.0 0.8"), "SEGMENT main_0: node 7 is not defined"},
      {"self_loop.in", replace("0 1 1.0 0.8", "1 1 1.0 0.8"), "SEGMENT main_0 starts and ends at node 1 (self-loop)"},
      {"dup_node.in", replace("NODE 9 9.0", "NODE 2 9.0"), "NODE 2 is defined twice"},
      {"no_segments.in", "NODE 0 0 0 0\n", "no SEGMENT cards"},
      {"bad_joint.in", replace("JOINTOUTLET OUT1 2 1 2", "JOINTOUTLET OUT1 2 1 42"), "segment 42 is not defined"},
      {"short.in", replace("SEGMENT side_0 2 2.7 10 5 6 0.2 0.1", "SEGMENT side_0 2 2.7 10 5"),
       "short.in:11: SEGMENT side_0 inlet area: 'MAT1' is not a number"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const auto file = write_file(dir, c.name, c.text);
    const auto msg = error_of([&] { (void)read_network(file); });
    EXPECT_CONTAINS(msg, c.name == "zero_area.in"
                             ? std::string("zero_area.in:11: SEGMENT side_0: area 0 is not positive")
                             : c.expected);
    EXPECT_CONTAINS(msg, file);
  }
}

/// Big-endian bytes of a value, as legacy BINARY files store them.
template <class T>
std::string big_endian(T v) {
  std::string b(sizeof v, '\0');
  std::memcpy(b.data(), &v, sizeof v);
  if (std::endian::native == std::endian::little) std::reverse(b.begin(), b.end());
  return b;
}

TEST(ReadLegacyVtk, BinaryFileWithOldCellLayout) {
  std::string s = "# vtk DataFile Version 4.2\nbinary test\nBINARY\nDATASET POLYDATA\nPOINTS 3 double\n";
  for (const double x : {0.0, 0.0, 0.0, 10.0, 0.0, 0.0, 10.0, 5.0, 0.0}) s += big_endian(x);
  s += "\nLINES 1 4\n";
  for (const int32_t v : {3, 0, 1, 2}) s += big_endian(v);
  s += "\nPOINT_DATA 3\nSCALARS radius float 1\nLOOKUP_TABLE default\n";
  for (const float r : {2.0F, 1.5F, 1.0F}) s += big_endian(r);
  s += "\n";
  const auto file = write_file(scratch_dir("io_legacy_binary"), "bin.vtk", s);
  ReadOptions opt;
  opt.length_unit = "mm";
  const auto cl = read_centerlines(file, opt);
  ASSERT_EQ(cl.branches.size(), 1u);
  ASSERT_EQ(cl.branches[0].points.size(), 3u);
  EXPECT_NEAR(cl.branches[0].points[2].y(), 5e-3, 1e-15);
  EXPECT_NEAR(cl.branches[0].radii[1], 1.5e-3, 1e-15);
  // Cut short inside the point coordinates: an error, not garbage.
  const auto cut = write_file(scratch_dir("io_legacy_binary"), "cut.vtk", s.substr(0, 100));
  EXPECT_CONTAINS(error_of([&] { (void)read_network(cut); }), "cut.vtk");
}

TEST_F(ReadersWithVtk, TruncatedFlowireVtpIsAnError) {
  const auto dir = scratch_dir("io_truncated_vtp");
  const auto file = (dir / "net.vtp").string();
  write_network_vtp(sample_network(), file);
  std::ifstream in(file, std::ios::binary);
  const std::string full((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const double f : {0.1, 0.5, 0.9, 0.99}) {
    const auto cut =
        write_file(dir, "cut.vtp", full.substr(0, static_cast<size_t>(f * static_cast<double>(full.size()))));
    ::testing::internal::CaptureStderr();
    const auto msg = error_of([&] { (void)read_network(cut); });
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
    EXPECT_CONTAINS(msg, "cut.vtp");
  }
}

TEST(ReadFormats, EveryReaderIsFoundByExtensionAndByContent) {
  // Files of each format in the reader table (flowire's .vtp, its .yaml, an svOneDSolver
  // deck), read once under their own extension and once renamed to one no
  // reader claims: the content alone must pick the same reader and the same network.
  const auto dir = scratch_dir("io_formats");
  const Network net = sample_network();
  write_network_vtp(net, (dir / "net.vtp").string());
  write_network_yaml(net, (dir / "net.yaml").string());
  write_file(dir, "deck.in", small_deck());
  ASSERT_EQ(network_readers().size(), 3u);  // one file below for each
  for (const std::string f : {"net.vtp", "net.yaml", "deck.in"}) {
    const auto own = read_network((dir / f).string());
    std::filesystem::copy_file(dir / f, dir / (f + ".dat"), std::filesystem::copy_options::overwrite_existing);
    const auto sniffed = read_network((dir / (f + ".dat")).string());
    EXPECT_EQ(own.num_segments(), sniffed.num_segments()) << f;
    EXPECT_EQ(own.num_nodes(), sniffed.num_nodes()) << f;
  }
  EXPECT_EQ(network_extensions(), ".vtp, .vtk, .yaml, .yml, .in");
}

TEST(ReadBadInput, UnknownFormatAndMissingFile) {
  const auto dir = scratch_dir("io_bad_format");
  const auto file = write_file(dir, "net.txt", "just words\n");
  EXPECT_CONTAINS(error_of([&] { (void)read_network(file); }), "unknown network format");
  EXPECT_CONTAINS(error_of([&] { (void)read_network((dir / "absent.yaml").string()); }), "absent.yaml");
  EXPECT_CONTAINS(error_of([&] { (void)read_network(dir.string()); }), "directory");
}

}  // namespace
}  // namespace flowire::vessels
