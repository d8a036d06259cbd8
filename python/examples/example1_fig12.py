"""Example 1 of Wang et al. (2020), §4.1: a disc released on the free end of
an EFG cantilever. Plots the disc–beam contact force against time (the
paper's Fig. 12) and the beam tip's and the disc's vertical displacement.

Runs the repository's `examples/paper_cantilever_disc.toml` as it is (the
paper's Newmark parameters γ = 1.5, β = 0.8) and, built from the same file
as a dict with `Model.from_dict`, with γ = ½, β = ¼ (no numerical damping).

    python python/examples/example1_fig12.py             # writes example1_fig12.png
    python python/examples/example1_fig12.py --fast      # the first 40 ms only
    python python/examples/example1_fig12.py -o fig.png

EFGDEM_FAST=1 in the environment does the same as --fast (the tests use it).
"""

import argparse
import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import efgdem  # noqa: E402

SCENARIO = Path(__file__).resolve().parents[2] / "examples" / "paper_cantilever_disc.toml"


def load_dict(path):
    """The scenario file as a dict (tomllib: Python ≥ 3.11), or None."""
    try:
        import tomllib
    except ImportError:
        return None
    with open(path, "rb") as f:
        return tomllib.load(f)


def history(model, t_end):
    """Step `model` to `t_end`, recording after every step the time, the
    total normal force of the disc–body contacts (the CLI's `contact_fn`)
    and the probes `tip_uy`, `disc_uy`."""
    rows = [(0.0, 0.0, 0.0, 0.0)]
    while model.time + 0.5 * model.dt < t_end:
        model.step()
        c = model.contacts()
        fn = c["fn_elastic"][c["kind"] == efgdem.CONTACT_DISC_BODY].sum()
        rows.append((model.time, fn, model.probe("tip_uy"), model.probe("disc_uy")))
    return np.array(rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", default="example1_fig12.png")
    ap.add_argument("--scenario", default=str(SCENARIO))
    ap.add_argument("--fast", action="store_true", help="the first 40 ms only")
    args = ap.parse_args()
    fast = args.fast or os.environ.get("EFGDEM_FAST") == "1"

    runs = []
    model = efgdem.Model.from_scenario(args.scenario)
    t_end = 0.04 if fast else model.end_time
    r = model.disc_radii()[0]
    runs.append(("ours, Newmark γ = 1.5, β = 0.8 (the paper's parameters)", history(model, t_end)))
    d = load_dict(args.scenario)
    if d is not None:
        d["body"][0]["newmark"] = {"gamma": 0.5, "beta": 0.25}
        avg = efgdem.Model.from_dict(d, base_dir=str(Path(args.scenario).parent))
        runs.append(("ours, Newmark γ = ½, β = ¼", history(avg, t_end)))

    # the disc's weight: m g with m = ρ π r² t (density and thickness of the scenario)
    sc = d if d is not None else {}
    rho = next((m["density"] for m in sc.get("material", []) if m["name"] == "disc"), 1000.0)
    thick = sc.get("granular", {}).get("thickness", 1.0)
    mg = rho * np.pi * r * r * thick * 9.81

    fig, (ax, bx) = plt.subplots(2, 1, figsize=(7.5, 7.5), sharex=True,
                                 gridspec_kw={"height_ratios": [3, 2]})
    styles = ["-", "--"]
    for (label, h), ls in zip(runs, styles):
        k = int(np.argmax(h[:, 1]))
        line, = ax.plot(h[:, 0], h[:, 1], ls, lw=1.3,
                        label=f"{label}: peak {h[k, 1]:.1f} N at {h[k, 0]:.4f} s")
        ax.plot(h[k, 0], h[k, 1], "o", ms=4, color=line.get_color())
    ax.axhline(mg, color="0.3", ls=":", lw=1.0, label=f"m g = {mg:.1f} N")
    ax.set_ylabel("normal contact force (N)")
    ax.set_ylim(bottom=min(0.0, ax.get_ylim()[0]), top=1.25 * max(h[:, 1].max() for _, h in runs))
    ax.set_title("Fig. 12 — disc–beam contact force (Example 1, efgdem from Python)",
                 fontsize=10)
    ax.legend(fontsize=8, loc="upper right")
    ax.grid(alpha=0.3)
    label, h = runs[0]
    bx.plot(h[:, 0], 1e3 * h[:, 2], "-", lw=2.5, color="C0", alpha=0.5, label="beam end (top right corner)")
    bx.plot(h[:, 0], 1e3 * h[:, 3], "--", lw=1.2, color="C3", label="disc centre")
    bx.set_title(f"vertical displacement, {label}", fontsize=9)
    bx.set_xlabel("t (s)")
    bx.set_ylabel("vertical displacement (mm)")
    bx.legend(fontsize=7, loc="lower left")
    bx.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(args.output, dpi=150)
    plt.close(fig)
    for label, h in runs:
        k = int(np.argmax(h[:, 1]))
        print(f"{label}: peak contact force {h[k, 1]:.2f} N at t = {h[k, 0]:.4f} s")
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
