"""The Python API under misuse and interruption: objects used before they were constructed,
times that are not finite, and long calls ended by Ctrl-C (SIGINT) within a moment."""
import math
import os
import signal
import threading
import time

import pytest

import flowire

RLC_TUBE = """\
vessels:
  generator: {type: straight_tube, length: 0.12, radius: 1.5 mm}
  max_segment_length: 1 cm
flow:
  model: rlc
  inlet: {pressure: {waveform: sine, systolic: 120 mmHg, diastolic: 80 mmHg, period: 0.8 s}}
  outlets: {resistance: 1e9}
solve: {dt: 1 ms, duration: 0.1 s}
"""

ARCH_WIRE = """\
vessels:
  generator: {type: aortic_arch}
wire: {length: 0.3, segment_length: 5 mm}
insertion: {speed: 1 cm/s}
solve: {dt: 1 ms, duration: 1 s}
"""


ARGS = {"at": (0.0,), "step": (1,)}  # arguments of the methods that take some


@pytest.mark.parametrize("cls", [flowire.CoSimulation, flowire.Flow, flowire.Network, flowire.FlowFrame])
def test_an_object_never_constructed_raises_instead_of_crashing(cls):
    obj = cls.__new__(cls)  # memory without a constructor run
    names = [n for n in dir(cls) if not n.startswith("_")]
    assert names
    for name in names:
        with pytest.raises(flowire.Error, match="not constructed"):
            attr = getattr(obj, name)
            if callable(attr):
                attr(*ARGS.get(name, ()))


def test_a_time_that_is_not_finite_is_refused(write_scene):
    f = flowire.Flow(write_scene(RLC_TUBE))
    for t in (math.inf, -math.inf, math.nan):
        with pytest.raises(flowire.Error, match="finite"):
            f.at(t)
    assert f.at(0.05).time == 0.05  # and the object still works


def interrupt_after(seconds):
    timer = threading.Timer(seconds, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    return timer


def test_ctrl_c_ends_a_long_flow_integration(write_scene):
    f = flowire.Flow(write_scene(RLC_TUBE))
    interrupt_after(0.5)
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        f.at(1e9)  # years of flow: it would not end by itself
    assert time.monotonic() - start < 5.0
    assert f.time < 1e9


def test_ctrl_c_ends_a_long_stepping(write_scene):
    sim = flowire.CoSimulation(write_scene(ARCH_WIRE))
    interrupt_after(0.5)
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        sim.step(10**9)
    assert time.monotonic() - start < 5.0
    steps = sim.step_count
    assert 0 < steps < 10**9
    sim.step(2)  # the object is still usable
    assert sim.step_count == steps + 2
