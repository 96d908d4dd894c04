// The signed distance to a triangulated surface: against the exact distance to the sphere and
// cylinder it approximates (error falling as h², asserted as a slope), against brute force,
// against its own gradient and Hessian, open ends, and bad files.
#include "flowire/vessels/surface.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

#include <vtkCylinderSource.h>
#include <vtkNew.h>
#include <vtkSphereSource.h>
#include <vtkTriangleFilter.h>
#include <vtkXMLPolyDataWriter.h>

#include "flowire/common/error.hpp"
#include "flowire_test.hpp"

using namespace flowire;
using namespace flowire::vessels;

namespace {

std::string fmt_name(const char* what, int n) { return std::string(what) + "_" + std::to_string(n) + ".vtp"; }

std::string write_sphere(const std::filesystem::path& dir, int resolution, double radius) {
  vtkNew<vtkSphereSource> s;
  s->SetRadius(radius);
  s->SetThetaResolution(resolution);
  s->SetPhiResolution(resolution);
  s->Update();
  const auto path = (dir / fmt_name("sphere", resolution)).string();
  vtkNew<vtkXMLPolyDataWriter> w;
  w->SetInputConnection(s->GetOutputPort());
  w->SetFileName(path.c_str());
  w->Write();
  return path;
}

/// An open tube (no caps) along y, centred at the origin, `resolution` facets around.
std::string write_tube(const std::filesystem::path& dir, int resolution, double radius, double height) {
  vtkNew<vtkCylinderSource> c;
  c->SetRadius(radius);
  c->SetHeight(height);
  c->SetResolution(resolution);
  c->CappingOff();
  vtkNew<vtkTriangleFilter> tri;
  tri->SetInputConnection(c->GetOutputPort());
  const auto path = (dir / fmt_name("tube", resolution)).string();
  vtkNew<vtkXMLPolyDataWriter> w;
  w->SetInputConnection(tri->GetOutputPort());
  w->SetFileName(path.c_str());
  w->Write();
  return path;
}

}  // namespace

TEST(Surface, SphereDistanceConvergesAtSecondOrder) {
  const auto dir = flowire::testing::scratch_dir("surface_sphere");
  const double R = 2e-3;
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.3, 1.7);
  std::vector<Vec3> pts;
  for (int i = 0; i < 400; ++i) {
    Vec3 d(g(rng), g(rng), g(rng));
    double r = u(rng);
    if (std::abs(r - 1.0) < 0.15) r += r < 1.0 ? -0.15 : 0.15;  // clear of the faceted wall
    pts.push_back(r * R * d.normalized());
  }
  std::vector<double> hs, errs;
  for (int n : {8, 16, 32, 64}) {
    const LumenSurface s(read_surface(write_sphere(dir, n, R)));
    EXPECT_EQ(s.counts().boundary_edges, 0);
    double err = 0.0;
    for (const auto& x : pts) {
      const double exact = x.norm() - R;
      const auto q = s.distance(x);
      ASSERT_EQ(q.distance < 0.0, exact < 0.0) << "sign at |x|/R = " << x.norm() / R << ", n = " << n;
      err = std::max(err, std::abs(q.distance - exact));
    }
    hs.push_back(1.0 / n);
    errs.push_back(err);
  }
  const double p = flowire::testing::loglog_slope(hs, errs);
  EXPECT_NEAR(p, 2.0, 0.25) << "errors " << errs[0] << " " << errs[1] << " " << errs[2] << " " << errs[3];
}

TEST(Surface, OpenTubeDistanceConvergesAtSecondOrderAndItsEndsAreOpen) {
  const auto dir = flowire::testing::scratch_dir("surface_tube");
  const double R = 1e-3, H = 10e-3;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> ang(0.0, 2.0 * M_PI), rad(0.0, 1.8), ax(-0.3, 0.3);
  std::vector<Vec3> pts;
  for (int i = 0; i < 400; ++i) {
    double r = rad(rng);
    if (std::abs(r - 1.0) < 0.1) r += r < 1.0 ? -0.1 : 0.1;
    const double a = ang(rng);
    pts.push_back(Vec3(r * R * std::cos(a), ax(rng) * H, r * R * std::sin(a)));
  }
  std::vector<double> hs, errs;
  for (int n : {12, 24, 48, 96}) {
    const LumenSurface s(read_surface(write_tube(dir, n, R, H)));
    EXPECT_EQ(s.counts().boundary_loops, 2);
    double err = 0.0;
    for (const auto& x : pts) {
      const double exact = std::hypot(x.x(), x.z()) - R;
      const auto q = s.distance(x);
      ASSERT_EQ(q.distance < 0.0, exact < 0.0) << "sign at rho/R = " << std::hypot(x.x(), x.z()) / R;
      err = std::max(err, std::abs(q.distance - exact));
    }
    hs.push_back(1.0 / n);
    errs.push_back(err);
    // Beyond the open ends, on and near the axis: not outside, and the distance is to the rim.
    for (double y : {0.51 * H, 0.6 * H, -0.7 * H}) {
      const Vec3 x(0.2 * R, y, 0.0);
      const auto q = s.distance(x);
      EXPECT_TRUE(q.open);
      EXPECT_LT(q.distance, 0.0) << "a point beyond an open end is not outside (y = " << y << ")";
    }
  }
  EXPECT_NEAR(flowire::testing::loglog_slope(hs, errs), 2.0, 0.25);
}

TEST(Surface, HierarchyEqualsBruteForceWithAndWithoutHints) {
  const auto dir = flowire::testing::scratch_dir("surface_bvh");
  const LumenSurface s(read_surface(write_sphere(dir, 40, 1.0)));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.6, 1.6);
  std::uniform_int_distribution<int> tri(0, s.counts().triangles - 1);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 x(u(rng), u(rng), u(rng));
    const auto a = s.distance_brute_force(x);
    const auto b = s.distance(x);
    const auto c = s.distance(x, tri(rng));
    EXPECT_EQ(a.distance, b.distance);
    EXPECT_EQ(a.distance, c.distance);
    EXPECT_EQ(a.triangle, b.triangle);
    EXPECT_EQ(a.triangle, c.triangle);
  }
}

TEST(Surface, GradientAndHessianMatchFiniteDifferences) {
  const auto dir = flowire::testing::scratch_dir("surface_fd");
  const LumenSurface s(read_surface(write_tube(dir, 16, 1e-3, 10e-3)));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.5e-3, 1.5e-3), y(-3e-3, 3e-3);
  int checked = 0, by_feature[3] = {0, 0, 0};
  const double h = 1e-8;
  for (int i = 0; i < 3000 && checked < 400; ++i) {
    const Vec3 x(u(rng), y(rng), u(rng));
    Eigen::Matrix3d H;
    const auto q = s.distance(x, -1, &H);
    if (std::abs(q.distance) < 5e-5) continue;
    // Finite differences only within one feature's region (the Hessian jumps across them).
    bool same = true;
    for (int k = 0; k < 3 && same; ++k)
      for (double sgn : {-1.0, 1.0}) {
        const auto r = s.distance(x + sgn * 10 * h * Vec3::Unit(k));
        same = same && r.triangle == q.triangle && r.feature == q.feature;
      }
    if (!same) continue;
    ++checked;
    ++by_feature[static_cast<int>(q.feature)];
    for (int k = 0; k < 3; ++k) {
      const Vec3 e = Vec3::Unit(k);
      Eigen::Matrix3d Hp, Hm;
      const auto p = s.distance(x + h * e, -1, &Hp), m = s.distance(x - h * e, -1, &Hm);
      EXPECT_NEAR((p.distance - m.distance) / (2 * h), q.gradient[k], 1e-6);
      const Vec3 col = (p.gradient - m.gradient) / (2 * h);
      EXPECT_LT((col - H.col(k)).norm(), 1e-5 * (1.0 + H.norm()));
    }
  }
  EXPECT_GE(checked, 200);
  EXPECT_GT(by_feature[0], 10);  // faces
  EXPECT_GT(by_feature[1], 10);  // edges
}

TEST(Surface, OrientationFromInsidePointsAndFromTheEnclosedVolumeAgree) {
  const auto dir = flowire::testing::scratch_dir("surface_orient");
  auto mesh = read_surface(write_tube(dir, 20, 1e-3, 10e-3));
  // Turn every triangle around: the lumen is still found inside.
  for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
  const LumenSurface by_volume(mesh);
  const LumenSurface by_points(mesh, {Vec3(0, 0, 0), Vec3(0, 2e-3, 0)});
  EXPECT_LT(by_volume.distance(Vec3(0.1e-3, 0, 0)).distance, 0.0);
  EXPECT_LT(by_points.distance(Vec3(0.1e-3, 0, 0)).distance, 0.0);
  EXPECT_GT(by_points.distance(Vec3(2e-3, 0, 0)).distance, 0.0);
}

TEST(Surface, EndCapsAreRemoved) {
  const auto dir = flowire::testing::scratch_dir("surface_caps");
  vtkNew<vtkCylinderSource> c;
  c->SetRadius(1.0);
  c->SetHeight(10.0);
  c->SetResolution(24);
  c->CappingOn();
  vtkNew<vtkTriangleFilter> tri;
  tri->SetInputConnection(c->GetOutputPort());
  const auto path = (dir / "capped.vtp").string();
  vtkNew<vtkXMLPolyDataWriter> w;
  w->SetInputConnection(tri->GetOutputPort());
  w->SetFileName(path.c_str());
  w->Write();
  auto mesh = read_surface(path);
  EXPECT_EQ(LumenSurface(mesh).counts().boundary_edges, 0);
  const int removed =
      remove_end_caps(mesh, {{Vec3(0, 5, 0), Vec3(0, 1, 0), 1.0}, {Vec3(0, -5, 0), Vec3(0, -1, 0), 1.0}});
  EXPECT_GT(removed, 0);
  const LumenSurface open(mesh);
  EXPECT_EQ(open.counts().boundary_loops, 2);
  EXPECT_LT(open.distance(Vec3(0, 6, 0)).distance, 0.0);
}

namespace {
void expect_input_error(const std::string& path, const std::string& what) {
  try {
    (void)LumenSurface(read_surface(path));
    FAIL() << "no error for " << path;
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}
}  // namespace

TEST(Surface, BadFilesAreInputErrorsNamingTheFile) {
  const auto dir = flowire::testing::scratch_dir("surface_bad");
  expect_input_error((dir / "missing.stl").string(), "no such file");
  {
    std::ofstream f(dir / "points.obj");
    f << "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  }
  expect_input_error((dir / "points.obj").string(), "no triangles");
  {
    std::ofstream f(dir / "nan.stl");
    f << "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex nan 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
         "endsolid s\n";
  }
  expect_input_error((dir / "nan.stl").string(), "not finite");
  {
    std::ofstream f(dir / "degenerate.obj");
    f << "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n";
  }
  expect_input_error((dir / "degenerate.obj").string(), "no triangles");
  {
    std::ofstream f(dir / "notes.txt");
    f << "hello\n";
  }
  expect_input_error((dir / "notes.txt").string(), "unknown surface format");
}

#include "flowire/vessels/io.hpp"

namespace {
struct RealCase {
  const char* surface;
  const char* centerline;
  const char* unit;
  double factor;
};
const RealCase kReal[] = {
    {"feelpp-aortic-arch/aorta2.stl", "feelpp-aortic-arch/centerlinesAORTA.vtk", "cm", 1e-2},
    {"vmtk-abdominal-aorta-bifurcation/aorta-surface.vtp", "vmtk-abdominal-aorta-bifurcation/aorta-centerline.vtp",
     "mm", 1e-3},
    {"simvascular-demo-aorta-iliac/model_surface.vtp", "simvascular-demo-aorta-iliac/demo-centerlines.vtp", "cm", 1e-2},
    {"aneurisk-c0015-ica-vampy/artery.vtp", "aneurisk-c0015-ica-vampy/artery_centerlines.vtp", "mm", 1e-3},
};
}  // namespace

// Every centerline point lies inside its own lumen surface, about one radius from the wall
// (the radius is the maximum inscribed sphere's: the distance to the surface, measured by VMTK).
TEST(Surface, RealLumensHoldTheirCenterlinesOneRadiusFromTheWall) {
  for (const auto& rc : kReal) {
    FLOWIRE_REQUIRE_SHARED(std::string("data/real/") + rc.surface);
    const auto dir = flowire::testing::shared_dir() / "data/real";
    ReadOptions ro;
    ro.length_unit = rc.unit;
    const auto cl = read_centerlines((dir / rc.centerline).string(), ro);
    std::vector<Vec3> inside;
    for (const auto& b : cl.branches) inside.insert(inside.end(), b.points.begin(), b.points.end());
    const LumenSurface s(read_surface((dir / rc.surface).string(), rc.factor), inside);
    std::vector<double> ratio;
    int outside = 0;
    for (const auto& b : cl.branches)
      for (size_t i = 1; i + 1 < b.points.size(); ++i) {  // the end points lie on the caps or the rims
        const auto q = s.distance(b.points[i]);
        if (q.distance >= 0.0) ++outside;
        ratio.push_back(-q.distance / b.radii[i]);
      }
    std::sort(ratio.begin(), ratio.end());
    EXPECT_EQ(outside, 0) << rc.surface;
    EXPECT_NEAR(ratio[ratio.size() / 2], 1.0, 0.03) << rc.surface;
    std::printf("%s: %d triangles, %d boundary loops, %d components; |d|/r median %.3f, 5%% %.3f\n", rc.surface,
                s.counts().triangles, s.counts().boundary_loops, s.counts().components, ratio[ratio.size() / 2],
                ratio[ratio.size() / 20]);
  }
}
