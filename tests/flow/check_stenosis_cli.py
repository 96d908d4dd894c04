"""Checks the two runs of stenosis_losses_through_cli (tests/flow/CMakeLists.txt): DIR/young_tsai
and DIR/none of examples/stenosis/network.yaml."""
import csv
import json
import sys

d = sys.argv[1]
on = json.load(open(f"{d}/young_tsai/summary.json"))["flow"]
found = on["losses"]["stenosis"]["stenoses"]
assert len(found) == 1, found
st = found[0]
assert abs(st["area_reduction"] - 0.75) < 1e-6, st
assert abs(st["reference_radius"] - 2e-3) < 1e-9 and abs(st["throat_radius"] - 1e-3) < 1e-9, st


def frames(run):
    """Per frame: the inlet's pressure (node 0; the outlet is node 1) and the flow leaving the throat."""
    p = {}
    for r in csv.DictReader(open(f"{d}/{run}/nodes.csv")):
        if r["node"] == "0":
            p[float(r["time"])] = float(r["pressure"])
    q = {}
    for r in csv.DictReader(open(f"{d}/{run}/segments.csv")):
        if int(r["node_from"]) == st["node"]:
            q[float(r["time"])] = float(r["flow_rate"])
    return p, q


p_on, q_on = frames("young_tsai")
p_off, _ = frames("none")
assert len(p_on) > 20 and p_on.keys() == p_off.keys() == q_on.keys()
largest = max(st["coefficient"] * q * q for q in q_on.values())
worst = 0.0
for t in sorted(p_on):
    loss = st["coefficient"] * abs(q_on[t]) * q_on[t]
    assert p_on[t] > p_off[t], (t, p_on[t], p_off[t])
    # The walls nearly rigid (the test sets 1 GPa), one flow runs through the whole vessel: the loss
    # raises the inlet's pressure by K Q|Q| at the throat (5% of the largest loss with the default
    # 0.4 MPa wall, which stores more blood upstream of the throat when the loss is on).
    worst = max(worst, abs((p_on[t] - p_off[t]) - loss) / largest)
print(f"largest departure of the inlet pressure's rise from K Q|Q| over the beat: {worst:.4f} of the largest loss")
assert worst < 0.003, worst
