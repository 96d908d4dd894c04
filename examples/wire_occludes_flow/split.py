"""Flow split of the Y at the end of each run: the flow into each daughter (segments whose
nodes lie on either side of the parent's axis), from segments.csv and nodes.csv."""
import csv, json, sys

out, runs = sys.argv[1], sys.argv[2:]


def split(run):
    d = f"{out}/{run}"
    nodes = {}
    for row in csv.DictReader(open(f"{d}/nodes.csv")):
        nodes[int(row["node"])] = float(row["y"])  # the last frame wins
    last, flows = None, {}
    for row in csv.DictReader(open(f"{d}/segments.csv")):
        t = float(row["time"])
        if last is None or t > last:
            last, flows = t, {}
        a, b = int(row["node_from"]), int(row["node_to"])
        side = 1 if nodes[a] + nodes[b] > 1e-6 else 2 if nodes[a] + nodes[b] < -1e-6 else 0
        if side and side not in flows:  # the first segment of the daughter
            flows[side] = (float(row["flow_rate"]), float(row["occupied_fraction"]))
    s = json.load(open(f"{d}/summary.json"))
    tip_side = 1 if s["wire"]["tip"][1] > 0 else 2
    return flows, tip_side, s


print("| run | occlusion | Q daughter with the wire (mL/s) | Q other daughter (mL/s) | share with the wire | total (mL/s) |")
print("|---|---|---|---|---|---|")
for run in runs:
    flows, side, s = split(run)
    other = 3 - side
    qw, qo = flows[side][0] * 1e6, flows[other][0] * 1e6
    occ = s.get("occlusion", {}).get("model", "none")
    print(f"| {run} | {occ} | {qw:.4f} | {qo:.4f} | {qw / (qw + qo):.1%} | {qw + qo:.4f} |")
