// Output files of the contract: nodes.csv, segments.csv, network.vtp / .pvd (the PNG: test_render.cpp).
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "flow_test_networks.hpp"
#include "flowire/flow/output.hpp"
#include "flowire/vessels/io.hpp"
#include "flowire_test.hpp"

namespace flowire::flow {
namespace {

using namespace flowire::flow::test;

std::vector<std::string> lines_of(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

TEST(FlowOutput, CsvFilesFollowTheContract) {
  const auto dir = flowire::testing::scratch_dir("flow_output_csv");
  const Network net = murray_tree(2);
  FlowSpec spec = default_spec(net, Waveform::sine(16000.0, 10666.0, 0.8));
  auto s = make_solver(net, spec);
  const auto frames = sample_frames(*s, 0.0, 0.8, 4, false);
  ASSERT_EQ(frames.size(), 4u);
  EXPECT_DOUBLE_EQ(frames[1].time, 0.2);
  write_nodes_csv(net, frames, dir / "nodes.csv");
  write_segments_csv(*s, frames, dir / "segments.csv");
  const auto nodes = lines_of(dir / "nodes.csv");
  ASSERT_EQ(nodes.size(), 1u + 4u * static_cast<size_t>(net.num_nodes()));
  EXPECT_EQ(nodes[0], "time,node,x,y,z,pressure");
  EXPECT_EQ(nodes[1].substr(0, 4), "0,0,");
  const auto segs = lines_of(dir / "segments.csv");
  ASSERT_EQ(segs.size(), 1u + 4u * static_cast<size_t>(net.num_segments()));
  EXPECT_EQ(
      segs[0],
      "time,segment,node_from,node_to,length,radius,resistance,flow_rate,mean_velocity,wall_shear_stress,reynolds,"
      "occupied_fraction,resistance_factor");
  // Row of segment 0 at t = 0.2: flow equals the solver's.
  std::stringstream row(segs[1 + static_cast<size_t>(net.num_segments())]);
  std::vector<double> v;
  for (std::string c; std::getline(row, c, ',');) v.push_back(std::stod(c));
  ASSERT_EQ(v.size(), 13u);
  EXPECT_DOUBLE_EQ(v[0], 0.2);
  EXPECT_EQ(v[11], 0.0);  // no wire: nothing occupied,
  EXPECT_EQ(v[12], 1.0);  // the resistance unchanged
  EXPECT_NEAR(v[7], frames[1].flow[0], 1e-11 * std::abs(frames[1].flow[0]));
  EXPECT_NEAR(v[6], s->resistance(0), 1e-8 * s->resistance(0));
  // No temporary files left behind.
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 2);
}

TEST(FlowOutput, VtpSeriesOverACycle) {
  const auto dir = flowire::testing::scratch_dir("flow_output_vtp");
  const Network net = murray_tree(3);
  auto s = make_solver(net, default_spec(net, Waveform::sine(16000.0, 10666.0, 0.8)));
  const auto frames = sample_frames(*s, 0.0, 0.8, 10, false);
  write_network_series(*s, frames, dir);
  EXPECT_TRUE(std::filesystem::exists(dir / "network.vtp"));
  EXPECT_TRUE(std::filesystem::exists(dir / "network_000009.vtp"));
  const auto pvd = lines_of(dir / "network.pvd");
  ASSERT_EQ(pvd.size(), 3u + 10u + 2u);
  EXPECT_NE(pvd[3].find("timestep=\"0\""), std::string::npos);
  EXPECT_NE(pvd[4].find("timestep=\"0.08\""), std::string::npos);
  std::ifstream in(dir / "network.vtp");
  std::stringstream ss;
  ss << in.rdbuf();
  for (const char* name : {"\"pressure\"", "\"flow_rate\"", "\"radius\"", "\"mean_velocity\"", "\"wall_shear_stress\""})
    EXPECT_NE(ss.str().find(name), std::string::npos) << name;
#ifdef FLOWIRE_TEST_HAVE_VTK
  // The written network reads back to the same topology (reading .vtp needs VTK).
  const Network back = vessels::read_network((dir / "network.vtp").string());
  EXPECT_EQ(back.num_segments(), net.num_segments());
#endif
}

}  // namespace
}  // namespace flowire::flow
