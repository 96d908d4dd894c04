#pragma once
// Private to the network readers. Two things every reader shares:
// - its entry points, one pair (centerlines, network) per file format, which the dispatch
//   table in io.cpp (network_readers) lists: read_polydata.cpp (.vtp / .vtk poly data and
//   the centerline conventions in them), read_yaml.cpp (flowire YAML), read_svonedsolver.cpp
//   (svOneDSolver input decks);
// - what is done with every network once its file is parsed (read_common.cpp): the length
//   unit (the file's own or the caller's), scaling to metres, the size limit before segments
//   are built, and the checks on the built network (disconnected pieces, plausible radii).
#include <optional>
#include <string>

#include "flowire/vessels/io.hpp"
#include "flowire/vessels/network.hpp"

namespace flowire::vessels::detail {

// ---------------------------------------------------------------------------------------
// Entry points of the readers (the members of NetworkReader), ReadOptions as documented in io.hpp.

/// .vtp (VTK XML) and .vtk (legacy VTK) poly data: flowire's own networks, VMTK paths and
/// branch-split centerlines, SimVascular ROM centerlines, plain polylines (read_polydata.cpp).
[[nodiscard]] Centerlines read_polydata_centerlines(const std::string& path, const ReadOptions& opt);
[[nodiscard]] Network read_polydata_network(const std::string& path, const ReadOptions& opt);

/// flowire's YAML network file (read_yaml.cpp).
[[nodiscard]] Centerlines read_yaml_centerlines(const std::string& path, const ReadOptions& opt);
[[nodiscard]] Network read_yaml_network(const std::string& path, const ReadOptions& opt);

/// svOneDSolver input deck, CGS (read_svonedsolver.cpp).
[[nodiscard]] Centerlines read_svonedsolver_centerlines(const std::string& path, const ReadOptions& opt);
[[nodiscard]] Network read_svonedsolver_network(const std::string& path, const ReadOptions& opt);

// ---------------------------------------------------------------------------------------
// Shared by the readers (read_common.cpp).

/// The whole text of a network file, within the input size limit for geometry.
[[nodiscard]] std::string read_network_text(const std::string& path);

/// Factor from file units to metres. `declared`: the unit the file itself states, if any; it
/// wins over the caller's unit, with a warning when they differ. `where` names the file.
[[nodiscard]] double length_factor(const ReadOptions& opt, const std::optional<std::string>& declared,
                                   const std::string& where);

/// Scales every point and radius by f (file units to metres).
void scale(Centerlines& c, double f);

/// Network::build, after refusing centerlines that would build an absurd number of segments
/// (wrong unit, corrupt coordinates) before it allocates them.
[[nodiscard]] Network build_checked(const Centerlines& c, const BuildOptions& opt);

/// The checks on every network read: a network in several pieces is an error naming them (or
/// the inlet's piece is kept, with a warning, under `keep_inlet_piece`); radii that look like
/// another length unit are warned about. `factor`: the file-to-metre factor used.
[[nodiscard]] Network finish(Network net, const ReadOptions& opt, double factor, const std::string& path);

}  // namespace flowire::vessels::detail
