#pragma once
// Shared by the reader tests (test_io.cpp, test_read_*.cpp, test_polydata.cpp, test_io_write.cpp):
// the files they write (VTK XML and legacy VTK poly data with named arrays, a VMTK-style aorta,
// an svOneDSolver deck, a network to write and read back), the error a read throws, and the
// real anatomies of the shared data folder (../shared/data/real; each test skips, saying so, if
// a file is absent).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/vessels/io.hpp"
#include "flowire/vessels/network.hpp"
#include "flowire_test.hpp"

namespace flowire::vessels::test {

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

inline std::string numbers(const std::vector<double>& v) {
  std::string s;
  for (const double x : v) s += fmt::format(" {}", x);
  return s;
}

inline std::string data_array(const TestArray& a) {
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
inline std::string vtp_text(const TestPoly& p) {
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
inline std::string legacy_text(const TestPoly& p) {
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

inline std::string write_file(const std::filesystem::path& dir, const std::string& name, const std::string& text) {
  const auto path = (dir / name).string();
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

/// Points from a to b (inclusive) every `step`.
inline std::vector<Vec3> line_points(const Vec3& a, const Vec3& b, double step, bool include_first = true) {
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

/// Tests that read .vtp files: skipped, saying so, where flowire is built without VTK.
class ReadersWithVtk : public ::testing::Test {
 protected:
  void SetUp() override {
#ifndef FLOWIRE_HAVE_VTK
    GTEST_SKIP() << "built without VTK: .vtp/.vtk readers are off";
#endif
  }
};

/// A small deck: parent 0 -> 1 -> 2 (vessel "main", two segments) and a daughter starting 0.3 cm
/// off node 1 (node 5), joined to node 1 by a JOINT whose node field names the daughter's node.
inline std::string small_deck(const std::string& daughter_in_area = "0.2") {
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

// ---------------------------------------------------------------------------------------
// A network to write and read back, and the check that it came back the same

inline Network sample_network() {
  Centerlines c;
  c.source = "sample";
  c.branches.push_back({"aorta", {Vec3(0, 0, 0), Vec3(0, 0, -0.03), Vec3(0.001, 0, -0.06)}, {0.012, 0.011, 0.010}});
  c.branches.push_back({"left <iliac>", {Vec3(0.001, 0, -0.06), Vec3(-0.02, 0, -0.09)}, {0.005, 0.004}});
  c.branches.push_back(
      {"right \"iliac\"\n\\2", {Vec3(0.001, 0, -0.06), Vec3(0.0234567891234, 1e-7, -0.0912)}, {0.0051, 0.0037}});
  BuildOptions b;
  b.max_segment_length = 7e-3;
  const Network built = Network::build(c, b);
  // Non-circular sections (Segment::shape), as a lumen surface gives them: the writers must keep them.
  std::vector<Vec3> nodes(built.nodes().begin(), built.nodes().end());
  std::vector<Segment> segments(built.segments().begin(), built.segments().end());
  for (size_t s = 0; s < segments.size(); ++s) segments[s].shape = 1.0 + 0.01 * static_cast<double>(s);
  std::vector<Branch> branches(built.branches().begin(), built.branches().end());
  return Network::from_graph(std::move(nodes), std::move(segments), std::move(branches), built.source());
}

inline void expect_identical(const Network& a, const Network& b) {
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
    EXPECT_EQ(a.segment(s).shape, b.segment(s).shape) << "segment " << s;
    EXPECT_EQ(a.segment(s).branch, b.segment(s).branch);
  }
  for (int k = 0; k < a.num_branches(); ++k) {
    EXPECT_EQ(a.branch(k).name, b.branch(k).name);
    EXPECT_EQ(a.branch(k).nodes, b.branch(k).nodes);
    EXPECT_EQ(a.branch(k).segments, b.branch(k).segments);
  }
}

// ---------------------------------------------------------------------------------------
// The real anatomies of ../shared/data/real

/// A file of the shared real anatomies, by its path under data/real.
inline std::string real(const std::string& rel) {
  return (flowire::testing::shared_dir() / "data/real" / rel).string();
}

inline Network read_real(const std::string& rel, const char* unit, double max_segment_length = 5e-3) {
  ReadOptions opt;
  opt.length_unit = unit;
  opt.build.max_segment_length = max_segment_length;
  return read_network(real(rel), opt);
}

/// Radii (m) of a human artery: 0.3 mm to 20 mm.
inline void expect_physiological(const NetworkCounts& c) {
  EXPECT_GE(c.radius_min, 0.3e-3);
  EXPECT_LE(c.radius_max, 20e-3);
}

inline std::string describe(const NetworkCounts& c) {
  return "branches " + std::to_string(c.branches) + ", nodes " + std::to_string(c.nodes) + ", segments " +
         std::to_string(c.segments) + ", junctions " + std::to_string(c.junctions) + ", ends " +
         std::to_string(c.ends) + ", loops " + std::to_string(c.loops) + ", length " + std::to_string(c.total_length) +
         " m, radius " + std::to_string(c.radius_min) + " - " + std::to_string(c.radius_max) + " m";
}

}  // namespace flowire::vessels::test
