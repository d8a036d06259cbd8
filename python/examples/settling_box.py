"""Settle discs in a box under gravity and plot the force chains.

Builds the scenario as a Python dict (the same schema as a TOML scenario
file), lets about 2000 discs fall from a loose start into a closed box, then
draws every disc and every contact as a line whose width is proportional to
its normal force (disc–disc: between the centres; disc–wall: from the
centre to the wall).

    python python/examples/settling_box.py            # writes settling_box.png
    python python/examples/settling_box.py --fast     # a small, quick version
    python python/examples/settling_box.py -o out.png

EFGDEM_FAST=1 in the environment does the same as --fast (the tests use it).
"""

import argparse
import os
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import EllipseCollection, LineCollection  # noqa: E402

import efgdem  # noqa: E402


def scenario(width, height, count, steps):
    """A closed box of `width` × `height` with `count` loose discs (r 0.8–1.2)."""
    corners = [(0.0, 0.0), (width, 0.0), (width, height), (0.0, height)]
    names = ["floor", "right", "lid", "left"]
    walls = [
        {"name": n, "from": list(corners[k]), "to": list(corners[(k + 1) % 4])}
        for k, n in enumerate(names)
    ]
    return {
        "simulation": {"dt": 4.0e-4, "steps": steps, "gravity": [0.0, -9.81]},
        "material": [
            {"name": "grain", "density": 1.0, "kn": 1.0e6, "ks": 1.0e6, "friction": 0.5}
        ],
        "granular": {
            "material": "grain",
            "discs": {
                "generate": "random",
                "box": [[0.0, 0.0], [width, height]],
                "radius": [0.8, 1.2],
                "count": count,
                "seed": 3,
            },
            "damping": {"kind": "critical-ratio", "zeta": 0.2},
        },
        "wall": walls,
        "probe": [{"name": "kinetic", "quantity": "kinetic"}],
    }


def plot_force_chains(model, path, title):
    pos = model.disc_positions()  # (n, 2), row i = disc number i + 1
    r = model.disc_radii()
    c = model.contacts()  # structured array, one row per closed contact
    fn = c["fn_elastic"]
    dd = c[c["kind"] == efgdem.CONTACT_DISC_DISC]
    dw = c[c["kind"] == efgdem.CONTACT_DISC_WALL]
    segs = np.concatenate(
        [
            np.stack([pos[dd["disc_index"]], pos[dd["other_index"]]], axis=1),
            np.stack([pos[dw["disc_index"]], np.column_stack([dw["x"], dw["y"]])], axis=1),
        ]
    )
    f = np.concatenate([dd["fn_elastic"], dw["fn_elastic"]])
    mean = fn.mean() if len(fn) else 1.0
    widths = 0.9 * f / mean

    lo, hi = pos.min(axis=0) - r.max(), pos.max(axis=0) + r.max()
    fig, ax = plt.subplots(figsize=(7.5, 7.5 * (hi[1] - lo[1]) / (hi[0] - lo[0]) + 0.8))
    ax.add_collection(
        EllipseCollection(
            2 * r, 2 * r, np.zeros_like(r), units="xy", offsets=pos,
            offset_transform=ax.transData, facecolors="#e6e6e6",
            edgecolors="#b0b0b0", linewidths=0.3,
        )
    )
    lines = LineCollection(segs, linewidths=widths, colors="#b2182b", capstyle="round")
    ax.add_collection(lines)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", default="settling_box.png")
    ap.add_argument("--fast", action="store_true", help="150 discs, few steps")
    args = ap.parse_args()
    fast = args.fast or os.environ.get("EFGDEM_FAST") == "1"

    if fast:
        width, height, count, t_end = 24.0, 50.0, 150, 1.5
    else:
        width, height, count, t_end = 100.0, 130.0, 2000, 8.0
    steps = int(round(t_end / 4.0e-4))
    model = efgdem.Model.from_dict(scenario(width, height, count, steps))
    print(model)

    t0 = time.perf_counter()
    chunk = 500
    while model.step_count < model.steps:
        model.step(min(chunk, model.steps - model.step_count))
        if model.step_count % 5000 == 0 or model.step_count == model.steps:
            print(f"t = {model.time:6.3f} s   kinetic energy {model.probe('kinetic'):.3e}"
                  f"   contacts {len(model.contacts())}")
    wall = time.perf_counter() - t0
    print(f"{model.steps} steps of {count} discs in {wall:.2f} s "
          f"({count * model.steps / wall / 1e6:.1f} M disc-steps/s)")

    c = model.contacts()
    plot_force_chains(
        model, args.output,
        f"{count} discs settled under gravity, t = {model.time:.1f} s: "
        f"{len(c)} contacts, line width ∝ normal force",
    )
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
