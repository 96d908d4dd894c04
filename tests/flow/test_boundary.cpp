// The outlet catalogue (spec.hpp OutletBC): each kind written as the svZeroDSolver block of its
// name and read back; its impedance against its steady law; bad values refused naming the place;
// a coronary bed read from a scene and simulated by the rlc model against the exact solution of
// a compliant tube loaded by the bed's impedance.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <nlohmann/json.hpp>

#include "flowire/common/config.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/rlc.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/flow/spec.hpp"
#include "flowire/flow/svzerod/block.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

using cd = std::complex<double>;

OutletBC coronary(double pim = 500.0) {
  OutletBC o;
  o.type = OutletBC::Type::Coronary;
  o.coronary = {.ra = 3e7, .ca = 1e-9, .ram = 5e7, .cim = 4e-9, .rv = 7e7, .pim = Waveform::constant(pim), .pv = 200};
  return o;
}

/// Every kind, with values that differ from each other and from the defaults.
std::vector<OutletBC> every_kind() {
  std::vector<OutletBC> all;
  all.push_back(OutletBC::at_pressure(1234.0));
  OutletBC table = OutletBC::at_pressure(0.0);
  table.pressure = Waveform::table({0.0, 0.3, 0.8}, {100.0, 900.0, 100.0});
  all.push_back(table);
  OutletBC q;
  q.type = OutletBC::Type::Flow;
  q.flow = Waveform::constant(2e-6);
  all.push_back(q);
  all.push_back(OutletBC::with_resistance(3e8, 400.0));
  all.push_back(OutletBC::rcr(1e7, 2e-9, 9e7, 650.0));
  OutletBC cor = coronary();
  cor.coronary.pim = Waveform::table({0.0, 0.4, 0.8}, {1000.0, 14000.0, 1000.0});
  all.push_back(cor);
  return all;
}

TEST(OutletCatalogue, EachKindWritesTheSvZeroDBlockItReadsBack) {
  for (const OutletBC& o : every_kind()) {
    const nlohmann::json bc = o.to_svzerod("out");
    SCOPED_TRACE(bc.dump());
    EXPECT_EQ(bc.at("bc_type").get<std::string>(), std::string(o.kind()));
    // The svZeroDSolver engine takes it as the block of that name, every value asked for.
    double period = -1.0;
    svzerod::BlockInput in(bc.at("bc_values"), "t.json", "out", period);
    EXPECT_NO_THROW((void)svzerod::Registry::instance().create(svzerod::Section::BoundaryCondition,
                                                               bc.at("bc_type").get<std::string>(), in));
    const OutletBC back = OutletBC::from_svzerod(bc, "t.json");
    ASSERT_EQ(back.type, o.type);
    EXPECT_EQ(back.steady_resistance(), o.steady_resistance());
    EXPECT_EQ(back.steady_pressure(), o.steady_pressure());
    for (double t : {0.0, 0.1, 0.35, 0.77}) {
      EXPECT_EQ(back.pressure(t), o.pressure(t));
      EXPECT_EQ(back.flow(t), o.flow(t));
      EXPECT_EQ(back.coronary.pim(t), o.coronary.pim(t));
    }
    if (o.type == OutletBC::Type::Rcr || o.type == OutletBC::Type::Coronary) {
      EXPECT_EQ(back.impedance(20.0), o.impedance(20.0));
    }
  }
  // A sine is written as a table of one period that passes through the sine.
  OutletBC sine = OutletBC::at_pressure(0.0);
  sine.pressure = Waveform::sine(1200.0, 800.0, 0.8);
  const OutletBC back = OutletBC::from_svzerod(sine.to_svzerod("s"), "t.json");
  for (double t : {0.0, 0.2, 0.4, 0.6})  // on the table's samples
    EXPECT_NEAR(back.pressure(t), sine.pressure(t), 1e-9);
  EXPECT_NEAR(back.pressure(0.1234), sine.pressure(0.1234), 400.0 * 0.5 * std::pow(2 * M_PI / 128, 2));
}

TEST(OutletCatalogue, ImpedancesTendToTheSteadyLawAndToTheirProximalResistance) {
  for (const OutletBC& o : every_kind()) {
    if (o.type == OutletBC::Type::Pressure || o.type == OutletBC::Type::Flow) {
      EXPECT_THROW((void)o.impedance(1.0), Error);
      continue;
    }
    EXPECT_NEAR(std::abs(o.impedance(0.0) - o.steady_resistance()), 0.0, 1e-12 * o.steady_resistance());
    // Towards high frequency every capacitor shorts what lies behind it.
    const double proximal =
        o.type == OutletBC::Type::Rcr ? o.rp : (o.type == OutletBC::Type::Coronary ? o.coronary.ra : o.resistance);
    EXPECT_NEAR(std::abs(o.impedance(1e9) - proximal), 0.0, 1e-3 * proximal);
  }
  // The coronary bed at one frequency, by its circuit written as admittances node by node.
  const OutletBC k = coronary();
  const double w = 25.0;
  const cd iw(0.0, w);
  const cd y_im = iw * k.coronary.cim + 1.0 / k.coronary.rv;                // Cim ∥ Rv
  const cd y_a = iw * k.coronary.ca + 1.0 / (k.coronary.ram + 1.0 / y_im);  // Ca ∥ (Ram + ...)
  EXPECT_NEAR(std::abs(k.impedance(w) - (k.coronary.ra + 1.0 / y_a)), 0.0, 1e-9 * std::abs(k.impedance(w)));
}

TEST(OutletCatalogue, ValuesNoOutletCanHaveAreRefusedNamingThePlace) {
  auto refused = [](OutletBC o, const std::string& message) {
    try {
      o.check("m.json: boundary_conditions[2]");
      ADD_FAILURE() << "accepted " << message;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
      EXPECT_NE(std::string(e.what()).find("m.json: boundary_conditions[2]"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  refused(OutletBC::with_resistance(-1.0), "resistance -1 must be positive");
  refused(OutletBC::rcr(1e7, -1e-9, 1e8), "C = -1e-09 must be a finite value >= 0");
  refused(OutletBC::rcr(0.0, 1e-9, 0.0), "Rp + Rd must be positive");
  refused(OutletBC::rcr(1e7, 1e-9, std::nan("")), "Rd = nan");
  OutletBC k = coronary();
  k.coronary.rv = 0.0;
  refused(k, "needs Rv > 0");
  k = coronary();
  k.coronary.ram = -5.0;
  refused(k, "Ram = -5");
  // svZeroDSolver forms that are not outlets, or are incomplete.
  const auto from = [](const std::string& text) {
    return OutletBC::from_svzerod(nlohmann::json::parse(text), "m.json");
  };
  EXPECT_THROW(from(R"({"bc_name": "x", "bc_type": "ClosedLoopRCR", "bc_values": {"Rp": 1, "C": 1, "Rd": 1}})"), Error);
  try {
    from(
        R"({"bc_name": "lca", "bc_type": "CORONARY", "bc_values": {"Ra1": 1, "Ra2": 1, "Ca": 1, "Cc": 1, "Pim": 0, "P_v": 0}})");
    ADD_FAILURE() << "accepted a coronary bed without Rv1";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("m.json: 'lca': the value 'Rv1' is missing"), std::string::npos) << e.what();
  }
}

TEST(OutletCatalogue, ACoronaryBedLoadsACompliantTubeWithItsImpedance) {
  // A 30 cm compliant tube (r = 5 mm, E = 0.4 MPa, h = r/10) fed a 4 Hz pressure wave into a
  // coronary bed read from the scene: the inlet flow's mean and first harmonic against the exact
  // transmission line loaded by the bed's impedance Z(ω) (the intramyocardial and venous
  // pressures constant, so sources of the mean only). An RCR of the same steady resistance in its
  // place changes the harmonic by far more than the tolerance: the bed's own dynamics are what
  // the agreement shows.
  vessels::Centerlines c;
  c.branches.push_back({"tube", {Vec3(0, 0, 0), Vec3(0.3, 0, 0)}, {5e-3, 5e-3}});
  const Network net = Network::build(c, {.max_segment_length = 2.5e-3});
  config::Schema schema;
  declare_scene_keys(schema);
  const double T = 0.25;
  const auto cfg = config::load_config_text(R"(
flow:
  model: rlc
  inlet: {pressure: {waveform: sine, systolic: 13000, diastolic: 11000, period: 0.25 s}, node: 0}
  outlets:
    tube: {coronary: {Ra: 3e7, Ca: 1e-9, Ram: 5e7, Cim: 4e-9, Rv: 7e7, Pim: 500, Pv: 200}}
  wall: {youngs_modulus: 0.4 MPa, thickness_ratio: 0.1}
)",
                                            "s.yaml", schema);
  FlowSpec spec = from_config(cfg, net);
  spec.dt = T / 400;
  const OutletBC* bed = nullptr;
  for (const auto& o : spec.outlets)
    if (o.type == OutletBC::Type::Coronary) bed = &o;
  ASSERT_NE(bed, nullptr);
  EXPECT_EQ(bed->coronary.cim, 4e-9);
  auto inlet_flow = [&](const FlowSpec& s) {
    auto solver = make_solver(net, s);
    EXPECT_TRUE(periodic_info(*solver).converged);
    const int n = 400;
    const int seg = 0;  // from node 0
    EXPECT_EQ(net.segment(seg).node_from, 0);
    std::array<cd, 2> q{};
    for (int k = 0; k < n; ++k) {
      solver->advance(20.0 * T + T * k / n);
      for (int h = 0; h < 2; ++h)
        q[h] += solver->segment_flow(seg) * std::exp(cd(0.0, -2.0 * M_PI * h * k / n)) / static_cast<double>(n);
    }
    return q;
  };
  const auto q = inlet_flow(spec);
  const double w = 2.0 * M_PI / T, r = 5e-3, mu = spec.viscosity, rho = spec.density, l = 0.3;
  const double E = 0.4e6, h = 0.5e-3;
  auto line = [&](cd load) {
    const cd z(8.0 * mu / (M_PI * std::pow(r, 4)), w * rho / (M_PI * r * r));
    const cd y(0.0, w * 3.0 * M_PI * r * r * r / (2.0 * E * h));
    const auto zc = std::sqrt(z / y), th = std::tanh(std::sqrt(z * y) * l);
    return zc * (load + zc * th) / (zc + load * th);
  };
  // Mean: P̄ = Q̄ (R_tube + Ra + Ram + Rv) + Pv.
  const double r_tube = 8.0 * mu * l / (M_PI * std::pow(r, 4));
  EXPECT_NEAR(q[0].real(), (12000.0 - 200.0) / (r_tube + bed->steady_resistance()), 1e-6 * std::abs(q[0]));
  const cd p1(0.0, -(13000.0 - 11000.0) / 4.0);  // the sine's first harmonic
  const cd exact = p1 / line(bed->impedance(w));
  EXPECT_LT(std::abs(q[1] / exact - 1.0), 0.01) << "simulated " << q[1] << " exact " << exact;
  const OutletBC same_resistance =
      OutletBC::rcr(bed->coronary.ra, bed->coronary.ca + bed->coronary.cim, bed->coronary.ram + bed->coronary.rv);
  EXPECT_GT(std::abs(p1 / line(same_resistance.impedance(w)) / exact - 1.0), 0.1) << "the bed would not show";
}

TEST(OutletCatalogue, SceneOutletsOfEveryKindAndTheirBadValues) {
  vessels::Centerlines c;
  c.branches.push_back({"trunk", {Vec3(0, 0, 0), Vec3(0.1, 0, 0)}, {4e-3, 4e-3}});
  c.branches.push_back({"left", {Vec3(0.1, 0, 0), Vec3(0.15, 0.03, 0)}, {3e-3, 3e-3}});
  c.branches.push_back({"right", {Vec3(0.1, 0, 0), Vec3(0.15, -0.03, 0)}, {3e-3, 3e-3}});
  const Network net = Network::build(c, {.max_segment_length = 1e-2});
  config::Schema schema;
  declare_scene_keys(schema);
  auto spec = [&](const std::string& outlets) {
    return from_config(
        config::load_config_text("flow:\n  inlet: {pressure: 1000, node: trunk}\n  outlets: " + outlets + "\n",
                                 "s.yaml", schema),
        net);
  };
  // A fixed outflow at one daughter, the other drains through a resistance: mass balance
  // puts the rest of the inlet flow through the resistance.
  const FlowSpec s = spec("{left: {flow: 1e-6}, right: {resistance: 1e8}}");
  auto solver = make_solver(net, s);
  std::vector<double> p(static_cast<size_t>(net.num_nodes())), q(static_cast<size_t>(net.num_segments()));
  solver->solve_at(0.0, p, q);
  for (const auto& o : s.outlets) {
    const int seg = *net.node_segments(o.node).first;
    const double out = net.segment(seg).node_to == o.node ? q[static_cast<size_t>(seg)] : -q[static_cast<size_t>(seg)];
    if (o.type == OutletBC::Type::Flow) {
      EXPECT_NEAR(out, 1e-6, 1e-15);
    } else {
      ASSERT_EQ(o.type, OutletBC::Type::Resistance);
      EXPECT_NEAR(out, p[static_cast<size_t>(o.node)] / 1e8, 1e-15);
    }
  }
  // Bad values: one line naming the file, the line and the key.
  auto refused = [&](const std::string& outlets, const std::string& message) {
    try {
      (void)spec(outlets);
      ADD_FAILURE() << "accepted " << outlets;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  refused("{left: {coronary: {Ra: 1e7, Ca: 1e-9, Ram: 1e7, Cim: 1e-9}}}", "s.yaml:3: flow.outlets.left.coronary");
  refused("{left: {coronary: {Ra: -1e7, Rv: 1e7}}}", "flow.outlets.left.coronary.Ra");
  refused("{rcr: {Rp: 1e7, C: -1e-9, Rd: 1e8}}", "flow.outlets.rcr.C");
  refused("{left: {flow: 1e-6, resistance: 1e8}}", "give one of pressure, resistance, rcr, coronary or flow");
  refused("{nowhere: {resistance: 1e8}}", "nowhere");
}

}  // namespace
}  // namespace flowire::flow
