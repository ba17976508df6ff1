#!/usr/bin/env bash
# Runs the given fuzz targets (default: all eight) one after another, each for
# $FUZZ_SECONDS seconds (default 600), with the limits of docs/FUZZING.md.
# Logs go to fuzz/logs/<target>.log; crashes to fuzz/artifacts/<target>/.
set -u
cd "$(dirname "$0")"
seconds="${FUZZ_SECONDS:-600}"
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(obj ply off stl pipeline volume_medit volume_gmsh volume_vtk)
python3 seed.py >/dev/null
mkdir -p logs
for t in "${targets[@]}"; do
    echo "== $t: start $(date -u +%FT%TZ) on $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- ../crates || echo +dirty)"
    cargo +nightly fuzz run "$t" -- \
        -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 -max_len=4096 \
        -print_final_stats=1 >"logs/$t.log" 2>&1
    rc=$?
    echo "== $t: end $(date -u +%FT%TZ) exit $rc"
    grep -E "^stat::number_of_executed_units|^stat::average_exec_per_sec|^Done|SUMMARY|panicked|Test unit written" "logs/$t.log" | head -8
done
