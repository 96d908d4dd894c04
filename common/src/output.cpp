#include "flowire/common/output.hpp"

#include <fmt/format.h>

#include <fstream>
#include <system_error>

#include "flowire/common/error.hpp"

namespace flowire {

namespace {
bool g_writes_outputs = true;
}  // namespace

bool writes_outputs() { return g_writes_outputs; }
void set_writes_outputs(bool writes) { g_writes_outputs = writes; }

void write_atomically(const std::filesystem::path& target,
                      const std::function<void(const std::filesystem::path& tmp)>& writer) {
  namespace fs = std::filesystem;
  if (!g_writes_outputs) return;
  const fs::path tmp = target.parent_path() / (target.filename().string() + ".partial");
  // A folder that cannot be made or a file that cannot be moved into place is bad input
  // (an output path under a regular file, a read-only folder): one error naming the file.
  std::error_code ec;
  if (!target.parent_path().empty()) {
    fs::create_directories(target.parent_path(), ec);
    if (ec)
      throw_input_error(target.string(),
                        fmt::format("cannot create the folder {}: {}", target.parent_path().string(), ec.message()));
  }
  try {
    writer(tmp);
    if (!fs::exists(tmp)) throw_input_error(target.string(), "the file could not be written");
    fs::rename(tmp, target, ec);
    if (ec) throw_input_error(target.string(), fmt::format("the file could not be put in place: {}", ec.message()));
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
}

void write_text_atomically(const std::filesystem::path& target, const std::string& text) {
  write_atomically(target, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw_input_error(target.string(), "cannot open for writing");
    out << text;
    if (!out) throw_input_error(target.string(), "write failed (disk full?)");
  });
}

}  // namespace flowire
