#!/usr/bin/env bash
# Ranks × threads on one machine (docs/performance.md, "MPI ranks"):
# `examples/settle_100k.toml` (100 000 discs settling in a box) for STEPS
# steps with a history row only at the start and the end and no frames
# (each output gathers the whole state on rank 0), run as
# 1 rank × 1 thread, 1 rank × 2 threads and 2 ranks × 1 thread, the three
# interleaved ROUNDS times; then 2, 3 and 4 ranks (oversubscribed where
# there are fewer cores) for the traffic per step and rank. Prints
# particle-steps/s, peak resident memory per rank and, on ranks, bytes and
# messages sent per step and rank from each run's summary.json.
#
#   cargo build --release --features mpi      # a system MPI (docs/howto/mpi.md)
#   STEPS=2000 ROUNDS=3 examples/mpi_ranks_bench.sh
#   MPIRUN_ARGS="--bind-to none --mca mpi_yield_when_idle 1" examples/mpi_ranks_bench.sh
#
# (the second form for a machine shared with other work: ranks neither
# pinned to a core nor spinning while they wait)
set -euo pipefail
cd "$(dirname "$0")/.."
steps=${STEPS:-2000}
rounds=${ROUNDS:-3}
bin=${BIN:-target/release/efgdem}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
sed -e "s/^steps = .*/steps = $steps/" -e "s/^every = .*/every = $steps/" \
    -e "s/^vtk_every = .*/vtk_every = 0/" examples/settle_100k.toml >"$tmp/bench.toml"

run() { # name ranks threads
    local out="$tmp/$1"
    if [ "$2" -gt 1 ]; then
        # shellcheck disable=SC2086
        mpirun --oversubscribe ${MPIRUN_ARGS:-} -np "$2" "$bin" run "$tmp/bench.toml" -o "$out" \
            --threads "$3" -q --overwrite
    else
        "$bin" run "$tmp/bench.toml" -o "$out" --threads "$3" -q --overwrite
    fi
    python3 - "$out/summary.json" "$1" "$steps" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
name, steps = sys.argv[2], int(sys.argv[3])
line = f"{name:8} {s['particle_steps_per_second'] / 1e6:6.2f} M particle-steps/s"
ranks = s.get("ranks")
if ranks:
    for k, r in enumerate(ranks["per_rank"]):
        line += (f" | rank {k}: {r['owned']} discs + {r['ghosts']} ghosts,"
                 f" {r['peak_memory_bytes'] / 2**20:.0f} MiB,"
                 f" {r['bytes_sent'] / steps / 1e3:.1f} kB and"
                 f" {r['messages'] / steps:.1f} messages per step")
else:
    line += f" | {s['peak_memory_bytes'] / 2**20:.0f} MiB"
print(line, flush=True)
EOF
}

for _ in $(seq "$rounds"); do
    run 1x1 1 1
    run 1x2 1 2
    run 2x1 2 1
done
for n in 3 4; do
    run "${n}x1" "$n" 1
done
