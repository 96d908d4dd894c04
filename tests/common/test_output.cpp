// Atomic output (common/src/output.cpp): a file appears whole or not at all, an existing
// file survives a failed rewrite, and no temporary is left behind.
#include "flowire/common/output.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "flowire/common/error.hpp"
#include "flowire_test.hpp"

namespace flowire {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The files in @p dir, recursively (to see that no temporary was left).
std::vector<std::string> listing(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) out.push_back(fs::relative(e.path(), dir).string());
  std::sort(out.begin(), out.end());
  return out;
}

TEST(Output, TextIsWrittenWholeIntoNewFoldersAndReplacesAnOldFile) {
  const auto dir = testing::scratch_dir("common_output_text");
  const fs::path target = dir / "a" / "b" / "summary.json";
  const std::string text = std::string("{\"x\": 1}\n") + std::string(100000, 'y') + '\0' + "tail";
  write_text_atomically(target, text);
  EXPECT_EQ(slurp(target), text);  // binary: the NUL and everything after it
  write_text_atomically(target, "short\n");
  EXPECT_EQ(slurp(target), "short\n");
  EXPECT_EQ(listing(dir), (std::vector<std::string>{"a", "a/b", "a/b/summary.json"}));
}

TEST(Output, AFailingWriterLeavesTheOldFileAndNoTemporary) {
  const auto dir = testing::scratch_dir("common_output_fail");
  const fs::path target = dir / "trace.csv";
  write_text_atomically(target, "old\n");
  EXPECT_THROW(write_atomically(target,
                                [](const fs::path& tmp) {
                                  std::ofstream(tmp) << "half a fi";
                                  throw std::runtime_error("disk gone");
                                }),
               std::runtime_error);
  EXPECT_EQ(slurp(target), "old\n");
  EXPECT_EQ(listing(dir), std::vector<std::string>{"trace.csv"});
  // A writer that never creates the temporary: an input error naming the target.
  try {
    write_atomically(dir / "never.vtp", [](const fs::path&) {});
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("never.vtp"), std::string::npos) << e.what();
  }
  EXPECT_EQ(listing(dir), std::vector<std::string>{"trace.csv"});
}

TEST(Output, TheWriterIsGivenATemporaryNextToTheTarget) {
  const auto dir = testing::scratch_dir("common_output_tmp");
  fs::path seen;
  write_atomically(dir / "net.vtp", [&](const fs::path& tmp) {
    seen = tmp;
    EXPECT_FALSE(fs::exists(dir / "net.vtp"));  // not visible until complete
    std::ofstream(tmp) << "data";
  });
  EXPECT_EQ(seen.parent_path(), dir);
  EXPECT_NE(seen.filename(), "net.vtp");
  EXPECT_EQ(slurp(dir / "net.vtp"), "data");
}

TEST(Output, AnUnwritablePlaceIsAnInputErrorNamingTheFile) {
  // The output folder's parent is a regular file: no folder can be made there.
  const auto dir = testing::scratch_dir("common_output_unwritable");
  std::ofstream(dir / "plain_file") << "x";
  const fs::path target = dir / "plain_file" / "out" / "summary.json";
  try {
    write_text_atomically(target, "{}");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find(target.string()), std::string::npos) << e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a flowire::Error (the command line would report an unexpected failure, exit 3): " << e.what();
  }
}

}  // namespace
}  // namespace flowire
