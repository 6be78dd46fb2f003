#!/usr/bin/env bash
# Step and precompute benchmarks, then 3D haptic contact (Google Benchmark); medians of 5
# repetitions go to out/bench_step.json, out/bench_contact.json and the console. Arguments go
# to both programs (e.g. --benchmark_filter=...). The servo-loop timing with the other core
# busy takes 18 s of wall time and is run on its own: build/bin/vtb_bench_servo.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
mkdir -p "$VTB_ROOT/out"
for b in step contact; do
  "$VTB_BUILD/bin/vtb_bench_$b" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
    --benchmark_out="$VTB_ROOT/out/bench_$b.json" --benchmark_out_format=json "$@"
done
