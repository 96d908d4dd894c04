#pragma once
/// @file io.hpp
/// @brief Reading vessel networks from centerline files and writing them back.
///
/// Formats read (chosen by extension, then by the arrays the file holds):
/// - `.vtp` (VTK XML poly data, read with VTK) and `.vtk` (legacy VTK poly data, ASCII or BINARY,
///   parsed by flowire itself, also without VTK):
///   - flowire's own `.vtp` (field array `flowire_network`): read back to the identical network;
///   - VMTK `vmtkbranchextractor` output (cell arrays `GroupIds`, `Blanking`, `CenterlineIds`,
///     `TractIds`): one branch per group, junctions at the blanked bifurcation regions;
///   - SimVascular ROM centerlines (point arrays `BranchId`, `BifurcationId`): one branch per
///     `BranchId`, each bifurcation region (`BranchId` = -1) collapsed into one junction;
///   - VMTK `vmtkcenterlines` output (one polyline per inlet→outlet path, paths overlapping
///     along shared trunks): the paths are merged into one tree from their common inlet; a
///     path stays on the tree while its points are within `merge_tolerance` × local radius
///     of it, and the last such point becomes the junction;
///   - any other set of polylines: cells sharing points, or points closer than 1e-6 of their
///     radius (the last bits two writers round differently), are joined, one branch per chain
///     between junctions and ends. A point repeated in several cells (a junction written once
///     per branch) keeps in each branch the radius that branch's cell gives it; a chain is
///     also cut where two cells meet with different radii.
///   The radius comes from the point array `radius` / `radii` (any case),
///   `MaximumInscribedSphereRadius`, or else `sqrt(CenterlineSectionArea / pi)`.
/// - `.yaml` / `.yml`: flowire's network file,
///   `branches: [{name, points: [[x, y, z, r], ...]}]` with an optional `length_unit`
///   (and, as written by `write_network_yaml`, optional exact `nodes` / `segments`).
/// - `.in`: svOneDSolver input deck (`NODE`, `SEGMENT`, `JOINT` cards, CGS units): each deck
///   segment keeps its length and gets the mean of its end radii sqrt(area / pi) (pieces cut by
///   `BuildOptions` interpolate the taper); the daughters of every `JOINT` start at the outlet
///   node of its inlet segment; branches are the runs of one vessel between junctions.
/// Files with another extension are recognised by their content.
///
/// Every reader reports bad input (missing radius array, non-positive or non-finite radius
/// or coordinate, empty or truncated file, duplicate points, self-loops, a network in several
/// pieces) as one `flowire::Error` naming the file and the point, line or cell at fault.
#include <string>
#include <string_view>
#include <vector>

#include "flowire/vessels/network.hpp"

namespace flowire::vessels {

/// @brief How a network file is read.
struct ReadOptions {
  /// Unit of the file's coordinates and radii: "m", "cm", "mm" or "um". Empty: the unit the
  /// file declares (flowire files: their `length_unit`; svOneDSolver decks: cm), else m.
  /// A file that declares its unit keeps it; a different unit given here is then reported
  /// in a warning and ignored.
  std::string length_unit;
  /// Factor from file units to metres; when > 0 it is used instead of `length_unit`.
  double length_factor = 0.0;
  /// How branches become segments (`read_network` only).
  BuildOptions build;
  /// If the network falls into several disconnected pieces: false (default) is an error that
  /// names the pieces; true keeps the piece that holds the widest end (the inlet) and warns.
  bool keep_inlet_piece = false;
  /// Overlapping VMTK paths are the same vessel while their points stay within this fraction
  /// of the local radius of each other; the point where they part becomes a junction.
  double merge_tolerance = 0.2;
  /// Warn when the radii look like another unit (largest radius above 5 cm or below 1 um).
  bool check_units = true;
};

/// @brief Read a centerline file into raw branches (metres), without building segments.
/// svOneDSolver decks give one branch per vessel chain between junctions, with the node
/// radius taken as the mean of the adjoining segment ends.
/// @throws flowire::Error (input) naming the file and the place at fault.
Centerlines read_centerlines(const std::string& path, const ReadOptions& options = {});

/// @brief Read a network file and build the network (see the file comment for formats).
/// flowire's own `.vtp` and `.yaml` files with `nodes`/`segments` give back the exact network
/// they were written from; svOneDSolver decks keep the deck's segments (lengths from the
/// deck), split further only by `options.build`.
/// @throws flowire::Error (input) naming the file and the place at fault.
Network read_network(const std::string& path, const ReadOptions& options = {});

/// @brief One network format: what read_centerlines() and read_network() dispatch on, and
/// what every list of formats (error messages, the CLI's help, the fuzz target) is made from.
struct NetworkReader {
  std::string_view name;                      ///< what writes it, for messages
  std::vector<std::string_view> extensions;   ///< lower case, with the dot
  bool (*recognises)(std::string_view head);  ///< by the first 4 KiB, for other extensions
  Centerlines (*centerlines)(const std::string& path, const ReadOptions& options);
  Network (*network)(const std::string& path, const ReadOptions& options);
};

/// @brief The formats read, in the order they are tried.
const std::vector<NetworkReader>& network_readers();
/// @brief Their extensions, comma separated (".vtp, .vtk, ...").
std::string network_extensions();

/// @brief A named array attached to the nodes (point data) or segments (cell data) of a
/// written network: `values.size() == count * components`, components 1 or 3.
struct DataArray {
  std::string name;
  std::vector<double> values;
  int components = 1;
};

/// @brief Write a network as VTK XML poly data (`.vtp`, raw appended binary, opens in
/// ParaView): points = nodes, one VTK_LINE cell per segment (cell `i` is segment `i`), cell data
/// `radius`, `radius_from`, `radius_to`, `length`, `branch_id`, `segment_id`, point data
/// `radius` (for display: mean of the radii the segments at the node have there), then the
/// caller's arrays; field data `flowire_network`, `branch_names` and the branch node /
/// segment lists, from which `read_network` rebuilds the identical network. Written atomically (no partial file on
/// failure).
/// @throws flowire::Error (usage) if an array has the wrong size, (input) if the file cannot
/// be written.
void write_network_vtp(const Network& net, const std::string& path, const std::vector<DataArray>& point_data = {},
                       const std::vector<DataArray>& cell_data = {});

/// @brief Write a network as flowire YAML: `length_unit: m`, `branches` with points
/// `[x, y, z, r]` along each branch (readable by any YAML tool), plus exact `nodes` and
/// `segments` lists from which `read_network` rebuilds the identical network.
void write_network_yaml(const Network& net, const std::string& path);

/// @brief Write a network in the format chosen by the extension of `path` (.vtp or .yaml/.yml).
void write_network(const Network& net, const std::string& path);

}  // namespace flowire::vessels
