#pragma once
/// @file outlet_file.hpp
/// @brief Outlet boundary conditions from the files patient models keep them in
/// (`flow.outlets.file`): an svOneDSolver input deck (`.in`: each outlet SEGMENT's bcType and
/// DATATABLE), SimVascular's `rcrt.dat` (an RCR per cap name) and an svZeroDSolver model (`.json`:
/// each `boundary_conditions` entry a vessel names as its outlet, any kind of the catalogue:
/// RESISTANCE, RCR, CORONARY, PRESSURE, FLOW); and an openBF model (`.yaml`, SI: each outlet
/// vessel's condition by its label, openbf::outlet_condition).
///
/// All are in the CGS units of those tools: resistances in dyn s/cm⁵ (× 1e5 → Pa s/m³),
/// capacitances in cm⁵/dyn (× 1e-5 → m³/Pa), pressures in dyn/cm² (× 0.1 → Pa), the deck's node
/// flows in cm³/s (× 1e-6 → m³/s), the deck's node coordinates in cm unless a length factor says otherwise.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "flowire/flow/spec.hpp"

namespace flowire::flow {

/// @brief One outlet's condition as a file gives it: by the position of its end (a deck) or by
/// name (rcrt.dat: the cap's face name).
struct FileOutlet {
  OutletBC bc;       ///< its condition, SI (bc.node unset)
  std::string name;  ///< the deck's SEGMENT name, rcrt.dat's face name, the svZeroDSolver bc_name
  std::vector<std::string>
      aliases;  ///< further names the outlet goes by (svZeroDSolver: the vessel ending there, its branch)
  bool has_position = false;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< the outlet node [m] (decks)
  std::string where;                                   ///< file:line, for messages
};

/// @brief Read the outlets of @p path: `.in` (svOneDSolver deck; @p length_factor turns its
/// coordinates into metres), `rcrt.dat` (by its content: a first line with one integer) or an
/// svZeroDSolver model (a JSON object) or an openBF model (openbf::is_model).
/// RCR, RESISTANCE and PRESSURE outlets; a datatable that varies in time, a CORONARY or other
/// outlet kind, a negative value or a missing table are bad input naming file and line.
std::vector<FileOutlet> read_outlet_file(const std::string& path, double length_factor = 1e-2);

}  // namespace flowire::flow
