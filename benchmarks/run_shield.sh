#!/usr/bin/env bash
# The measurements of docs/explanation/passive-safety.md: every planner with and without the shield, on the same suites.
# One results folder per suite holds both settings (rows keyed by the `shield` column).
set -euo pipefail
VIAPATH=${VIAPATH:-.venv/bin/viapath}
PYTHON=${PYTHON:-.venv/bin/python}
OUT=${OUT:-out/shield}
WORKERS=${WORKERS:-1}
ALL=viapath,follow,stop,dwa,vo,nav-orca,nav-hl,nav-hrvo,nav-sf
mkdir -p "$OUT"
$VIAPATH suite mixed --count 200 --seed 0 --out "$OUT/suite-mixed-200"
$VIAPATH suite eth-ucy --count 100 --seed 0 --out "$OUT/suite-eth-ucy-100"   # needs VIAPATH_DATA
$VIAPATH suite eth-ucy --count 100 --seed 7 --out "$OUT/suite-eth-ucy-100-s7"
for setting in on off; do
  $VIAPATH bench "$OUT/suite-mixed-200" --planners $ALL --shield $setting --workers $WORKERS --no-plots --out "$OUT/mixed"
  $VIAPATH bench "$OUT/suite-eth-ucy-100" --planners $ALL --shield $setting --workers $WORKERS --no-plots --out "$OUT/eth-ucy"
  $VIAPATH bench "$OUT/suite-eth-ucy-100-s7" --seed 7 --planners viapath --shield $setting --workers $WORKERS --no-plots --out "$OUT/eth-ucy-s7"
done
$VIAPATH bench "$OUT/suite-mixed-200" --planners viapath --shield friendly --workers $WORKERS --no-plots --out "$OUT/mixed"
$VIAPATH bench "$OUT/suite-eth-ucy-100" --planners viapath --shield friendly --workers $WORKERS --no-plots --out "$OUT/eth-ucy"
$PYTHON benchmarks/shield_tables.py "$OUT/mixed" "$OUT/eth-ucy" "$OUT/eth-ucy-s7"
$PYTHON benchmarks/bench_shield.py --runs 3
