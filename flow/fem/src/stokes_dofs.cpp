// Unknown numbering over the MPI ranks, the matrices' sparsity, the linear solver set-up.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numbers>

#include "stokes_internal.hpp"

namespace flowire::flow::fem::internal {

void default_option(const char* name, const char* value) {
  PetscBool set = PETSC_FALSE;
  FLOWIRE_PETSC(PetscOptionsHasName(nullptr, nullptr, name, &set));
  if (!set) FLOWIRE_PETSC(PetscOptionsSetValue(nullptr, name, value));
}

Numbering number(const TetMesh& mesh, int rank, int size, int fixed_group) {
  Numbering num;
  const size_t nn = mesh.nodes.size();
  std::vector<char> wall(nn, 0);
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    if (mesh.groups[static_cast<size_t>(mesh.face_group[f])].kind == BoundaryGroup::Kind::Wall ||
        mesh.face_group[f] == fixed_group)
      for (int n : mesh.faces[f]) wall[static_cast<size_t>(n)] = 1;
  std::vector<int> free_nodes;
  for (size_t n = 0; n < nn; ++n)
    if (!wall[n]) free_nodes.push_back(static_cast<int>(n));
  const long nf = static_cast<long>(free_nodes.size()), nv = mesh.num_vertices;
  num.vertex_node.assign(static_cast<size_t>(nv), -1);
  for (size_t n = 0; n < nn; ++n)
    if (mesh.vertex_index[n] >= 0) num.vertex_node[static_cast<size_t>(mesh.vertex_index[n])] = static_cast<int>(n);
  num.vdof.assign(nn, -1);
  num.pdof.assign(static_cast<size_t>(nv), -1);
  num.pindex.assign(static_cast<size_t>(nv), -1);
  PetscInt offset = 0, poffset = 0;
  for (int r = 0; r < size; ++r) {
    const auto [fa, fb] = split(nf, size, r);
    const auto [va, vb] = split(nv, size, r);
    if (r == rank) {
      num.begin = offset;
      num.local = static_cast<PetscInt>(3 * (fb - fa) + (vb - va));
      num.v_local = static_cast<PetscInt>(3 * (fb - fa));
      num.p_begin = poffset;
      num.p_local = static_cast<PetscInt>(vb - va);
    }
    for (long f = fa; f < fb; ++f) {
      num.vdof[static_cast<size_t>(free_nodes[static_cast<size_t>(f)])] = offset + static_cast<PetscInt>(3 * (f - fa));
      if (r == rank) num.my_nodes.push_back(free_nodes[static_cast<size_t>(f)]);
    }
    for (long v = va; v < vb; ++v) {
      num.pdof[static_cast<size_t>(v)] = offset + static_cast<PetscInt>(3 * (fb - fa) + (v - va));
      num.pindex[static_cast<size_t>(v)] = poffset + static_cast<PetscInt>(v - va);
      if (r == rank) num.my_vertices.push_back(static_cast<int>(v));
    }
    offset += static_cast<PetscInt>(3 * (fb - fa) + (vb - va));
    poffset += static_cast<PetscInt>(vb - va);
  }
  num.total = offset;
  return num;
}

NodeTets node_tets(const TetMesh& mesh) {
  NodeTets nt;
  nt.offset.assign(mesh.nodes.size() + 1, 0);
  for (const auto& t : mesh.tets)
    for (int n : t) ++nt.offset[static_cast<size_t>(n) + 1];
  for (size_t i = 0; i < mesh.nodes.size(); ++i) nt.offset[i + 1] += nt.offset[i];
  nt.tets.resize(static_cast<size_t>(nt.offset.back()));
  std::vector<int> fill(nt.offset.begin(), nt.offset.end() - 1);
  for (size_t e = 0; e < mesh.tets.size(); ++e)
    for (int n : mesh.tets[e]) nt.tets[static_cast<size_t>(fill[static_cast<size_t>(n)]++)] = static_cast<int>(e);
  return nt;
}

void sparsity(const TetMesh& mesh, const Numbering& num, const NodeTets& nt, bool coupled, std::vector<PetscInt>& ia,
              std::vector<PetscInt>& ja, std::vector<PetscInt>& pia, std::vector<PetscInt>& pja) {
  ia.assign(1, 0);
  ja.clear();
  std::vector<PetscInt> vel, pre;
  std::vector<int> mark(mesh.nodes.size(), -1);
  int stamp = 0;
  auto gather = [&](int node) {
    vel.clear();
    pre.clear();
    ++stamp;
    for (int k = nt.offset[static_cast<size_t>(node)]; k < nt.offset[static_cast<size_t>(node) + 1]; ++k)
      for (int m : mesh.tets[static_cast<size_t>(nt.tets[static_cast<size_t>(k)])]) {
        if (mark[static_cast<size_t>(m)] == stamp) continue;
        mark[static_cast<size_t>(m)] = stamp;
        if (num.vdof[static_cast<size_t>(m)] >= 0) vel.push_back(num.vdof[static_cast<size_t>(m)]);
        const int v = mesh.vertex_index[static_cast<size_t>(m)];
        if (v >= 0) pre.push_back(v);
      }
  };
  std::vector<PetscInt> row;
  for (int node : num.my_nodes) {
    gather(node);
    for (int c = 0; c < 3; ++c) {
      row.clear();
      for (PetscInt d : vel) {
        if (coupled)
          for (int k = 0; k < 3; ++k) row.push_back(d + k);
        else
          row.push_back(d + c);
      }
      for (int v : pre) row.push_back(num.pdof[static_cast<size_t>(v)]);
      std::sort(row.begin(), row.end());
      ja.insert(ja.end(), row.begin(), row.end());
      ia.push_back(static_cast<PetscInt>(ja.size()));
    }
  }
  pia.assign(1, 0);
  pja.clear();
  for (int v : num.my_vertices) {
    gather(num.vertex_node[static_cast<size_t>(v)]);
    row.clear();
    for (PetscInt d : vel)
      for (int c = 0; c < 3; ++c) row.push_back(d + c);
    row.push_back(num.pdof[static_cast<size_t>(v)]);
    std::sort(row.begin(), row.end());
    ja.insert(ja.end(), row.begin(), row.end());
    ia.push_back(static_cast<PetscInt>(ja.size()));
    row.clear();
    for (int w : pre) row.push_back(num.pindex[static_cast<size_t>(w)]);
    std::sort(row.begin(), row.end());
    pja.insert(pja.end(), row.begin(), row.end());
    pia.push_back(static_cast<PetscInt>(pja.size()));
  }
}

void configure_solver(KSP ksp, Mat a, Mat mp, const Numbering& num, const StokesOptions& opt, bool symmetric, IsH& isu,
                      IsH& isp) {
  FLOWIRE_PETSC(KSPSetOptionsPrefix(ksp, "fem_"));
  FLOWIRE_PETSC(KSPSetOperators(ksp, a, a));
  PC pc = nullptr;
  FLOWIRE_PETSC(KSPGetPC(ksp, &pc));
  if (opt.solver == LinearSolver::Mumps) {
    FLOWIRE_PETSC(KSPSetType(ksp, KSPPREONLY));
    // Stokes is symmetric (indefinite): MUMPS LDLᵀ needs half the work of LU.
    FLOWIRE_PETSC(PCSetType(pc, symmetric ? PCCHOLESKY : PCLU));
    FLOWIRE_PETSC(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
  } else {
    if (opt.velocity_pc != "gamg" && opt.velocity_pc != "hypre")
      throw_usage_error(fmt::format("fem: velocity preconditioner '{}' is not one of: gamg, hypre", opt.velocity_pc));
    FLOWIRE_PETSC(KSPSetType(ksp, KSPFGMRES));
    FLOWIRE_PETSC(KSPGMRESSetRestart(ksp, 200));
    FLOWIRE_PETSC(KSPSetTolerances(ksp, opt.rtol, 1e-300, PETSC_DEFAULT, opt.max_iterations));
    FLOWIRE_PETSC(PCSetType(pc, PCFIELDSPLIT));
    FLOWIRE_PETSC(ISCreateStride(PETSC_COMM_WORLD, num.v_local, num.begin, 1, isu.out()));
    FLOWIRE_PETSC(ISSetBlockSize(isu, 3));
    FLOWIRE_PETSC(ISCreateStride(PETSC_COMM_WORLD, num.p_local, num.begin + num.v_local, 1, isp.out()));
    FLOWIRE_PETSC(PCFieldSplitSetIS(pc, "u", isu));
    FLOWIRE_PETSC(PCFieldSplitSetIS(pc, "p", isp));
    FLOWIRE_PETSC(PCFieldSplitSetType(pc, PC_COMPOSITE_SCHUR));
    FLOWIRE_PETSC(PCFieldSplitSetSchurFactType(pc, PC_FIELDSPLIT_SCHUR_FACT_UPPER));
    FLOWIRE_PETSC(PCFieldSplitSetSchurPre(pc, PC_FIELDSPLIT_SCHUR_PRE_USER, mp));
    default_option("-fem_fieldsplit_u_ksp_type", "preonly");
    default_option("-fem_fieldsplit_u_pc_type", opt.velocity_pc.c_str());
    default_option("-fem_fieldsplit_p_ksp_type", "preonly");
    default_option("-fem_fieldsplit_p_pc_type", "jacobi");
  }
  FLOWIRE_PETSC(KSPSetFromOptions(ksp));
}

}  // namespace flowire::flow::fem::internal
