// Atomic output (common/src/output.cpp): a file appears whole or not at all, an existing
// file survives a failed rewrite, and no temporary is left behind.
#include "flowire/common/output.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"
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

TEST(Output, TemporariesAreHiddenAndUniqueToTheProcessAndTheCall) {
  const auto dir = testing::scratch_dir("common_output_unique");
  std::vector<fs::path> seen;
  for (int i = 0; i < 3; ++i)
    write_atomically(dir / "wire_00001.vtp", [&](const fs::path& tmp) {
      seen.push_back(tmp);
      std::ofstream(tmp) << "frame " << i;
    });
  const std::regex form(R"(^\.wire_00001\.vtp\.([0-9]+)\.[0-9a-f]+\.partial$)");
  for (const auto& t : seen) {
    std::smatch m;
    const std::string name = t.filename().string();
    ASSERT_TRUE(std::regex_match(name, m, form)) << name;
    EXPECT_EQ(std::stol(m[1].str()), static_cast<long>(::getpid()));
  }
  EXPECT_NE(seen[0], seen[1]);
  EXPECT_NE(seen[1], seen[2]);
  EXPECT_EQ(slurp(dir / "wire_00001.vtp"), "frame 2");
  EXPECT_EQ(listing(dir), std::vector<std::string>{"wire_00001.vtp"});
}

TEST(Output, AStreamThatFailsAtItsCloseLeavesNoFile) {
  // A body that puts the stream in a failed state stands for a write the disk refused: the
  // target must not appear, not even empty.
  const auto dir = testing::scratch_dir("common_output_stream_fail");
  try {
    write_stream_atomically(dir / "nodes.csv", [](std::ostream& out) {
      out << "time,node\n";
      out.setstate(std::ios::badbit);
    });
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("nodes.csv"), std::string::npos) << e.what();
  }
  // An empty result is refused too (every flowire output has at least a header).
  EXPECT_THROW(write_stream_atomically(dir / "empty.csv", [](std::ostream&) {}), Error);
  EXPECT_TRUE(listing(dir).empty());
}

TEST(Output, ASecondHolderOfAFolderIsRefusedNamingTheFirst) {
  const auto dir = testing::scratch_dir("common_output_lock");
  {
    const OutputFolder first(dir / "run");
    try {
      const OutputFolder second(dir / "run");
      ADD_FAILURE() << "a held folder was taken twice";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
      const std::string what = e.what();
      EXPECT_NE(what.find("another flowire run"), std::string::npos) << what;
      EXPECT_NE(what.find(std::to_string(::getpid())), std::string::npos) << what;
    }
  }
  const OutputFolder again(dir / "run");  // released with its holder
}

TEST(Output, AFolderIsClearedOfTheTemporariesOfDeadProcessesOnly) {
  const auto dir = testing::scratch_dir("common_output_stale");
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ASSERT_GT(child, 0);
  ASSERT_EQ(::waitpid(child, nullptr, 0), child);  // a pid that no longer exists
  auto temp = [](long pid) { return fmt::format(".wire_00003.vtp.{}.00ff00ff00ff00ff.partial", pid); };
  fs::create_directories(dir / "fem");
  for (const fs::path& p :
       {dir / temp(child), dir / "fem" / temp(child), dir / temp(::getpid()), dir / "notes.partial", dir / "wire.csv"})
    std::ofstream(p) << "x";
  { const OutputFolder folder(dir); }
  // Kept: this process's own temporary (it may be writing it) and files of other forms.
  std::vector<std::string> kept{temp(::getpid()), ".flowire-run.lock", "fem", "notes.partial", "wire.csv"};
  std::sort(kept.begin(), kept.end());
  EXPECT_EQ(listing(dir), kept);
}

TEST(Input, OnlyRegularFilesOfAtMostTheLimitAreRead) {
  const auto dir = testing::scratch_dir("common_input_kinds");
  std::ofstream(dir / "scene.yaml") << "name: x\n";
  EXPECT_EQ(read_input((dir / "scene.yaml").string(), 100, "a scene"), "name: x\n");
  auto refused = [](const std::string& path, std::uintmax_t limit, const std::string& says) {
    try {
      (void)read_input(path, limit, "a scene");
      ADD_FAILURE() << path << " was read";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(path, 0), 0U) << what;  // the file first
      EXPECT_NE(what.find(says), std::string::npos) << what;
    }
  };
  refused((dir / "scene.yaml").string(), 4, "at most");
  refused((dir / "missing.yaml").string(), 100, "no such file");
  refused(dir.string(), 100, "is a folder");
  refused("/dev/zero", 100, "not a regular file");
  ASSERT_EQ(::mkfifo((dir / "pipe.yaml").c_str(), 0600), 0);
  refused((dir / "pipe.yaml").string(), 100, "not a regular file");  // opening it would block for ever
}

}  // namespace
}  // namespace flowire
