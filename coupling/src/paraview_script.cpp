#include "flowire/coupling/paraview_script.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "flowire/common/output.hpp"

namespace flowire::coupling {

namespace {

/// A Python string literal (the names flowire writes need no escaping, but a title may).
std::string py_string(const std::string& s) {
  std::string out = "\"";
  for (const char ch : s) {
    if (ch == '\\' || ch == '"') out += '\\';
    if (ch == '\n') {
      out += "\\n";
      continue;
    }
    out += ch;
  }
  return out + "\"";
}

constexpr const char* kBody = R"PY(

HERE = os.path.dirname(os.path.abspath(__file__)) if "__file__" in globals() else os.getcwd()


def load(folder=HERE, view=None):
    """Open the run's files in `folder` and show them in `view`; returns the sources."""
    view = view or GetActiveViewOrCreate("RenderView")
    shown = {"view": view}
    if NETWORK:
        net = OpenDataFile(os.path.join(folder, NETWORK))
        RenameSource("network", net)
        points = CellDatatoPointData(registrationName="network radius at nodes", Input=net)
        points.PassCellData = 1
        tube = Tube(registrationName="network tubes", Input=points)
        tube.Scalars = ["POINTS", "radius"]
        tube.VaryRadius = "By Absolute Scalar"  # each vessel at its own radius
        tube.NumberofSides = 24
        tube.Capping = 1
        display = Show(tube, view)
        field = "pressure" if "pressure" in net.PointData.keys() else "radius"
        ColorBy(display, ("POINTS", field))
        lut = GetColorTransferFunction(field)
        lut.ApplyPreset("Cool to Warm", True)
        lut.AutomaticRescaleRangeMode = "Clamp and update every timestep"  # each output's own range
        display.RescaleTransferFunctionToDataRange(True, False)
        display.Opacity = 0.45  # the wire shows through the vessel walls
        display.SetScalarBarVisibility(view, True)
        bar = GetScalarBar(lut, view)
        bar.Title = "blood pressure [Pa]" if field == "pressure" else "vessel radius [m]"
        bar.ComponentTitle = ""
        shown.update(network=net, network_tubes=tube, network_display=display, field=field)
    if WIRE:
        wire = OpenDataFile(os.path.join(folder, WIRE))
        RenameSource("wire", wire)
        wire_tube = Tube(registrationName="wire tube", Input=wire)
        wire_tube.Radius = WIRE_DRAW_RADIUS
        wire_tube.NumberofSides = 12
        display = Show(wire_tube, view)
        display.ColorArrayName = ["POINTS", ""]  # one solid colour
        display.AmbientColor = display.DiffuseColor = [0.15, 0.15, 0.15]
        shown.update(wire=wire, wire_tube=wire_tube, wire_display=display)
    if WALL:
        wall = OpenDataFile(os.path.join(folder, WALL))
        RenameSource("wall", wall)
        warped = WarpByVector(registrationName="wall, deformed", Input=wall)
        warped.Vectors = ["POINTS", "displacement"]  # to scale: the wall where it is
        display = Show(warped, view)
        ColorBy(display, ("POINTS", "displacement_magnitude"))
        lut = GetColorTransferFunction("displacement_magnitude")
        lut.ApplyPreset("Viridis (matplotlib)", True)
        display.RescaleTransferFunctionToDataRange(True, False)
        display.Opacity = 0.35  # the wire shows through
        display.SetScalarBarVisibility(view, True)
        GetScalarBar(lut, view).Title = "wall displacement [m]"
        shown.update(wall=wall, wall_warped=warped, wall_display=display)
    scene = GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    view.OrientationAxesVisibility = 1
    if TITLE:
        text = Text(registrationName="title")
        text.Text = TITLE
        Show(text, view).WindowLocation = "Upper Center"
    view.ResetCamera()
    return shown


def main(argv):
    shot = argv[argv.index("--screenshot") + 1] if "--screenshot" in argv else None
    shown = load()
    view = shown["view"]
    scene = GetAnimationScene()
    if len(scene.TimeKeeper.TimestepValues or []) > 1:
        scene.AnimationTime = scene.TimeKeeper.TimestepValues[-1]  # the last output
    if shot:
        SaveScreenshot(shot, view, ImageResolution=[1200, 900])
    elif sys.argv and os.path.basename(sys.argv[0]).startswith("pv"):
        Interact(view)
    else:
        Render(view)


if __name__ == "__main__":
    main(sys.argv[1:])
)PY";

}  // namespace

bool write_paraview_script(const std::filesystem::path& dir, const ParaViewScene& s) {
  if (s.network.empty() && s.wire.empty() && s.wall.empty()) return false;
  std::string text =
      "# ParaView view of this run, written by flowire: the vessel network as tubes of the vessels'\n"
      "# own radii, coloured by blood pressure (by radius without flow), with the wire (drawn thicker)\n"
      "# and, where the scene has one, the wall that yields, warped by its displacement.\n"
      "#   paraview --script=view.py                  (in the ParaView window)\n"
      "#   pvpython view.py                           (a render window)\n"
      "#   pvpython --force-offscreen-rendering view.py --screenshot view.png   (a picture)\n"
      "import os\nimport sys\n\nfrom paraview.simple import *  # noqa: F401,F403\n\n";
  text += fmt::format(
      "NETWORK = {}\nWIRE = {}\nWIRE_DRAW_RADIUS = {:.6g}  # [m] 3 x the wire radius, at least 1.2 mm\n"
      "WALL = {}\nTITLE = {}\n",
      py_string(s.network), py_string(s.wire), std::max(3.0 * s.wire_radius, 1.2e-3), py_string(s.wall),
      py_string(s.title));
  text += kBody;
  write_text_atomically(dir / "view.py", text);
  return true;
}

}  // namespace flowire::coupling
