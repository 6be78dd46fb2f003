#!/usr/bin/env bash
# The CLI contract (DESIGN.md §2): --help everywhere, bad input -> one clear line on stderr,
# a non-zero exit and no output files; a good scene -> the three files and exit 0.
set -u
vtb=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0
check() { # name, condition
  if eval "$2"; then echo "ok   $1"; else echo "FAIL $1"; fail=1; fi
}

"$vtb" --help >/dev/null; check "vtb --help" '[ $? -eq 0 ]'
"$vtb" run --help >/dev/null; check "vtb run --help" '[ $? -eq 0 ]'
"$vtb" mesh --help >/dev/null; check "vtb mesh --help" '[ $? -eq 0 ]'

sed 's/young_modulus/youngs_modulus/' "$src/experiments/scenes/plate_step.toml" > "$work/typo.toml"
"$vtb" run "$work/typo.toml" --out "$work/out_typo" 2> "$work/err"; rc=$?
check "typo exits 1" '[ $rc -eq 1 ]'
check "typo names file, key and suggestion" 'grep -q "typo.toml:[0-9]*: \[material\].youngs_modulus: unknown key; did you mean .young_modulus.?" "$work/err"'
check "typo is one line" '[ $(wc -l < "$work/err") -eq 1 ]'
check "typo writes nothing" '[ ! -e "$work/out_typo" ]'

"$vtb" run "$src/experiments/scenes/plate_step.toml" --dt -1 --out "$work/out_dt" 2> "$work/err"; rc=$?
check "negative dt exits 1 with a message" '[ $rc -eq 1 ] && grep -q "dt" "$work/err" && [ ! -e "$work/out_dt" ]'

"$vtb" run "$work/none.toml" 2> "$work/err"; rc=$?
check "missing scene" '[ $rc -eq 1 ] && grep -q "none.toml: cannot open scene file" "$work/err"'

printf 'not a mesh' > "$work/broken.msh"
sed "s#generate = .*#file = \"$work/broken.msh\"#" "$src/experiments/scenes/plate_step.toml" > "$work/broken.toml"
"$vtb" run "$work/broken.toml" --out "$work/out_broken" 2> "$work/err"; rc=$?
check "broken mesh exits 1 naming the file" '[ $rc -eq 1 ] && grep -q "broken.msh" "$work/err" && [ ! -e "$work/out_broken" ]'

"$vtb" run "$src/experiments/scenes/plate_step.toml" --duration 0.05 --out "$work/out_good" > /dev/null; rc=$?
check "good scene runs" '[ $rc -eq 0 ] && [ -s "$work/out_good/probes.csv" ] && [ -s "$work/out_good/reactions.csv" ] && [ -s "$work/out_good/summary.json" ]'

"$vtb" run "$src/experiments/scenes/plate_step.toml" --solver explicit --dt 1e-3 --duration 0.2 --out "$work/out_unstable" > /dev/null 2> "$work/err"; rc=$?
check "unstable run exits 2 with stable=false" '[ $rc -eq 2 ] && grep -q "\"stable\": false" "$work/out_unstable/summary.json" && grep -q "unstable" "$work/err"'

"$vtb" mesh generate rectangle --size 0.2 0.05 --divisions 4 2 -o "$work/r.msh" > /dev/null; rc=$?
check "mesh generate + info" '[ $rc -eq 0 ] && "$vtb" mesh info "$work/r.msh" | grep -q "nodes: 15"'

if [ $fail -eq 0 ]; then echo "cli contract: all checks passed"; fi
exit $fail
