#pragma once
/// @file compare_output.hpp
/// @brief The files of a network-vs-FEM comparison (compare.hpp, pulsatile.hpp), written by
/// rank 0 only, each atomically.
///
/// One instant (`write_outputs`): fem_compare.csv
/// (`branch,s,x,y,z,pressure_network,pressure_fem,rel_diff` then `pressure_fem_centre,
/// rel_diff_drop,path_distance,near_junction,flow_network,flow_fem,rel_diff_flow,radius_network,
/// radius_fem`), fem_outlets.csv
/// (`outlet,flow_network,flow_fem` then `rel_diff,pressure_network,pressure_fem`), fem_compare.md (tables like the
/// paper's Table 1, flows, branch drops, timings), fem.vtu (quadratic tetrahedra, point
/// data `velocity` and `pressure`), fem_forces.csv (`boundary,fx,fy,fz`: the force of the
/// fluid on the wall, boundary_forces), fem_compare.png (network vs FEM pressure along the
/// path from the inlet, drawn by flow/fem/scripts/plot_fem_compare.py with matplotlib;
/// a warning, not an error, when python3/matplotlib is missing).
///
/// A series (`write_pulsatile_outputs`): fem_pulsatile.csv (`time`, then the columns of
/// fem_compare.csv), fem_pulsatile_outlets.csv (`time`, then the columns of
/// fem_outlets.csv), and with the frames' fields fem.pvd + fem_NNNN.vtu.
#include <span>
#include <string>

#include "flowire/flow/fem/compare.hpp"
#include "flowire/flow/fem/mesh.hpp"
#include "flowire/flow/fem/stokes.hpp"

namespace flowire::flow::fem {

/// @brief Write a solution as quadratic tetrahedra (.vtu, point data `velocity` and
/// `pressure`; edge nodes take the mean pressure of their vertices).
void write_vtu(const std::string& path, const TetMesh& mesh, const StokesSolution& sol);

/// @brief Write the output files of one comparison into `out_dir` (created if needed),
/// fem_forces.csv (`boundary,fx,fy,fz`: the `forces`) too. Only rank 0 writes.
/// @throws flowire::Error (input) when the folder cannot be created.
void write_outputs(const std::string& out_dir, const Network& net, const TetMesh& mesh, const StokesSolution& sol,
                   const CompareResult& result, const FemOptions& opt);

/// @brief Write the files of a series of comparisons (`frames`, each at its `time`) into
/// `out_dir` (created if needed); with `fields` (one per frame) also fem.pvd and
/// fem_NNNN.vtu. Only rank 0 writes.
/// @throws flowire::Error (input) when the folder cannot be created.
void write_pulsatile_outputs(const std::string& out_dir, const Network& net, const TetMesh& mesh,
                             std::span<const CompareResult> frames, std::span<const StokesSolution> fields);

}  // namespace flowire::flow::fem
