// Reading lumen surfaces (vessels/src/surface_io.cpp) from files VTK's own writers produce:
// a closed tetrahedron round-trips through .stl (binary and ASCII), .obj and .vtp with its
// enclosed volume (so its orientation) intact, polygons become fans and triangle strips keep
// one orientation, the length factor scales, and bad files are input errors naming the file.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <vtkCellArray.h>
#include <vtkNew.h>
#include <vtkOBJWriter.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSTLWriter.h>
#include <vtkXMLPolyDataWriter.h>

#include "flowire/common/error.hpp"
#include "flowire/vessels/surface.hpp"
#include "flowire_test.hpp"

using namespace flowire::vessels;
namespace fs = std::filesystem;

namespace {

/// The tetrahedron (0,0,0), (a,0,0), (0,a,0), (0,0,a) with outward triangles: volume a³/6.
vtkNew<vtkPolyData> tetrahedron(double a) {
  vtkNew<vtkPoints> pts;
  pts->InsertNextPoint(0, 0, 0);
  pts->InsertNextPoint(a, 0, 0);
  pts->InsertNextPoint(0, a, 0);
  pts->InsertNextPoint(0, 0, a);
  vtkNew<vtkCellArray> polys;
  const vtkIdType faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (const auto& f : faces) polys->InsertNextCell(3, f);
  vtkNew<vtkPolyData> pd;
  pd->SetPoints(pts);
  pd->SetPolys(polys);
  return pd;
}

/// Volume enclosed by a closed triangulation (divergence theorem), positive when outward.
double enclosed_volume(const SurfaceMesh& m) {
  double v = 0.0;
  for (const auto& t : m.triangles)
    v += m.vertices[static_cast<size_t>(t[0])].dot(
             m.vertices[static_cast<size_t>(t[1])].cross(m.vertices[static_cast<size_t>(t[2])])) /
         6.0;
  return v;
}

/// Sum of the triangles' area vectors (½ (b − a) × (c − a)).
Vec3 area_vector(const SurfaceMesh& m) {
  Vec3 s = Vec3::Zero();
  for (const auto& t : m.triangles) {
    const Vec3& a = m.vertices[static_cast<size_t>(t[0])];
    s += 0.5 * (m.vertices[static_cast<size_t>(t[1])] - a).cross(m.vertices[static_cast<size_t>(t[2])] - a);
  }
  return s;
}

std::string write_vtp(vtkPolyData* pd, const fs::path& path) {
  vtkNew<vtkXMLPolyDataWriter> w;
  w->SetFileName(path.string().c_str());
  w->SetInputData(pd);
  EXPECT_EQ(w->Write(), 1);
  return path.string();
}

TEST(SurfaceIo, AClosedTetrahedronRoundTripsThroughEveryFormat) {
  const auto dir = flowire::testing::scratch_dir("surface_io_roundtrip");
  auto pd = tetrahedron(2.0);
  std::vector<std::string> files;
  for (const bool binary : {true, false}) {
    vtkNew<vtkSTLWriter> w;
    const auto path = dir / (binary ? "tet_binary.stl" : "tet_ascii.stl");
    w->SetFileName(path.string().c_str());
    w->SetInputData(pd);
    if (binary)
      w->SetFileTypeToBinary();
    else
      w->SetFileTypeToASCII();
    ASSERT_EQ(w->Write(), 1);
    files.push_back(path.string());
  }
  {
    vtkNew<vtkOBJWriter> w;
    const auto path = dir / "tet.obj";
    w->SetFileName(path.string().c_str());
    w->SetInputData(pd);
    ASSERT_EQ(w->Write(), 1);
    files.push_back(path.string());
  }
  files.push_back(write_vtp(pd, dir / "tet.vtp"));
  for (const auto& f : files) {
    const SurfaceMesh m = read_surface(f);
    EXPECT_EQ(m.source, f);
    ASSERT_EQ(m.triangles.size(), 4u) << f;
    // STL stores each triangle's corners: 12 points unmerged; the others share 4.
    EXPECT_EQ(m.vertices.size(), f.ends_with(".stl") ? 12u : 4u) << f;
    EXPECT_NEAR(enclosed_volume(m), 8.0 / 6.0, 1e-6) << f;  // STL stores floats
    EXPECT_LT(area_vector(m).norm(), 1e-6) << f;            // closed
    // In millimetres: the length factor scales every coordinate.
    const SurfaceMesh mm = read_surface(f, 1e-3);
    EXPECT_NEAR(enclosed_volume(mm), 8.0 / 6.0 * 1e-9, 1e-15) << f;
  }
}

TEST(SurfaceIo, PolygonsBecomeFansAndStripsKeepOneOrientation) {
  const auto dir = flowire::testing::scratch_dir("surface_io_cells");
  // A regular hexagon of unit circumradius in the plane z = 0, counter-clockwise seen from +z.
  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToDouble();
  for (int k = 0; k < 6; ++k) pts->InsertNextPoint(std::cos(k * M_PI / 3), std::sin(k * M_PI / 3), 0.0);
  vtkNew<vtkCellArray> polys;
  const vtkIdType hex[6] = {0, 1, 2, 3, 4, 5};
  polys->InsertNextCell(6, hex);
  vtkNew<vtkPolyData> polygon;
  polygon->SetPoints(pts);
  polygon->SetPolys(polys);
  const SurfaceMesh h = read_surface(write_vtp(polygon, dir / "hexagon.vtp"));
  EXPECT_EQ(h.triangles.size(), 4u);
  EXPECT_LT((area_vector(h) - Vec3(0, 0, 1.5 * std::sqrt(3.0))).norm(), 1e-12);  // all four face +z
  // A strip of unit squares along x: points (i, 0) and (i, 1) alternating; its triangles
  // (0,1,2), (1,2,3) → (2,1,3), ... must all face the same way as the first.
  vtkNew<vtkPoints> sp;
  sp->SetDataTypeToDouble();
  for (int i = 0; i < 4; ++i) {
    sp->InsertNextPoint(i, 0, 0);
    sp->InsertNextPoint(i, 1, 0);
  }
  vtkNew<vtkCellArray> strips;
  const vtkIdType ids[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  strips->InsertNextCell(8, ids);
  vtkNew<vtkPolyData> strip;
  strip->SetPoints(sp);
  strip->SetStrips(strips);
  const SurfaceMesh s = read_surface(write_vtp(strip, dir / "strip.vtp"));
  ASSERT_EQ(s.triangles.size(), 6u);
  for (const auto& t : s.triangles) {
    const Vec3& a = s.vertices[static_cast<size_t>(t[0])];
    const Vec3 n = (s.vertices[static_cast<size_t>(t[1])] - a).cross(s.vertices[static_cast<size_t>(t[2])] - a);
    EXPECT_NEAR(n.z(), -1.0, 1e-12);  // (0,0),(0,1),(1,0): clockwise seen from +z
  }
  EXPECT_NEAR(area_vector(s).norm(), 3.0, 1e-12);
}

std::string input_error(const std::string& path, double factor = 1.0) {
  try {
    (void)read_surface(path, factor);
  } catch (const flowire::Error& e) {
    EXPECT_EQ(e.kind(), flowire::ErrorKind::Input) << e.what();
    return e.what();
  }
  return "";
}

TEST(SurfaceIo, TheExtensionChoosesTheReaderAndBadFilesNameThemselves) {
  const auto dir = flowire::testing::scratch_dir("surface_io_errors");
  auto pd = tetrahedron(1.0);
  // Upper-case extensions are the same formats.
  const auto upper = write_vtp(pd, dir / "TET.VTP");
  EXPECT_EQ(read_surface(upper).triangles.size(), 4u);
  std::ofstream(dir / "shape.ply") << "ply\n";
  EXPECT_NE(input_error((dir / "shape.ply").string()).find("unknown surface format '.ply'"), std::string::npos);
  std::ofstream(dir / "empty.stl").flush();
  const std::string empty = (dir / "empty.stl").string();
  EXPECT_EQ(input_error(empty), empty + ": the surface file is empty");
  std::ofstream(dir / "text.vtp") << "not xml at all\n";
  EXPECT_NE(input_error((dir / "text.vtp").string()).find("text.vtp: not a VTK XML poly data file"), std::string::npos);
  try {
    (void)read_surface(upper, 0.0);
    ADD_FAILURE() << "a zero length factor was accepted";
  } catch (const flowire::Error& e) {
    EXPECT_EQ(e.kind(), flowire::ErrorKind::Usage);
  }
}

}  // namespace
