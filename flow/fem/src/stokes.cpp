// Taylor–Hood P2/P1 Stokes / Navier–Stokes: element matrices computed here, a PETSc AIJ
// matrix with exact (CSR) preallocation, MUMPS or a fieldsplit Schur preconditioner;
// Navier–Stokes by Newton with density continuation and SUPG/LSIC/backflow stabilization.
#include "flowire/flow/fem/stokes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>

#include "stokes_internal.hpp"

namespace flowire::flow::fem::internal {

void add_scaled(StokesSolution& sol, double c, const StokesSolution& other) {
  for (size_t n = 0; n < sol.velocity.size(); ++n) sol.velocity[n] += c * other.velocity[n];
  for (size_t k = 0; k < sol.pressure.size(); ++k) sol.pressure[k] += c * other.pressure[k];
  for (size_t g = 0; g < sol.group_flow.size(); ++g) sol.group_flow[g] += c * other.group_flow[g];
  for (size_t g = 0; g < sol.group_pressure.size(); ++g) sol.group_pressure[g] += c * other.group_pressure[g];
}

void check_conditions(const TetMesh& mesh, std::span<const GroupCondition> cond) {
  if (cond.size() != mesh.groups.size())
    throw_usage_error(
        fmt::format("fem: {} boundary conditions given for {} boundary groups", cond.size(), mesh.groups.size()));
  bool level = false;
  for (size_t g = 0; g < cond.size(); ++g) {
    if (mesh.groups[g].kind == BoundaryGroup::Kind::Wall) continue;
    const auto& c = cond[g];
    const double vals[3] = {c.pressure, c.flow, c.resistance};
    for (double v : vals)
      if (!std::isfinite(v))
        throw_usage_error(fmt::format("fem: boundary value of {} is not finite", mesh.groups[g].name));
    if (c.type == GroupCondition::Type::Resistance && c.resistance < 0.0)
      throw_usage_error(fmt::format("fem: negative resistance {} on {}", c.resistance, mesh.groups[g].name));
    if (c.type != GroupCondition::Type::Flow) level = true;
  }
  if (!level)
    throw_usage_error(
        "fem: every open boundary has a prescribed flow, which leaves the pressure level undetermined; "
        "give at least one a pressure or a resistance");
}

void split_conditions(const TetMesh& mesh, std::span<const GroupCondition> cond, std::vector<int>& unknown,
                      std::vector<double>& known) {
  unknown.clear();
  known.assign(mesh.groups.size(), 0.0);
  for (size_t g = 0; g < mesh.groups.size(); ++g) {
    if (mesh.groups[g].kind == BoundaryGroup::Kind::Wall) continue;
    if (cond[g].type == GroupCondition::Type::Pressure)
      known[g] = cond[g].pressure;
    else
      unknown.push_back(static_cast<int>(g));
  }
}

void unit_fields(System& sys, const TetMesh& mesh, const std::vector<int>& unknown, std::vector<StokesSolution>& units,
                 std::vector<std::vector<double>>& flux) {
  units.clear();
  flux.clear();
  for (int g : unknown) {
    std::vector<double> e(mesh.groups.size(), 0.0);
    e[static_cast<size_t>(g)] = 1.0;
    units.push_back(sys.solve(e, false));
    flux.push_back(units.back().group_flow);
  }
}

double max_abs(const std::vector<Vec3>& v) {
  double m = 0.0;
  for (const Vec3& x : v) m = std::max(m, x.cwiseAbs().maxCoeff());
  return m;
}

StokesSolution solve_linear_stokes(const TetMesh& mesh, std::span<const GroupCondition> cond,
                                   const StokesOptions& opt) {
  System sys(mesh, opt, false);
  std::vector<int> unknown;
  std::vector<double> known;
  split_conditions(mesh, cond, unknown, known);
  sys.prepare_stokes();
  StokesSolution sol = sys.solve(known, true);
  if (!unknown.empty()) {
    std::vector<StokesSolution> units;
    std::vector<std::vector<double>> flux;
    unit_fields(sys, mesh, unknown, units, flux);
    const std::vector<double> p = boundary_pressures(mesh, cond, unknown, sol.group_flow, flux);
    for (size_t k = 0; k < unknown.size(); ++k) add_scaled(sol, p[static_cast<size_t>(unknown[k])], units[k]);
  }
  sol.unknowns = sys.unknowns();
  sol.krylov_iterations = sys.krylov_iterations;
  sol.factorizations = sys.factorizations;
  sol.assemble_seconds = sys.assemble_seconds;
  sol.solve_seconds = sys.solve_seconds;
  return sol;
}

double mean_pressure(const TetMesh& mesh, const std::vector<double>& pressure, int g) {
  double sum = 0.0, area = 0.0, phi[6], dphi[6][2];
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.face_group[f] != g) continue;
    const auto& tri = mesh.faces[f];
    double pv[3];
    for (int k = 0; k < 3; ++k)
      pv[k] = pressure[static_cast<size_t>(mesh.vertex_index[static_cast<size_t>(tri[static_cast<size_t>(k)])])];
    for (const QuadPoint& q : tri_quadrature()) {
      tri_p2(q.xi, phi);
      tri_p2_grad(q.xi, dphi);
      Vec3 ts = Vec3::Zero(), tt = Vec3::Zero();
      for (int k = 0; k < 6; ++k) {
        ts += dphi[k][0] * mesh.nodes[static_cast<size_t>(tri[static_cast<size_t>(k)])];
        tt += dphi[k][1] * mesh.nodes[static_cast<size_t>(tri[static_cast<size_t>(k)])];
      }
      const double da = q.weight * ts.cross(tt).norm();
      const double l[3] = {1.0 - q.xi[0] - q.xi[1], q.xi[0], q.xi[1]};
      sum += da * (l[0] * pv[0] + l[1] * pv[1] + l[2] * pv[2]);
      area += da;
    }
  }
  return area > 0.0 ? sum / area : 0.0;
}

}  // namespace flowire::flow::fem::internal

namespace flowire::flow::fem {

using namespace internal;  // NOLINT(google-build-using-namespace): this file is the solver's own

std::vector<double> group_fluxes(const TetMesh& mesh, const std::vector<Vec3>& velocity) {
  std::vector<double> flux(mesh.groups.size(), 0.0);
  double phi[6], dphi[6][2];
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& tri = mesh.faces[f];
    double sum = 0.0;
    for (const QuadPoint& q : tri_quadrature()) {
      tri_p2(q.xi, phi);
      tri_p2_grad(q.xi, dphi);
      Vec3 ts = Vec3::Zero(), tt = Vec3::Zero(), u = Vec3::Zero();
      for (int k = 0; k < 6; ++k) {
        const auto n = static_cast<size_t>(tri[static_cast<size_t>(k)]);
        ts += dphi[k][0] * mesh.nodes[n];
        tt += dphi[k][1] * mesh.nodes[n];
        u += phi[k] * velocity[n];
      }
      sum += q.weight * u.dot(ts.cross(tt));
    }
    flux[static_cast<size_t>(mesh.face_group[f])] += sum;
  }
  return flux;
}

std::vector<double> boundary_pressures(const TetMesh& mesh, std::span<const GroupCondition> cond,
                                       const std::vector<int>& open, const std::vector<double>& base_flux,
                                       const std::vector<std::vector<double>>& unit_flux) {
  check_conditions(mesh, cond);
  std::vector<double> p(mesh.groups.size(), 0.0);
  for (size_t g = 0; g < cond.size(); ++g)
    if (mesh.groups[g].kind != BoundaryGroup::Kind::Wall && cond[g].type == GroupCondition::Type::Pressure)
      p[g] = cond[g].pressure;
  const auto n = static_cast<Eigen::Index>(open.size());
  if (n == 0) return p;
  // Row i: the condition of group open[i]; column j: the pressure of open[j].
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd rhs(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto gi = static_cast<size_t>(open[static_cast<size_t>(i)]);
    const auto& c = cond[gi];
    switch (c.type) {
      case GroupCondition::Type::Pressure:  // p_i = P
        a(i, i) = 1.0;
        rhs[i] = c.pressure;
        break;
      case GroupCondition::Type::Flow:  // Q_i = F0_i + Σ_j F_j,i p_j = Q
        for (Eigen::Index j = 0; j < n; ++j) a(i, j) = unit_flux[static_cast<size_t>(j)][gi];
        rhs[i] = c.flow - base_flux[gi];
        break;
      case GroupCondition::Type::Resistance:  // p_i − R (F0_i + Σ_j F_j,i p_j) = P_d
        for (Eigen::Index j = 0; j < n; ++j) a(i, j) = -c.resistance * unit_flux[static_cast<size_t>(j)][gi];
        a(i, i) += 1.0;
        rhs[i] = c.pressure + c.resistance * base_flux[gi];
        break;
    }
  }
  // Scale every row to a unit largest entry: flow rows (m³/s/Pa) and pressure rows differ
  // by many orders of magnitude.
  for (Eigen::Index i = 0; i < n; ++i) {
    const double s = a.row(i).cwiseAbs().maxCoeff();
    if (s > 0.0) {
      a.row(i) /= s;
      rhs[i] /= s;
    }
  }
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(a);
  if (lu.rank() < n || lu.rcond() < 1e-13)
    throw_usage_error("fem: the boundary conditions do not determine the boundary pressures");
  const Eigen::VectorXd x = lu.solve(rhs);
  for (Eigen::Index i = 0; i < n; ++i) p[static_cast<size_t>(open[static_cast<size_t>(i)])] = x[i];
  return p;
}

StokesSolution solve_stokes(const TetMesh& mesh, std::span<const double> group_pressure, const StokesOptions& opt) {
  if (group_pressure.size() != mesh.groups.size())
    throw_usage_error(fmt::format("fem: {} boundary pressures given for {} boundary groups", group_pressure.size(),
                                  mesh.groups.size()));
  std::vector<GroupCondition> cond(mesh.groups.size());
  for (size_t g = 0; g < cond.size(); ++g) cond[g] = GroupCondition::at_pressure(group_pressure[g]);
  return solve_stokes(mesh, std::span<const GroupCondition>(cond), opt);
}

StokesSolution solve_stokes(const TetMesh& mesh, std::span<const GroupCondition> cond, const StokesOptions& opt) {
  if (!(opt.viscosity > 0.0)) throw_usage_error("fem: viscosity must be > 0");
  if (mesh.tets.empty()) throw_usage_error("fem: empty mesh");
  check_conditions(mesh, cond);
  ensure_petsc();
  return opt.equations == Equations::NavierStokes ? solve_navier_stokes(mesh, cond, opt)
                                                  : solve_linear_stokes(mesh, cond, opt);
}

StokesBasis::StokesBasis(const TetMesh& mesh, const StokesOptions& opt) : mesh_(mesh) {
  if (opt.equations != Equations::Stokes)
    throw_usage_error("fem: the boundary-value basis is for Stokes only (Navier–Stokes is not linear)");
  if (!(opt.viscosity > 0.0)) throw_usage_error("fem: viscosity must be > 0");
  if (mesh.tets.empty()) throw_usage_error("fem: empty mesh");
  if (opt.body_force || opt.traction)
    throw_usage_error("fem: the boundary-value basis takes no body force or traction");
  ensure_petsc();
  System sys(mesh, opt, false);
  sys.prepare_stokes();
  for (size_t g = 0; g < mesh.groups.size(); ++g) {
    if (mesh.groups[g].kind == BoundaryGroup::Kind::Wall) continue;
    open_.push_back(static_cast<int>(g));
    std::vector<double> e(mesh.groups.size(), 0.0);
    e[g] = 1.0;
    unit_.push_back(sys.solve(e, false));
    flux_.push_back(unit_.back().group_flow);
  }
  unknowns_ = sys.unknowns();
  assemble_seconds_ = sys.assemble_seconds;
  solve_seconds_ = sys.solve_seconds;
}

std::vector<double> StokesBasis::pressures(std::span<const GroupCondition> cond) const {
  // The basis spans every open group: the "base" field is zero and every group pressure
  // is an unknown of the small system (pressure groups get an identity row).
  const std::vector<double> zero(mesh_.groups.size(), 0.0);
  return boundary_pressures(mesh_, cond, open_, zero, flux_);
}

StokesSolution StokesBasis::solve(std::span<const GroupCondition> cond) const {
  const std::vector<double> p = pressures(cond);
  StokesSolution sol;
  sol.velocity.assign(mesh_.nodes.size(), Vec3::Zero());
  sol.pressure.assign(static_cast<size_t>(mesh_.num_vertices), 0.0);
  sol.group_flow.assign(mesh_.groups.size(), 0.0);
  sol.group_pressure.assign(mesh_.groups.size(), 0.0);
  for (size_t k = 0; k < open_.size(); ++k) add_scaled(sol, p[static_cast<size_t>(open_[k])], unit_[k]);
  sol.unknowns = unknowns_;
  sol.factorizations = 1;
  return sol;
}

std::vector<Vec3> boundary_forces(const TetMesh& mesh, const StokesSolution& sol, const StokesOptions& opt) {
  if (sol.velocity.size() != mesh.nodes.size() || sol.pressure.size() != static_cast<size_t>(mesh.num_vertices) ||
      sol.group_pressure.size() != mesh.groups.size())
    throw_usage_error("fem: boundary_forces: the solution belongs to another mesh");
  static const ReferenceNs ref;
  NsParams prm = ns_params(opt);
  if (opt.equations == Equations::Stokes) prm.rho = 0.0;
  const State st{&sol.velocity, &sol.pressure, &sol.group_pressure};
  // A profile inlet carries a prescribed velocity: its traction is not part of the
  // residual.
  const bool profile = opt.equations == Equations::NavierStokes && opt.inlet == InletCondition::Profile;
  std::vector<Vec3> force(mesh.groups.size(), Vec3::Zero());
  std::vector<int> mark(mesh.nodes.size(), -1);
  double res[34], jac[34 * 34], fres[18], fjac[18 * 18];
  for (size_t g = 0; g < mesh.groups.size(); ++g) {
    if (!mesh.groups[g].no_slip()) continue;
    const int tag = static_cast<int>(g);
    for (size_t f = 0; f < mesh.faces.size(); ++f)
      if (mesh.face_group[f] == tag)
        for (int n : mesh.faces[f]) mark[static_cast<size_t>(n)] = tag;
    Vec3 sum = Vec3::Zero();
    for (int e = 0; e < mesh.num_tets(); ++e) {
      const auto& t = mesh.tets[static_cast<size_t>(e)];
      bool touches = false;
      for (int n : t) touches = touches || mark[static_cast<size_t>(n)] == tag;
      if (!touches) continue;
      if (!ns_element(mesh, ref, e, prm, st, res, jac))
        throw_numerical_error(fmt::format("fem: tetrahedron {} is inverted or degenerate", e));
      for (int i = 0; i < 10; ++i)
        if (mark[static_cast<size_t>(t[static_cast<size_t>(i)])] == tag)
          sum -= Vec3(res[3 * i], res[3 * i + 1], res[3 * i + 2]);
    }
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      const auto& grp = mesh.groups[static_cast<size_t>(mesh.face_group[f])];
      if (grp.no_slip() || (profile && grp.kind == BoundaryGroup::Kind::Inlet)) continue;
      const auto& tri = mesh.faces[f];
      bool touches = false;
      for (int n : tri) touches = touches || mark[static_cast<size_t>(n)] == tag;
      if (!touches) continue;
      bool any = false;
      ns_face(mesh, f, prm, st, fres, fjac, any);
      for (int k = 0; k < 6; ++k)
        if (mark[static_cast<size_t>(tri[static_cast<size_t>(k)])] == tag)
          sum -= Vec3(fres[3 * k], fres[3 * k + 1], fres[3 * k + 2]);
    }
    force[g] = sum;
  }
  return force;
}

std::vector<Vec3> surface_forces(const TetMesh& mesh, const StokesSolution& sol, double viscosity) {
  if (sol.velocity.size() != mesh.nodes.size() || sol.pressure.size() != static_cast<size_t>(mesh.num_vertices))
    throw_usage_error("fem: surface_forces: the solution belongs to another mesh");
  // The tetrahedron behind each boundary triangle and the local vertices of the triangle.
  struct Key {
    std::array<int, 3> v;
    bool operator<(const Key& o) const { return v < o.v; }
  };
  std::map<Key, size_t> face_of;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (!mesh.groups[static_cast<size_t>(mesh.face_group[f])].no_slip()) continue;
    Key k{{mesh.faces[f][0], mesh.faces[f][1], mesh.faces[f][2]}};
    std::sort(k.v.begin(), k.v.end());
    face_of.emplace(k, f);
  }
  static constexpr int kFaceVerts[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  static const std::array<std::array<double, 3>, 4> kVert{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  std::vector<Vec3> force(mesh.groups.size(), Vec3::Zero());
  double phi[6], dphi[6][2], g10[10][3], psi[4];
  for (const auto& t : mesh.tets)
    for (const auto& fv : kFaceVerts) {
      Key k{{t[static_cast<size_t>(fv[0])], t[static_cast<size_t>(fv[1])], t[static_cast<size_t>(fv[2])]}};
      std::sort(k.v.begin(), k.v.end());
      const auto it = face_of.find(k);
      if (it == face_of.end()) continue;
      const auto& tri = mesh.faces[it->second];
      // Tetrahedron-local vertex of each triangle vertex.
      int local[3];
      for (int a = 0; a < 3; ++a)
        for (int l = 0; l < 4; ++l)
          if (t[static_cast<size_t>(l)] == tri[static_cast<size_t>(a)]) local[a] = l;
      Vec3 sum = Vec3::Zero();
      for (const QuadPoint& q : tri_quadrature()) {
        tri_p2(q.xi, phi);
        tri_p2_grad(q.xi, dphi);
        Vec3 ts = Vec3::Zero(), tt = Vec3::Zero();
        for (int m = 0; m < 6; ++m) {
          ts += dphi[m][0] * mesh.nodes[static_cast<size_t>(tri[static_cast<size_t>(m)])];
          tt += dphi[m][1] * mesh.nodes[static_cast<size_t>(tri[static_cast<size_t>(m)])];
        }
        const Vec3 nds = ts.cross(tt);  // outward normal times the area element
        const double lam[3] = {1.0 - q.xi[0] - q.xi[1], q.xi[0], q.xi[1]};
        std::array<double, 3> xi{};
        for (int a = 0; a < 3; ++a)
          for (int c = 0; c < 3; ++c)
            xi[static_cast<size_t>(c)] += lam[a] * kVert[static_cast<size_t>(local[a])][static_cast<size_t>(c)];
        tet_p2_grad(xi, g10);
        tet_p1(xi, psi);
        Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
        for (int i = 0; i < 10; ++i)
          j += mesh.nodes[static_cast<size_t>(t[static_cast<size_t>(i)])] *
               Eigen::RowVector3d(g10[i][0], g10[i][1], g10[i][2]);
        const Eigen::Matrix3d jinv_t = j.inverse().transpose();
        Eigen::Matrix3d grad = Eigen::Matrix3d::Zero();
        for (int i = 0; i < 10; ++i)
          grad += sol.velocity[static_cast<size_t>(t[static_cast<size_t>(i)])] *
                  (jinv_t * Eigen::Vector3d(g10[i][0], g10[i][1], g10[i][2])).transpose();
        double p = 0.0;
        for (int l = 0; l < 4; ++l)
          p += psi[l] *
               sol.pressure[static_cast<size_t>(mesh.vertex_index[static_cast<size_t>(t[static_cast<size_t>(l)])])];
        const Eigen::Matrix3d sigma = -p * Eigen::Matrix3d::Identity() + viscosity * (grad + grad.transpose());
        sum -= q.weight * (sigma * nds);
      }
      force[static_cast<size_t>(mesh.face_group[it->second])] += sum;
    }
  return force;
}

void initialize() { internal::ensure_petsc(); }

}  // namespace flowire::flow::fem
