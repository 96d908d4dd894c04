// Cross-check of flowire's FEM with PETSc's own finite-element machinery on the same mesh.
//
// flowire meshes a straight tube with gmsh and writes the mesh as .msh; PETSc reads that
// file itself (DMPlex's gmsh reader, quadratic geometry), discretizes Stokes with its
// own Taylor–Hood elements (PetscFE P2/P1, pointwise weak forms as in PETSc's Stokes
// tutorial snes/tutorials/ex62, here with the gradient form of the viscous term and a
// pressure traction on the end faces instead of ex62's manufactured solution) and solves
// with MUMPS, and its outlet flow is L⁻¹∫u_x (see axial_velocity). The gmsh reader of PETSc 3.18 is used with
// straight-sided (vertex) geometry, so flowire solves the same mesh with its edge nodes moved to the edge midpoints:
// the same discrete problem assembled twice by independent code, whose outlet flows must agree to round-off. flowire's
// curved-mesh flow is checked against Hagen–Poiseuille.
//
// Usage: fem_petsc_plex_check DIR   (writes DIR/tube.msh). Exit status 0 when the flows
// agree to 1e-8 and the curved one is within 0.5% of Hagen–Poiseuille, 1 otherwise, 77
// (skip) when PETSc cannot read the mesh or lacks MUMPS.
#include <petscdmplex.h>
#include <petscds.h>
#include <petscsnes.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <string>

#include "fem_test_cases.hpp"
#include "flowire/flow/fem/element.hpp"
#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/network_mesh.hpp"
#include "flowire/flow/fem/stokes.hpp"
#include "flowire/flow/solver.hpp"

namespace {

constexpr double kR = 2e-3, kL = 30e-3, kEta = 3.5e-3, kDp = 20.0;
constexpr PetscInt kWall = 1, kInlet = 2, kOutlet = 3;  // gmsh physical tags: group index + 1

// Pointwise functions (PETSc's signature). constants: [0] viscosity, [1] inlet pressure.
void f0_zero(PetscInt dim, PetscInt, PetscInt, const PetscInt[], const PetscInt[], const PetscScalar[],
             const PetscScalar[], const PetscScalar[], const PetscInt[], const PetscInt[], const PetscScalar[],
             const PetscScalar[], const PetscScalar[], PetscReal, const PetscReal[], PetscInt, const PetscScalar[],
             PetscScalar f0[]) {
  for (PetscInt c = 0; c < dim; ++c) f0[c] = 0.0;
}
// Viscous stress in gradient form and pressure: f1 = η∇u − p I.
void f1_u(PetscInt dim, PetscInt, PetscInt, const PetscInt uOff[], const PetscInt[], const PetscScalar u[],
          const PetscScalar[], const PetscScalar u_x[], const PetscInt[], const PetscInt[], const PetscScalar[],
          const PetscScalar[], const PetscScalar[], PetscReal, const PetscReal[], PetscInt,
          const PetscScalar constants[], PetscScalar f1[]) {
  const PetscReal eta = PetscRealPart(constants[0]);
  for (PetscInt c = 0; c < dim; ++c) {
    for (PetscInt d = 0; d < dim; ++d) f1[c * dim + d] = eta * u_x[c * dim + d];
    f1[c * dim + c] -= u[uOff[1]];
  }
}
// Continuity: −div u (the symmetric saddle-point form).
void f0_p(PetscInt dim, PetscInt, PetscInt, const PetscInt[], const PetscInt[], const PetscScalar[],
          const PetscScalar[], const PetscScalar u_x[], const PetscInt[], const PetscInt[], const PetscScalar[],
          const PetscScalar[], const PetscScalar[], PetscReal, const PetscReal[], PetscInt, const PetscScalar[],
          PetscScalar f0[]) {
  f0[0] = 0.0;
  for (PetscInt d = 0; d < dim; ++d) f0[0] -= u_x[d * dim + d];
}
void g3_uu(PetscInt dim, PetscInt, PetscInt, const PetscInt[], const PetscInt[], const PetscScalar[],
           const PetscScalar[], const PetscScalar[], const PetscInt[], const PetscInt[], const PetscScalar[],
           const PetscScalar[], const PetscScalar[], PetscReal, PetscReal, const PetscReal[], PetscInt,
           const PetscScalar constants[], PetscScalar g3[]) {
  const PetscReal eta = PetscRealPart(constants[0]);
  for (PetscInt c = 0; c < dim; ++c)
    for (PetscInt d = 0; d < dim; ++d) g3[((c * dim + c) * dim + d) * dim + d] = eta;
}
void g2_up(PetscInt dim, PetscInt, PetscInt, const PetscInt[], const PetscInt[], const PetscScalar[],
           const PetscScalar[], const PetscScalar[], const PetscInt[], const PetscInt[], const PetscScalar[],
           const PetscScalar[], const PetscScalar[], PetscReal, PetscReal, const PetscReal[], PetscInt,
           const PetscScalar[], PetscScalar g2[]) {
  for (PetscInt d = 0; d < dim; ++d) g2[d * dim + d] = -1.0;
}
void g1_pu(PetscInt dim, PetscInt, PetscInt, const PetscInt[], const PetscInt[], const PetscScalar[],
           const PetscScalar[], const PetscScalar[], const PetscInt[], const PetscInt[], const PetscScalar[],
           const PetscScalar[], const PetscScalar[], PetscReal, PetscReal, const PetscReal[], PetscInt,
           const PetscScalar[], PetscScalar g1[]) {
  for (PetscInt d = 0; d < dim; ++d) g1[d * dim + d] = -1.0;
}
// Traction on the inlet face: the weak form gets + p_in ∫ n·v (outlet: p = 0, nothing).
void f0_inlet(PetscInt dim, PetscInt, PetscInt, const PetscInt[], const PetscInt[], const PetscScalar[],
              const PetscScalar[], const PetscScalar[], const PetscInt[], const PetscInt[], const PetscScalar[],
              const PetscScalar[], const PetscScalar[], PetscReal, const PetscReal[], const PetscReal n[], PetscInt,
              const PetscScalar constants[], PetscScalar f0[]) {
  for (PetscInt c = 0; c < dim; ++c) f0[c] = constants[1] * n[c];
}
// The axial velocity. For a discrete Taylor–Hood solution ∫_Ω u_x = ∫_∂Ω x u·n − ∫_Ω x div u,
// and the last term vanishes exactly because x is in the P1 pressure space: with the
// inlet at x = 0, the outlet at x = L and u = 0 on the wall, ∫_Ω u_x = L·Q_out.
void axial_velocity(PetscInt, PetscInt, PetscInt, const PetscInt[], const PetscInt[], const PetscScalar u[],
                    const PetscScalar[], const PetscScalar[], const PetscInt[], const PetscInt[], const PetscScalar[],
                    const PetscScalar[], const PetscScalar[], PetscReal, const PetscReal[], PetscInt,
                    const PetscScalar[], PetscScalar f[]) {
  f[0] = u[0];
}
PetscErrorCode zero(PetscInt, PetscReal, const PetscReal[], PetscInt nc, PetscScalar* u, void*) {
  for (PetscInt c = 0; c < nc; ++c) u[c] = 0.0;
  return 0;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct PlexResult {
  double q_out = 0.0, seconds = 0.0, read_seconds = 0.0;
  PetscInt cells = 0, unknowns = 0;
};

/// PETSc's own Taylor–Hood solution on the mesh file; returns nonzero PETSc error codes.
PetscErrorCode plex_solve(const std::string& file, PlexResult& res) {
  DM dm;
  PetscFunctionBeginUser;
  const auto t0 = std::chrono::steady_clock::now();
  // Straight (vertex) geometry: PETSc 3.18 crashes in the boundary residual with gmsh's
  // quadratic coordinate field (DMFieldGetDegree on its trace).
  PetscCall(PetscOptionsSetValue(nullptr, "-dm_plex_gmsh_highorder", "false"));
  PetscCall(DMPlexCreateFromFile(PETSC_COMM_WORLD, file.c_str(), "tube", PETSC_TRUE, &dm));
  PetscCall(DMSetOptionsPrefix(dm, "xc_"));
  PetscCall(DMSetFromOptions(dm));
  res.read_seconds = seconds_since(t0);
  PetscInt dim = 0, c0 = 0, c1 = 0;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &c0, &c1));
  res.cells = c1 - c0;
  // Fields: P2 velocity, P1 pressure, one quadrature for both (3 points per direction of the
  // collapsed tensor rule: exact to degree 5; on straight cells every integrand is of degree 2).
  PetscFE fe_u, fe_p;
  PetscCall(PetscFECreateLagrange(PETSC_COMM_SELF, dim, dim, PETSC_TRUE, 2, 2, &fe_u));
  PetscCall(PetscFECreateLagrange(PETSC_COMM_SELF, dim, 1, PETSC_TRUE, 1, 2, &fe_p));
  PetscCall(PetscFECopyQuadrature(fe_u, fe_p));
  PetscCall(PetscObjectSetName(reinterpret_cast<PetscObject>(fe_u), "velocity"));
  PetscCall(PetscObjectSetName(reinterpret_cast<PetscObject>(fe_p), "pressure"));
  PetscCall(DMSetField(dm, 0, nullptr, reinterpret_cast<PetscObject>(fe_u)));
  PetscCall(DMSetField(dm, 1, nullptr, reinterpret_cast<PetscObject>(fe_p)));
  PetscCall(DMCreateDS(dm));
  PetscDS ds;
  PetscCall(DMGetDS(dm, &ds));
  PetscCall(PetscDSSetResidual(ds, 0, f0_zero, f1_u));
  PetscCall(PetscDSSetResidual(ds, 1, f0_p, nullptr));
  PetscCall(PetscDSSetJacobian(ds, 0, 0, nullptr, nullptr, nullptr, g3_uu));
  PetscCall(PetscDSSetJacobian(ds, 0, 1, nullptr, nullptr, g2_up, nullptr));
  PetscCall(PetscDSSetJacobian(ds, 1, 0, nullptr, g1_pu, nullptr, nullptr));
  const PetscScalar constants[2] = {kEta, kDp};
  PetscCall(PetscDSSetConstants(ds, 2, const_cast<PetscScalar*>(constants)));
  // The wall with its closure (rim edges and vertices too): no slip.
  DMLabel face_sets, wall;
  PetscCall(DMGetLabel(dm, "Face Sets", &face_sets));
  PetscCheck(face_sets, PETSC_COMM_WORLD, PETSC_ERR_ARG_WRONG, "the mesh has no 'Face Sets' label");
  PetscCall(DMCreateLabel(dm, "wall"));
  PetscCall(DMGetLabel(dm, "wall", &wall));
  IS wall_faces;
  PetscCall(DMLabelGetStratumIS(face_sets, kWall, &wall_faces));
  PetscCheck(wall_faces, PETSC_COMM_WORLD, PETSC_ERR_ARG_WRONG, "no wall faces (physical tag 1)");
  PetscCall(DMLabelSetStratumIS(wall, 1, wall_faces));
  PetscCall(ISDestroy(&wall_faces));
  PetscCall(DMPlexLabelComplete(dm, wall));
  const PetscInt one = 1, inlet_id = kInlet;
  PetscCall(DMAddBoundary(dm, DM_BC_ESSENTIAL, "wall", wall, 1, &one, 0, 0, nullptr,
                          reinterpret_cast<void (*)(void)>(zero), nullptr, nullptr, nullptr));
  PetscInt bd = 0;
  PetscCall(DMAddBoundary(dm, DM_BC_NATURAL, "inlet", face_sets, 1, &inlet_id, 0, 0, nullptr, nullptr, nullptr, nullptr,
                          &bd));
  PetscWeakForm wf;
  PetscCall(PetscDSGetBoundary(ds, bd, &wf, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr,
                               nullptr, nullptr, nullptr));
  PetscCall(PetscWeakFormSetIndexBdResidual(wf, face_sets, kInlet, 0, 0, 0, f0_inlet, 0, nullptr));

  SNES snes;
  Vec x;
  PetscCall(SNESCreate(PETSC_COMM_WORLD, &snes));
  PetscCall(SNESSetOptionsPrefix(snes, "xc_"));
  PetscCall(SNESSetDM(snes, dm));
  PetscCall(DMPlexSetSNESLocalFEM(dm, nullptr, nullptr, nullptr));
  PetscCall(SNESSetType(snes, SNESKSPONLY));
  KSP ksp;
  PC pc;
  PetscCall(SNESGetKSP(snes, &ksp));
  PetscCall(KSPSetType(ksp, KSPPREONLY));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, PCLU));
  PetscCall(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
  PetscCall(SNESSetFromOptions(snes));
  PetscCall(DMCreateGlobalVector(dm, &x));
  PetscCall(VecGetSize(x, &res.unknowns));
  PetscCall(VecSet(x, 0.0));
  PetscCall(SNESSolve(snes, nullptr, x));
  SNESConvergedReason reason;
  PetscCall(SNESGetConvergedReason(snes, &reason));
  PetscCheck(reason > 0, PETSC_COMM_WORLD, PETSC_ERR_NOT_CONVERGED, "the PETSc solve failed (%s)",
             SNESConvergedReasons[reason]);
  PetscScalar integral[2] = {0.0, 0.0};
  PetscCall(PetscDSSetObjective(ds, 0, axial_velocity));
  PetscCall(DMPlexComputeIntegralFEM(dm, x, integral, nullptr));
  res.q_out = PetscRealPart(integral[0]) / kL;
  res.seconds = seconds_since(t0);
  PetscCall(VecDestroy(&x));
  PetscCall(SNESDestroy(&snes));
  PetscCall(PetscFEDestroy(&fe_u));
  PetscCall(PetscFEDestroy(&fe_p));
  PetscCall(DMDestroy(&dm));
  PetscFunctionReturn(0);
}

}  // namespace

int main(int argc, char** argv) {
  if (PetscInitialize(&argc, &argv, nullptr, nullptr) != 0) return 1;
  int status = 1;
  try {
    if (argc < 2) throw std::runtime_error("usage: fem_petsc_plex_check DIR");
    using namespace flowire::flow::fem;
    std::filesystem::create_directories(argv[1]);
    const std::string msh = (std::filesystem::path(argv[1]) / "tube.msh").string();
    MeshOptions mo;
    mo.size_factor = 0.35;
    mo.save_msh = msh;
    const TetMesh mesh = build_mesh(test::tube(kR, kL), mo);
    std::vector<double> p(mesh.groups.size(), 0.0);
    p[1] = kDp;
    StokesOptions so;
    so.viscosity = kEta;
    const StokesSolution curved = solve_stokes(mesh, p, so);
    // The same mesh with every edge node at the midpoint of its edge: the straight-sided
    // geometry PETSc builds from the vertices of the file.
    TetMesh straight = mesh;
    for (const auto& t : straight.tets)
      for (size_t e = 0; e < 6; ++e)
        straight.nodes[static_cast<size_t>(t[4 + e])] =
            0.5 * (mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(kTetEdges[e][0])])] +
                   mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(kTetEdges[e][1])])]);
    const StokesSolution sol = solve_stokes(straight, p, so);
    const double q_flowire = sol.group_flow[2];
    const double q_hp = std::numbers::pi * std::pow(kR, 4) * kDp / (8.0 * kEta * kL);
    PlexResult plex;
    PetscPushErrorHandler(PetscReturnErrorHandler, nullptr);
    const PetscErrorCode code = plex_solve(msh, plex);
    PetscPopErrorHandler();
    if (code != 0) {
      const char* text = nullptr;
      PetscErrorMessage(code, &text, nullptr);
      std::printf("SKIP: PETSc could not solve on %s: %s\n", msh.c_str(), text ? text : "unknown error");
      status = 77;
    } else {
      const double diff = plex.q_out / q_flowire - 1.0;
      std::printf(
          "tube r = %.1f mm, L = %.0f mm, dp = %.0f Pa; %d flowire tets / %ld PETSc cells, %d / %ld unknowns\n"
          "outlet flow on the straight-sided mesh: flowire %.10e, PETSc DMPlex/PetscFE %.10e m^3/s "
          "(relative difference %.3e); PETSc read %.1f s, total %.1f s\n"
          "Hagen-Poiseuille %.10e: flowire curved mesh %.3e, straight-sided (both codes) %.3e\n",
          kR * 1e3, kL * 1e3, kDp, mesh.num_tets(), static_cast<long>(plex.cells), sol.unknowns,
          static_cast<long>(plex.unknowns), q_flowire, plex.q_out, diff, plex.read_seconds, plex.seconds, q_hp,
          curved.group_flow[2] / q_hp - 1.0, q_flowire / q_hp - 1.0);
      // Same discrete problem (affine P2/P1, every integrand a polynomial integrated
      // exactly by both): the flows agree to the solvers' round-off. The curved mesh is
      // the accurate one (the straight sides cut the lumen by a few percent).
      const bool ok =
          std::abs(diff) < 1e-8 && plex.cells == mesh.num_tets() && std::abs(curved.group_flow[2] / q_hp - 1.0) < 5e-3;
      status = ok ? 0 : 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fem_petsc_plex_check: %s\n", e.what());
    status = 1;
  }
  flowire::flow::finalize_petsc();
  PetscFinalize();
  return status;
}
