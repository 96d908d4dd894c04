"""The Python API against independent values: Hagen-Poiseuille flow of a tube, statics of a
clamped wire, the command line's own outputs, and the no-copy sharing of arrays."""
import json
import math
import subprocess

import numpy as np
import pytest

import flowire

TUBE = """\
vessels:
  generator: {type: straight_tube, length: 0.12, radius: 1.5 mm}
  max_segment_length: 1 cm
flow:
  viscosity: 4e-3
  inlet: {pressure: {waveform: sine, systolic: 120 mmHg, diastolic: 80 mmHg, period: 0.8 s}}
  outlets: {pressure: 0}
solve: {dt: 10 ms, duration: 0.1 s}
output: {png: false}
"""

MMHG = 133.322387415


def test_flow_of_a_tube_is_hagen_poiseuille(write_scene):
    scene = write_scene(TUBE)
    f = flowire.Flow(scene)
    net = f.network
    length, radius, mu = 0.12, 1.5e-3, 4e-3
    inlet = int(np.argmin(net.nodes[:, 0])) if np.ptp(net.nodes[:, 0]) > 0 else 0
    axis = net.nodes[-1] - net.nodes[0]
    axis /= np.linalg.norm(axis)
    for t in (0.0, 0.13, 0.5):
        p_in = (120 - 80) / 2 * MMHG * math.sin(2 * math.pi * t / 0.8) + (120 + 80) / 2 * MMHG
        frame = f.at(t)
        assert frame.time == t
        q = math.pi * radius**4 * p_in / (8 * mu * length)
        np.testing.assert_allclose(np.abs(frame.flow), q, rtol=1e-12)
        # pressure falls linearly from the inlet end to 0 at the outlet
        x = (net.nodes - net.nodes[inlet]) @ axis
        x = np.abs(x)
        np.testing.assert_allclose(frame.pressure, p_in * (1 - x / length), rtol=1e-10, atol=1e-9 * p_in)
    assert len(net.nodes) == 13 and len(net.segments) == 12  # 12 cm in 1 cm pieces


def test_network_arrays_are_read_only_views_that_keep_their_owner(write_scene):
    net = flowire.Flow(write_scene(TUBE)).network
    a, b = net.nodes, net.nodes
    assert a is not b and np.shares_memory(a, b)        # two views of one memory, no copy
    assert a.__array_interface__["data"][0] == b.__array_interface__["data"][0]
    assert not a.flags.owndata and not a.flags.writeable
    with pytest.raises(ValueError):
        a[0, 0] = 1.0
    seg = net.segments
    assert seg.dtype == np.int32 and seg.shape == (12, 2)
    assert seg.strides[1] == 4 and seg.strides[0] > 8    # strided over the segment records
    assert net.radius.strides == (seg.strides[0],)      # fields of the same records
    # the owner stays alive as long as a view does
    assert a.base is net
    nodes = flowire.Flow(write_scene(TUBE, "other.yaml")).network.nodes
    import gc
    gc.collect()
    np.testing.assert_allclose(nodes, net.nodes)


def test_flow_frame_arrays_are_views_of_the_frame(write_scene):
    frame = flowire.Flow(write_scene(TUBE)).at(0.2)
    p = frame.pressure
    assert p.base is frame and not p.flags.owndata and not p.flags.writeable
    assert np.shares_memory(p, frame.pressure)


def test_read_network_matches_network_info(flowire_exe, shared_dir):
    path = shared_dir / "data/real/feelpp-aortic-arch/centerlinesAORTA.vtk"
    net = flowire.read_network(path, length_unit="cm")
    info = json.loads(subprocess.run([flowire_exe, "network", "info", str(path), "--length-unit", "cm", "--json"],
                                     check=True, capture_output=True, text=True).stdout)
    counts = net.counts()
    for k in ("branches", "nodes", "segments", "junctions", "ends", "loops"):
        assert counts[k] == info[k], k
    assert net.nodes.shape == (info["nodes"], 3)
    assert net.segments.shape == (info["segments"], 2) and net.radius.shape == (info["segments"],)
    assert net.segments.min() >= 0 and net.segments.max() < info["nodes"]
    assert net.radius.min() == pytest.approx(info["radius_min"], rel=1e-12)
    assert net.radius.max() == pytest.approx(info["radius_max"], rel=1e-12)
    # the network's length from the arrays: sum of the node distances of every segment
    seg_len = np.linalg.norm(net.nodes[net.segments[:, 1]] - net.nodes[net.segments[:, 0]], axis=1)
    assert seg_len.sum() == pytest.approx(info["total_length"], rel=1e-9)
    # in mm the same file is 10 times smaller
    cm = flowire.read_network(str(path), length_unit="cm", max_segment_length=1.0)   # branches not split
    mm = flowire.read_network(str(path), length_unit="mm", max_segment_length=1.0)
    np.testing.assert_allclose(mm.nodes, cm.nodes / 10, rtol=1e-12)


def test_read_network_of_a_yaml_file_gives_its_points(tmp_path):
    p = tmp_path / "y.yaml"
    p.write_text("length_unit: mm\nbranches:\n"
                 "  - {name: a, points: [[0,0,0,2], [10,0,0,2]]}\n"
                 "  - {name: b, points: [[10,0,0,1.5], [20,5,0,1.5]]}\n"
                 "  - {name: c, points: [[10,0,0,1.5], [20,-5,0,1.5]]}\n")
    net = flowire.read_network(p, max_segment_length=0.1)   # no branch split
    assert sorted(map(tuple, np.round(net.nodes * 1e3, 12))) == [(0, 0, 0), (10, 0, 0), (20, -5, 0), (20, 5, 0)]
    np.testing.assert_allclose(sorted(net.radius), [1.5e-3, 1.5e-3, 2e-3])
    assert net.counts()["junctions"] == 1 and net.counts()["ends"] == 3


def test_bad_input_raises_with_the_command_lines_message(flowire_exe, write_scene):
    scene = write_scene(TUBE.replace("viscosity: 4e-3", "viscosity: 4e-3\n  viscosty: 1"))
    cli = subprocess.run([flowire_exe, "run", str(scene), "--out", str(scene.parent / "cli")], capture_output=True,
                         text=True)
    assert cli.returncode == 2
    line = cli.stderr.strip().splitlines()[-1]
    assert line.startswith("flowire: error: ")
    with pytest.raises(flowire.InputError) as e:
        flowire.run(scene, out=scene.parent / "py")
    assert str(e.value) == line[len("flowire: error: "):]
    assert str(scene) in str(e.value) and "viscosty" in str(e.value)
    with pytest.raises(flowire.InputError, match="no such file"):
        flowire.run(scene.parent / "absent.yaml")
    with pytest.raises(flowire.Error):
        flowire.read_network(scene.parent / "absent.vtp")


WIRE = """\
name: short_push
vessels:
  generator: {type: y_bifurcation, parent_radius: 4 mm, parent_length: 60 mm, child_length: 50 mm, angle: 0.6 rad}
  max_segment_length: 4 mm
flow:
  inlet: {pressure: {waveform: sine, systolic: 120 mmHg, diastolic: 80 mmHg, period: 0.8 s}}
  outlets: {resistance: 2 mmHg*s/mL}
wire:
  length: 0.3
  radius: 0.3 mm
  youngs_modulus: 20 GPa
  segment_length: 2 mm
  entry: 0
  base: {position: [0.002, 0, 0], direction: [1, 0, 0]}
  tip: {length: 2 cm, youngs_modulus: 5 GPa, shape: j, angle: 120 deg, bend_radius: 3 mm}
insertion: {speed: 2 cm/s, initial_length: 1 cm}
contact: {friction: 0.1}
solve: {dt: 5 ms, duration: 0.2 s}
output: {every: 0.1 s, png: false}
"""


def _without_timings(summary):
    """The summary without wall-clock times and the output folder."""
    def strip(d):
        return {k: strip(v) if isinstance(v, dict) else v for k, v in d.items()
                if k not in ("timings", "output.dir") and "seconds" not in k}
    return strip(summary)


def test_run_gives_the_command_lines_summary_and_files(flowire_exe, write_scene):
    scene = write_scene(WIRE)
    cli_out, py_out = scene.parent / "cli", scene.parent / "py"
    subprocess.run([flowire_exe, "run", str(scene), "--out", str(cli_out), "--set", "wire.segment_length=3mm"],
                   check=True, capture_output=True)
    summary = flowire.run(scene, out=py_out, set={"wire.segment_length": "3mm"})
    assert summary["status"] == "ok" and summary["steps"] == 40
    assert _without_timings(summary) == _without_timings(json.loads((cli_out / "summary.json").read_text()))
    assert _without_timings(summary) == _without_timings(json.loads((py_out / "summary.json").read_text()))
    for f in ("tip_trace.csv", "wire.csv", "nodes.csv", "segments.csv"):
        assert (py_out / f).read_text() == (cli_out / f).read_text(), f


def test_stepping_from_python_is_the_run(write_scene):
    """Stepped from Python with the scene's own speed, the co-simulation ends where run() does."""
    scene = write_scene(WIRE)
    summary = flowire.run(scene, out=scene.parent / "run")
    sim = flowire.CoSimulation(scene)
    assert sim.planned_steps == 40 and sim.dt == pytest.approx(5e-3)
    while sim.step_count < sim.planned_steps:
        sim.step()
    assert sim.time == pytest.approx(0.2)
    np.testing.assert_array_equal(sim.tip, summary["wire"]["tip"])
    np.testing.assert_array_equal(sim.base_force, summary["wire"]["base_force"])
    assert sim.inserted_length == summary["wire"]["inserted_length"]
    w = sim.wire()
    np.testing.assert_array_equal(w["x"][-1], sim.tip)          # base → tip
    np.testing.assert_allclose(w["force"], w["drag"] + w["contact"], rtol=1e-12, atol=1e-15)
    assert np.abs(w["drag"]).max() > 0 and np.abs(w["flow_velocity"]).max() > 0   # the blood acts
    assert w["s"][0] == 0 and np.all(np.diff(w["s"]) > 0)
    np.testing.assert_array_equal(sim.vertices, w["x"])
    frame = sim.flow()
    assert frame.time == pytest.approx(0.2) and frame.pressure.shape == (len(sim.network.nodes),)


def test_insertion_set_every_step_feeds_that_length(write_scene):
    scene = write_scene(WIRE)
    sim = flowire.CoSimulation(scene)
    start = sim.inserted_length
    speeds = [0.02 * (1 + math.sin(k / 5)) for k in range(30)]
    for v in speeds:
        sim.insertion_speed = v
        assert sim.insertion_speed == v
        sim.step()
    assert sim.inserted_length == pytest.approx(start + sum(speeds) * sim.dt, rel=1e-12)
    sim.insertion_speed = -0.01   # pulling back
    sim.step(4)
    assert sim.inserted_length == pytest.approx(start + sum(speeds) * sim.dt - 4 * 0.01 * sim.dt, rel=1e-12)


CANTILEVER = """\
wire:
  length: 0.1
  radius: 0.25 mm
  youngs_modulus: 50 GPa
  segments: 100
  base: {position: [0, 0, 0], direction: [1, 0, 0]}
insertion: {speed: 0, initial_length: 0.1}
loads:
  - {type: tip_force, value: [0, -2e-4, 0]}
solve: {mode: static}
"""


def test_clamp_force_of_a_cantilever_balances_the_tip_load(write_scene):
    """Statics: the clamp force is minus the tip load; the small tip deflection is F L^3 / (3 E I)."""
    sim = flowire.CoSimulation(write_scene(CANTILEVER))
    np.testing.assert_allclose(sim.base_force, [0, 2e-4, 0], atol=1e-9)
    E, r, L, F = 50e9, 0.25e-3, 0.1, 2e-4
    deflection = F * L**3 / (3 * E * math.pi * r**4 / 4)
    assert -sim.tip[1] == pytest.approx(deflection, rel=2e-2)
    assert sim.wire()["x"].shape == (101, 3)
    assert sim.network is None and sim.flow() is None


def test_cmake_install_puts_an_importable_package_under_lib_python3_dist_packages(tmp_path):
    import os
    import sys
    build = os.environ.get("FLOWIRE_BINARY_DIR")
    if not build:
        pytest.skip("FLOWIRE_BINARY_DIR is not set: run these tests through ctest")
    prefix = tmp_path / "prefix"
    subprocess.run(["cmake", "--install", build, "--prefix", str(prefix)], check=True, capture_output=True)
    site = prefix / "lib/python3/dist-packages"
    code = "import flowire, sys; print(flowire.__file__); print(flowire.read_network(sys.argv[1]).counts()['nodes'])"
    p = tmp_path / "net.yaml"
    p.write_text("branches:\n  - {name: a, points: [[0,0,0,0.002], [0.004,0,0,0.002]]}\n")
    r = subprocess.run([sys.executable, "-c", code, str(p)], check=True, capture_output=True, text=True,
                       env={"PYTHONPATH": str(site), "PATH": os.environ.get("PATH", "")}, cwd=tmp_path)
    file, nodes = r.stdout.split()
    assert file.startswith(str(site)) and int(nodes) >= 2
