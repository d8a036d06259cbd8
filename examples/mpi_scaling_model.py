#!/usr/bin/env python3
"""Communication model of efgdem on MPI ranks, checked against measured runs,
and the strong and weak scaling it predicts up to 64 ranks
(docs/performance.md, "MPI ranks").

Reads the summaries that `KEEP=dir examples/mpi_ranks_bench.sh` keeps
(1x1.json, 2x1.json, 3x1.json, 4x1.json: the same bed on 1 to 4 ranks).

Model of what a rank sends while stepping (the gathers for the outputs
aside), per step:

    bytes    = c * (40 * G + B / R) + 9 * (P - 1)
    messages = c + (P - 1) + M / R

c: the rank's cuts (neighbours), G: the ghosts one side of a cut holds,
40 bytes a ghost (position, velocity, spin), B: bytes per cut and rebuild
of the contact list (ghost records and migrating discs), R: steps per
rebuild, 9 * (P - 1): the step's global values (largest displacement, the
step check) to every other rank, M: messages of a rebuild. G, B and M are
calibrated on the 2-rank run (one cut); the model then predicts the 3- and
4-rank runs (slabs across the wide bed: the two end ranks have one cut,
the others two), and the script exits 1 when a rank's measured bytes per
step differ from the prediction by more than 15 %.

Scaling to 64 ranks: square regions of n discs (recursive bisection of a
large 2D bed), 4 cuts each of k * sqrt(n) ghosts (k, the ghost rows per
disc along a cut, from the 2-rank run, the bed filling its 200 m tall box)
and 8 neighbours (the corners too); one rank per core stepping at the
measured one-core rate r1, communication not overlapped with computing:

    t(n, P) = (n + 4 k sqrt(n)) / r1 + 8 a + log2(P) a + bytes / b

a the latency and b the bandwidth of the network (two typical clusters
below). Efficiency: weak, t(n, 1) / t(n, P) at n discs per rank; strong,
t(N, 1) / (P t(N / P, P)).

    python3 examples/mpi_scaling_model.py DIR [--discs N]
"""
import argparse
import json
import math
import sys

NETWORKS = {
    "InfiniBand HDR (a = 1.5 us, b = 12 GB/s)": (1.5e-6, 12e9),
    "25 Gb Ethernet (a = 20 us, b = 3 GB/s)": (20e-6, 3e9),
}


def load(d, name):
    with open(f"{d}/{name}.json") as f:
        return json.load(f)


def per_step(s):
    steps = s["last_step"]
    return [(r["step_bytes_sent"] / steps, r["step_messages"] / steps, r["ghosts"])
            for r in s["ranks"]["per_rank"]]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dir")
    ap.add_argument("--tolerance", type=float, default=0.15)
    a = ap.parse_args()
    one, two = load(a.dir, "1x1"), load(a.dir, "2x1")
    steps, rebuilds = two["last_step"], two["neighbour_rebuilds"]
    n_total = two["discs"]
    rate1 = one["particle_steps_per_second"]
    # calibration on 2 ranks: one cut
    m2 = per_step(two)
    g = sum(x[2] for x in m2) / 2
    b_cut = sum(x[0] - 40 * g - 9 for x in m2) / 2 * steps / rebuilds
    m_cut = sum(x[1] - 2 for x in m2) / 2 * steps / rebuilds
    print(f"{n_total} discs, {steps} steps, {rebuilds} rebuilds of the contact list")
    print(f"calibrated on 2 ranks: G = {g:.1f} ghosts a cut side, "
          f"B = {b_cut / 1e3:.1f} kB and M = {m_cut:.2f} messages a cut and rebuild")

    def model(c, p):
        return (c * (40 * g + b_cut * rebuilds / steps) + 9 * (p - 1),
                c + (p - 1) + m_cut * rebuilds / steps)

    worst = 0.0
    print("\nranks rank cuts  measured kB/step  model kB/step  ratio  measured msg/step  model")
    for p in (3, 4):
        for r, (b, m, _) in enumerate(per_step(load(a.dir, f"{p}x1"))):
            c = 1 if r in (0, p - 1) else 2
            mb, mm = model(c, p)
            worst = max(worst, abs(b / mb - 1))
            print(f"{p:5} {r:4} {c:4} {b / 1e3:17.2f} {mb / 1e3:14.2f} {b / mb:6.3f}"
                  f" {m:18.2f} {mm:6.2f}")
    print(f"largest deviation of the bytes: {100 * worst:.1f} % "
          f"(tolerance {100 * a.tolerance:.0f} %)")

    # scaling: the ghost rows k from the 2-rank bed (its box 200 m tall)
    width = 3340.0 * n_total / 100000
    along = math.sqrt(n_total * 200.0 / width)
    k = g / along
    per_ghost_rebuild = b_cut / g
    print(f"\nscaling model: k = {k:.2f} ghost rows, one core {rate1 / 1e6:.1f} M particle-steps/s,"
          f" a rebuild every {steps / rebuilds:.0f} steps")

    def t(n, p, lat, bw):
        ghosts = 4 * k * math.sqrt(n) if p > 1 else 0.0
        comp = (n + ghosts) / rate1
        if p == 1:
            return comp, 0.0
        sent = ghosts * (40 + per_ghost_rebuild * rebuilds / steps) + 9 * (p - 1)
        comm = 8 * lat + math.ceil(math.log2(p)) * lat + sent / bw
        return comp + comm, comm

    for net, (lat, bw) in NETWORKS.items():
        print(f"\n{net}")
        print("ranks | weak, 250 000 discs a rank: efficiency, comm. share"
              " | strong, 10^6 discs: speed-up, efficiency | strong, 10^7 discs: speed-up, efficiency")
        for p in (1, 2, 4, 8, 16, 32, 64):
            tw, cw = t(250_000, p, lat, bw)
            t1w = t(250_000, 1, lat, bw)[0]
            row = f"{p:5} | {t1w / tw:6.3f} {cw / tw:6.3f}"
            for big in (1_000_000, 10_000_000):
                sp = t(big, 1, lat, bw)[0] / t(big / p, p, lat, bw)[0]
                row += f" | {sp:6.1f} {sp / p:6.3f}"
            print(row)
    return 1 if worst > a.tolerance else 0


if __name__ == "__main__":
    sys.exit(main())
