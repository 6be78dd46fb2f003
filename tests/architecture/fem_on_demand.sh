#!/usr/bin/env bash
# deal.II enters a process only when a FEM runs (docs/architecture.md, "The FEM plugin"): the
# dynamic loader's own log (LD_DEBUG=files) of `vtb run` names neither the plugin nor deal.II
# on a spring run that asks nothing of the continuum, names both on `--solver fem`, and a FEM
# option that the base library rejects fails before anything is loaded.
# Usage: fem_on_demand.sh VTB SRC_DIR
set -u
vtb=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0
# A free plate (no supports, no loads: no load check) on Lloyd's springs (no fit): nothing of
# the continuum is asked.
cat > "$work/free.toml" <<'TOML'
[scene]
name = "free-plate"
duration = 0.01
output_interval = 0.01
[mesh]
generate = { shape = "rectangle", size = [0.1, 0.05], divisions = [10, 5] }
[material]
young_modulus = 5.0e4
poisson_ratio = 0.3
density = 1000.0
thickness = 0.001
[initial]
velocity = [0.05, 0.0]
[solver]
dt = 1.0e-3
springs = "lloyd"
TOML
loaded() { grep -E "calling init: .*($1)" "$2" > /dev/null; }

LD_DEBUG=files "$vtb" run "$work/free.toml" --out "$work/springs" 2> "$work/springs.log" > /dev/null
[ $? -eq 0 ] && [ -s "$work/springs/summary.json" ] || { echo "FAIL: the spring run did not finish"; fail=1; }
if loaded "libdeal\.ii|vtb_fem_plugin" "$work/springs.log"; then
  echo "FAIL: a spring run loaded the FEM:"
  grep -E "calling init: .*(libdeal\.ii|vtb_fem_plugin)" "$work/springs.log"
  fail=1
fi

LD_DEBUG=files "$vtb" run "$work/free.toml" --solver fem --out "$work/fem" 2> "$work/fem.log" > /dev/null
[ $? -eq 0 ] && [ -s "$work/fem/summary.json" ] || { echo "FAIL: the FEM run did not finish"; fail=1; }
for lib in vtb_fem_plugin libdeal.ii; do
  loaded "$lib" "$work/fem.log" || { echo "FAIL: the FEM run did not load $lib"; fail=1; }
done

sed 's/^springs = "lloyd"/kind = "fem"\ndegree = 3/' "$work/free.toml" > "$work/bad.toml"
LD_DEBUG=files "$vtb" run "$work/bad.toml" --out "$work/bad" 2> "$work/bad.log" > /dev/null
status=$?
[ $status -eq 1 ] || { echo "FAIL: degree = 3 exited $status, not 1"; fail=1; }
grep -q "\[solver\].degree" "$work/bad.log" || { echo "FAIL: no one-line error for degree = 3"; fail=1; }
loaded "libdeal\.ii|vtb_fem_plugin" "$work/bad.log" && { echo "FAIL: a rejected FEM option loaded deal.II"; fail=1; }
[ -e "$work/bad" ] && { echo "FAIL: a rejected run wrote $work/bad"; fail=1; }

[ $fail -eq 0 ] && echo "fem_on_demand: a spring run loads no deal.II; --solver fem loads the plugin and deal.II"
exit $fail
