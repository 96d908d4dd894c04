"""Shared helpers of the flowire_bench plots (Debian's python3-matplotlib, Agg backend)."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# Operating points of the published method (../shared/papers), marked where they apply.
PUBLISHED_DENSE_FRAME_S = 9e-3        # dense inverse, one flow frame, 2,477 vessels
PUBLISHED_DENSE_VESSELS = 2477
PUBLISHED_ROD_STEP_S = (5e-3, 36e-3)  # the published rods, one step
PUBLISHED_FRAME_S = 24.6e-3           # the published whole frame without rendering


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def num(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return float("nan")


def save(fig, path):
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
    print(f"wrote {path}", file=sys.stderr)
