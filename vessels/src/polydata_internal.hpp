#pragma once
// Private to the poly data readers (.vtp, .vtk). A VTK-independent view of poly data (points,
// line cells and named arrays) and the sources that share it:
// - the containers read into PolyData: read_vtk_xml.cpp (VTK XML .vtp, with VTK) and
//   read_legacy_vtk.cpp (legacy .vtk, without VTK);
// - what every centerline convention needs of it (polydata.cpp): arrays by name, the radius at
//   every point, the checks on line cells and points, cells turned into polylines;
// - one reader per centerline convention: read_flowire_vtp.cpp (flowire's own networks),
//   read_vmtk_paths.cpp (vmtkcenterlines), read_vmtk_branch_split.cpp (vmtkbranchextractor),
//   read_simvascular_rom.cpp (SimVascular ROM centerlines), read_polylines.cpp (any other
//   polylines);
// - read_polydata.cpp: which container a file is and which convention it holds.
// Everything here is in file units: the caller scales to metres.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
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

// ---------------------------------------------------------------------------------------
// The containers.

/// Read a .vtp / .vtk file: the container told by its first bytes, not its extension
/// (read_polydata.cpp).
[[nodiscard]] PolyData read_vtk_polydata(const std::string& path);

/// Counts declared in a VTK XML header (NumberOfPoints, NumberOfTuples, ...) must fit in a file
/// of `size` bytes: a corrupt header must not make VTK allocate gigabytes (read_vtk_xml.cpp).
void check_declared_sizes(const std::string& path, const std::string& text, uintmax_t size);

/// VTK XML poly data read with VTK (throws flowire::Error if VTK is not built in).
[[nodiscard]] PolyData read_vtk_xml_polydata(const std::string& path);

/// Legacy VTK poly data (ASCII or BINARY) parsed without VTK; `text` is the whole file.
[[nodiscard]] PolyData read_legacy_polydata(const std::string& path, const std::string& text);

// ---------------------------------------------------------------------------------------
// Shared by the conventions (polydata.cpp).

/// The array of that name, any case, or nullptr.
[[nodiscard]] const NumericArray* find_array(const std::vector<NumericArray>& arrays, std::string_view name);
[[nodiscard]] const StringArray* find_strings(const std::vector<StringArray>& arrays, std::string_view name);

/// Integer value of tuple i, first component (arrays stored as double); LLONG_MIN if it is not
/// finite or too large.
[[nodiscard]] long long int_at(const NumericArray& a, size_t i);

/// Array `a` must hold n tuples; `what` is "point" or "cell".
void require_tuples(const PolyData& pd, const NumericArray& a, size_t n, const char* what);

/// Radius at every point, from the first radius-like point array found (`radius`, `radii`,
/// `MaximumInscribedSphereRadius`, `misr`, any case), else sqrt(CenterlineSectionArea / pi).
[[nodiscard]] std::vector<double> point_radii(const PolyData& pd);

/// At least one line cell, else an error saying what the file holds instead.
void require_lines(const PolyData& pd);

/// Checks every line cell (ids in range, at least two points) and every point the cells use
/// (finite coordinates, finite positive radius).
void validate(const PolyData& pd, const std::vector<double>& radii);

/// Point ids of a cell with consecutive coincident points removed (VMTK writes a few) or,
/// when `allow_duplicates` is false, reported.
[[nodiscard]] std::vector<long long> cell_ids(const PolyData& pd, size_t c, bool allow_duplicates);

/// The points `ids` with their radii, as one polyline.
[[nodiscard]] Polyline make_polyline(const PolyData& pd, const std::vector<double>& radii,
                                     const std::vector<long long>& ids, std::string name);

/// Appends q to p, skipping points of q that coincide with the last point of p.
void append_points(Polyline& p, const Polyline& q, size_t from = 0);

/// The point ids a canonical edge {a, b} (a < b) was read from: `at_a` is the file point at a,
/// `at_b` the one at b, in the first line cell holding the edge. Each cell keeps its own
/// radius there (a junction point repeated in every branch carries each branch's radius).
struct EdgeOrigin {
  long long at_a = -1, at_b = -1;
};
using EdgeOrigins = std::map<std::pair<long long, long long>, EdgeOrigin>;

/// Point adjacency from line cells (each consecutive pair of ids is an edge; duplicates merged),
/// on the ids `canon` maps every point to.
[[nodiscard]] std::vector<std::vector<long long>> adjacency(const PolyData& pd, const std::vector<long long>& canon,
                                                            bool allow_duplicates, EdgeOrigins* origins = nullptr);

// ---------------------------------------------------------------------------------------
// One reader per convention. But for flowire's own, each is given poly data whose cells and
// points validate() has checked, with its point radii, and returns branches in file units.

/// flowire's own .vtp (read_flowire_vtp.cpp): the exact network (metres), or nullopt if the
/// field array `flowire_network` is absent.
[[nodiscard]] std::optional<Network> polydata_to_network(const PolyData& pd);
/// Its branches as centerlines: each node with the radius its branch has there.
[[nodiscard]] std::vector<Polyline> flowire_network_branches(const Network& net);

/// vmtkcenterlines output (read_vmtk_paths.cpp): whether the polylines are inlet→outlet paths
/// that overlap along shared trunks (within `tol` × local radius) ...
[[nodiscard]] bool paths_overlap(std::vector<Polyline> paths, double tol);
/// ... and its line cells, as such paths, merged into one tree of branches.
[[nodiscard]] std::vector<Polyline> vmtk_paths(const PolyData& pd, const std::vector<double>& radii,
                                               double merge_tolerance);

/// vmtkbranchextractor output (read_vmtk_branch_split.cpp): one branch per group.
[[nodiscard]] std::vector<Polyline> branch_split_vmtk(const PolyData& pd, const std::vector<double>& radii);

/// SimVascular ROM centerlines (read_simvascular_rom.cpp): one branch per BranchId.
[[nodiscard]] std::vector<Polyline> simvascular_rom(const PolyData& pd, const std::vector<double>& radii);

/// Any other polylines (read_polylines.cpp): chains between junctions and ends;
/// `allow_duplicates`: drop consecutive coincident points (VMTK files hold some) instead of
/// reporting them.
[[nodiscard]] std::vector<Polyline> graph_chains(const PolyData& pd, const std::vector<double>& radii,
                                                 bool allow_duplicates);

// ---------------------------------------------------------------------------------------
// Telling the conventions apart (read_polydata.cpp).

/// What kind of centerline file a poly data holds.
enum class PolyKind { FlowireNetwork, BranchSplitVmtk, SimVascularRom, OverlappingPaths, Graph };

[[nodiscard]] PolyKind classify(const PolyData& pd, double merge_tolerance);
[[nodiscard]] const char* kind_name(PolyKind k);

/// Centerlines in file units (no scaling), read by the convention `classify` finds.
[[nodiscard]] Centerlines polydata_to_centerlines(const PolyData& pd, double merge_tolerance);

}  // namespace flowire::vessels::detail
