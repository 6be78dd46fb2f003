#!/usr/bin/env bash
# Bounded fuzzing (libFuzzer, clang, ASan + UBSan) of the .msh reader, the scene parser and the surface readers,
# starting from tests/fuzz/corpus. Any crash, leak, sanitizer report or timeout fails it.
# By default the run is bounded by a fixed number of inputs per target from a fixed seed
# (about 100 s each here; libFuzzer's corpus evolution still varies slightly between runs,
# so this narrows, not removes, the role of luck in the test command's verdict); set
# FUZZ_SECONDS=N for an open-ended, randomly seeded exploration of N seconds per target.
# Needs the packages of setup.sh.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${VTB_FUZZ_BUILD:-$root/build-fuzz}
seconds=${FUZZ_SECONDS:-}
declare -A runs=([msh]=3000000 [scene]=800000 [surface]=800000)
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
    -DVTB_FUZZ=ON -DVTB_WITH_CGAL=OFF -DVTB_BUILD_TESTS=OFF -DVTB_BUILD_BENCHMARKS=OFF >/dev/null
fi
cmake --build "$build" -j "$(nproc)" --target fuzz_msh fuzz_scene fuzz_surface
for target in msh scene surface; do
  work=$(mktemp -d)
  cp "$root/tests/fuzz/corpus/$target"/* "$work/"
  if [ -n "$seconds" ]; then bound=(-max_total_time="$seconds"); else bound=(-seed=20261122 -runs="${runs[$target]}"); fi
  echo "fuzz_$target: ${bound[*]} from $(ls "$work" | wc -l) seeds"
  status=0
  (cd "$work" && "$build/bin/fuzz_$target" "${bound[@]}" -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 "$work" > "$work.log" 2>&1) || status=$?
  grep -E "^stat::(number_of_executed_units|new_units_added)|SUMMARY|ERROR" "$work.log" || true
  if [ $status -ne 0 ]; then echo "fuzz_$target: libFuzzer exited with $status"; tail -30 "$work.log"; exit 1; fi
  # libFuzzer writes crash-*/leak-*/timeout-*/oom-* files on a finding.
  for kind in crash leak timeout oom; do
    if compgen -G "$work/$kind-*" >/dev/null; then
      echo "fuzz_$target: FINDING ($kind): $(ls "$work"/$kind-*)"
      mkdir -p "$root/out/fuzz-findings" && cp "$work"/$kind-* "$root/out/fuzz-findings/"
      exit 1
    fi
  done
  rm -rf "$work"
done
echo "fuzzing: no findings"
