"""Overhead of stepping from Python against `efgdem run` on the same scenario.

A dense hexagonal packing of 10 000 discs (r = 1) under gravity in a closed
box, no probes, no frames: the CLI's time loop (`run_seconds` of its
summary.json) against `model.step(100)` called from a Python loop (timed
around the loop; building is excluded from both); also the CPU time of each
(build and run, all threads: the machine is shared, and CPU time is less
disturbed by other load than wall time). The two alternate (which one goes first too), and the
medians are compared (and the minima). The final positions of both are checked to be
bitwise equal.

    python python/bench_step.py                      # 1 thread, 5 repetitions
    python python/bench_step.py --threads 2 --repeat 7
    python python/bench_step.py --cli target/release/efgdem

The installed module (maturin develop) links its own compilation of the
efgdem crate, whose machine code for the DEM kernel can differ from the
CLI's (the two builds differ in `-C metadata` only, and the kernel's speed
moves by a few per cent with it). To compare the same machine code:

    cargo build --release --workspace
    python python/bench_step.py --module target/release/libefgdem_python.so
"""

import argparse
import json
import resource
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

efgdem = None  # imported in main() (--module: a given build of it)

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


def children_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_cli(exe, scenario, out, threads):
    c0 = children_cpu()
    subprocess.run([exe, "run", str(scenario), "-o", str(out), "-q", "--threads", str(threads)],
                   check=True, capture_output=True)
    cpu = children_cpu() - c0
    s = json.loads((out / "summary.json").read_text())
    pos = np.loadtxt(out / "discs_final.csv", delimiter=",", skiprows=1)[:, :2]
    return s["run_seconds"], cpu, pos


def run_python(scenario, threads, per_call):
    c0 = time.process_time()
    m = efgdem.Model.from_scenario(scenario, threads=threads)
    n = m.steps
    t0 = time.perf_counter()
    while m.step_count < n:
        m.step(min(per_call, n - m.step_count))
    wall = time.perf_counter() - t0
    return wall, time.process_time() - c0, m.disc_positions()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--discs", type=int, default=10_000)
    ap.add_argument("--steps", type=int, default=5_000)
    ap.add_argument("--per-call", type=int, default=100)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--cli", default=str(ROOT / "target" / "release" / "efgdem"))
    ap.add_argument("--module", help="load the module from this shared library (e.g. "
                    "target/release/libefgdem_python.so after `cargo build --release "
                    "--workspace`, whose efgdem code is the CLI's own) instead of the "
                    "installed one")
    args = ap.parse_args()
    global efgdem
    if args.module:
        import importlib.machinery
        import importlib.util
        loader = importlib.machinery.ExtensionFileLoader("efgdem", args.module)
        spec = importlib.util.spec_from_file_location("efgdem", args.module, loader=loader)
        efgdem = importlib.util.module_from_spec(spec)
        loader.exec_module(efgdem)
    else:
        import efgdem as installed
        efgdem = installed
    print(f"module: {efgdem.__file__}", flush=True)

    w = 200.0
    h = 2.0 * np.ceil(args.discs / (w / 2.0) * np.sqrt(3.0) / 2.0 + 2.0)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        sc = tmp / "bench.toml"
        sc.write_text(SCENARIO.format(discs=args.discs, steps=args.steps, w=w, h=h))
        cli, py, cli_cpu, py_cpu = [], [], [], []
        for k in range(args.repeat):
            # alternate which goes first (the machine's load drifts)
            for which in (["cli", "py"] if k % 2 == 0 else ["py", "cli"]):
                if which == "cli":
                    t, cpu, pos_cli = run_cli(args.cli, sc, tmp / f"cli{k}", args.threads)
                    cli.append(t)
                    cli_cpu.append(cpu)
                else:
                    t, cpu, pos_py = run_python(sc, args.threads, args.per_call)
                    py.append(t)
                    py_cpu.append(cpu)
            assert pos_py.tobytes() == pos_cli.tobytes(), "Python and CLI results differ"
            print(f"run {k + 1}: cli {cli[-1]:.3f} s (cpu {cli_cpu[-1]:.3f} s), "
                  f"python {py[-1]:.3f} s (cpu {py_cpu[-1]:.3f} s)", flush=True)
    c, p = statistics.median(cli), statistics.median(py)
    rate = args.discs * args.steps
    print(f"\n{args.discs} discs, {args.steps} steps, {args.per_call} steps per call, "
          f"{args.threads} thread(s), {args.repeat} repetitions (median; final positions "
          f"bitwise equal)")
    print(f"  efgdem run    : {c:.3f} s  ({rate / c / 1e6:.1f} M disc-steps/s)")
    print(f"  Python step() : {p:.3f} s  ({rate / p / 1e6:.1f} M disc-steps/s)")
    print(f"  overhead      : {100.0 * (p / c - 1.0):+.1f} %  "
          f"(min against min: {100.0 * (min(py) / min(cli) - 1.0):+.1f} %)")
    cc, pc = statistics.median(cli_cpu), statistics.median(py_cpu)
    print(f"  CPU time, build + run (all threads): efgdem run {cc:.3f} s, Python {pc:.3f} s: "
          f"{100.0 * (pc / cc - 1.0):+.1f} % (min against min: "
          f"{100.0 * (min(py_cpu) / min(cli_cpu) - 1.0):+.1f} %)")


if __name__ == "__main__":
    main()
