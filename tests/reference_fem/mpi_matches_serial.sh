#!/usr/bin/env bash
# `vtb run --solver fem` under `mpirun -np 2` (distributed triangulation, Trilinos) gives the
# serial answer to direct-solver precision: probes and reactions agree to 1e-9 relative
# (measured ~3e-11), on Cook's membrane (a structured 16 x 16 trapezoid, P2, static), the
# 123-node plate (2D, dynamic), the 458-node slab (3D, drive) and a generated strip with P2
# elements, one refinement and the static solve, and a block pressed 30 % deep with the
# neo-Hookean law (Newton on the distributed tangent, static load stepping).
set -u
vtb=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
fail=0
# A third case takes the other paths of the distributed code: P2, a refinement, the static solve.
cat > "$work/p2_static.toml" <<'TOML'
[scene]
name = "p2-refined-static"
duration = 1.0
output_interval = 1.0
[mesh]
generate = { shape = "rectangle", size = [0.2, 0.05], divisions = [8, 2] }
[material]
young_modulus = 5.0e4
poisson_ratio = 0.3333
density = 1000.0
thickness = 0.001
[[fix]]
group = "left"
[[load]]
group = "right"
total_force = [0.0, -0.01]
[[probe]]
name = "tip"
point = [0.2, 0.025]
[solver]
kind = "fem"
degree = 2
refinements = 1
static = true
TOML
cat > "$work/nh_press.toml" <<'TOML'
[scene]
name = "neo-hookean-press"
duration = 1.0
output_interval = 1.0
[mesh]
generate = { shape = "box", size = [0.02, 0.02, 0.01], divisions = [4, 4, 2] }
[material]
young_modulus = 5.0e3
poisson_ratio = 0.45
density = 1000.0
[[fix]]
group = "bottom"
[[drive]]
box = [[0.005, 0.005, 0.01], [0.015, 0.015, 0.01]]
displacement = [0.0, 0.0, -0.003]
[[probe]]
name = "under"
point = [0.01, 0.01, 0.005]
[solver]
kind = "fem"
static = true
kinematics = "neo-hookean"
TOML
python3 "$src/tests/reference_fem/cook_msh.py" "$work/cook.msh" 16
cat > "$work/cook.toml" <<TOML
[scene]
name = "cook"
duration = 1.0
output_interval = 1.0
[mesh]
file = "$work/cook.msh"
[material]
young_modulus = 1.0
poisson_ratio = 0.3333333333333333
density = 1.0
thickness = 1.0
[[fix]]
group = "clamp"
[[load]]
group = "load"
total_force = [0.0, 1.0]
[[probe]]
name = "tip"
point = [48.0, 52.0]
[solver]
kind = "fem"
degree = 2
static = true
TOML
# The iterative solves (AMG-preconditioned CG) under MPI against the serial direct ones: the
# 3D slab's drive (linear, dynamic) and the neo-Hookean press (its block 1.5x as fine), both
# P2 so that the systems (about 10k dofs) are larger than the AMG's coarsest level (2,000
# dofs, solved directly); `linear_solver = "cg"` for the distributed run. CG stops at 1e-12 of
# the right-hand side and Newton's corrections at 1e-8 (its last step quadratic): 1e-8
# relative, as the serial tests (tests/reference_fem/test_amg_solvers.cc) hold them.
for f in "$src/experiments/scenes/slab_press.toml" "$work/nh_press.toml"; do
  p2=(-e 's/divisions = \[4, 4, 2\]/divisions = [6, 6, 3]/' -e "s|^file = \"\\([^/]\\)|file = \"$(dirname "$f")/\\1|")
  sed "${p2[@]}" -e 's/^\[solver\]$/[solver]\ndegree = 2\nlinear_solver = "direct"/' "$f" > "$work/p2_$(basename "$f")"
  sed "${p2[@]}" -e 's/^\[solver\]$/[solver]\ndegree = 2\nlinear_solver = "cg"/' "$f" > "$work/cg_$(basename "$f")"
done
for case in "$work/cook.toml 1.0 1e-9" "$src/experiments/scenes/plate123_step.toml 0.5 1e-9" \
  "$src/experiments/scenes/slab_press.toml 0.6 1e-9" "$work/p2_static.toml 1.0 1e-9" "$work/nh_press.toml 1.0 1e-9" \
  "$work/p2_slab_press.toml 0.6 1e-8 cg" "$work/p2_nh_press.toml 1.0 1e-8 cg"; do
  set -- $case
  name=$(basename "$1")
  mpi_scene=$1
  if [ "${4:-}" = cg ]; then mpi_scene="$work/cg_${name#p2_}"; fi
  "$vtb" run "$1" --solver fem --duration "$2" --out "$work/serial_$name" > /dev/null || fail=1
  timeout 300 mpirun -np 2 "$vtb" run "$mpi_scene" --solver fem --duration "$2" --out "$work/mpi_$name" > /dev/null || fail=1
  set -- "$name" "$3" "${4:-}"
  python3 - "$work/serial_$1" "$work/mpi_$1" "$1" "$2" "$3" <<'PY' || fail=1
import csv, sys, json
a_dir, b_dir, name, tol, solver = sys.argv[1:6]
tol = float(tol)
for f in ("probes.csv", "reactions.csv"):
    a = list(csv.reader(open(f"{a_dir}/{f}")))[1:]
    b = list(csv.reader(open(f"{b_dir}/{f}")))[1:]
    assert len(a) == len(b) and len(a) > 0, f"{name} {f}: {len(a)} vs {len(b)} rows"
    scale = max(abs(float(r[i])) for r in a for i in (2, 3, 4)) or 1.0
    diff = max(abs(float(x[i]) - float(y[i])) for x, y in zip(a, b) for i in (2, 3, 4))
    print(f"{name} {f}: max difference {diff / scale:.2e} relative")
    assert diff <= tol * scale, f"{name} {f}: MPI differs from serial by {diff / scale:.2e}"
summary = json.load(open(f"{b_dir}/summary.json"))
assert summary["mpi_ranks"] == 2
if solver == "cg":
    assert summary["iterative_solver"] == 1, summary.get("iterative_solver")
PY
done
[ $fail -eq 0 ] && echo "mpi matches serial: all checks passed"
exit $fail
