#pragma once
/// @file paraview_script.hpp
/// @brief `view.py` next to a run's VTK output: a ParaView script that opens the network as
/// tubes of the vessels' own radii coloured by blood pressure (by radius without flow),
/// and the wire as a tube, over time when the outputs are series.
///   paraview --script=view.py                     (the ParaView window)
///   pvpython view.py                              (a render window)
///   pvpython --force-offscreen-rendering view.py --screenshot view.png   (a picture)
#include <filesystem>
#include <string>

namespace flowire::coupling {

/// @brief What the script shows (file names relative to the output folder; empty: none).
struct ParaViewScene {
  std::string network;       ///< network.vtp or network.pvd
  std::string wire;          ///< wire.pvd
  std::string wall;          ///< wall.pvd (a wall that yields: warped by its displacement)
  double wire_radius = 0.0;  ///< [m]; drawn at max(3 × radius, 1.2 mm) to be seen, as network.png does
  std::string title;
};

/// @brief Write `view.py` into @p dir (atomically) if the scene shows anything; returns
/// whether it was written.
bool write_paraview_script(const std::filesystem::path& dir, const ParaViewScene& scene);

}  // namespace flowire::coupling
