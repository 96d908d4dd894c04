#pragma once
// Internal to the readers: a VTK-independent view of poly data (points, line cells and
// named arrays) and the functions that turn it into centerlines or a network.
#include <optional>
#include <string>
#include <vector>

#include "flowire/vessels/io.hpp"
#include "flowire/vessels/network.hpp"

namespace flowire::vessels::detail {

struct NumericArray {
  std::string name;
  int components = 1;
  std::vector<double> values;  // tuples, row major
  [[nodiscard]] size_t tuples() const { return components > 0 ? values.size() / static_cast<size_t>(components) : 0; }
};

struct StringArray {
  std::string name;
  std::vector<std::string> values;
};

/// Poly data as read from a .vtp / .vtk file: only line and poly-line cells are kept.
struct PolyData {
  std::string source;  // file name for messages
  std::vector<Vec3> points;
  std::vector<std::vector<long long>> lines;  // point ids per line cell
  std::vector<NumericArray> point_data;
  std::vector<NumericArray> cell_data;  // one tuple per line cell
  std::vector<NumericArray> field_data;
  std::vector<StringArray> field_strings;
  long long other_cells = 0;  // vertices, polygons, strips (ignored)
};

/// What kind of centerline file a poly data holds.
enum class PolyKind { FlowireNetwork, BranchSplitVmtk, SimVascularRom, OverlappingPaths, Graph };

[[nodiscard]] const NumericArray* find_array(const std::vector<NumericArray>& arrays, std::string_view name);
[[nodiscard]] PolyKind classify(const PolyData& pd, double merge_tolerance);
[[nodiscard]] const char* kind_name(PolyKind k);

/// Centerlines in file units (no scaling), for every kind except FlowireNetwork.
[[nodiscard]] Centerlines polydata_to_centerlines(const PolyData& pd, double merge_tolerance);

/// flowire's own .vtp: the exact network (metres), or nullopt if the marker is absent.
[[nodiscard]] std::optional<Network> polydata_to_network(const PolyData& pd);

/// Read a .vtp / .vtk file with VTK (throws flowire::Error if VTK is not built in).
[[nodiscard]] PolyData read_vtk_polydata(const std::string& path);

/// Legacy VTK poly data (ASCII or BINARY) parsed without VTK; `text` is the whole file.
[[nodiscard]] PolyData read_legacy_polydata(const std::string& path, const std::string& text);

/// Overlapping inlet→outlet paths (file units) merged into one tree of branches.
[[nodiscard]] std::vector<Polyline> merge_paths(std::vector<Polyline> paths, double merge_tolerance,
                                                const std::string& source);

}  // namespace flowire::vessels::detail
