// The wall's compliance under a wire's contact against the converged 3D solution of the same
// solid, solved through PETSc (MUMPS) on meshes refined about the load: a force spread over the
// wire's footprint (LumenCompliance::locate_patch) converges as the mesh is refined, a point
// force does not (its displacement is singular in 3D), and the wall's own condensed compliance
// (CHOLMOD's columns) is PETSc's solution of the same system.
#include <gtest/gtest.h>
#include <petscksp.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "flowire/flow/petsc_runtime.hpp"
#include "flowire/solid/elastic_solid.hpp"
#include "flowire/solid/lumen_compliance.hpp"
#include "flowire/solid/tube_wall.hpp"
#include "flowire_test.hpp"

namespace flowire::solid {
namespace {

// A tube of 2 mm lumen radius and 0.5 mm wall (the iliac's scale), 12 mm long, ends held; a
// 0.035" wire (radius 0.445 mm) pressing outwards at mid-length.
constexpr double kA = 2e-3, kB = 2.5e-3, kL = 12e-3, kWire = 0.445e-3;
const Vec3 kLoad(kA, 0.0, kL / 2);

struct Sample {
  int tets = 0;
  double patch = 0.0;  ///< patch-mean normal displacement under a unit patch force [m/N]
  double point = 0.0;  ///< the same for a point force
  double cholmod_patch = 0.0;
};

void check(PetscErrorCode code, const char* what) { flow::check_petsc(code, what, "test"); }

/// K u = f for each right-hand side, K the solid's tangent at rest (held rows and columns as the
/// identity), through PETSc: a sequential AIJ matrix, LU by MUMPS.
std::vector<Eigen::VectorXd> petsc_solve(const ElasticSolid& s, const std::vector<Eigen::VectorXd>& rhs) {
  flow::ensure_petsc("test");
  const int n = s.num_dofs();
  Eigen::SparseMatrix<double, Eigen::RowMajor> k = s.hessian(Eigen::VectorXd::Zero(n));
  for (int r = 0; r < n; ++r)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(k, r); it; ++it)
      if (s.held(r) || s.held(static_cast<int>(it.col()))) it.valueRef() = r == it.col() ? 1.0 : 0.0;
  k.makeCompressed();
  std::vector<PetscInt> ia(k.outerIndexPtr(), k.outerIndexPtr() + n + 1),
      ja(k.innerIndexPtr(), k.innerIndexPtr() + k.nonZeros());
  std::vector<PetscScalar> va(k.valuePtr(), k.valuePtr() + k.nonZeros());
  Mat a;
  check(MatCreateSeqAIJWithArrays(PETSC_COMM_SELF, n, n, ia.data(), ja.data(), va.data(), &a), "MatCreate");
  KSP ksp;
  check(KSPCreate(PETSC_COMM_SELF, &ksp), "KSPCreate");
  check(KSPSetOperators(ksp, a, a), "KSPSetOperators");
  check(KSPSetType(ksp, KSPPREONLY), "KSPSetType");
  PC pc;
  check(KSPGetPC(ksp, &pc), "KSPGetPC");
  check(PCSetType(pc, PCLU), "PCSetType");
  check(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS), "mumps");
  std::vector<Eigen::VectorXd> out;
  for (const auto& f : rhs) {
    Eigen::VectorXd fh = f;
    for (int r = 0; r < n; ++r)
      if (s.held(r)) fh[r] = 0.0;
    Eigen::VectorXd u(n);
    Vec b, x;
    check(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, n, fh.data(), &b), "VecCreate");
    check(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, n, u.data(), &x), "VecCreate");
    check(KSPSolve(ksp, b, x), "KSPSolve");
    check(VecDestroy(&b), "VecDestroy");
    check(VecDestroy(&x), "VecDestroy");
    out.push_back(u);
  }
  check(KSPDestroy(&ksp), "KSPDestroy");
  check(MatDestroy(&a), "MatDestroy");
  return out;
}

Sample sample(double refine_size, bool with_cholmod) {
  TubeWall tube{kA, kB, kL, 1e-3, false};
  tube.refine_size = refine_size;
  tube.refine_radius = 1.5 * kWire;
  tube.refine_at = kLoad;
  ElasticSolid s{mesh_tube_wall(tube), NeoHookean::from_young_poisson(1e6, 0.45)};
  s.hold(s.mesh().group_named("end_0"));
  s.hold(s.mesh().group_named("end_1"));
  LumenCompliance lumen(s, s.mesh().group_named("lumen"));
  const LumenPoint patch = lumen.locate_patch(kLoad, kWire), point = lumen.locate(kLoad);
  const Vec3 d = -patch.normal;  // outwards
  const auto u = petsc_solve(s, {lumen.nodal_forces(std::vector<LumenPoint>{patch}, std::vector<Vec3>{d}),
                                 lumen.nodal_forces(std::vector<LumenPoint>{point}, std::vector<Vec3>{d})});
  Sample r;
  r.tets = s.mesh().num_tets();
  r.patch = d.dot(lumen.interpolate(patch, u[0]));
  r.point = d.dot(lumen.interpolate(point, u[1]));
  if (with_cholmod) {
    s.linearize();
    r.cholmod_patch = lumen.compliance(std::vector<LumenPoint>{patch}, std::vector<Vec3>{d})(0, 0);
  }
  return r;
}

TEST(WallPatchConvergence, AWiresFootprintConvergesWhereAPointForceDoesNot) {
  // The mesh the wall uses (twice the thickness, no refinement), then refined about the load.
  const Sample coarse = sample(0.0, true);
  std::vector<double> sizes{0.24e-3, 0.12e-3, 0.06e-3};
  std::vector<Sample> s;
  for (double h : sizes) s.push_back(sample(h, false));
  std::printf("uniform 1 mm: %d tets, patch %.6e, point %.6e m/N (CHOLMOD patch %.6e)\n", coarse.tets, coarse.patch,
              coarse.point, coarse.cholmod_patch);
  for (size_t i = 0; i < s.size(); ++i)
    std::printf("refined %.3g mm: %d tets, patch %.6e, point %.6e m/N\n", 1e3 * sizes[i], s[i].tets, s[i].patch,
                s[i].point);
  EXPECT_NEAR(coarse.cholmod_patch, coarse.patch, 1e-8 * coarse.patch);  // two solvers, one system
  // The footprint's compliance converges at second order (measured 2.07: 10.040, 10.122, 10.141
  // mm/N at 0.24, 0.12, 0.06 mm about the load); its Richardson limit is the reference.
  const double d1 = s[1].patch - s[0].patch, d2 = s[2].patch - s[1].patch;
  const double order = std::log2(std::abs(d1 / d2));
  const double converged = s[2].patch + d2 / (std::abs(d1 / d2) - 1.0);
  std::printf("patch: order %.2f, converged %.6e m/N; the wall's mesh %.2f%% off, refined to 0.24 mm %.2f%%\n", order,
              converged, 100.0 * (coarse.patch / converged - 1.0), 100.0 * (s[0].patch / converged - 1.0));
  EXPECT_GT(order, 1.5);
  EXPECT_LT(std::abs(s[2].patch / converged - 1.0), 1e-3);
  // The wall's own mesh (twice its thickness), which a scene uses by default: stiffer than the
  // solid by the discretization error of P2 elements two to a thickness (measured 5.9%).
  EXPECT_LT(std::abs(coarse.patch / converged - 1.0), 0.08);
  // A point force's compliance grows at every refinement instead (by 37% and 106% here): the
  // displacement under it is singular, so a point-loaded wall's stiffness is the mesh's.
  for (size_t i = 1; i < s.size(); ++i) EXPECT_GT(s[i].point, 1.3 * s[i - 1].point) << i;
}

}  // namespace
}  // namespace flowire::solid
