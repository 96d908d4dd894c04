// The vessels: section (coupling/src/config_vessels.cpp): its keys, and the network they build.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <numbers>

#include "flowire/flow/openbf.hpp"
#include "flowire/flow/rlc.hpp"
#include "flowire/flow/solver.hpp"
#include "flowire_test.hpp"
#include "scene_config_test.hpp"
#include "scene_sections.hpp"

namespace flowire::coupling {
namespace {

TEST(ConfigVessels, DeclaresTheVesselKeysOfTheScene) {
  test::expect_section_of_scene(test::declared_paths(declare_vessel_keys), {"vessels"});
}

TEST(ConfigVessels, AGeneratorGivenInTheSceneBuildsThatNetwork) {
  const auto c = test::scene("vessels:\n  generator: {type: straight_tube, length: 50 mm, radius: 3 mm}\n");
  const vessels::Network net = build_scene_network(c);
  EXPECT_NEAR(net.counts().total_length, 0.05, 1e-12);
  EXPECT_NEAR(net.counts().radius_max, 3e-3, 1e-15);
  EXPECT_EQ(net.counts().ends, 2);
  // max_segment_length (5 mm declared): 50 mm in 10 cylinders.
  EXPECT_EQ(net.counts().segments, 10);
}

TEST(ConfigVessels, BadVesselsAreRejectedNamingFileLineAndKey) {
  EXPECT_NE(test::input_error([] {
              (void)test::scene("vessels:\n  generator:\n    type: straight_tube\n    radius: -2 mm\n");
            }).find("scene.yaml:4: vessels.generator.radius"),
            std::string::npos);
  const auto both = test::scene("vessels:\n  file: a.vtp\n  generator: {type: aortic_arch}\n");
  EXPECT_NE(test::input_error([&] {
              (void)build_scene_network(both);
            }).find("exactly one of vessels.file or vessels.generator"),
            std::string::npos);
}

#ifdef FLOWIRE_TEST_HAVE_VTK
// vessels.radius through a scene: an elliptic tube (half-axes 3 and 2 mm, a 128-gon, as an OBJ
// surface) around a centerline file that gives the inscribed radius 2 mm. With the surface the
// network's radius is √(A/π) of the section (√(ab) to 3e-4); inscribed keeps the file's; surface
// radii without a surface are bad input naming the key.
TEST(ConfigVessels, ASurfaceGivesTheNetworkTheRadiusOfItsSectionsArea) {
  const auto dir = flowire::testing::scratch_dir("config-vessels-sections");
  const double a = 3e-3, b = 2e-3, pi = std::numbers::pi;
  const int n = 128, rings = 22;
  {
    std::ofstream obj(dir / "tube.obj");
    obj.precision(17);
    for (int r = 0; r < rings; ++r)
      for (int k = 0; k < n; ++k)
        obj << "v " << -1e-3 + 0.042 * r / (rings - 1) << " " << a * std::cos(2 * pi * k / n) << " "
            << b * std::sin(2 * pi * k / n) << "\n";
    for (int r = 0; r + 1 < rings; ++r)
      for (int k = 0; k < n; ++k) {
        const int i0 = r * n + k + 1, i1 = r * n + (k + 1) % n + 1;
        obj << "f " << i0 << " " << i1 << " " << i1 + n << "\nf " << i0 << " " << i1 + n << " " << i0 + n << "\n";
      }
    std::ofstream net(dir / "tube.yaml");
    net << "branches:\n  - name: tube\n    points: [[0, 0, 0, 0.002], [0.04, 0, 0, 0.002]]\n";
  }
  const std::string vessels =
      "vessels: {file: " + (dir / "tube.yaml").string() + ", surface: " + (dir / "tube.obj").string();
  const SceneNetwork sn = build_scene_network_and_radii(test::scene(vessels + "}\n"));
  EXPECT_EQ(sn.radius["source"], "surface");
  EXPECT_EQ(sn.radius["measured"].get<int>(), sn.radius["points"].get<int>());
  ASSERT_TRUE(sn.surface);  // kept for the wall contact
  const double r_section = std::sqrt(0.5 * n * a * b * std::sin(2 * pi / n) / pi);
  EXPECT_NEAR(r_section / std::sqrt(a * b), 1.0, 3e-4);  // the 128-gon's deficit
  EXPECT_NEAR(sn.network.counts().radius_max, r_section, 1e-9 * r_section);
  EXPECT_NEAR(sn.network.counts().radius_min, r_section, 1e-9 * r_section);
  const SceneNetwork kept = build_scene_network_and_radii(test::scene(vessels + ", radius: inscribed}\n"));
  EXPECT_EQ(kept.radius["source"], "inscribed");
  EXPECT_EQ(kept.network.counts().radius_max, 2e-3);
  EXPECT_NE(test::input_error([&] {
              (void)build_scene_network(
                  test::scene("vessels: {file: " + (dir / "tube.yaml").string() + ", radius: surface}\n"));
            }).find("vessels.radius"),
            std::string::npos);
}
#endif

// An openBF model as vessels.file: its network laid out in the body, its own flow (inlet,
// outlets, walls, blood) wherever the scene states none, and that flow the same as the lumped
// model of the model itself (openbf::simulate) in the mean.
TEST(ConfigVessels, AnOpenbfModelAsVesselsCarriesItsOwnFlowAsItsLumpedModelDoes) {
  FLOWIRE_REQUIRE_SHARED("peers/openbf-models/boileau2015/adan56/adan56.yaml");
  const auto file = flowire::testing::shared_dir() / "peers/openbf-models/boileau2015/adan56/adan56.yaml";
  const auto cfg = test::scene("vessels: {file: " + file.string() +
                               ", max_segment_length: 1 cm}\nflow:\n  outlets: {radial_R: {resistance: 7e9}}\n"
                               "solve: {dt: 1 ms}\n");
  const vessels::Network net = build_scene_network(cfg);
  const flow::openbf::Model m = flow::openbf::read(file.string());
  EXPECT_EQ(net.counts().branches, static_cast<int>(m.vessels.size()));
  const flow::FlowSpec spec = scene_flow(cfg, net);
  EXPECT_EQ(spec.model, flow::Model::Rlc);
  EXPECT_EQ(spec.density, m.rho);
  EXPECT_EQ(spec.viscosity, m.mu);
  ASSERT_EQ(spec.inlets.size(), 1u);
  EXPECT_EQ(spec.inlets[0].type, flow::InletBC::Type::Flow);
  EXPECT_EQ(spec.outlets.size(), static_cast<size_t>(net.counts().ends - 1));
  EXPECT_EQ(spec.branch_walls.size(), m.vessels.size());
  // The outlet the scene names keeps its own condition; the others are the model's.
  int named = 0;
  for (const auto& o : spec.outlets) {
    const auto& seg = net.segment(*net.node_segments(o.node).first);
    const std::string& branch = net.branches()[static_cast<size_t>(seg.branch)].name;
    if (branch == "radial_R") {
      ++named;
      EXPECT_EQ(o.type, flow::OutletBC::Type::Resistance);
      EXPECT_EQ(o.resistance, 7e9);
    } else {
      for (const auto& v : m.vessels) {
        if (v.label == branch) {
          EXPECT_EQ(o.steady_resistance(), flow::openbf::outlet_condition(m, v).steady_resistance());
        }
      }
    }
  }
  EXPECT_EQ(named, 1);

  // The mean pressures of the scene's flow against the lumped model's own, at the root and at
  // the ends, both over the last cycle: the same linearized model, discretized in two ways
  // (segments of 1 cm here, 2 cm there): within 0.23% of each other at all 32 ends (measured).
  const flow::FlowSpec own = scene_flow(
      test::scene("vessels: {file: " + file.string() + ", max_segment_length: 1 cm}\nflow: {}\nsolve: {dt: 1 ms}\n"),
      net);
  auto solver = flow::make_solver(net, own);
  ASSERT_TRUE(flow::periodic_info(*solver).converged);
  const double t0 = std::ceil(solver->time()) + 1.0;
  std::vector<double> mean(static_cast<size_t>(net.num_nodes()), 0.0);
  const int n = 1000;
  for (int i = 0; i < n; ++i) {
    solver->advance(t0 + static_cast<double>(i) / n);
    for (int e : net.ends()) mean[static_cast<size_t>(e)] += solver->node_pressure(e) / n;
  }
  const flow::openbf::Waveforms w = flow::openbf::simulate(m);
  std::map<std::string, std::pair<double, double>> lumped;  // label -> mean pressure in, out
  std::map<std::string, int> rows;
  for (size_t r = 0; r < w.names.size(); ++r) {
    auto& [pin, pout] = lumped[w.names[r]];
    pin += w.pressure_in[r], pout += w.pressure_out[r];
    ++rows[w.names[r]];
  }
  int compared = 0;
  for (int e : net.ends()) {
    const auto& seg = net.segment(*net.node_segments(e).first);
    const std::string& label = net.branches()[static_cast<size_t>(seg.branch)].name;
    const bool inlet = e == own.inlets[0].node;
    const double expected = (inlet ? lumped[label].first : lumped[label].second) / rows[label];
    EXPECT_NEAR(mean[static_cast<size_t>(e)], expected, 0.005 * expected) << label << (inlet ? " (root)" : "");
    ++compared;
  }
  EXPECT_EQ(compared, net.counts().ends);
}

}  // namespace
}  // namespace flowire::coupling
