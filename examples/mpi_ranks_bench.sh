#!/usr/bin/env bash
# Ranks × threads on one machine (docs/performance.md, "MPI ranks"):
# `examples/settle_100k.toml` (discs settling in a box 200 m tall; DISCS
# of them, the box widened in proportion, 100 000 by default) for STEPS
# steps with a history row only at the start and the end and no frames
# (each output gathers the whole state on rank 0), run as 1 rank × 1
# thread, 1 rank × 2 threads and 2 ranks × 1 thread, the three interleaved
# ROUNDS times; then 3 and 4 ranks (oversubscribed where there are fewer
# cores) for the traffic per step and rank. Prints particle-steps/s and,
# per rank, its discs and ghosts, its peak and final resident memory, and
# the bytes and messages it sent per step while stepping (the gathers
# for the outputs aside) from each run's summary.json. With KEEP=dir the
# summaries are kept there as <name>.json (examples/mpi_scaling_model.py
# reads them).
#
#   cargo build --release --features mpi      # a system MPI (docs/howto/mpi.md)
#   STEPS=1000 ROUNDS=3 examples/mpi_ranks_bench.sh
#   DISCS=1000000 STEPS=100 ROUNDS=2 examples/mpi_ranks_bench.sh
#   MPIRUN_ARGS="--bind-to none --mca mpi_yield_when_idle 1" examples/mpi_ranks_bench.sh
#   ONLY="1x1 2x1" DISCS=500000 examples/mpi_ranks_bench.sh   # chosen runs only
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

run() { # name ranks threads
    local out="$tmp/$1"
    if [ "$2" -gt 1 ]; then
        # shellcheck disable=SC2086
        mpirun --oversubscribe ${MPIRUN_ARGS:-} -np "$2" "$bin" run "$tmp/bench.toml" -o "$out" \
            --threads "$3" -q --overwrite >/dev/null
    else
        "$bin" run "$tmp/bench.toml" -o "$out" --threads "$3" -q --overwrite >/dev/null
    fi
    if [ -n "${KEEP:-}" ]; then
        mkdir -p "$KEEP"
        cp "$out/summary.json" "$KEEP/$1.json"
    fi
    python3 - "$out/summary.json" "$1" "$steps" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
name, steps = sys.argv[2], int(sys.argv[3])
mib = lambda b: f"{(b or 0) / 2**20:.0f}"
line = f"{name:8} {s['particle_steps_per_second'] / 1e6:6.2f} M particle-steps/s"
ranks = s.get("ranks")
if ranks:
    for k, r in enumerate(ranks["per_rank"]):
        line += (f" | rank {k}: {r['owned']} discs + {r['ghosts']} ghosts,"
                 f" peak {mib(r['peak_memory_bytes'])} MiB, end {mib(r['memory_bytes'])} MiB,"
                 f" {r['step_bytes_sent'] / steps / 1e3:.2f} kB and"
                 f" {r['step_messages'] / steps:.2f} messages per step")
else:
    line += f" | peak {mib(s['peak_memory_bytes'])} MiB"
print(line, flush=True)
PY
}

want() { [ -z "${ONLY:-}" ] || [[ " $ONLY " == *" $1 "* ]]; }
for _ in $(seq "$rounds"); do
    want 1x1 && run 1x1 1 1
    want 1x2 && run 1x2 1 2
    want 2x1 && run 2x1 2 1
done
for n in 3 4; do
    want "${n}x1" && run "${n}x1" "$n" 1
done
