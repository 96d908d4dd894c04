#pragma once
// The fit tests' probe scene (test_fit.cpp, and the fit under MPI in test_study.cpp): a
// J-tipped wire pushed 4 cm along a wide straight tube (along x) without touching its wall.
// The J stands off the axis by a few mm in the direction the base rotation turns it to, so
// the tip trace's (y, z) fixes the rotation. 200 steps: a run takes well under a second.

namespace flowire::testing {

inline constexpr const char* kFitProbeScene = R"(name: fit_probe
vessels:
  generator: {type: straight_tube, length: 80 mm, radius: 8 mm}
  max_segment_length: 5 mm
wire:
  length: 0.1
  radius: 0.3 mm
  youngs_modulus: 20 GPa
  segment_length: 2 mm
  entry: 0
  tip: {length: 2 cm, youngs_modulus: 5 GPa, shape: j, angle: 90 deg, bend_radius: 3 mm}
insertion: {speed: 2 cm/s, initial_length: 1 cm, rotation_angle: 0 deg}
solve: {dt: 10 ms, duration: 2 s}
output: {every: 0, vtk: false}
)";

}  // namespace flowire::testing
