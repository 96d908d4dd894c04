// Which reader reads a network file (io.cpp): every format of the reader table found by its
// extension and, renamed, by its content alone; unknown formats, missing files and folders
// refused with one error naming the file.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "flowire/common/error.hpp"
#include "flowire/vessels/io.hpp"
#include "reader_test_util.hpp"

namespace flowire::vessels {
namespace {

using flowire::testing::scratch_dir;
using namespace flowire::vessels::test;

TEST(ReadFormats, EveryReaderIsFoundByExtensionAndByContent) {
  // Files of each format in the reader table (flowire's .vtp, its .yaml, an svOneDSolver
  // deck), read once under their own extension and once renamed to one no
  // reader claims: the content alone must pick the same reader and the same network.
  const auto dir = scratch_dir("io_formats");
  const Network net = sample_network();
  write_network_vtp(net, (dir / "net.vtp").string());
  write_network_yaml(net, (dir / "net.yaml").string());
  write_file(dir, "deck.in", small_deck());
  ASSERT_EQ(network_readers().size(), 3u);  // one file below for each
  for (const std::string f : {"net.vtp", "net.yaml", "deck.in"}) {
    const auto own = read_network((dir / f).string());
    std::filesystem::copy_file(dir / f, dir / (f + ".dat"), std::filesystem::copy_options::overwrite_existing);
    const auto sniffed = read_network((dir / (f + ".dat")).string());
    EXPECT_EQ(own.num_segments(), sniffed.num_segments()) << f;
    EXPECT_EQ(own.num_nodes(), sniffed.num_nodes()) << f;
  }
  EXPECT_EQ(network_extensions(), ".vtp, .vtk, .yaml, .yml, .in");
}

TEST(ReadBadInput, UnknownFormatAndMissingFile) {
  const auto dir = scratch_dir("io_bad_format");
  const auto file = write_file(dir, "net.txt", "just words\n");
  EXPECT_CONTAINS(error_of([&] { (void)read_network(file); }), "unknown network format");
  EXPECT_CONTAINS(error_of([&] { (void)read_network((dir / "absent.yaml").string()); }), "absent.yaml");
  EXPECT_CONTAINS(error_of([&] { (void)read_network(dir.string()); }), "directory");
}

TEST(RealData, SurfaceOnlyPhantomIsRejectedClearly) {
  FLOWIRE_REQUIRE_SHARED("data/real/cathsim-elastrat-arch-phantom/phantom-elastrat-simple.obj");
  try {
    (void)read_network(real("cathsim-elastrat-arch-phantom/phantom-elastrat-simple.obj"));
    FAIL() << "a surface mesh is not a network";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("phantom-elastrat-simple.obj"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace flowire::vessels
