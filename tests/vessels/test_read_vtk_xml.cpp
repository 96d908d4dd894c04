// VTK XML poly data read with VTK (read_vtk_xml.cpp): a flowire .vtp cut short anywhere is one
// error naming the file, VTK printing nothing.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>

#include "flowire/vessels/io.hpp"
#include "reader_test_util.hpp"

namespace flowire::vessels {
namespace {

using flowire::testing::scratch_dir;
using namespace flowire::vessels::test;

TEST_F(ReadersWithVtk, TruncatedFlowireVtpIsAnError) {
  const auto dir = scratch_dir("io_truncated_vtp");
  const auto file = (dir / "net.vtp").string();
  write_network_vtp(sample_network(), file);
  std::ifstream in(file, std::ios::binary);
  const std::string full((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const double f : {0.1, 0.5, 0.9, 0.99}) {
    const auto cut =
        write_file(dir, "cut.vtp", full.substr(0, static_cast<size_t>(f * static_cast<double>(full.size()))));
    ::testing::internal::CaptureStderr();
    const auto msg = error_of([&] { (void)read_network(cut); });
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
    EXPECT_CONTAINS(msg, "cut.vtp");
  }
}

}  // namespace
}  // namespace flowire::vessels
