#!/usr/bin/env bash
# `vtb run --solver fem` under `mpirun -np 2` (distributed triangulation, Trilinos) gives the
# serial answer to direct-solver precision: probes and reactions agree to 1e-9 relative
# (measured ~3e-11), on the 123-node plate (2D, dynamic) and the 458-node slab (3D, drive).
set -u
vtb=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
fail=0
for case in "plate123_step.toml 0.5" "slab_press.toml 0.6"; do
  set -- $case
  "$vtb" run "$src/experiments/scenes/$1" --solver fem --duration "$2" --out "$work/serial_$1" > /dev/null || fail=1
  timeout 300 mpirun -np 2 "$vtb" run "$src/experiments/scenes/$1" --solver fem --duration "$2" --out "$work/mpi_$1" > /dev/null || fail=1
  python3 - "$work/serial_$1" "$work/mpi_$1" "$1" <<'PY' || fail=1
import csv, sys, json
a_dir, b_dir, name = sys.argv[1:4]
for f in ("probes.csv", "reactions.csv"):
    a = list(csv.reader(open(f"{a_dir}/{f}")))[1:]
    b = list(csv.reader(open(f"{b_dir}/{f}")))[1:]
    assert len(a) == len(b) and len(a) > 0, f"{name} {f}: {len(a)} vs {len(b)} rows"
    scale = max(abs(float(r[i])) for r in a for i in (2, 3, 4)) or 1.0
    diff = max(abs(float(x[i]) - float(y[i])) for x, y in zip(a, b) for i in (2, 3, 4))
    print(f"{name} {f}: max difference {diff / scale:.2e} relative")
    assert diff <= 1e-9 * scale, f"{name} {f}: MPI differs from serial by {diff / scale:.2e}"
assert json.load(open(f"{b_dir}/summary.json"))["mpi_ranks"] == 2
PY
done
[ $fail -eq 0 ] && echo "mpi matches serial: all checks passed"
exit $fail
