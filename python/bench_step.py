"""Overhead of stepping from Python against `efgdem run` on the same scenario.

A dense hexagonal packing of 10 000 discs (r = 1) under gravity in a closed
box, no probes, no frames: the CLI's time loop (`run_seconds` of its
summary.json) against `model.step(100)` called from a Python loop (timed
around the loop; building is excluded from both). Runs alternate, and the
medians are compared. The final positions of both are checked to be
bitwise equal.

    python python/bench_step.py                      # 1 thread, 5 repetitions
    python python/bench_step.py --threads 2 --repeat 7
    python python/bench_step.py --cli target/release/efgdem
"""

import argparse
import json
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

import efgdem

ROOT = Path(__file__).resolve().parents[1]

SCENARIO = """\
# bench_step.py: {discs} discs, hexagonal packing, settling under gravity
[simulation]
dt = 4.0e-4
steps = {steps}
gravity = [0.0, -9.81]

[[material]]
name = "grain"
density = 1.0
kn = 1.0e6
ks = 1.0e6
friction = 0.5

[granular]
material = "grain"
discs = {{ generate = "hex", box = [[0.0, 0.0], [{w}, {h}]], radius = 1.0, count = {discs}, jitter = 0.3, seed = 2 }}
damping = {{ kind = "critical-ratio", zeta = 0.2 }}

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [{w}, 0.0]

[[wall]]
name = "left"
from = [0.0, 0.0]
to = [0.0, {h}]

[[wall]]
name = "right"
from = [{w}, 0.0]
to = [{w}, {h}]

[[wall]]
name = "lid"
from = [0.0, {h}]
to = [{w}, {h}]

[output]
every = {steps}
"""


def run_cli(exe, scenario, out, threads):
    subprocess.run([exe, "run", str(scenario), "-o", str(out), "-q", "--threads", str(threads)],
                   check=True)
    s = json.loads((out / "summary.json").read_text())
    pos = np.loadtxt(out / "discs_final.csv", delimiter=",", skiprows=1)[:, :2]
    return s["run_seconds"], pos


def run_python(scenario, threads, per_call):
    m = efgdem.Model.from_scenario(scenario, threads=threads)
    n = m.steps
    t0 = time.perf_counter()
    while m.step_count < n:
        m.step(min(per_call, n - m.step_count))
    return time.perf_counter() - t0, m.disc_positions()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--discs", type=int, default=10_000)
    ap.add_argument("--steps", type=int, default=5_000)
    ap.add_argument("--per-call", type=int, default=100)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--cli", default=str(ROOT / "target" / "release" / "efgdem"))
    args = ap.parse_args()

    w = 200.0
    h = 2.0 * np.ceil(args.discs / (w / 2.0) * np.sqrt(3.0) / 2.0 + 2.0)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        sc = tmp / "bench.toml"
        sc.write_text(SCENARIO.format(discs=args.discs, steps=args.steps, w=w, h=h))
        cli, py = [], []
        for k in range(args.repeat):
            t, pos_cli = run_cli(args.cli, sc, tmp / f"cli{k}", args.threads)
            cli.append(t)
            t, pos_py = run_python(sc, args.threads, args.per_call)
            py.append(t)
            assert pos_py.tobytes() == pos_cli.tobytes(), "Python and CLI results differ"
            print(f"run {k + 1}: cli {cli[-1]:.3f} s, python {py[-1]:.3f} s", flush=True)
    c, p = statistics.median(cli), statistics.median(py)
    rate = args.discs * args.steps
    print(f"\n{args.discs} discs, {args.steps} steps, {args.per_call} steps per call, "
          f"{args.threads} thread(s), {args.repeat} repetitions (median; final positions "
          f"bitwise equal)")
    print(f"  efgdem run    : {c:.3f} s  ({rate / c / 1e6:.1f} M disc-steps/s)")
    print(f"  Python step() : {p:.3f} s  ({rate / p / 1e6:.1f} M disc-steps/s)")
    print(f"  overhead      : {100.0 * (p / c - 1.0):+.1f} %  "
          f"(min against min: {100.0 * (min(py) / min(cli) - 1.0):+.1f} %)")


if __name__ == "__main__":
    main()
