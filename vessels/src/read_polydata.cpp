// .vtp (VTK XML) and .vtk (legacy VTK) poly data files: which container a file is (by its first
// bytes, whatever its extension), which centerline convention it holds, and its length unit.
// The conventions are told apart by their arrays, in this order:
// 1. field array flowire_network: flowire's own network (read_flowire_vtp.cpp), in metres;
// 2. cell arrays GroupIds, CenterlineIds and TractIds: VMTK branch-split centerlines
//    (read_vmtk_branch_split.cpp);
// 3. point array BranchId: SimVascular ROM centerlines (read_simvascular_rom.cpp);
// 4. two or more line cells that share no point id and overlap along their first points (within
//    merge_tolerance × radius): VMTK paths (read_vmtk_paths.cpp);
// 5. anything else: plain polylines (read_polylines.cpp).
// Every file but flowire's own is in the caller's length unit (metres if none is given).
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"
#include "polydata_internal.hpp"
#include "read_internal.hpp"

namespace flowire::vessels::detail {
namespace {

/// The file's bytes (at most `limit`), for checks made before VTK sees the file.
std::string head_of(const std::string& path, size_t limit) {
  std::ifstream in = open_input(path, input_limit::kGeometry, "a VTK file");
  std::string s(limit, '\0');
  in.read(s.data(), static_cast<std::streamsize>(limit));
  s.resize(static_cast<size_t>(in.gcount()));
  return s;
}

/// VMTK writes a few consecutive coincident points: in its files they are dropped, not errors.
bool is_vmtk(const PolyData& pd) { return find_array(pd.point_data, "MaximumInscribedSphereRadius") != nullptr; }

}  // namespace

PolyData read_vtk_polydata(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw_input_error(path, "cannot open the file for reading");
  if (size == 0) throw_input_error(path, "the file is empty");
  const std::string head = head_of(path, 1 << 20);
  const bool xml = head.find("<VTKFile") != std::string::npos;
  const bool legacy = head.rfind("# vtk DataFile", 0) == 0;
  if (!xml && !legacy)
    throw_input_error(path, "not a VTK file (neither VTK XML '<VTKFile' nor legacy '# vtk DataFile' header)");
  if (xml && head.find("type=\"PolyData\"") == std::string::npos)
    throw_input_error(path, "the VTK XML file does not hold PolyData (centerlines are poly data)");
  if (legacy && head.find("POLYDATA") == std::string::npos)
    throw_input_error(path, "the legacy VTK file does not hold POLYDATA (centerlines are poly data)");
  if (xml) check_declared_sizes(path, head, size);
  if (xml && head.find("</VTKFile>") == std::string::npos && size <= head.size())
    throw_input_error(path, "the XML ends before </VTKFile> (truncated file)");
  if (legacy) {
    std::ifstream in(path, std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return read_legacy_polydata(path, text);
  }
  return read_vtk_xml_polydata(path);
}

const char* kind_name(PolyKind k) {
  switch (k) {
    case PolyKind::FlowireNetwork:
      return "flowire network";
    case PolyKind::BranchSplitVmtk:
      return "VMTK branch-split centerlines";
    case PolyKind::SimVascularRom:
      return "SimVascular ROM centerlines";
    case PolyKind::OverlappingPaths:
      return "VMTK centerlines (overlapping paths)";
    case PolyKind::Graph:
      return "polylines";
  }
  return "polylines";
}

PolyKind classify(const PolyData& pd, double merge_tolerance) {
  if (find_array(pd.field_data, "flowire_network")) return PolyKind::FlowireNetwork;
  if (find_array(pd.cell_data, "GroupIds") && find_array(pd.cell_data, "CenterlineIds") &&
      find_array(pd.cell_data, "TractIds"))
    return PolyKind::BranchSplitVmtk;
  if (find_array(pd.point_data, "BranchId")) return PolyKind::SimVascularRom;
  if (pd.lines.size() < 2) return PolyKind::Graph;
  // Overlapping paths never share point ids (vmtkcenterlines duplicates the trunk points).
  std::vector<int> owner(pd.points.size(), -1);
  for (size_t c = 0; c < pd.lines.size(); ++c)
    for (const long long id : pd.lines[c]) {
      if (id < 0 || static_cast<size_t>(id) >= pd.points.size()) return PolyKind::Graph;  // validated later
      auto& o = owner[static_cast<size_t>(id)];
      if (o >= 0 && o != static_cast<int>(c)) return PolyKind::Graph;
      o = static_cast<int>(c);
    }
  try {
    const auto radii = point_radii(pd);
    validate(pd, radii);
    std::vector<Polyline> paths;
    for (size_t c = 0; c < pd.lines.size(); ++c) paths.push_back(make_polyline(pd, radii, cell_ids(pd, c, true), {}));
    if (paths_overlap(std::move(paths), std::max(merge_tolerance, 1e-6))) return PolyKind::OverlappingPaths;
  } catch (const Error&) {
    return PolyKind::Graph;  // the graph reader reports the problem
  }
  return PolyKind::Graph;
}

Centerlines polydata_to_centerlines(const PolyData& pd, double merge_tolerance) {
  Centerlines c;
  c.source = pd.source;
  const auto kind = classify(pd, merge_tolerance);
  if (kind == PolyKind::FlowireNetwork) {
    c.branches = flowire_network_branches(*polydata_to_network(pd));
    return c;
  }
  require_lines(pd);
  const auto radii = point_radii(pd);
  validate(pd, radii);
  const bool vmtk = is_vmtk(pd);
  switch (kind) {
    case PolyKind::BranchSplitVmtk:
      c.branches = branch_split_vmtk(pd, radii);
      break;
    case PolyKind::SimVascularRom:
      c.branches = simvascular_rom(pd, radii);
      break;
    case PolyKind::OverlappingPaths:
      c.branches = vmtk_paths(pd, radii, merge_tolerance);
      break;
    default:
      c.branches = graph_chains(pd, radii, vmtk);
      break;
  }
  return c;
}

Centerlines read_polydata_centerlines(const std::string& path, const ReadOptions& opt) {
  const auto pd = read_vtk_polydata(path);
  const bool own = find_array(pd.field_data, "flowire_network") != nullptr;
  const double f = length_factor(opt, own ? std::optional<std::string>("m") : std::nullopt, path);
  auto c = polydata_to_centerlines(pd, opt.merge_tolerance);
  scale(c, f);
  return c;
}

Network read_polydata_network(const std::string& path, const ReadOptions& opt) {
  const auto pd = read_vtk_polydata(path);
  if (find_array(pd.field_data, "flowire_network")) {
    const double f = length_factor(opt, std::string("m"), path);
    return finish(*polydata_to_network(pd), opt, f, path);
  }
  const double f = length_factor(opt, std::nullopt, path);
  auto c = polydata_to_centerlines(pd, opt.merge_tolerance);
  scale(c, f);
  return finish(build_checked(c, opt.build), opt, f, path);
}

}  // namespace flowire::vessels::detail
