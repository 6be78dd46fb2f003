#!/usr/bin/env bash
# Step and precompute benchmarks (Google Benchmark); medians of 5 repetitions go to
# out/bench_step.json and the console.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
mkdir -p "$VTB_ROOT/out"
"$VTB_BUILD/bin/vtb_bench_step" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
  --benchmark_out="$VTB_ROOT/out/bench_step.json" --benchmark_out_format=json "$@"
