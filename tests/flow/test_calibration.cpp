// The calibration file alone (flow/calibration.hpp), without a 3D solve: written and read back
// equal (laws, fits, outlet alphas, identity), the laws making a solver Newton's, and every
// refusal naming the file and the place: not JSON, not a calibration, a law out of range, a
// calibration of another network (another count, another radius).
#include "flowire/flow/calibration.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "flow_test_networks.hpp"
#include "flowire/common/error.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

Calibration made_for(const Network& net) {
  Calibration c;
  identify(c, net);
  c.equations = "navier_stokes";
  c.pressure = "total";
  c.inlet_flows = {1e-6, 2e-6, 3e-6};
  c.check_inlet_flow = 1.5e-6;
  BranchFit f;
  f.branch = 0;
  f.name = "branch_0";
  f.poiseuille_resistance = 2e8;
  f.linear = 2.2e8;
  f.quadratic = 3e13;
  f.flows = {1e-6, 2e-6};
  f.drops = {250.0, 560.0};
  f.residual = 1.5e-3;
  f.pieces = 2;
  c.fits = {f};
  for (int s = 0; s < net.num_segments(); ++s) c.laws.push_back({1.0 + 0.01 * s, 1e12 * s});
  c.end_alpha.assign(static_cast<size_t>(net.num_nodes()), 1.0);
  c.end_alpha.back() = 1.37;
  return c;
}

std::string error_of(const std::string& path, const Network& net) {
  try {
    (void)read_calibration(path, net, "vessels.calibration");
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    return e.what();
  }
  return "";
}

TEST(Calibration, WrittenAndReadBackEqualAndItsLawsMakeTheSolverNewtons) {
  const Network net = test::murray_tree(3);
  const Calibration c = made_for(net);
  const std::string path = (testing::scratch_dir("calibration_round_trip") / "calibration.json").string();
  write_calibration(path, c);
  const Calibration r = read_calibration(path, net);
  EXPECT_EQ(r.nodes, net.num_nodes());
  EXPECT_EQ(r.segments, net.num_segments());
  EXPECT_EQ(r.equations, "navier_stokes");
  EXPECT_EQ(r.pressure, "total");
  EXPECT_EQ(r.inlet_flows, c.inlet_flows);
  EXPECT_EQ(r.check_inlet_flow, c.check_inlet_flow);
  ASSERT_EQ(r.laws.size(), c.laws.size());
  for (size_t s = 0; s < c.laws.size(); ++s) {
    EXPECT_EQ(r.laws[s].resistance_factor, c.laws[s].resistance_factor) << s;
    EXPECT_EQ(r.laws[s].quadratic, c.laws[s].quadratic) << s;
  }
  EXPECT_EQ(r.end_alpha, c.end_alpha);
  ASSERT_EQ(r.fits.size(), 1u);
  EXPECT_EQ(r.fits[0].name, "branch_0");
  EXPECT_EQ(r.fits[0].linear, c.fits[0].linear);
  EXPECT_EQ(r.fits[0].quadratic, c.fits[0].quadratic);
  FlowSpec spec = default_spec(net, Waveform::constant(1000.0));
  spec.segment_laws = r.laws;
  EXPECT_EQ(make_solver(net, spec)->name(), "newton");
}

TEST(Calibration, RefusesAFileThatIsNoCalibrationALawOutOfRangeAndAnotherNetworksNamingWhere) {
  const Network net = test::murray_tree(3);
  const auto dir = testing::scratch_dir("calibration_refusals");
  const std::string good = (dir / "calibration.json").string();
  write_calibration(good, made_for(net));
  nlohmann::json j;
  std::ifstream(good) >> j;
  auto write = [&](const std::string& name, const std::string& text) {
    const std::string p = (dir / name).string();
    std::ofstream(p) << text;
    return p;
  };
  const std::string not_json = write("bad.json", "{ not json");
  EXPECT_NE(error_of(not_json, net).find("bad.json"), std::string::npos);
  nlohmann::json other = j;
  other["format"] = "something-else";
  EXPECT_NE(error_of(write("other.json", other.dump()), net).find("other.json"), std::string::npos);
  nlohmann::json negative = j;
  negative["segments"][2]["quadratic"] = -1.0;
  const std::string e = error_of(write("negative.json", negative.dump()), net);
  EXPECT_NE(e.find("segments[2]"), std::string::npos) << e;
  // Another network: one level more, and the same tree with every radius 1% larger.
  EXPECT_NE(error_of(good, test::murray_tree(4)).find("another network"), std::string::npos);
  std::vector<vessels::Segment> segs;
  std::vector<Vec3> nodes;
  for (int i = 0; i < net.num_nodes(); ++i) nodes.push_back(net.node(i));
  for (int s = 0; s < net.num_segments(); ++s) {
    auto seg = net.segment(s);
    seg.radius *= 1.01;
    seg.radius_from *= 1.01;
    seg.radius_to *= 1.01;
    segs.push_back(seg);
  }
  const Network wider = Network::from_graph(nodes, segs);
  EXPECT_NE(error_of(good, wider).find("another network"), std::string::npos);
}

}  // namespace
}  // namespace flowire::flow
