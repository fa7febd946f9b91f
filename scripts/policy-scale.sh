#!/usr/bin/env bash
# The general policy's CPU time and memory on 1,000, 5,000 and 10,000 blocks: writes
# docs/results/general/scale.txt (docs/results/general/README.md says what it holds).
#
# It trains the preset's network (`dqn --preset general --seed 1`) and the same recipe with
# one round of message passing (neural's example `general_rounds`, as the command line does
# not set the rounds), writes one uniform random problem of each size (`generate --seed 1`),
# and plans each with each network and with the near-optimal planner, under
# `/usr/bin/time`: user + system CPU seconds and the largest resident set of the whole
# `solve` process (reading the problem, the lower bound, playing, checking the plan).
set -euo pipefail
cd "$(dirname "$0")/.."

cargo build --release -p blockstack
cargo build --release -p neural --example general_rounds
target="${CARGO_TARGET_DIR:-target}/release"
bs="$target/blockstack"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

"$bs" dqn --preset general --seed 1 --out "$work/preset.safetensors" > /dev/null
"$target/examples/general_rounds" 1 1 "$work/one-round.safetensors"

# The rounds a network file's config names (its safetensors header's metadata).
rounds() {
    python3 - "$1" <<'PY'
import json, struct, sys
raw = open(sys.argv[1], "rb").read()
size = struct.unpack("<Q", raw[:8])[0]
meta = json.loads(json.loads(raw[8:8 + size])["__metadata__"]["metadata"])
print(meta["config"]["shape"]["rounds"])
PY
}

out="docs/results/general/scale.txt"
{
    echo "# scripts/policy-scale.sh at commit $(git rev-parse --short HEAD), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
    printf '%-7s %-22s %7s %8s %12s %8s %11s\n' blocks planner rounds actions "lower bound" "CPU s" "max RSS MB"
    for blocks in 1000 5000 10000; do
        "$bs" generate --blocks "$blocks" --seed 1 --out "$work/p$blocks" > /dev/null
        task="$work/p$blocks/p01.pddl"
        for planner in preset one-round near-optimal; do
            case "$planner" in
                near-optimal) args=(--solver near-optimal); name="near-optimal planner"; r="-" ;;
                preset) args=(--model "$work/preset.safetensors"); name="general preset"; r="$(rounds "$work/preset.safetensors")" ;;
                one-round) args=(--model "$work/one-round.safetensors"); name="general, one round"; r="$(rounds "$work/one-round.safetensors")" ;;
            esac
            /usr/bin/time -f "%U %S %M" -o "$work/time" "$bs" solve --pddl "$task" "${args[@]}" > "$work/plan"
            read -r user sys rss < "$work/time"
            actions="$(sed -n 's/^; cost = \([0-9]*\).*/\1/p' "$work/plan")"
            bound="$(sed -n 's/^; lower bound = \([0-9]*\).*/\1/p' "$work/plan")"
            awk -v b="$blocks" -v n="$name" -v r="$r" -v a="$actions" -v l="$bound" -v u="$user" -v s="$sys" -v m="$rss" \
                'BEGIN { printf "%-7s %-22s %7s %8s %12s %8.2f %11.1f\n", b, n, r, a, l, u + s, m / 1024 }'
        done
    done
} > "$out"
cat "$out"
