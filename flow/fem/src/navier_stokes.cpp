// Steady Navier–Stokes: Newton on the Taylor–Hood system with density continuation, the
// inlet either a pressure (with its flow or resistance) or a prescribed velocity profile.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "stokes_internal.hpp"

namespace flowire::flow::fem::internal {

namespace {

/// The prescribed inlet velocity shape of group g (zero elsewhere and on the wall):
/// `user(x)` when given, else the Poiseuille profile −n (1 − r²/R²) of the end disk
/// (centre, outward normal and radius from the faces; peak 1 m/s into the domain), or with
/// @p flat the uniform −n (1 m/s).
std::vector<Vec3> inlet_shape(const TetMesh& mesh, int g, const std::function<Vec3(const Vec3&)>& user, bool flat) {
  std::vector<Vec3> shape(mesh.nodes.size(), Vec3::Zero());
  std::vector<char> wall(mesh.nodes.size(), 0), inlet(mesh.nodes.size(), 0);
  Vec3 centre = Vec3::Zero(), normal = Vec3::Zero();
  double area = 0.0, phi[6], dphi[6][2];
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& tri = mesh.faces[f];
    if (mesh.groups[static_cast<size_t>(mesh.face_group[f])].kind == BoundaryGroup::Kind::Wall)
      for (int n : tri) wall[static_cast<size_t>(n)] = 1;
    if (mesh.face_group[f] != g) continue;
    for (int n : tri) inlet[static_cast<size_t>(n)] = 1;
    for (const QuadPoint& q : tri_quadrature()) {
      tri_p2(q.xi, phi);
      tri_p2_grad(q.xi, dphi);
      Vec3 ts = Vec3::Zero(), tt = Vec3::Zero(), x = Vec3::Zero();
      for (int k = 0; k < 6; ++k) {
        const auto& xk = mesh.nodes[static_cast<size_t>(tri[static_cast<size_t>(k)])];
        ts += dphi[k][0] * xk;
        tt += dphi[k][1] * xk;
        x += phi[k] * xk;
      }
      const Vec3 nds = q.weight * ts.cross(tt);
      normal += nds;
      centre += nds.norm() * x;
      area += nds.norm();
    }
  }
  if (!(area > 0.0)) throw_usage_error(fmt::format("fem: boundary group {} has no faces", g));
  centre /= area;
  normal.normalize();
  const double r2 = area / std::numbers::pi;
  for (size_t n = 0; n < shape.size(); ++n) {
    if (!inlet[n] || wall[n]) continue;
    const Vec3& x = mesh.nodes[n];
    if (user) {
      shape[n] = user(x);
    } else if (flat) {
      shape[n] = -normal;
    } else {
      const Vec3 d = x - centre;
      const double rho2 = (d - d.dot(normal) * normal).squaredNorm();
      shape[n] = -std::max(0.0, 1.0 - rho2 / r2) * normal;
    }
  }
  return shape;
}

/// The unknowns of the small boundary system: the amplitude of the prescribed inlet
/// velocity (group `fixed`) and the pressures of the other groups without a pressure
/// condition.
struct BoundarySystem {
  const TetMesh& mesh;
  std::span<const GroupCondition> cond;
  int fixed = -1;            // group with a prescribed velocity shape, or -1
  std::vector<int> unknown;  // groups, `fixed` (if any) first

  /// The pressure of group g in field x: its imposed pressure, or for the fixed group
  /// the mean of the pressure field over it.
  [[nodiscard]] double pressure(const StokesSolution& x, int g) const {
    return g == fixed ? mean_pressure(mesh, x.pressure, g) : x.group_pressure[static_cast<size_t>(g)];
  }
  /// The condition of group g applied to field x (left side) and its target.
  [[nodiscard]] double lhs(const StokesSolution& x, int g) const {
    const auto& c = cond[static_cast<size_t>(g)];
    const double q = x.group_flow[static_cast<size_t>(g)];
    switch (c.type) {
      case GroupCondition::Type::Pressure:
        return pressure(x, g);
      case GroupCondition::Type::Flow:
        return q;
      case GroupCondition::Type::Resistance:
        return pressure(x, g) - c.resistance * q;
    }
    return 0.0;
  }
  [[nodiscard]] double target(int g) const {
    const auto& c = cond[static_cast<size_t>(g)];
    return c.type == GroupCondition::Type::Flow ? c.flow : c.pressure;
  }
  /// The values of the unknowns that make base + Σ z_j units[j] satisfy the conditions.
  [[nodiscard]] std::vector<double> solve(const StokesSolution& base, const std::vector<StokesSolution>& units) const {
    const auto n = static_cast<Eigen::Index>(unknown.size());
    Eigen::MatrixXd a(n, n);
    Eigen::VectorXd rhs(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const int g = unknown[static_cast<size_t>(i)];
      for (Eigen::Index j = 0; j < n; ++j) a(i, j) = lhs(units[static_cast<size_t>(j)], g);
      rhs[i] = target(g) - lhs(base, g);
      const double sc = a.row(i).cwiseAbs().maxCoeff();
      if (sc > 0.0) {
        a.row(i) /= sc;
        rhs[i] /= sc;
      }
    }
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(a);
    if (lu.rank() < n || lu.rcond() < 1e-13)
      throw_usage_error("fem: the boundary conditions do not determine the boundary values");
    const Eigen::VectorXd z = lu.solve(rhs);
    return {z.data(), z.data() + n};
  }
};

/// A Navier–Stokes iterate: the field and the amplitude of the prescribed inlet velocity.
struct NsState {
  StokesSolution x;
  double amplitude = 0.0;
};

/// Newton's method for Navier–Stokes at density `rho`, from `state` (updated in place
/// when it converges). Returns the number of Newton steps, or -1 when the iteration
/// fails (no convergence, growing updates, NaN, a failed factorization).
int newton(System& sys, const BoundarySystem& bs, const std::vector<Vec3>* shape, const StokesOptions& opt, double rho,
           NsState& state, int& steps_done) {
  NsParams prm = ns_params(opt);
  prm.rho = rho;
  const TetMesh& mesh = bs.mesh;
  NsState y = state;
  double last = std::numeric_limits<double>::infinity();
  // ρ = 0 is Stokes: linear, so one step solves it.
  const int max_it = rho == 0.0 ? 1 : std::max(1, opt.newton_max_iterations);
  for (int it = 1; it <= max_it; ++it) {
    const State st{&y.x.velocity, &y.x.pressure, &y.x.group_pressure};
    StokesSolution next;
    double amplitude = y.amplitude;
    try {
      sys.prepare_newton(prm, st, shape);
      ++steps_done;
      // The linearized field is affine in the unknown boundary values z (inlet amplitude,
      // unknown group pressures): x + δx₀ + Σ_j (z'_j − z_j) x_j.
      next = sys.solve_rhs();
      add_scaled(next, 1.0, y.x);
      if (!bs.unknown.empty()) {
        std::vector<StokesSolution> units;
        for (int g : bs.unknown) {
          if (g == bs.fixed) {
            StokesSolution ua = sys.solve_lift();
            for (size_t n = 0; n < ua.velocity.size(); ++n) ua.velocity[n] += (*shape)[n];
            ua.group_flow = group_fluxes(mesh, ua.velocity);
            add_scaled(next, -y.amplitude, ua);
            units.push_back(std::move(ua));
          } else {
            std::vector<double> e(mesh.groups.size(), 0.0);
            e[static_cast<size_t>(g)] = 1.0;
            units.push_back(sys.solve(e, false));
            add_scaled(next, -y.x.group_pressure[static_cast<size_t>(g)], units.back());
          }
        }
        const std::vector<double> z = bs.solve(next, units);
        for (size_t j = 0; j < units.size(); ++j) {
          add_scaled(next, z[j], units[j]);
          if (bs.unknown[j] == bs.fixed) amplitude = z[j];
        }
      }
    } catch (const Error& e) {
      if (e.kind() != ErrorKind::Numerical) throw;
      return -1;
    }
    double du = 0.0;
    for (size_t n = 0; n < next.velocity.size(); ++n)
      du = std::max(du, (next.velocity[n] - y.x.velocity[n]).cwiseAbs().maxCoeff());
    const double umax = max_abs(next.velocity);
    const double change = umax > 0.0 ? du / umax : 0.0;
    if (!std::isfinite(change)) return -1;
    y.x = std::move(next);
    y.amplitude = amplitude;
    if (rho == 0.0 || change <= opt.newton_tolerance) {
      state = std::move(y);
      return it;
    }
    // Newton may take a few long steps before it converges; updates that stay large
    // or grow after that mean the density step was too long.
    if (change > 1e2 || (it >= 6 && change > 0.5 * last)) return -1;
    last = change;
  }
  return -1;
}

double inlet_reynolds(const TetMesh& mesh, const StokesSolution& sol, double rho, double eta) {
  for (size_t g = 0; g < mesh.groups.size(); ++g)
    if (mesh.groups[g].kind == BoundaryGroup::Kind::Inlet) {
      const double area = mesh.area(static_cast<int>(g));
      const double d = 2.0 * std::sqrt(area / std::numbers::pi);
      return rho * std::abs(sol.group_flow[g]) / area * d / eta;
    }
  return 0.0;
}

}  // namespace

StokesSolution solve_navier_stokes(const TetMesh& mesh, std::span<const GroupCondition> cond,
                                   const StokesOptions& opt) {
  if (!(opt.density >= 0.0) || !std::isfinite(opt.density)) throw_usage_error("fem: density must be >= 0");
  if (!(opt.backflow >= 0.0)) throw_usage_error("fem: the backflow coefficient must be >= 0");
  if (opt.solver != LinearSolver::Mumps)
    throw_usage_error(
        "fem: Navier–Stokes needs the direct solver (mumps): the fieldsplit preconditioner's Schur "
        "approximation (the pressure mass matrix) ignores convection");
  BoundarySystem bs{mesh, cond, -1, {}};
  if (opt.inlet == InletCondition::Profile) {
    for (size_t g = 0; g < mesh.groups.size(); ++g)
      if (mesh.groups[g].kind == BoundaryGroup::Kind::Inlet) bs.fixed = static_cast<int>(g);
    if (bs.fixed < 0) throw_usage_error("fem: the mesh has no inlet group for the inlet velocity profile");
    if (cond[static_cast<size_t>(bs.fixed)].type == GroupCondition::Type::Resistance)
      throw_usage_error("fem: an inlet with a velocity profile takes a pressure or a flow, not a resistance");
    bs.unknown.push_back(bs.fixed);
  }
  std::vector<int> unknown;
  std::vector<double> known;
  split_conditions(mesh, cond, unknown, known);
  for (int g : unknown)
    if (g != bs.fixed) bs.unknown.push_back(g);
  std::vector<Vec3> shape;
  if (bs.fixed >= 0) {
    shape = inlet_shape(mesh, bs.fixed, opt.inlet_velocity, opt.flat_inlet);
    known[static_cast<size_t>(bs.fixed)] = 0.0;
  }
  System sys(mesh, opt, true, bs.fixed);
  NsState state;
  state.x.velocity.assign(mesh.nodes.size(), Vec3::Zero());
  state.x.pressure.assign(static_cast<size_t>(mesh.num_vertices), 0.0);
  state.x.group_flow.assign(mesh.groups.size(), 0.0);
  state.x.group_pressure = known;
  const std::vector<Vec3>* sh = bs.fixed >= 0 ? &shape : nullptr;
  int newton_steps = 0, accepted = 0, tried = 0;
  double s = 0.0, ds = 1.0;
  if (const StokesSolution* guess = opt.initial_guess) {
    if (guess->velocity.size() != mesh.nodes.size() || guess->pressure.size() != state.x.pressure.size() ||
        guess->group_pressure.size() != mesh.groups.size())
      throw_usage_error("fem: the initial guess belongs to another mesh");
    NsState start = state;
    start.x.velocity = guess->velocity;
    start.x.pressure = guess->pressure;
    for (int g : bs.unknown)
      start.x.group_pressure[static_cast<size_t>(g)] = guess->group_pressure[static_cast<size_t>(g)];
    if (sh) {
      // The inlet velocity must be a multiple of the shape: the least-squares amplitude.
      double uw = 0.0, ww = 0.0;
      for (size_t n = 0; n < shape.size(); ++n) {
        uw += shape[n].dot(guess->velocity[n]);
        ww += shape[n].squaredNorm();
      }
      start.amplitude = ww > 0.0 ? uw / ww : 0.0;
      start.x.group_pressure[static_cast<size_t>(bs.fixed)] = 0.0;
      for (size_t n = 0; n < shape.size(); ++n)
        if (shape[n] != Vec3::Zero()) start.x.velocity[n] = start.amplitude * shape[n];
    }
    start.x.group_flow = group_fluxes(mesh, start.x.velocity);
    ++tried;
    if (newton(sys, bs, sh, opt, opt.density, start, newton_steps) >= 0) {
      state = std::move(start);
      s = 1.0;
      accepted = 1;
    }
  }
  if (s < 1.0 && newton(sys, bs, sh, opt, 0.0, state, newton_steps) < 0)
    throw_numerical_error("fem: the Stokes start of the Navier–Stokes solve failed");
  // Continuation in the density (Re ∝ ρ) from the Stokes solution.
  while (s < 1.0) {
    if (tried == opt.continuation_max_steps || ds < 1e-4) {
      throw_numerical_error(fmt::format(
          "fem: Navier–Stokes did not converge: the density continuation stalled at {:.3g} of the target "
          "(inlet Reynolds number {:.0f} reached; {} Newton steps in {} tries); refine the mesh or lower the "
          "Reynolds number",
          s, inlet_reynolds(mesh, state.x, s * opt.density, opt.viscosity), newton_steps, tried));
    }
    const double s_try = std::min(1.0, s + ds);
    ++tried;
    NsState y = state;
    const int its = newton(sys, bs, sh, opt, s_try * opt.density, y, newton_steps);
    if (its < 0) {
      ds *= 0.25;
      continue;
    }
    state = std::move(y);
    s = s_try;
    ++accepted;
    if (its <= 5) ds *= 2.0;
  }
  StokesSolution x = std::move(state.x);
  for (const Vec3& u : x.velocity)
    if (!u.allFinite()) throw_numerical_error("fem: the solution contains NaN");
  if (bs.fixed >= 0) x.group_pressure[static_cast<size_t>(bs.fixed)] = mean_pressure(mesh, x.pressure, bs.fixed);
  x.unknowns = sys.unknowns();
  x.krylov_iterations = sys.krylov_iterations;
  x.factorizations = sys.factorizations;
  x.newton_iterations = newton_steps;
  x.continuation_steps = accepted;
  x.reynolds = inlet_reynolds(mesh, x, opt.density, opt.viscosity);
  x.assemble_seconds = sys.assemble_seconds;
  x.solve_seconds = sys.solve_seconds;
  return x;
}

}  // namespace flowire::flow::fem::internal
