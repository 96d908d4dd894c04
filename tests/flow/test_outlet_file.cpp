// Outlet conditions from patient-model files (flow/outlet_file.hpp, flow.outlets.file): an
// svOneDSolver deck's RCR and RESISTANCE tables at the network ends of their outlet nodes, a
// SimVascular rcrt.dat by outlet name, in SI from CGS; on the OSMSC0006 aorto-femoral deck each of
// its nine outlets drains with P/Q = Rp + Rd of its own table; bad files refused naming the place.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "flow_test_networks.hpp"
#include "flowire/common/config.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/openbf.hpp"
#include "flowire/flow/outlet_file.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire/flow/spec.hpp"
#include "flowire/vessels/io.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

using test::flow_schema;

std::string write(const std::filesystem::path& p, const std::string& text) {
  std::ofstream(p) << text;
  return p.string();
}

/// A Y in cm: trunk 0 -> 1, left 1 -> 2 (RCR), right 1 -> 3 (RESISTANCE); @p left_table and
/// @p right_kind vary the bad cases.
std::string y_deck(const std::string& left_table = "0.0 100.0\n0.0 0.0005\n0.0 1500.0\n",
                   const std::string& right_kind = "RESISTANCE") {
  return "NODE 0 0.0 0.0 0.0\nNODE 1 0.0 0.0 -4.0\nNODE 2 -1.0 0.0 -6.0\nNODE 3 1.0 0.0 -6.0\n"
         "SEGMENT trunk 0 4.0 10 0 1 1.0 1.0 0.0 MAT1 NONE 0.0 0 0 NOBOUND NONE\n"
         "SEGMENT left 1 2.2360679775 10 1 2 0.3 0.3 0.0 MAT1 NONE 0.0 0 0 RCR RCR_L\n"
         "SEGMENT right 2 2.2360679775 10 1 3 0.3 0.3 0.0 MAT1 NONE 0.0 0 0 " +
         right_kind +
         " R_R\n"
         "JOINT J1 1 IN1 OUT1\nJOINTINLET IN1 1 0\nJOINTOUTLET OUT1 2 1 2\n"
         "DATATABLE RCR_L LIST\n" +
         left_table +
         "ENDDATATABLE\n"
         "DATATABLE R_R LIST\n0.0 2000.0\n10.0 2000.0\nENDDATATABLE\n"
         "MATERIAL MAT1 OLUFSEN 1.06 0.04 0.0 1.0 2.0e7 -22.5267 8.65e5\n";
}

FlowSpec spec_with(const std::string& outlets, const Network& net) {
  return from_config(
      config::load_config_text("flow:\n  inlet: {flow: 1e-5}\n  outlets: " + outlets + "\n", "s.yaml", flow_schema()),
      net);
}

std::string refused(const std::string& outlets, const Network& net) {
  try {
    (void)spec_with(outlets, net);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    return e.what();
  }
  ADD_FAILURE() << "accepted: " << outlets;
  return {};
}

}  // namespace

TEST(OutletFile, ADecksOutletsTakeTheirTablesInSiAtTheirEnds) {
  const auto dir = flowire::testing::scratch_dir("outlet-file-deck");
  const std::string deck = write(dir / "y.in", y_deck());
  const Network net = vessels::read_network(deck);
  const FlowSpec s = spec_with("{file: " + deck + "}", net);
  ASSERT_EQ(s.outlets.size(), 2u);
  for (const OutletBC& o : s.outlets) {
    const Vec3 x = net.node(o.node);
    EXPECT_EQ(net.degree(o.node), 1);
    if (x.x() < 0.0) {  // the left end, (-1, 0, -6) cm
      EXPECT_NEAR((x - Vec3(-0.01, 0.0, -0.06)).norm(), 0.0, 1e-12);
      ASSERT_EQ(o.type, OutletBC::Type::Rcr);
      EXPECT_DOUBLE_EQ(o.rp, 100.0 * 1e5);   // dyn s/cm^5 -> Pa s/m^3
      EXPECT_DOUBLE_EQ(o.c, 0.0005 * 1e-5);  // cm^5/dyn -> m^3/Pa
      EXPECT_DOUBLE_EQ(o.rd, 1500.0 * 1e5);
    } else {
      ASSERT_EQ(o.type, OutletBC::Type::Resistance);
      EXPECT_DOUBLE_EQ(o.resistance, 2000.0 * 1e5);
      EXPECT_EQ(o.distal_pressure, 0.0);
    }
  }
  // The scene's own named outlet wins over the file's.
  int right = -1;
  for (int e : net.ends())
    if (net.node(e).x() > 0.0) right = e;
  const FlowSpec named = spec_with(fmt::format("{{file: {}, \"{}\": {{pressure: 7}}}}", deck, right), net);
  for (const OutletBC& o : named.outlets)
    if (o.node == right) {
      EXPECT_EQ(o.type, OutletBC::Type::Pressure);
      EXPECT_EQ(o.pressure.value, 7.0);
    }
}

TEST(OutletFile, AnRcrtDatGivesEachNamedOutletItsWindkessel) {
  const auto dir = flowire::testing::scratch_dir("outlet-file-rcrt");
  const std::string net_file = write(dir / "y.yaml",
                                     "length_unit: mm\nbranches:\n"
                                     "  - name: trunk\n    points: [[0, 0, 0, 5], [0, 0, -40, 5]]\n"
                                     "  - name: cap_left\n    points: [[0, 0, -40, 3], [-10, 0, -60, 3]]\n"
                                     "  - name: cap_right\n    points: [[0, 0, -40, 3], [10, 0, -60, 3]]\n");
  const Network net = vessels::read_network(net_file);
  const std::string rcrt = write(dir / "rcrt.dat",
                                 "2\n2\ncap_left\n90.0\n0.0008\n1200\n0.0 0.0\n1.0 0.0\n"
                                 "2\ncap_right\n100.0\n0.0004\n1100\n0.0 10.0\n1.0 10.0\n");
  const FlowSpec s = spec_with("{file: " + rcrt + "}", net);
  ASSERT_EQ(s.outlets.size(), 2u);
  for (const OutletBC& o : s.outlets) {
    ASSERT_EQ(o.type, OutletBC::Type::Rcr);
    const bool left = net.node(o.node).x() < 0.0;
    EXPECT_DOUBLE_EQ(o.rp, (left ? 90.0 : 100.0) * 1e5);
    EXPECT_DOUBLE_EQ(o.c, (left ? 0.0008 : 0.0004) * 1e-5);
    EXPECT_DOUBLE_EQ(o.rd, (left ? 1200.0 : 1100.0) * 1e5);
    EXPECT_DOUBLE_EQ(o.distal_pressure, left ? 0.0 : 1.0);  // 10 dyn/cm^2
  }
  // A name the network does not have, named with the file and the key.
  const std::string other = write(dir / "other.dat", "2\n2\ncap_aorta_2\n90.0\n0.0008\n1200\n0.0 0.0\n1.0 0.0\n");
  const std::string msg = refused("{file: " + other + "}", net);
  EXPECT_NE(msg.find("flow.outlets.file"), std::string::npos) << msg;
  EXPECT_NE(msg.find("no branch named 'cap_aorta_2'"), std::string::npos) << msg;
}

TEST(OutletFile, AnSvZeroDModelGivesEachOutletItsConditionOfAnyKindInSi) {
  // The Y of the rcrt.dat case; the model's vessels are SimVascular's `<branch>_seg<k>` pieces:
  // `left_seg1` ends in a coronary bed named after nothing in the network (found through its
  // vessel), `cap_right` names its branch; the inlet's FLOW is not an outlet.
  const auto dir = flowire::testing::scratch_dir("outlet-file-svzerod");
  const std::string net_file = write(dir / "y.yaml",
                                     "length_unit: mm\nbranches:\n"
                                     "  - name: trunk\n    points: [[0, 0, 0, 5], [0, 0, -40, 5]]\n"
                                     "  - name: left\n    points: [[0, 0, -40, 3], [-10, 0, -60, 3]]\n"
                                     "  - name: cap_right\n    points: [[0, 0, -40, 3], [10, 0, -60, 3]]\n");
  const Network net = vessels::read_network(net_file);
  const auto model = [&](const std::string& left_bc) {
    return R"({"vessels": [
  {"vessel_id": 0, "vessel_name": "trunk_seg0", "boundary_conditions": {"inlet": "INFLOW"}},
  {"vessel_id": 1, "vessel_name": "left_seg0"},
  {"vessel_id": 2, "vessel_name": "left_seg1", "boundary_conditions": {"outlet": "LCA_1"}},
  {"vessel_id": 3, "vessel_name": "right_seg0", "boundary_conditions": {"outlet": "cap_right"}}],
 "boundary_conditions": [
  {"bc_name": "INFLOW", "bc_type": "FLOW", "bc_values": {"Q": [1.0, 2.0, 1.0], "t": [0.0, 0.5, 1.0]}},
  )" + left_bc +
           R"(,
  {"bc_name": "cap_right", "bc_type": "RCR", "bc_values": {"Rp": 100.0, "C": 0.0004, "Rd": 1100.0, "Pd": 10.0}}]})";
  };
  const std::string good = write(
      dir / "model.json",
      model(R"({"bc_name": "LCA_1", "bc_type": "CORONARY", "bc_values": {"Ra1": 900.0, "Ra2": 1500.0, "Rv1": 400.0,
            "Ca": 2e-5, "Cc": 1.5e-4, "P_v": 0.0, "Pim": [0.0, 120000.0, 0.0], "t": [0.0, 0.4, 1.0]}})"));
  const FlowSpec s = spec_with("{file: " + good + "}", net);
  ASSERT_EQ(s.outlets.size(), 2u);
  for (const OutletBC& o : s.outlets) {
    if (net.node(o.node).x() < 0.0) {
      ASSERT_EQ(o.type, OutletBC::Type::Coronary);
      EXPECT_DOUBLE_EQ(o.coronary.ra, 900.0 * 1e5);
      EXPECT_DOUBLE_EQ(o.coronary.ram, 1500.0 * 1e5);
      EXPECT_DOUBLE_EQ(o.coronary.rv, 400.0 * 1e5);
      EXPECT_DOUBLE_EQ(o.coronary.ca, 2e-5 * 1e-5);
      EXPECT_DOUBLE_EQ(o.coronary.cim, 1.5e-4 * 1e-5);
      EXPECT_DOUBLE_EQ(o.coronary.pim(0.4), 12000.0);  // dyn/cm^2 -> Pa
      EXPECT_DOUBLE_EQ(o.coronary.pim(0.2), 6000.0);
    } else {
      ASSERT_EQ(o.type, OutletBC::Type::Rcr);
      EXPECT_DOUBLE_EQ(o.rp, 100.0 * 1e5);
      EXPECT_DOUBLE_EQ(o.c, 0.0004 * 1e-5);
      EXPECT_DOUBLE_EQ(o.rd, 1100.0 * 1e5);
      EXPECT_DOUBLE_EQ(o.distal_pressure, 1.0);
    }
  }
  // A negative value, and an outlet the network does not have: the file, the entry, the value.
  const std::string negative =
      write(dir / "negative.json",
            model(R"({"bc_name": "LCA_1", "bc_type": "RESISTANCE", "bc_values": {"R": -5.0, "Pd": 0.0}})"));
  std::string msg = refused("{file: " + negative + "}", net);
  EXPECT_NE(msg.find("negative.json: boundary_conditions[1]: 'LCA_1': the resistance -5 must be positive"),
            std::string::npos)
      << msg;
  const std::string elsewhere =
      write(dir / "elsewhere.json", model(R"({"bc_name": "LCA_1", "bc_type": "RESISTANCE",
      "bc_values": {"R": 5.0}})")
                                        .replace(model("X").find("left_seg1"), 9, "lad_seg07"));
  msg = refused("{file: " + elsewhere + "}", net);
  EXPECT_NE(msg.find("elsewhere.json: boundary_conditions[1]: outlet 'LCA_1' of the file does not match the network"),
            std::string::npos)
      << msg;
}

TEST(OutletFile, AnOpenbfModelGivesEachOutletVesselItsWindkesselByLabel) {
  // ADAN56's own network (its layout, whose branches are its labels) with its outlets from the
  // model file: each of its 31 outlets the model's condition, in SI as openBF writes it.
  FLOWIRE_REQUIRE_SHARED("peers/openbf-models/boileau2015/adan56/adan56.yaml");
  const auto file = (flowire::testing::shared_dir() / "peers/openbf-models/boileau2015/adan56/adan56.yaml").string();
  const openbf::Model m = openbf::read(file);
  const Network net = openbf::network(m, {.max_segment_length = 0.02});
  const FlowSpec s = spec_with("{file: " + file + "}", net);
  EXPECT_EQ(s.outlets.size(), 31u);
  for (const OutletBC& o : s.outlets) {
    const auto& seg = net.segment(*net.node_segments(o.node).first);
    const std::string& label = net.branches()[static_cast<size_t>(seg.branch)].name;
    int found = 0;
    for (const auto& v : m.vessels)
      if (v.label == label) {
        ++found;
        const OutletBC expected = openbf::outlet_condition(m, v);
        EXPECT_EQ(o.type, expected.type) << label;
        EXPECT_EQ(o.steady_resistance(), expected.steady_resistance()) << label;
        EXPECT_EQ(o.c, expected.c) << label;
      }
    EXPECT_EQ(found, 1) << label;
  }
}

TEST(OutletFile, BadFilesAreRefusedNamingFileAndLine) {
  const auto dir = flowire::testing::scratch_dir("outlet-file-bad");
  const Network net = vessels::read_network(write(dir / "y.in", y_deck()));
  const std::vector<std::pair<std::string, std::string>> cases = {
      {write(dir / "varying.in", y_deck("0.0 100.0\n0.0 0.0005\n0.0 1500.0\n", "PRESSURE_WAVE")),
       "outlet kind PRESSURE_WAVE is not read"},
      {write(dir / "two_rows.in", y_deck("0.0 100.0\n0.0 1500.0\n")), "an RCR outlet needs 3 rows"},
      {write(dir / "negative.in", y_deck("0.0 -100.0\n0.0 0.0005\n0.0 1500.0\n")), "must be >= 0"},
      {write(dir / "coronary.in", y_deck("0.0 100.0\n0.0 0.0005\n0.0 1500.0\n", "CORONARY")),
       "outlet kind CORONARY is not read"},
      {write(dir / "nothing.txt", "hello\n"), "not an outlet file flowire reads"},
  };
  for (const auto& [file, fragment] : cases) {
    const std::string msg = refused("{file: " + file + "}", net);
    EXPECT_NE(msg.find(fragment), std::string::npos) << msg;
    EXPECT_NE(msg.find("flow.outlets.file"), std::string::npos) << msg;
  }
  // A time-varying resistance table, named by its line.
  std::string varying = y_deck();
  varying.replace(varying.find("10.0 2000.0"), 11, "10.0 2500.0");
  const std::string msg = refused("{file: " + write(dir / "time.in", varying) + "}", net);
  EXPECT_NE(msg.find("time.in:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("changes in time"), std::string::npos) << msg;
  // The outlets of another network: the deck's outlet node is no end of this one.
  std::string moved = y_deck();
  moved.replace(moved.find("NODE 3 1.0 0.0 -6.0"), 19, "NODE 3 3.0 0.0 -6.0");
  const Network other = vessels::read_network(write(dir / "moved.in", moved));
  const std::string away = refused("{file: " + dir.string() + "/y.in}", other);
  EXPECT_NE(away.find("is not an outlet of the network"), std::string::npos) << away;
  // An outlet the file leaves without a condition and no default stated for it.
  const std::string one = write(dir / "one.dat", "2\n2\ncap_left\n90.0\n0.0008\n1200\n0.0 0.0\n1.0 0.0\n");
  const Network named =
      vessels::read_network(write(dir / "named.yaml",
                                  "length_unit: mm\nbranches:\n"
                                  "  - name: trunk\n    points: [[0, 0, 0, 5], [0, 0, -40, 5]]\n"
                                  "  - name: cap_left\n    points: [[0, 0, -40, 3], [-10, 0, -60, 3]]\n"
                                  "  - name: cap_right\n    points: [[0, 0, -40, 3], [10, 0, -60, 3]]\n"));
  const std::string missing = refused("{file: " + one + "}", named);
  EXPECT_NE(missing.find("have no condition in the file"), std::string::npos) << missing;
  EXPECT_NO_THROW((void)spec_with("{file: " + one + ", pressure: 0}", named));  // a stated default
}

// The OSMSC0006 aorto-femoral deck (svOneDSolver's test case 14) with its own nine RCR outlets:
// in steady flow every outlet's pressure over its flow is Rp + Rd of its table, to round-off,
// which checks the parsing, the CGS units and that each table reached its own end.
TEST(OutletFile, EachOutletOfARealDeckDrainsThroughItsOwnWindkessel) {
  FLOWIRE_REQUIRE_SHARED("data/real/svonedsolver-aortofemoral-coronary/14_AortoFem_Pulse_RCR.in");
  const std::string deck =
      (flowire::testing::shared_dir() / "data/real/svonedsolver-aortofemoral-coronary/14_AortoFem_Pulse_RCR.in")
          .string();
  const Network net = vessels::read_network(deck);
  const FlowSpec spec = spec_with("{file: " + deck + "}", net);
  ASSERT_EQ(spec.outlets.size(), 9u);
  const auto file = read_outlet_file(deck);
  flowire::testing::ExpectWarnings w;  // steady: the windkessels' compliance is not used, as the model says
  auto solver = make_solver(net, spec);
  solver->advance(0.0);
  for (const OutletBC& o : spec.outlets) {
    ASSERT_EQ(o.type, OutletBC::Type::Rcr);
    const int s = *net.node_segments(o.node).first;  // an end: one segment
    const double q = std::abs(solver->segment_flow(s));
    ASSERT_GT(q, 0.0);
    EXPECT_NEAR(solver->node_pressure(o.node) / q / (o.rp + o.rd), 1.0, 1e-9);
  }
  // Nine different tables: the largest and smallest Rp + Rd differ fourfold.
  double lo = 1e300, hi = 0.0;
  for (const auto& f : file) lo = std::min(lo, f.bc.rp + f.bc.rd), hi = std::max(hi, f.bc.rp + f.bc.rd);
  EXPECT_GT(hi / lo, 3.0);
  EXPECT_TRUE(w.contains("steady resistance (Rp + Rd"));
}

}  // namespace flowire::flow
