#!/usr/bin/env bash
# Ranks × threads on one machine (docs/performance.md, "MPI ranks"):
# `examples/settle_100k.toml` (discs settling in a box 200 m tall; DISCS
# of them, the box widened in proportion, 100 000 by default) for STEPS
# steps with a history row only at the start and the end and no frames,
# run as 1 rank × 1 thread, 1 rank × 2 threads and 2 ranks × 1 thread,
# the three interleaved ROUNDS times; then 3 and 4 ranks (oversubscribed
# where there are fewer cores) for the traffic per step and rank. Prints
# for each run the particle-steps/s of its steps (`run_seconds`), its
# whole wall-clock time (the process from start to exit: build, steps,
# the end's outputs) and the end's outputs alone (`output_seconds`: the
# gather of every disc, `discs_final.csv`, the summary), and per rank its
# discs and ghosts, its peak and final resident memory, and the bytes and
# messages it sent per step while stepping; at the end the medians (and
# min–max) of each run kind and the ratios 2 ranks ÷ 2 threads, per
# round. With KEEP=dir the summaries are kept there as <name>.json
# (examples/mpi_scaling_model.py reads them).
#
#   cargo build --release --features mpi      # a system MPI (docs/howto/mpi.md)
#   STEPS=1000 ROUNDS=3 examples/mpi_ranks_bench.sh
#   DISCS=1000000 STEPS=100 ROUNDS=2 examples/mpi_ranks_bench.sh
#   MPIRUN_ARGS="--bind-to none --mca mpi_yield_when_idle 1" examples/mpi_ranks_bench.sh
#   ONLY="1x1 2x1" DISCS=500000 examples/mpi_ranks_bench.sh   # chosen runs only
#   ONLY="2x1 half" DISCS=500000 examples/mpi_ranks_bench.sh   # a rank's memory against one
#                                   # process with its share of the discs (DISCS/2)
#   ONLY="4x1 quarter" DISCS=1000000 examples/mpi_ranks_bench.sh   # the same for 4 ranks
#                                   # (DISCS/4; `quarter` runs after the ranks)
#   ONLY="4x1 4x1r" DISCS=1000000 examples/mpi_ranks_bench.sh   # a restart on 4 ranks
#                                   # from a checkpoint (written half way by 4 ranks,
#                                   # `4x1c`) against the fresh 4-rank start
#
# (MPIRUN_ARGS as above for a machine shared with other work: ranks
# neither pinned to a core nor spinning while they wait)
set -euo pipefail
cd "$(dirname "$0")/.."
steps=${STEPS:-2000}
rounds=${ROUNDS:-3}
discs=${DISCS:-100000}
bin=${BIN:-target/release/efgdem}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
width=$(python3 -c "print(3340.0 * $discs / 100000)")
sed -e "s/^steps = .*/steps = $steps/" -e "s/^every = .*/every = $steps/" \
    -e "s/^vtk_every = .*/vtk_every = 0/" -e "s/count = 100000/count = $discs/" \
    -e "s/3340\.0/$width/g" examples/settle_100k.toml >"$tmp/bench.toml"
# the same bed with half the discs: a rank's share of 2 ranks in one process
half=$((discs / 2))
hwidth=$(python3 -c "print(3340.0 * $half / 100000)")
sed -e "s/^steps = .*/steps = $steps/" -e "s/^every = .*/every = $steps/" \
    -e "s/^vtk_every = .*/vtk_every = 0/" -e "s/count = 100000/count = $half/" \
    -e "s/3340\.0/$hwidth/g" examples/settle_100k.toml >"$tmp/half.toml"
# and with a quarter: a rank's share of 4 ranks
quarter=$((discs / 4))
qwidth=$(python3 -c "print(3340.0 * $quarter / 100000)")
sed -e "s/^steps = .*/steps = $steps/" -e "s/^every = .*/every = $steps/" \
    -e "s/^vtk_every = .*/vtk_every = 0/" -e "s/count = 100000/count = $quarter/" \
    -e "s/3340\.0/$qwidth/g" examples/settle_100k.toml >"$tmp/quarter.toml"

run() { # name ranks threads [scenario [more arguments of `efgdem run`]]
    local out="$tmp/${OUT:-$1}" t0 t1 toml="$tmp/${4:-bench}.toml" more=("${@:5}")
    t0=$(date +%s.%N)
    if [ "$2" -gt 1 ]; then
        # shellcheck disable=SC2086
        mpirun --oversubscribe ${MPIRUN_ARGS:-} -np "$2" "$bin" run "$toml" -o "$out" \
            --threads "$3" -q --overwrite "${more[@]}" >/dev/null
    else
        "$bin" run "$toml" -o "$out" --threads "$3" -q --overwrite "${more[@]}" >/dev/null
    fi
    t1=$(date +%s.%N)
    if [ -n "${KEEP:-}" ]; then
        mkdir -p "$KEEP"
        cp "$out/summary.json" "$KEEP/$1.json"
    fi
    python3 - "$out/summary.json" "$1" "$steps" "$t0" "$t1" "$tmp/results" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
name, steps = sys.argv[2], int(sys.argv[3])
wall = float(sys.argv[5]) - float(sys.argv[4])
mib = lambda b: f"{(b or 0) / 2**20:.0f}"
rate = s['particle_steps_per_second'] / 1e6
line = (f"{name:8} steps {rate:6.2f} M particle-steps/s, whole run {wall:6.2f} s"
        f" (end's outputs {s.get('output_seconds', 0):.2f} s)")
ranks = s.get("ranks")
peaks = []
if ranks:
    for k, r in enumerate(ranks["per_rank"]):
        peaks.append(r['peak_memory_bytes'] or 0)
        line += (f"\n         rank {k}: {r['owned']} discs + {r['ghosts']} ghosts,"
                 f" peak {mib(r['peak_memory_bytes'])} MiB, end {mib(r['memory_bytes'])} MiB,"
                 f" {r['step_bytes_sent'] / steps / 1e3:.2f} kB and"
                 f" {r['step_messages'] / steps:.2f} messages per step")
else:
    peaks.append(s['peak_memory_bytes'] or 0)
    line += f" | peak {mib(s['peak_memory_bytes'])} MiB"
print(line, flush=True)
with open(sys.argv[6], "a") as f:
    f.write(f"{name} {rate} {wall} {' '.join(str(p) for p in peaks)}\n")
PY
}

want() { [ -z "${ONLY:-}" ] || [[ " $ONLY " == *" $1 "* ]]; }
for _ in $(seq "$rounds"); do
    want 1x1 && run 1x1 1 1
    want 1x2 && run 1x2 1 2
    want 2x1 && run 2x1 2 1
    want half && run half 1 1 half
done
for n in 3 4; do
    want "${n}x1" && run "${n}x1" "$n" 1
done
want quarter && run quarter 1 1 quarter
# a restart on 4 ranks from a checkpoint written half way by 4 ranks
# (`4x1c`), each rank reading only its part: its peak memory against the
# fresh start's (`4x1`)
if want 4x1r; then
    run 4x1c 4 1 bench --checkpoint-every $((steps / 2))
    OUT=4x1c run 4x1r 4 1 bench --restart "$tmp/4x1c/checkpoint.bin"
fi
python3 - "$tmp/results" <<'PY'
import statistics, sys
runs = {}
for line in open(sys.argv[1]):
    name, rate, wall, *peaks = line.split()
    runs.setdefault(name, []).append((float(rate), float(wall), [int(p) for p in peaks]))
fmt = lambda v: f"{statistics.median(v):.2f} ({min(v):.2f}–{max(v):.2f})"
print("\nmedians (min–max):")
for name, rs in runs.items():
    peak = " / ".join(f"{statistics.median(p) / 2**20:.0f}" for p in zip(*(r[2] for r in rs)))
    print(f"{name:8} steps {fmt([r[0] for r in rs])} M particle-steps/s,"
          f" whole run {fmt([r[1] for r in rs])} s, peak MiB per rank {peak}")
if "1x2" in runs and "2x1" in runs:
    pairs = list(zip(runs["2x1"], runs["1x2"]))
    steps = [a[0] / b[0] for a, b in pairs]
    whole = [b[1] / a[1] for a, b in pairs]
    print(f"2 ranks ÷ 2 threads, per round: steps {fmt(steps)}, whole run {fmt(whole)}")
if "4x1r" in runs and "4x1" in runs:
    for k, (r, f) in enumerate(zip(zip(*(r[2] for r in runs["4x1r"])), zip(*(r[2] for r in runs["4x1"])))):
        r, f = statistics.median(r), statistics.median(f)
        print(f"peak memory per rank, restart ÷ fresh start: rank {k} of 4 {r / f:.2f}"
              f" ({r / 2**20:.0f} MiB ÷ {f / 2**20:.0f} MiB)")
for share, ranks, what in [("half", 2, "half the discs"), ("quarter", 4, "a quarter of the discs")]:
    if share not in runs or f"{ranks}x1" not in runs:
        continue
    one = statistics.median(r[2][0] for r in runs[share])
    for k, p in enumerate(zip(*(r[2] for r in runs[f"{ranks}x1"]))):
        print(f"peak memory per rank ÷ {share}: rank {k} of {ranks} {statistics.median(p) / one:.2f}"
              f" (its peak {statistics.median(p) / 2**20:.0f} MiB ÷ {one / 2**20:.0f} MiB"
              f" of one process with {what}; target ≤ 1.20)")
PY
