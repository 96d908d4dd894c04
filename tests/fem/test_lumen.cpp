// Real lumens from ../shared/data/real meshed by gmsh: one cap per centerline end, a closed
// (watertight) boundary, and the mesh volume against the volume VTK computes on its own
// from the file's surface (vtkFillHolesFilter + vtkMassProperties). Bad input: one error
// naming the file and the place.
#include <gtest/gtest.h>
#include <vtkClipPolyData.h>
#include <vtkFillHolesFilter.h>
#include <vtkImplicitBoolean.h>
#include <vtkMassProperties.h>
#include <vtkNew.h>
#include <vtkPlane.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataNormals.h>
#include <vtkSTLReader.h>
#include <vtkSphere.h>
#include <vtkTriangleFilter.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>

#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <string>

#include "flowire/common/error.hpp"
#include "flowire/flow/fem/boundary_values.hpp"
#include "flowire/flow/fem/compare.hpp"
#include "flowire/flow/fem/lumen.hpp"
#include "flowire/vessels/generators.hpp"
#include "flowire/vessels/io.hpp"
#include "flowire_test.hpp"

namespace flowire::flow::fem {
namespace {

namespace fs = std::filesystem;

struct Anatomy {
  std::string centerline, surface, unit;
  double factor;  // metres per file unit
};

Anatomy arch() {
  const fs::path d = testing::shared_dir() / "data/real/feelpp-aortic-arch";
  return {(d / "centerlinesAORTA.vtk").string(), (d / "aorta2.stl").string(), "cm", 1e-2};
}
Anatomy abdominal() {
  const fs::path d = testing::shared_dir() / "data/real/vmtk-abdominal-aorta-bifurcation";
  return {(d / "aorta-centerline.vtp").string(), (d / "aorta-surface.vtp").string(), "mm", 1e-3};
}

vessels::Network network_of(const Anatomy& a) {
  vessels::ReadOptions ro;
  ro.length_unit = a.unit;
  return vessels::read_network(a.centerline, ro);
}

/// Volume of the file's surface by VTK alone: a closed surface cut as prepare_lumen defines
/// it (vtkClipPolyData: the plane normal to the centerline half an end radius before each
/// end, within 3 radii of it), open ends closed by vtkFillHolesFilter, normals made
/// consistent and outward (vtkPolyDataNormals), then vtkMassProperties (m³).
double vtk_volume(const Anatomy& a, const vessels::Network& net) {
  vtkSmartPointer<vtkPolyData> pd;
  if (a.surface.ends_with(".stl")) {
    vtkNew<vtkSTLReader> r;
    r->SetFileName(a.surface.c_str());
    r->Update();
    pd = r->GetOutput();
  } else {
    vtkNew<vtkXMLPolyDataReader> r;
    r->SetFileName(a.surface.c_str());
    r->Update();
    pd = r->GetOutput();
  }
  if (!a.surface.ends_with(".stl"))
    for (int e : net.ends()) {
      const auto& sg = net.segment(*net.node_segments(e).first);
      const int other = sg.node_from == e ? sg.node_to : sg.node_from;
      const Vec3 out = (net.node(e) - net.node(other)).normalized();
      const Vec3 o = (net.node(e) - 0.5 * sg.radius * out) / a.factor;
      vtkNew<vtkPlane> plane;  // > 0 beyond the cut
      plane->SetOrigin(o.x(), o.y(), o.z());
      plane->SetNormal(out.x(), out.y(), out.z());
      vtkNew<vtkSphere> sphere;  // < 0 near the end
      sphere->SetCenter(o.x(), o.y(), o.z());
      sphere->SetRadius(3.0 * sg.radius / a.factor);
      vtkNew<vtkImplicitBoolean> beyond;  // max(-plane, sphere) < 0: beyond and near
      beyond->SetOperationTypeToIntersection();
      vtkNew<vtkPlane> minus;
      minus->SetOrigin(o.x(), o.y(), o.z());
      minus->SetNormal(-out.x(), -out.y(), -out.z());
      beyond->AddFunction(minus);
      beyond->AddFunction(sphere);
      vtkNew<vtkClipPolyData> clip;
      clip->SetInputData(pd);
      clip->SetClipFunction(beyond);
      clip->SetValue(0.0);
      clip->Update();
      pd = clip->GetOutput();
    }
  vtkNew<vtkFillHolesFilter> fill;
  fill->SetInputData(pd);
  fill->SetHoleSize(1e9);
  vtkNew<vtkTriangleFilter> tri;
  tri->SetInputConnection(fill->GetOutputPort());
  vtkNew<vtkPolyDataNormals> normals;
  normals->SetInputConnection(tri->GetOutputPort());
  normals->ConsistencyOn();
  normals->AutoOrientNormalsOn();
  normals->SplittingOff();
  vtkNew<vtkMassProperties> mp;
  mp->SetInputConnection(normals->GetOutputPort());
  mp->Update();
  return mp->GetVolume() * a.factor * a.factor * a.factor;
}

/// Every edge of the boundary triangles is shared by exactly two of them.
int open_boundary_edges(const TetMesh& m) {
  std::map<std::pair<int, int>, int> count;
  for (const auto& f : m.faces)
    for (int k = 0; k < 3; ++k) {
      int a = f[static_cast<size_t>(k)], b = f[static_cast<size_t>((k + 1) % 3)];
      if (a > b) std::swap(a, b);
      ++count[{a, b}];
    }
  int bad = 0;
  for (const auto& [e, c] : count) bad += c != 2 ? 1 : 0;
  return bad;
}

void check_lumen(const Anatomy& a, size_t expected_ends, double size_factor) {
  const vessels::Network net = network_of(a);
  const auto ends = net.ends();
  ASSERT_EQ(ends.size(), expected_ends);
  const LumenSurface lumen = prepare_lumen(net, read_surface(a.surface, a.factor));
  ASSERT_EQ(lumen.caps.size(), ends.size());
  for (size_t c = 0; c < lumen.caps.size(); ++c) {
    const LumenCap& cap = lumen.caps[c];
    EXPECT_EQ(cap.node, ends[c]);
    const double r_end = net.segment(*net.node_segments(cap.node).first).radius;
    std::printf(
        "cap at end %d: %d loop points, r_eq %.3f mm (centerline %.3f mm), %.3f mm from the end, "
        "planarity %.4f, file's own cap %d\n",
        cap.node, cap.loop_points, cap.radius * 1e3, r_end * 1e3, cap.distance * 1e3, cap.planarity,
        cap.was_capped ? 1 : 0);
    // The cap's equivalent radius is the vessel's at its end (MISR is inscribed: a bit smaller).
    EXPECT_GT(cap.radius, 0.8 * r_end);
    EXPECT_LT(cap.radius, 1.6 * r_end);
    EXPECT_LT(cap.distance, r_end);
  }
  MeshOptions mo;
  mo.size_factor = size_factor;
  const TetMesh mesh = build_mesh(net, lumen, mo);
  ASSERT_EQ(mesh.groups.size(), ends.size() + 1);
  EXPECT_EQ(open_boundary_edges(mesh), 0);
  for (size_t g = 0; g < mesh.groups.size(); ++g) EXPECT_GT(mesh.area(static_cast<int>(g)), 0.0) << mesh.groups[g].name;
  // Each inlet / outlet face has the area of its cap.
  for (const LumenCap& cap : lumen.caps) {
    const int g = mesh.group_of_node(cap.node);
    ASSERT_GE(g, 0);
    const double area = mesh.area(g), expected = std::numbers::pi * cap.radius * cap.radius;
    EXPECT_NEAR(area / expected, 1.0, 0.02) << mesh.groups[static_cast<size_t>(g)].name;
  }
  const double v_mesh = mesh.volume(), v_vtk = vtk_volume(a, net);
  std::printf(
      "%s: %d tets, %d nodes, mesh %.2f s; volume: mesh %.4f mL, VTK (filled holes) %.4f mL, capped "
      "triangulation %.4f mL; mesh / VTK - 1 = %.2e\n",
      a.surface.c_str(), mesh.num_tets(), mesh.num_nodes(), mesh.mesh_seconds, v_mesh * 1e6, v_vtk * 1e6,
      lumen.enclosed_volume * 1e6, v_mesh / v_vtk - 1.0);
  EXPECT_NEAR(v_mesh / v_vtk, 1.0, 0.005);  // measured: 1.0e-3 (arch), 4.5e-4 (abdominal)
}

TEST(FemLumen, FeelppAorticArchMeshesWithOneCapPerCenterlineEnd) {
  FLOWIRE_REQUIRE_SHARED("data/real/feelpp-aortic-arch/aorta2.stl");
  check_lumen(arch(), 5, 0.6);
}

TEST(FemLumen, VmtkAbdominalAortaClosedSurfaceIsRecapped) {
  FLOWIRE_REQUIRE_SHARED("data/real/vmtk-abdominal-aorta-bifurcation/aorta-surface.vtp");
  check_lumen(abdominal(), 3, 0.5);
}

/// The error must be flowire's input error and name `fragment` (the file).
template <class F>
void expect_input_error(F&& f, const std::string& fragment, const std::string& also = "") {
  try {
    f();
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    if (!also.empty()) {
      EXPECT_NE(std::string(e.what()).find(also), std::string::npos) << e.what();
    }
  }
}

TEST(FemLumen, MissingOrEmptySurfaceNamesTheFile) {
  const fs::path dir = testing::scratch_dir("fem_lumen_bad");
  const std::string missing = (dir / "nowhere.stl").string();
  expect_input_error([&] { (void)read_surface(missing); }, missing, "no such file");
  // A VTP with points and no polygons.
  const std::string empty = (dir / "empty.vtp").string();
  {
    vtkNew<vtkPoints> pts;
    pts->InsertNextPoint(0, 0, 0);
    pts->InsertNextPoint(1, 0, 0);
    vtkNew<vtkPolyData> pd;
    pd->SetPoints(pts);
    vtkNew<vtkXMLPolyDataWriter> w;
    w->SetFileName(empty.c_str());
    w->SetInputData(pd);
    ASSERT_EQ(w->Write(), 1);
  }
  expect_input_error([&] { (void)read_surface(empty); }, empty, "no triangles");
}

TEST(FemLumen, CapsThatMatchNoCenterlineEndAreRefused) {
  FLOWIRE_REQUIRE_SHARED("data/real/feelpp-aortic-arch/aorta2.stl");
  FLOWIRE_REQUIRE_SHARED("data/real/vmtk-abdominal-aorta-bifurcation/aorta-centerline.vtp");
  const Anatomy a = arch(), b = abdominal();
  // The arch surface with the abdominal centerlines: 5 open ends, 3 centerline ends.
  expect_input_error([&] { (void)prepare_lumen(network_of(b), read_surface(a.surface, a.factor)); }, a.surface,
                     "5 open ends");
  // The arch surface shifted by 5 cm: as many ends, none where the centerlines end.
  SurfaceMesh moved = read_surface(a.surface, a.factor);
  for (Vec3& x : moved.points) x.x() += 0.05;
  expect_input_error([&] { (void)prepare_lumen(network_of(a), moved); }, a.surface, "matches no centerline end");
  // The closed abdominal surface with the arch centerlines: nothing to cut at their ends.
  expect_input_error([&] { (void)prepare_lumen(network_of(a), read_surface(b.surface, b.factor)); }, b.surface,
                     "0 open ends");
}

/// A straight tube along x of radius r from 0 to `length` as an STL of `around` facets round and
/// `along` rings, open at both ends; with `oblique` > 0 one more ring, 1 mm further, cut
/// obliquely: at angle φ round, x = length + 1 mm + r (1 + cos φ) tan(oblique).
void write_faceted_tube(const std::string& stl, double r, double length, int around, int along, double oblique = 0.0) {
  std::ofstream o(stl);
  o.precision(17);
  o << "solid tube\n";
  auto at = [&](int i, int k) {
    const double phi = 2.0 * std::numbers::pi * (k % around) / around;
    const double x = i <= along ? length * i / along : length + 1e-3 + r * (1.0 + std::cos(phi)) * std::tan(oblique);
    return Vec3(x, r * std::cos(phi), r * std::sin(phi));
  };
  auto facet = [&](const Vec3& a, const Vec3& b, const Vec3& c) {
    o << "facet normal 0 0 0\nouter loop\n";
    for (const Vec3* x : {&a, &b, &c}) o << "vertex " << x->x() << ' ' << x->y() << ' ' << x->z() << '\n';
    o << "endloop\nendfacet\n";
  };
  const int rings = oblique > 0.0 ? along + 1 : along;
  for (int i = 0; i < rings; ++i)
    for (int k = 0; k < around; ++k) {
      facet(at(i, k), at(i + 1, k), at(i + 1, k + 1));
      facet(at(i, k), at(i + 1, k + 1), at(i, k + 1));
    }
  o << "endsolid tube\n";
}

/// A straight centerline along x from 0 to @p length, radius @p r, 2 mm segments.
vessels::Network straight_centerline(double length, double r) {
  vessels::StraightTubeParams tp;
  tp.length = length;
  tp.radius = r;
  vessels::BuildOptions bo;
  bo.max_segment_length = 2e-3;
  return vessels::Network::build(vessels::straight_tube(tp), bo);
}

/// The comparison on the lumen of @p stl: flow @p q in, 0 Pa out, viscosity @p eta.
CompareResult tube_comparison(const std::string& stl, const vessels::Network& net, double q, double eta) {
  BoundaryValues bv;
  bv.inlet_type = BoundaryValues::Inlet::Flow;
  bv.inlet_flow = q;
  bv.outlet_pressure = 0.0;
  bv.viscosity = eta;
  FemOptions fo;
  fo.surface = stl;
  fo.size_factor = 0.4;
  fo.samples_per_branch = 5;
  return compare(net, bv, fo, "");
}

/// Hagen–Poiseuille for a regular n-gon of circumradius r is, to 1e-3, that of the circle of
/// equal area: r_eq² = (n / 2π) r² sin(2π / n).
double polygon_equivalent_radius(double r, int n) {
  return r * std::sqrt(n / (2.0 * std::numbers::pi) * std::sin(2.0 * std::numbers::pi / n));
}

// The whole real-lumen path (surface file -> caps -> tags -> Stokes -> comparison) on a lumen
// whose answer is known: a straight tube given as an STL of 64 facets around, open at both
// ends, with a straight centerline. Hagen–Poiseuille for a regular n-gon is, to 1e-3, that of
// the circle of equal area, r_eq² = (n / 2π) r² sin(2π / n).
TEST(FemLumen, FacetedTubeSurfaceMatchesHagenPoiseuille) {
  const double r = 2e-3, length = 16e-3, q = 1e-6, eta = 3.5e-3;
  constexpr int kAround = 64, kAlong = 16;
  const fs::path dir = testing::scratch_dir("fem_lumen_tube");
  const std::string stl = (dir / "tube.stl").string();
  write_faceted_tube(stl, r, length, kAround, kAlong);
  const CompareResult res = tube_comparison(stl, straight_centerline(length, r), q, eta);
  const double r_eq = polygon_equivalent_radius(r, kAround);
  const double p_exact = 8.0 * eta * length * q / (std::numbers::pi * std::pow(r_eq, 4));
  std::printf(
      "faceted tube: %d tets; inlet pressure FEM %.6g Pa, Hagen-Poiseuille (r_eq) %.6g Pa, network "
      "(r) %.6g Pa\n",
      res.tets, res.inlet_pressure_fem, p_exact, res.inlet_pressure_network);
  EXPECT_NEAR(res.inlet_pressure_fem / p_exact, 1.0, 0.01);
  EXPECT_NEAR(res.inlet_flow_fem / q, 1.0, 1e-9);
  int interior = 0;
  for (const SamplePoint& sp : res.samples) {
    if (sp.s < 1e-9 || sp.s > length - 1e-9) continue;
    ++interior;
    std::printf("  s = %.1f mm: flow FEM / Q = %.5f, r_fem / r_eq = %.5f, p FEM / exact = %.5f\n", sp.s * 1e3,
                sp.flow_fem / q, sp.radius_fem / r_eq, sp.pressure_fem / (p_exact * (1.0 - sp.s / length)));
    EXPECT_NEAR(sp.flow_fem / q, 1.0, 0.01);       // the section flux quadrature
    EXPECT_NEAR(sp.radius_fem / r_eq, 1.0, 0.01);  // the section area
    EXPECT_NEAR(sp.pressure_fem / (p_exact * (1.0 - sp.s / length)), 1.0, 0.02);
  }
  EXPECT_EQ(interior, 3);
}

// An open end cut at 60° from square (the wall meets its cap at 30° on one side, which the
// patch classification cannot split) is cut again square just inside its innermost point: the
// lumen meshes, and the tube up to that cut obeys Hagen–Poiseuille as the square one does.
TEST(FemLumen, AnObliquelyCutOpenEndIsCutAgainSquareAndTheTubeStillMatchesHagenPoiseuille) {
  const double r = 2e-3, length = 16e-3, q = 1e-6, eta = 3.5e-3, oblique = std::numbers::pi / 3.0;
  constexpr int kAround = 64, kAlong = 16;
  const fs::path dir = testing::scratch_dir("fem_lumen_oblique");
  const std::string stl = (dir / "tube.stl").string();
  write_faceted_tube(stl, r, length, kAround, kAlong, oblique);
  // The centerline runs to the oblique end's centroid.
  const vessels::Network net = straight_centerline(length + 1e-3 + r * std::tan(oblique), r);
  const LumenSurface lumen = prepare_lumen(net, read_surface(stl, 1.0));
  EXPECT_EQ(lumen.recut_ends, 1);
  // The new outlet cap: square to the axis, just inside the old loop's innermost point.
  const double x_cut = length + 1e-3 - 0.1 * r;
  bool found = false;
  for (const LumenCap& c : lumen.caps)
    if (c.centroid.x() > 0.5 * length) {
      found = true;
      EXPECT_NEAR(c.centroid.x(), x_cut, 1e-9);
      EXPECT_NEAR(std::abs(c.normal.x()), 1.0, 1e-9);
      EXPECT_LT(c.planarity, 1e-9);
    }
  EXPECT_TRUE(found);
  const CompareResult res = tube_comparison(stl, net, q, eta);
  EXPECT_EQ(res.lumen_ends_recut, 1);
  const double r_eq = polygon_equivalent_radius(r, kAround);
  const double p_exact = 8.0 * eta * x_cut * q / (std::numbers::pi * std::pow(r_eq, 4));
  EXPECT_NEAR(res.inlet_pressure_fem / p_exact, 1.0, 0.01);
  EXPECT_NEAR(res.inlet_flow_fem / q, 1.0, 1e-9);
}

}  // namespace
}  // namespace flowire::flow::fem
