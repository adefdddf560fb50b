#!/usr/bin/env bash
# The measurements of docs/explanation/metrics.md. Two workers at most (the machine has two cores).
set -euo pipefail
VIAPATH=${VIAPATH:-.venv/bin/viapath}
OUT=${OUT:-out/bench}
CLI="$VIAPATH"
ALL=viapath,follow,stop,dwa,vo,nav-orca,nav-hl,nav-hrvo,nav-sf
mkdir -p "$OUT"

# 1. Generated suite: 200 scenarios, every planner.
$CLI suite mixed --count 200 --seed 0 --out "$OUT/suite-mixed-200"
/usr/bin/time -f "%e s wall" $CLI bench "$OUT/suite-mixed-200" --planners $ALL --workers 2 --out "$OUT/mixed-200"

# 2. ETH/UCY replays: 100 episodes over the five scenes, every planner.
$CLI suite eth-ucy --count 100 --seed 0 --out "$OUT/suite-eth-ucy-100"
/usr/bin/time -f "%e s wall" $CLI bench "$OUT/suite-eth-ucy-100" --planners $ALL --workers 2 --out "$OUT/eth-ucy-100"

# 3. Throughput: 1000 scenarios, viapath, oracle; 1 vs 2 workers on the first 200.
/usr/bin/time -f "%e s wall (generate 1000)" $CLI suite mixed --count 1000 --seed 1 --out "$OUT/suite-mixed-1000"
mkdir -p "$OUT/suite-mixed-1000-first200"
# scenarios 0-199 (by index: every family, not the alphabetical first files)
for f in "$OUT"/suite-mixed-1000/*-0[01][0-9][0-9].yaml; do cp "$f" "$OUT/suite-mixed-1000-first200/"; done
/usr/bin/time -f "%e s wall (200, 1 worker)" $CLI bench "$OUT/suite-mixed-1000-first200" --planners viapath --workers 1 --out "$OUT/tp-200-w1" --no-plots
/usr/bin/time -f "%e s wall (200, 2 workers)" $CLI bench "$OUT/suite-mixed-1000-first200" --planners viapath --workers 2 --out "$OUT/tp-200-w2" --no-plots
/usr/bin/time -f "%e s wall (1000, 2 workers)" $CLI bench "$OUT/suite-mixed-1000" --planners viapath --workers 2 --out "$OUT/tp-1000-w2" --no-plots
