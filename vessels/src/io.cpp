// Which reader reads a network file: the table of formats (network_readers), each chosen by
// the file's extension, else by the first 4 KiB of its content. The readers themselves, one
// source per format, are read_polydata.cpp (.vtp / .vtk, with the centerline conventions those
// hold), read_yaml.cpp (.yaml / .yml) and read_svonedsolver.cpp (.in); what they share after
// parsing (length units, final checks) is read_common.cpp.
#include "flowire/vessels/io.hpp"

#include <fmt/format.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"
#include "read_internal.hpp"

namespace flowire::vessels {
namespace {

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// What each format's files start with, for files whose extension names no format.
bool vtk_head(std::string_view head) {
  return head.find("<VTKFile") != std::string_view::npos || head.starts_with("# vtk DataFile");
}
bool yaml_head(std::string_view head) {
  return head.find("branches:") != std::string_view::npos || head.find("segments:") != std::string_view::npos;
}
bool deck_head(std::string_view head) {
  return head.find("NODE ") != std::string_view::npos && head.find("SEGMENT ") != std::string_view::npos;
}

/// The reader for `path`: by extension, else by the first 4 KiB of its content.
const NetworkReader& reader_for(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw_input_error(path, "is a directory, not a network file");
  const auto ext = lower(std::filesystem::path(path).extension().string());
  for (const auto& r : network_readers())
    for (const auto e : r.extensions)
      if (ext == e) return r;
  std::ifstream in = open_input(path, input_limit::kGeometry, "a network file");
  std::string head(4096, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  for (const auto& r : network_readers())
    if (r.recognises(head)) return r;
  std::string known;
  for (const auto& r : network_readers())
    known += fmt::format("{}{} ({})", known.empty() ? "" : ", ", fmt::join(r.extensions, "/"), r.name);
  throw_input_error(path, "unknown network format: expected " + known);
}

}  // namespace

const std::vector<NetworkReader>& network_readers() {
  static const std::vector<NetworkReader> readers = {
      {"VMTK, SimVascular or flowire centerlines",
       {".vtp", ".vtk"},
       vtk_head,
       detail::read_polydata_centerlines,
       detail::read_polydata_network},
      {"flowire network", {".yaml", ".yml"}, yaml_head, detail::read_yaml_centerlines, detail::read_yaml_network},
      {"svOneDSolver deck",
       {".in"},
       deck_head,
       detail::read_svonedsolver_centerlines,
       detail::read_svonedsolver_network},
  };
  return readers;
}

std::string network_extensions() {
  std::vector<std::string_view> all;
  for (const auto& r : network_readers()) all.insert(all.end(), r.extensions.begin(), r.extensions.end());
  return fmt::format("{}", fmt::join(all, ", "));
}

Centerlines read_centerlines(const std::string& path, const ReadOptions& opt) {
  return reader_for(path).centerlines(path, opt);
}

Network read_network(const std::string& path, const ReadOptions& opt) { return reader_for(path).network(path, opt); }

}  // namespace flowire::vessels
