// flowire's own .vtp (read_flowire_vtp.cpp): a written network comes back identical, with its
// data arrays beside it; read as centerlines it gives its branches back; a length unit given for
// it (it declares metres) is ignored with a warning.
#include <gtest/gtest.h>

#include <filesystem>
#include <vector>

#include "flowire/vessels/io.hpp"
#include "reader_test_util.hpp"

namespace flowire::vessels {
namespace {

namespace fs = std::filesystem;
using flowire::testing::ExpectWarnings;
using flowire::testing::scratch_dir;
using namespace flowire::vessels::test;

TEST_F(ReadersWithVtk, VtpRoundTripIsExact) {
  const auto net = sample_network();
  const auto dir = scratch_dir("io_vtp_roundtrip");
  const auto file = (dir / "net.vtp").string();
  std::vector<double> pressure(static_cast<size_t>(net.num_nodes()));
  for (size_t i = 0; i < pressure.size(); ++i) pressure[i] = 1000.0 + static_cast<double>(i);
  std::vector<double> flow(static_cast<size_t>(net.num_segments()), 1e-6);
  std::vector<double> velocity(3 * static_cast<size_t>(net.num_segments()), 0.1);
  write_network_vtp(net, file, {{"pressure", pressure, 1}}, {{"flow_rate", flow, 1}, {"velocity", velocity, 3}});
  EXPECT_FALSE(fs::exists(file + ".partial"));
  const auto back = read_network(file);
  expect_identical(net, back);
  // Reading our own file as centerlines gives the branches back.
  const auto cl = read_centerlines(file);
  ASSERT_EQ(cl.branches.size(), 3u);
  EXPECT_EQ(cl.branches[1].name, "left <iliac>");
  // A length unit given for a file in metres is ignored, with a warning.
  ExpectWarnings w;
  ReadOptions opt;
  opt.length_unit = "mm";
  expect_identical(net, read_network(file, opt));
  EXPECT_TRUE(w.contains("declares length_unit m"));
}

TEST_F(ReadersWithVtk, AVtpSegmentShapeBelowACirclesIsRefusedNamingTheCell) {
  // A shape factor is at least 1 (a circle's, the least resistance for an area): a file that
  // says less is damaged, and is refused naming the cell rather than read as a lower resistance.
  const auto net = sample_network();
  std::vector<Vec3> nodes(net.nodes().begin(), net.nodes().end());
  std::vector<Segment> segments(net.segments().begin(), net.segments().end());
  segments[2].shape = 0.5;
  std::vector<Branch> branches(net.branches().begin(), net.branches().end());
  const auto bad = Network::from_graph(std::move(nodes), std::move(segments), std::move(branches), "bad");
  const auto file = (scratch_dir("io_vtp_bad_shape") / "net.vtp").string();
  write_network_vtp(bad, file);
  const auto msg = error_of([&] { (void)read_network(file); });
  EXPECT_CONTAINS(msg, file);
  EXPECT_CONTAINS(msg, "line cell 2: shape 0.5 is not finite and at least 1");
}

}  // namespace
}  // namespace flowire::vessels
