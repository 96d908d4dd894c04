// libFuzzer target for the network readers: every input is written to a file with each
// supported extension and read with read_network. A flowire::Error is the expected answer to
// bad input; anything else (another exception, a crash, a sanitizer report) is a bug.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/vessels/io.hpp"

namespace {

/// A scratch directory for this process, removed at exit.
struct WorkDir {
  std::filesystem::path path;
  WorkDir() : path(std::filesystem::temp_directory_path() / ("flowire-fuzz-" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path);
    flowire::set_warning_handler([](std::string_view) {});
  }
  ~WorkDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  WorkDir(const WorkDir&) = delete;
  WorkDir& operator=(const WorkDir&) = delete;
};

const std::filesystem::path& work_dir() {
  static const WorkDir dir;
  return dir.path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // Each reader by its first extension, and one extension no reader claims (content sniffing).
  std::vector<std::string> exts = {".dat"};
  for (const auto& r : flowire::vessels::network_readers()) exts.emplace_back(r.extensions.front());
  for (const auto& ext : exts) {
    const auto path = (work_dir() / ("input" + ext)).string();
    {
      std::ofstream out(path, std::ios::binary | std::ios::trunc);
      out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    }
    for (const bool keep : {false, true}) {
      flowire::vessels::ReadOptions opt;
      opt.keep_inlet_piece = keep;
      opt.build.max_segment_length = 0.5;
      try {
        (void)flowire::vessels::read_network(path, opt);
      } catch (const flowire::Error&) {
      }
    }
  }
  return 0;
}
