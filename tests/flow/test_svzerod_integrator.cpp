// The svZeroDSolver network pieces on their own: generalized-α against circuits with
// closed-form solutions (and its order as a slope), the nonlinear blocks' derivatives
// against central finite differences of their residual, one factorization per phase for a
// linear model, and the block registry's errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>

#include "flowire/common/error.hpp"
#include "flowire/flow/svzerod/integrator.hpp"
#include "flowire/flow/svzerod/model.hpp"
#include "flowire/flow/svzerod/simulate.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

namespace fs = std::filesystem;
using namespace svzerod;

fs::path write_model(const std::string& name, const std::string& text) {
  const auto dir = flowire::testing::scratch_dir("flow_svzerod_integrator");
  const auto path = dir / name;
  std::ofstream(path) << text;
  return path;
}

/// Index of the unknown called `name`.
int dof(const Model& m, const std::string& name) {
  for (size_t i = 0; i < m.dofs.size(); ++i)
    if (m.dofs[i] == name) return m.dof_unknown[i];
  ADD_FAILURE() << "no unknown " << name;
  return 0;
}

// Constant flow Q0 into R then C, drained by the resistance Rd:
// C dP/dt = Q0 − P/Rd, P(0) = 0  ⇒  P_out(t) = Q0 Rd (1 − e^{−t/(Rd C)}).
constexpr double kQ0 = 2.0, kR = 0.5, kC = 0.8, kRd = 1.5;

const char* kRcModel = R"({"simulation_parameters": {"number_of_cardiac_cycles": 1,
  "number_of_time_pts_per_cardiac_cycle": 11, "steady_initial": false},
  "boundary_conditions": [{"bc_name": "IN", "bc_type": "FLOW", "bc_values": {"Q": 2.0}},
                          {"bc_name": "OUT", "bc_type": "RESISTANCE", "bc_values": {"R": 1.5, "Pd": 0.0}}],
  "vessels": [{"vessel_id": 0, "vessel_name": "v", "zero_d_element_type": "BloodVessel",
               "zero_d_element_values": {"R_poiseuille": 0.5, "C": 0.8},
               "boundary_conditions": {"inlet": "IN", "outlet": "OUT"}}]})";

/// |P_out(T) − exact| after integrating the RC circuit to T with `steps` steps.
double rc_error(const Model& m, int steps, double T) {
  System sys(m.block_pointers(), m.unknowns, m.period, m.file);
  sys.set_phase(false, 0.0);
  const double dt = T / steps;
  GeneralizedAlpha ga(sys, 0.5, dt, 1e-14, 10, m.file);
  const int qi = dof(m, "flow:IN:v"), pi = dof(m, "pressure:IN:v");
  const int qo = dof(m, "flow:v:OUT"), po = dof(m, "pressure:v:OUT");
  // The consistent initial state: P_out = 0, Q_in = Q0, and its derivatives.
  State s{Eigen::VectorXd::Zero(m.unknowns), Eigen::VectorXd::Zero(m.unknowns)};
  s.y[qi] = kQ0;
  s.y[pi] = kR * kQ0;
  s.yd[po] = kQ0 / kC;
  s.yd[pi] = kQ0 / kC;
  s.yd[qo] = kQ0 / (kC * kRd);
  for (int i = 0; i < steps; ++i) ga.step(s, i * dt);
  EXPECT_DOUBLE_EQ(ga.solves_per_step(), 1.0);
  EXPECT_EQ(sys.factorizations(), 1);  // linear, constant step: one factorization
  const double exact = kQ0 * kRd * (1.0 - std::exp(-T / (kRd * kC)));
  return std::abs(s.y[po] - exact);
}

TEST(FlowSvZeroDIntegrator, RcCircuitConvergesAtSecondOrder) {
  const Model m = read_model(write_model("rc.json", kRcModel).string());
  const double T = 1.0;
  std::vector<double> err;
  for (int steps : {10, 20, 40, 80, 160}) err.push_back(rc_error(m, steps, T));
  for (size_t k = 1; k < err.size(); ++k) {
    const double slope = std::log2(err[k - 1] / err[k]);
    EXPECT_NEAR(slope, 2.0, 0.15) << "steps " << (10 << k) << ": errors " << err[k - 1] << " → " << err[k];
  }
  EXPECT_LT(err.back(), 1e-4 * kQ0 * kRd);
}

// A pressure step P0 across R and L (no C), open to zero pressure:
// L dQ/dt = P0 − R Q, Q(0) = 0  ⇒  Q(t) = (P0/R)(1 − e^{−R t/L}).
TEST(FlowSvZeroDIntegrator, RlCircuitMatchesTheClosedForm) {
  const double p0 = 3.0, r = 2.0, l = 0.5;
  const Model m = read_model(write_model("rl.json", R"({"simulation_parameters": {"number_of_cardiac_cycles": 1,
    "number_of_time_pts_per_cardiac_cycle": 11, "steady_initial": false},
    "boundary_conditions": [{"bc_name": "IN", "bc_type": "PRESSURE", "bc_values": {"P": 3.0}},
                            {"bc_name": "OUT", "bc_type": "PRESSURE", "bc_values": {"P": 0.0}}],
    "vessels": [{"vessel_id": 0, "vessel_name": "v", "zero_d_element_type": "BloodVessel",
                 "zero_d_element_values": {"R_poiseuille": 2.0, "L": 0.5},
                 "boundary_conditions": {"inlet": "IN", "outlet": "OUT"}}]})")
                                 .string());
  System sys(m.block_pointers(), m.unknowns, m.period, m.file);
  sys.set_phase(false, 0.0);
  const double T = 0.75, dt = 1e-3;
  const int steps = static_cast<int>(std::lround(T / dt));
  GeneralizedAlpha ga(sys, 0.5, dt, 1e-14, 10, m.file);
  State s{Eigen::VectorXd::Zero(m.unknowns), Eigen::VectorXd::Zero(m.unknowns)};
  s.y[dof(m, "pressure:IN:v")] = p0;
  s.yd[dof(m, "flow:IN:v")] = p0 / l;
  s.yd[dof(m, "flow:v:OUT")] = p0 / l;
  double worst = 0.0;
  for (int i = 0; i < steps; ++i) {
    ga.step(s, i * dt);
    const double t = (i + 1) * dt;
    const double exact = p0 / r * (1.0 - std::exp(-r * t / l));
    worst = std::max(worst, std::abs(s.y[dof(m, "flow:v:OUT")] - exact));
    EXPECT_NEAR(s.y[dof(m, "flow:IN:v")], s.y[dof(m, "flow:v:OUT")], 1e-12);
  }
  EXPECT_LT(worst, 1e-5 * p0 / r);
}

/// A nonlinear model: stenoses in both vessel types and in a BloodVesselJunction.
const char* kStenosisModel = R"({"simulation_parameters": {"number_of_cardiac_cycles": 1,
    "number_of_time_pts_per_cardiac_cycle": 11},
    "boundary_conditions": [{"bc_name": "IN", "bc_type": "FLOW", "bc_values": {"Q": 1.0}},
                            {"bc_name": "OUT1", "bc_type": "RESISTANCE", "bc_values": {"R": 100.0, "Pd": 0.0}},
                            {"bc_name": "OUT2", "bc_type": "RESISTANCE", "bc_values": {"R": 200.0, "Pd": 0.0}}],
    "vessels": [{"vessel_id": 0, "vessel_name": "v1", "zero_d_element_type": "BloodVessel",
                 "zero_d_element_values": {"R_poiseuille": 2.0, "C": 0.3, "L": 0.7, "stenosis_coefficient": 5.0},
                 "boundary_conditions": {"inlet": "IN"}},
                {"vessel_id": 1, "vessel_name": "v2", "zero_d_element_type": "BloodVesselCRL",
                 "zero_d_element_values": {"R_poiseuille": 3.0, "C": 0.2, "L": 0.4, "stenosis_coefficient": 7.0},
                 "boundary_conditions": {"outlet": "OUT1"}},
                {"vessel_id": 2, "vessel_name": "v3", "zero_d_element_type": "BloodVessel",
                 "zero_d_element_values": {"R_poiseuille": 4.0, "C": 0.1},
                 "boundary_conditions": {"outlet": "OUT2"}}],
    "junctions": [{"junction_name": "J", "junction_type": "BloodVesselJunction", "inlet_vessels": [0],
                   "outlet_vessels": [1, 2],
                   "junction_values": {"R_poiseuille": [1.0, 2.0], "L": [0.1, 0.2],
                                       "stenosis_coefficient": [3.0, 4.0]}}]})";

/// A tree of NORMAL_JUNCTIONs, one fed directly by another, with a flow table at the inlet
/// and resistance, RCR and pressure outlets.
const char* kJunctionModel = R"({"simulation_parameters": {"number_of_cardiac_cycles": 2,
    "number_of_time_pts_per_cardiac_cycle": 51, "output_variable_based": true, "output_all_cycles": true,
    "output_derivative": true},
    "boundary_conditions": [
      {"bc_name": "IN", "bc_type": "FLOW", "bc_values": {"Q": [2.0, 5.0, 3.0, 2.0], "t": [0.0, 0.3, 0.6, 1.0]}},
      {"bc_name": "R3", "bc_type": "RESISTANCE", "bc_values": {"R": 300.0, "Pd": 10.0}},
      {"bc_name": "R4", "bc_type": "RCR", "bc_values": {"Rp": 50.0, "C": 2e-3, "Rd": 400.0, "Pd": 5.0}},
      {"bc_name": "R5", "bc_type": "RESISTANCE", "bc_values": {"R": 500.0}},
      {"bc_name": "R6", "bc_type": "RCR", "bc_values": {"Rp": 80.0, "C": 1e-3, "Rd": 600.0}},
      {"bc_name": "R2", "bc_type": "PRESSURE", "bc_values": {"P": 200.0}}],
    "vessels": [
      {"vessel_id": 0, "vessel_name": "v0", "zero_d_element_values": {"R_poiseuille": 10.0, "C": 1e-3, "L": 2.0},
       "boundary_conditions": {"inlet": "IN"}},
      {"vessel_id": 1, "vessel_name": "v1", "zero_d_element_values": {"R_poiseuille": 20.0, "C": 5e-4, "L": 3.0}},
      {"vessel_id": 2, "vessel_name": "v2", "zero_d_element_values": {"R_poiseuille": 30.0, "C": 4e-4},
       "boundary_conditions": {"outlet": "R2"}},
      {"vessel_id": 3, "vessel_name": "v3", "zero_d_element_type": "BloodVesselCRL",
       "zero_d_element_values": {"R_poiseuille": 40.0, "C": 3e-4, "L": 1.0}, "boundary_conditions": {"outlet": "R3"}},
      {"vessel_id": 4, "vessel_name": "v4", "zero_d_element_values": {"R_poiseuille": 50.0, "L": 4.0},
       "boundary_conditions": {"outlet": "R4"}},
      {"vessel_id": 5, "vessel_name": "v5", "zero_d_element_values": {"R_poiseuille": 60.0, "C": 2e-4},
       "boundary_conditions": {"outlet": "R5"}},
      {"vessel_id": 6, "vessel_name": "v6", "zero_d_element_values": {"R_poiseuille": 70.0, "C": 1e-4, "L": 5.0},
       "boundary_conditions": {"outlet": "R6"}}],
    "junctions": [
      {"junction_name": "J0", "junction_type": "NORMAL_JUNCTION", "inlet_vessels": [0], "outlet_vessels": [1, 2]},
      {"junction_name": "J1", "junction_type": "NORMAL_JUNCTION", "inlet_blocks": ["v1"],
       "outlet_blocks": ["v3", "v4", "J2"]},
      {"junction_name": "J2", "junction_type": "NORMAL_JUNCTION", "inlet_blocks": [], "outlet_blocks": ["v5", "v6"]}]})";

// Every nonlinear block: ∂f/∂y and ∂f/∂ẏ as the system assembles them against central
// differences of the residual f(y, ẏ) at a random state with flows of both signs.
TEST(FlowSvZeroDIntegrator, StenosisJacobiansMatchFiniteDifferences) {
  const Model m = read_model(write_model("stenosis.json", kStenosisModel).string());
  System sys(m.block_pointers(), m.unknowns, m.period, m.file);
  ASSERT_TRUE(sys.nonlinear());
  sys.set_phase(false, 0.0);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  const int n = m.unknowns;
  Eigen::VectorXd y(n), yd(n), fp(n), fm(n);
  for (int i = 0; i < n; ++i) y[i] = u(rng), yd[i] = u(rng);
  auto f = [&](const Eigen::VectorXd& a, const Eigen::VectorXd& ad, Eigen::VectorXd& out) {
    sys.update_solution(0.0, a, ad);
    sys.residual(a, ad, out);
  };
  sys.update_solution(0.0, y, yd);
  const Eigen::MatrixXd jy = Eigen::MatrixXd(sys.dfdy()), jyd = Eigen::MatrixXd(sys.dfdyd());
  const double h = 1e-6;
  double worst = 0.0;
  for (int j = 0; j < n; ++j) {
    for (int which = 0; which < 2; ++which) {
      Eigen::VectorXd a = y, ad = yd;
      Eigen::VectorXd& v = which == 0 ? a : ad;
      v[j] += h;
      f(a, ad, fp);
      v[j] -= 2.0 * h;
      f(a, ad, fm);
      const Eigen::VectorXd fd = (fp - fm) / (2.0 * h);
      const Eigen::VectorXd col = which == 0 ? jy.col(j) : jyd.col(j);
      const double err = (fd - col).cwiseAbs().maxCoeff() / (1.0 + col.cwiseAbs().maxCoeff());
      worst = std::max(worst, err);
      EXPECT_LT(err, 1e-7) << (which == 0 ? "d/dy" : "d/dydot") << " of unknown " << j;
    }
  }
  // The stenosis terms are there: the Jacobian moves with the state.
  sys.update_solution(0.0, 2.0 * y, yd);
  EXPECT_GT((jy - Eigen::MatrixXd(sys.dfdy())).norm(), 1.0);
  std::printf("stenosis Jacobians: worst relative difference to central differences %.2e\n", worst);
}

// NORMAL_JUNCTION connections share one pressure unknown (the junction keeps only its flow
// balance): on a tree with junctions side by side, one of them fed directly by another, the
// smaller system gives every variable (flows, pressures of every connection, RCR pressures,
// their time derivatives, at every step of every cycle) as the full system with the equations
// P_0 − P_i = 0 does, to rounding.
TEST(FlowSvZeroDIntegrator, SharedJunctionPressuresGiveTheFullSystemsSolution) {
  const auto path = write_model("junctions.json", kJunctionModel);
  Summary full_s, shared_s;
  const Result full = simulate(path.string(), &full_s, Options{.share_junction_pressures = false});
  const Result shared = simulate(path.string(), &shared_s);
  // 15 connections, 2 RCR pressures; J0 joins 3 connections, J1 and J2 (through J1:J2) 6.
  EXPECT_EQ(full_s.unknowns, 2 * 15 + 2);
  EXPECT_EQ(shared_s.unknowns, full_s.unknowns - 2 - 5);
  ASSERT_EQ(full.names, shared.names);
  ASSERT_EQ(full.columns, shared.columns);
  double worst = 0.0, scale = 0.0;
  for (size_t i = 0; i < full.data.size(); ++i)
    for (size_t c = 0; c < full.data[i].size(); ++c) scale = std::max(scale, std::abs(full.data[i][c]));
  for (size_t i = 0; i < full.data.size(); ++i) {
    EXPECT_EQ(full.times[i], shared.times[i]);
    for (size_t c = 0; c < full.data[i].size(); ++c)
      worst = std::max(worst, std::abs(full.data[i][c] - shared.data[i][c]) / scale);
  }
  EXPECT_LT(worst, 1e-12);
  // The pressures of a junction's connections are one value, and it moves over the cycle.
  auto series = [&](const std::string& name) {
    std::vector<double> v;
    for (size_t i = 0; i < shared.names.size(); ++i)
      if (shared.names[i] == name) v.push_back(shared.data[i][0]);
    return v;
  };
  const auto p_in = series("pressure:v1:J1"), p_j2 = series("pressure:J2:v6");
  ASSERT_EQ(p_in.size(), 101u);
  EXPECT_EQ(p_in, p_j2);
  EXPECT_GT(*std::max_element(p_in.begin(), p_in.end()) - *std::min_element(p_in.begin(), p_in.end()), 10.0);
  std::printf("shared junction pressures: %d unknowns for %d, largest difference %.2e of the largest value\n",
              shared_s.unknowns, full_s.unknowns, worst);
}

// The solve against the matrix it inverts: J x = b for random b, J = a_ẏ ∂f/∂ẏ + a_y ∂f/∂y
// assembled on its own, in both phases, for a linear model and a nonlinear one at a random
// state; after a factorization with pivoting (KLU's factors copied by rows) and after
// refactorizations on the same pivots (KLU's solve first, then the copy).
TEST(FlowSvZeroDIntegrator, SolveInvertsTheIterationMatrix) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const char* text : {kJunctionModel, kStenosisModel}) {
    const Model m = read_model(write_model("solve.json", text).string());
    System sys(m.block_pointers(), m.unknowns, m.period, m.file);
    const int n = m.unknowns;
    for (const bool steady : {true, false}) {
      sys.set_phase(steady, 0.0);
      for (int trial = 0; trial < 3; ++trial) {
        Eigen::VectorXd y(n), yd(n), b(n);
        for (int i = 0; i < n; ++i) y[i] = u(rng), yd[i] = u(rng), b[i] = 1e3 * u(rng);
        sys.update_solution(0.0, y, yd);
        const double a_yd = 0.75, a_y = 1e-3 * (1 + trial);
        sys.factorize(a_yd, a_y);
        const Eigen::SparseMatrix<double> j = a_yd * sys.dfdyd() + a_y * sys.dfdy();
        for (int again = 0; again < 3; ++again) {
          Eigen::VectorXd x = b;
          sys.solve(x);
          const Eigen::VectorXd r = j * x - b;
          const double scale = (Eigen::MatrixXd(j).cwiseAbs() * x.cwiseAbs()).maxCoeff() + b.cwiseAbs().maxCoeff();
          EXPECT_LT(r.cwiseAbs().maxCoeff() / scale, 1e-14)
              << (steady ? "steady" : "pulsatile") << " trial " << trial << " solve " << again;
          b = b.reverse().eval();
        }
      }
    }
  }
}

// A linear model whose only time table is a boundary value: J is factorized once in the
// steady phase and once for the whole pulsatile run.
TEST(FlowSvZeroDIntegrator, LinearModelIsFactorizedOncePerPhase) {
  FLOWIRE_REQUIRE_SHARED("peers/svzerodsolver/cases/pulsatileFlow_R_RCR.json");
  Summary s;
  (void)simulate((flowire::testing::shared_dir() / "peers/svzerodsolver/cases/pulsatileFlow_R_RCR.json").string(), &s);
  EXPECT_GT(s.steps, 100);
  EXPECT_EQ(s.factorizations, 2);
  EXPECT_DOUBLE_EQ(s.newton_iterations_per_step, 1.0);
}

// A resistance that follows a table over the cycle changes J at every step.
TEST(FlowSvZeroDIntegrator, TimeVaryingResistanceIsRefactorized) {
  Summary s;
  (void)simulate(write_model("rt.json", R"({"simulation_parameters": {"number_of_cardiac_cycles": 1,
    "number_of_time_pts_per_cardiac_cycle": 21, "steady_initial": false},
    "boundary_conditions": [{"bc_name": "IN", "bc_type": "FLOW", "bc_values": {"Q": 1.0}},
                            {"bc_name": "OUT", "bc_type": "RESISTANCE",
                             "bc_values": {"R": [1.0, 2.0, 1.0], "t": [0.0, 0.5, 1.0], "Pd": 0.0}}],
    "vessels": [{"vessel_id": 0, "vessel_name": "v", "zero_d_element_values": {"R_poiseuille": 1.0, "C": 0.1},
                 "boundary_conditions": {"inlet": "IN", "outlet": "OUT"}}]})")
                     .string(),
                 &s);
  EXPECT_EQ(s.steps, 20);
  EXPECT_GE(s.factorizations, 19);
}

TEST(FlowSvZeroDRegistry, UnknownBlockTypeNamesTheFileAndTheBlock) {
  const auto path = write_model("unknown_type.json", R"({"simulation_parameters": {"number_of_cardiac_cycles": 1,
    "number_of_time_pts_per_cardiac_cycle": 5},
    "boundary_conditions": [{"bc_name": "IN", "bc_type": "FLOW", "bc_values": {"Q": 1.0}},
                            {"bc_name": "OUT", "bc_type": "RESISTANCE", "bc_values": {"R": 1.0}}],
    "vessels": [{"vessel_id": 0, "vessel_name": "aorta7", "zero_d_element_type": "BloodVesselXYZ",
                 "zero_d_element_values": {"R_poiseuille": 1.0},
                 "boundary_conditions": {"inlet": "IN", "outlet": "OUT"}}]})");
  try {
    (void)read_model(path.string());
    FAIL() << "an unknown block type was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);  // the command line exits 2 on input errors
    const std::string what = e.what();
    EXPECT_NE(what.find(path.string()), std::string::npos) << what;
    EXPECT_NE(what.find("aorta7"), std::string::npos) << what;
    EXPECT_NE(what.find("BloodVesselXYZ"), std::string::npos) << what;
    EXPECT_NE(what.find("BloodVesselCRL"), std::string::npos) << what;  // lists the supported types
  }
  EXPECT_TRUE(Registry::instance().has(Section::Vessel, "BloodVessel"));
  EXPECT_FALSE(Registry::instance().has(Section::Vessel, "RCR"));  // a boundary condition, not a vessel
}

TEST(FlowSvZeroDRegistry, UnknownParameterNamesTheBlockAndTheKey) {
  const auto path = write_model("unknown_key.json", R"({"simulation_parameters": {"number_of_cardiac_cycles": 1,
    "number_of_time_pts_per_cardiac_cycle": 5},
    "boundary_conditions": [{"bc_name": "IN", "bc_type": "FLOW", "bc_values": {"Q": 1.0}},
                            {"bc_name": "OUT", "bc_type": "RCR", "bc_values": {"Rp": 1.0, "C": 1.0, "Rd": 1.0, "Cd": 2.0}}],
    "vessels": [{"vessel_id": 0, "vessel_name": "v", "zero_d_element_values": {"R_poiseuille": 1.0},
                 "boundary_conditions": {"inlet": "IN", "outlet": "OUT"}}]})");
  try {
    (void)read_model(path.string());
    FAIL() << "an unknown parameter was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    const std::string what = e.what();
    EXPECT_NE(what.find("'OUT'"), std::string::npos) << what;
    EXPECT_NE(what.find("'Cd'"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace flowire::flow
