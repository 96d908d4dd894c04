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

}  // namespace
}  // namespace flowire::vessels
