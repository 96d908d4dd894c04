#!/usr/bin/env python3
"""Plot a flowire study: one PNG per quantity, one panel per parameter (called by `flowire study`).

usage: plot_study.py OUT_DIR study.csv [--parameter KEY]... [--quantity NAME=COL[,COL...]]...
                     [--pairs pairs.csv]

Each quantity's PNG (OUT_DIR/NAME.png) has a row per column of the quantity (three for a
position) and a panel per parameter: the value against that parameter, one line per
combination of the other parameters (and case). With --pairs, every pairing of pairs.csv gets
a PNG of its RMS distance (eq. 11) against the other parameters. Values that are not numbers
(a drag law, a status) are drawn as categories. Exit status 4: matplotlib is missing.
"""
import csv
import sys

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: E402
except ImportError:
    print("plot_study.py: matplotlib is missing (Debian: python3-matplotlib)", file=sys.stderr)
    sys.exit(4)


def number(text):
    try:
        return float(text)
    except ValueError:
        return None


def short(text):
    """A value for a legend: numbers to 4 significant digits."""
    v = number(text)
    return text if v is None else f"{v:.4g}"


def axis_values(texts):
    """Numbers if every value is one, else category positions with their labels."""
    values = [number(t) for t in texts if t != ""]
    if values and all(v is not None for v in values):
        return [number(t) for t in texts], None
    labels = []
    for t in texts:
        if t not in labels:
            labels.append(t)
    return [labels.index(t) for t in texts], labels


def panel(ax, rows, x_key, y_key, group_keys):
    xs, x_labels = axis_values([r[x_key] for r in rows])
    ys, y_labels = axis_values([r[y_key] for r in rows])
    groups = {}
    for r, x, y in zip(rows, xs, ys):
        if x is None or y is None or r[y_key] == "":
            continue
        label = ", ".join(f"{k}={short(r[k])}" for k in group_keys if k != x_key)
        groups.setdefault(label, []).append((x, y))
    for label, points in groups.items():
        points.sort()
        ax.plot([p[0] for p in points], [p[1] for p in points], "o-", label=label or None, markersize=4)
    ax.set_xlabel(x_key)
    ax.set_ylabel(y_key)
    if x_labels:
        ax.set_xticks(range(len(x_labels)))
        ax.set_xticklabels(x_labels)
    if y_labels:
        ax.set_yticks(range(len(y_labels)))
        ax.set_yticklabels(y_labels)
    ax.grid(True, alpha=0.3)
    if 1 < len(groups) <= 8:
        ax.legend(fontsize=7)


def figure(path, title, rows, columns, parameters):
    if not parameters:
        parameters = ["run"]
    fig, axes = plt.subplots(len(columns), len(parameters), figsize=(5 * len(parameters), 3.6 * len(columns)),
                             squeeze=False)
    for i, col in enumerate(columns):
        for j, key in enumerate(parameters):
            panel(axes[i][j], rows, key, col, parameters)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def read(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    out, table = argv[1], argv[2]
    parameters, quantities, pairs = [], [], None
    args = argv[3:]
    i = 0
    while i < len(args):
        if args[i] == "--parameter":
            parameters.append(args[i + 1])
        elif args[i] == "--quantity":
            name, _, cols = args[i + 1].partition("=")
            quantities.append((name, cols.split(",")))
        elif args[i] == "--pairs":
            pairs = args[i + 1]
        else:
            print(f"plot_study.py: unknown argument {args[i]}", file=sys.stderr)
            return 2
        i += 2
    rows = [r for r in read(table) if r["status"] != "missing"]
    for name, cols in quantities:
        figure(f"{out}/{name}.png", name, rows, cols, parameters)
    if pairs:
        prows = read(pairs)
        for name in dict.fromkeys(r["pair"] for r in prows):
            mine = [r for r in prows if r["pair"] == name and r["rms"] != ""]
            others = [k for k in parameters if len({r[k] for r in mine}) > 1]
            figure(f"{out}/{name}.png", f"{name}: RMS distance of the tip traces (m, eq. 11)", mine, ["rms"],
                   others)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
