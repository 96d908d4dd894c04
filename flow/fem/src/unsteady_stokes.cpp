// Time-dependent Stokes (BDF2) on a factorized system: each step is one solve per unit
// boundary field.
#include <algorithm>
#include <cmath>

#include "stokes_internal.hpp"

namespace flowire::flow::fem {

using internal::ensure_petsc;
using internal::System;

struct UnsteadyStokes::Impl {
  Impl(const TetMesh& m, const StokesOptions& o) : mesh(m), sys(m, o, false) {}
  ~Impl() {
    for (Vec* v : {&prev, &curr, &hist})
      if (*v) VecDestroy(v);
    for (Vec& v : units) VecDestroy(&v);
  }
  const TetMesh& mesh;
  System sys;
  double rho = 0.0, dt = 0.0, time = 0.0;
  int steps = 0;
  std::vector<int> open;
  std::vector<Vec> units;                              // unit fields (pressure 1 on open[k])
  std::vector<std::vector<double>> flux;               // their fluxes
  Vec prev = nullptr, curr = nullptr, hist = nullptr;  // x^{n−1}, x^n, scratch
  StokesSolution current;
};

UnsteadyStokes::UnsteadyStokes(const TetMesh& mesh, const StokesOptions& opt, double dt) {
  if (opt.equations != Equations::Stokes)
    throw_usage_error("fem: time-dependent solves are for Stokes (Navier–Stokes frames are solved one by one)");
  if (opt.body_force || opt.traction) throw_usage_error("fem: time-dependent Stokes takes no body force or traction");
  if (!(opt.viscosity > 0.0)) throw_usage_error("fem: viscosity must be > 0");
  if (!(opt.density > 0.0) || !std::isfinite(opt.density)) throw_usage_error("fem: density must be > 0");
  if (!(dt > 0.0) || !std::isfinite(dt)) throw_usage_error("fem: the time step must be > 0");
  if (mesh.tets.empty()) throw_usage_error("fem: empty mesh");
  ensure_petsc();
  impl_ = std::make_unique<Impl>(mesh, opt);
  Impl& m = *impl_;
  m.rho = opt.density;
  m.dt = dt;
  // BDF2: (3u^{n+1} − 4u^n + u^{n−1})/(2Δt): the matrix is K + (3ρ/2Δt) M.
  m.sys.prepare_unsteady(1.5 * opt.density / dt);
  m.prev = m.sys.new_vector();
  m.curr = m.sys.new_vector();
  m.hist = m.sys.new_vector();
  for (size_t g = 0; g < mesh.groups.size(); ++g) {
    if (mesh.groups[g].kind == BoundaryGroup::Kind::Wall) continue;
    m.open.push_back(static_cast<int>(g));
    std::vector<double> e(mesh.groups.size(), 0.0);
    e[g] = 1.0;
    FLOWIRE_PETSC(VecSet(m.hist, 0.0));
    m.flux.push_back(m.sys.solve_with_history(e, m.hist).group_flow);
    m.units.push_back(m.sys.new_vector());
    FLOWIRE_PETSC(VecCopy(m.sys.x(), m.units.back()));
  }
  m.current.velocity.assign(mesh.nodes.size(), Vec3::Zero());
  m.current.pressure.assign(static_cast<size_t>(mesh.num_vertices), 0.0);
  m.current.group_flow.assign(mesh.groups.size(), 0.0);
  m.current.group_pressure.assign(mesh.groups.size(), 0.0);
}

UnsteadyStokes::~UnsteadyStokes() = default;

const StokesSolution& UnsteadyStokes::step(std::span<const GroupCondition> cond) {
  Impl& m = *impl_;
  // History h = ρ(4u^n − u^{n−1})/(2Δt); the field with zero group pressures, then the
  // group pressures from the conditions (every open group is a column of the small
  // system, as in StokesBasis), then the combination.
  FLOWIRE_PETSC(VecAXPBYPCZ(m.hist, 4.0 * m.rho / (2.0 * m.dt), -m.rho / (2.0 * m.dt), 0.0, m.curr, m.prev));
  const std::vector<double> zero(m.mesh.groups.size(), 0.0);
  const StokesSolution base = m.sys.solve_with_history(zero, m.hist);
  const std::vector<double> p = boundary_pressures(m.mesh, cond, m.open, base.group_flow, m.flux);
  std::swap(m.prev, m.curr);
  FLOWIRE_PETSC(VecCopy(m.sys.x(), m.curr));
  for (size_t k = 0; k < m.open.size(); ++k)
    FLOWIRE_PETSC(VecAXPY(m.curr, p[static_cast<size_t>(m.open[k])], m.units[k]));
  m.current = m.sys.gather(m.curr);
  m.current.group_pressure = p;
  m.current.unknowns = m.sys.unknowns();
  m.current.factorizations = m.sys.factorizations;
  m.current.assemble_seconds = m.sys.assemble_seconds;
  m.current.solve_seconds = m.sys.solve_seconds;
  for (const Vec3& u : m.current.velocity)
    if (!u.allFinite()) throw_numerical_error("fem: time-dependent Stokes produced NaN");
  m.time += m.dt;
  ++m.steps;
  return m.current;
}

const StokesSolution& UnsteadyStokes::current() const { return impl_->current; }
double UnsteadyStokes::time() const { return impl_->time; }
double UnsteadyStokes::dt() const { return impl_->dt; }
const std::vector<std::vector<double>>& UnsteadyStokes::unit_flux() const { return impl_->flux; }
const std::vector<int>& UnsteadyStokes::open_groups() const { return impl_->open; }

}  // namespace flowire::flow::fem
