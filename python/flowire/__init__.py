"""flowire: guidewire and blood-flow co-simulation in vessel networks.

    import flowire
    net = flowire.read_network("aorta.vtp", length_unit="mm")   # nodes (N x 3), segments (M x 2), radius (M)
    summary = flowire.run("scene.yaml", out="out", set={"wire.segments": 200})
    sim = flowire.CoSimulation("scene.yaml")                     # step it, steer it, read the wire
    frame = flowire.Flow("scene.yaml").at(0.2)                   # pressure (N), flow (M) at t = 0.2 s

Errors in the input raise flowire.InputError, numerical failures flowire.NumericalError (both
flowire.Error); the message is the one `flowire run` prints: the file and the place first.
See docs/python.md.
"""
import json as _json

from ._flowire import (CoSimulation as _CoSimulation, Error, Flow as _Flow, FlowFrame, InputError, Network,
                       NumericalError, read_network as _read_network, take_warnings)
from ._flowire import _run

__all__ = ["read_network", "run", "CoSimulation", "Flow", "FlowFrame", "Network", "Error", "InputError",
           "NumericalError", "take_warnings"]


def _value(v):
    """A Python value as `--set KEY=VALUE` writes it."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (list, tuple)):
        return "[" + ",".join(_value(x) for x in v) + "]"
    if hasattr(v, "tolist"):  # numpy scalars and arrays
        return _value(v.tolist())
    if isinstance(v, float):
        return repr(v)
    return str(v)


def _overrides(set):
    """`set` as `--set` strings: a dict {key: value}, a list of "key=value", or None."""
    if set is None:
        return []
    if isinstance(set, dict):
        return [f"{k}={_value(v)}" for k, v in set.items()]
    if isinstance(set, str):
        return [set]
    return [str(s) for s in set]


def read_network(path, length_unit=None, max_segment_length=0.0):
    """Read a vessel network file as `flowire network info` does.

    length_unit: unit of the file's coordinates and radii ("m", "cm", "mm", "um"); None: the
    unit the file declares, else m. Returns a Network with read-only numpy views nodes (N x 3)
    [m], segments (M x 2) node ids, radius (M) [m], length (M) [m], and counts().
    """
    return _read_network(str(path), length_unit, float(max_segment_length))


def run(scene, out=None, set=None):
    """Run a scene file as `flowire run SCENE [--out OUT] [--set K=V]...` does.

    Writes the scene's outputs (into `out`, else the scene's output.dir) and returns the
    summary (what summary.json holds) as a dict. `set`: {key: value} or ["key=value", ...].
    Raises InputError for bad input, NumericalError for a numerical failure (summary.json
    then says so too).
    """
    return _json.loads(_run(str(scene), "" if out is None else str(out), _overrides(set)))


class CoSimulation(_CoSimulation):
    """A scene's co-simulation stepped from Python (see docs/python.md).

    CoSimulation(scene, set=None) builds what the scene has, computes the flow at t = 0 and
    settles the wire against the walls, as `flowire run` does, but writes no files. Then
    step(n=1) advances n steps of solve.dt; set insertion_speed / rotation_speed between steps.
    """

    def __init__(self, scene, set=None):
        super().__init__(str(scene), _overrides(set))


class Flow(_Flow):
    """The network flow of a scene (its vessels: and flow: sections): at(t) -> FlowFrame."""

    def __init__(self, scene, set=None):
        super().__init__(str(scene), _overrides(set))
