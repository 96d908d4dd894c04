// The network writers (io_write.cpp): flowire YAML read back to the identical network (and its
// branches alone a valid network file); arrays of the wrong size, or an unknown extension, are
// errors that leave no file behind. (The .vtp round trip is in test_read_flowire_vtp.cpp.)
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/vessels/io.hpp"
#include "reader_test_util.hpp"

namespace flowire::vessels {
namespace {

namespace fs = std::filesystem;
using flowire::testing::scratch_dir;
using namespace flowire::vessels::test;

TEST(WriteNetwork, YamlRoundTripIsExact) {
  const auto net = sample_network();
  const auto file = (scratch_dir("io_yaml_roundtrip") / "net.yaml").string();
  write_network_yaml(net, file);
  expect_identical(net, read_network(file));
  const auto cl = read_centerlines(file);  // the branches alone are a valid network file too
  ASSERT_EQ(cl.branches.size(), 3u);
  EXPECT_EQ(cl.branches[2].name, "right \"iliac\"\n\\2");
  EXPECT_EQ(cl.branches[0].points.size(), net.branch(0).nodes.size());
}

TEST(WriteNetwork, BadArrayLeavesNoFile) {
  const auto net = sample_network();
  const auto file = (scratch_dir("io_write_bad") / "net.vtp").string();
  EXPECT_THROW(write_network_vtp(net, file, {{"pressure", {1.0, 2.0}, 1}}), Error);
  EXPECT_THROW(
      write_network_vtp(net, file, {}, {{"radius", std::vector<double>(static_cast<size_t>(net.num_segments())), 1}}),
      Error);
  EXPECT_FALSE(fs::exists(file));
  EXPECT_FALSE(fs::exists(file + ".partial"));
  EXPECT_THROW(write_network(net, (scratch_dir("io_write_bad") / "net.obj").string()), Error);
}

}  // namespace
}  // namespace flowire::vessels
