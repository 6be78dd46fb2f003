#!/usr/bin/env bash
# The CLI of a build without the CGAL mesh generators (VTB_WITH_CGAL=OFF): everything that needs
# no CGAL mesh runs; what does (the plate, the Mesh_3 solids, a surface, an unstructured mesh, a
# scene that generates one) exits 1 with one line saying so and writes nothing.
source "$(dirname "$0")/check_lib.sh"
"$vtb" --help >/dev/null; check "vtb --help" '[ $? -eq 0 ]'
"$vtb" mesh generate rectangle --size 0.2 0.05 --divisions 4 2 -o "$work/r.msh" >/dev/null; rc=$?
check "a structured mesh needs no CGAL" '[ $rc -eq 0 ] && "$vtb" mesh info "$work/r.msh" | grep -q "nodes: 15"'
for args in "plate --nodes 123" "slab --nodes 500" "surface $src/meshes/data/bean.off --nodes 600" \
  "box --size 0.1 0.1 0.1 --nodes 300"; do
  shape=${args%% *}
  "$vtb" mesh generate $args -o "$work/$shape.msh" >/dev/null 2>"$work/err"; rc=$?
  check "mesh generate $shape: exit 1, one line, nothing written" '[ $rc -eq 1 ] && [ $(wc -l < "$work/err") -eq 1 ] && grep -q "no CGAL meshers" "$work/err" && [ ! -e "$work/$shape.msh" ]'
done
"$vtb" run "$src/experiments/scenes/plate_step.toml" --duration 0.05 --out "$work/run" >/dev/null 2>&1; rc=$?
check "a run on a committed mesh" '[ $rc -eq 0 ] && [ -s "$work/run/summary.json" ]'
"$vtb" haptics "$src/experiments/scenes/bean_press.toml" --lockstep --out "$work/bean" >/dev/null 2>"$work/err"; rc=$?
check "a scene that generates a surface mesh: exit 1 naming the scene" '[ $rc -eq 1 ] && grep -q "bean_press.toml" "$work/err" && grep -q "no CGAL meshers" "$work/err" && [ ! -e "$work/bean/summary.json" ]'
exit $fail
