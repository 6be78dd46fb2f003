#!/usr/bin/env bash
# The CLI contract (README.md, docs/scenes.md, docs/harness.md): --help everywhere, bad input -> one clear line on stderr,
# a non-zero exit and no output files; a good scene -> the three files and exit 0.
source "$(dirname "$0")/check_lib.sh"

"$vtb" --help >/dev/null; check "vtb --help" '[ $? -eq 0 ]'
"$vtb" run --help >/dev/null; check "vtb run --help" '[ $? -eq 0 ]'
"$vtb" mesh --help >/dev/null; check "vtb mesh --help" '[ $? -eq 0 ]'
"$vtb" solvers > "$work/solvers.txt"; rc=$?
# One entry per solver name of solver_names.hh (the k* constants that are not filters).
entries=$(grep -c '^inline constexpr const char\* k[A-Za-z]* = ' "$src/core/problem/include/vtb/problem/solver_names.hh")
filters=$(grep -c '^inline constexpr const char\* kFilter[A-Z][A-Za-z]* = ' "$src/core/problem/include/vtb/problem/solver_names.hh")
# fem-mesh is a reference of vtb compare only (the scene's own FEM beside the continuum), not a solver.
references=$(grep -c '^inline constexpr const char\* kFemMesh = ' "$src/core/problem/include/vtb/problem/solver_names.hh")
expected=$((entries - filters - references))
check "vtb solvers lists the registry ($expected entries, with their keys)" '[ $rc -eq 0 ] && [ $(grep -c "\[solver\] keys:" "$work/solvers.txt") -eq $expected ] && grep -q "^implicit-euler " "$work/solvers.txt" && grep -q "^filtered-tensor " "$work/solvers.txt"'

sed 's/young_modulus/youngs_modulus/' "$src/experiments/scenes/plate_step.toml" > "$work/typo.toml"
"$vtb" run "$work/typo.toml" --out "$work/out_typo" 2> "$work/err"; rc=$?
check "typo exits 1" '[ $rc -eq 1 ]'
check "typo names file, key and suggestion" 'grep -q "typo.toml:[0-9]*: \[material\].youngs_modulus: unknown key; did you mean .young_modulus.?" "$work/err"'
check "typo is one line" '[ $(wc -l < "$work/err") -eq 1 ]'
check "typo writes nothing" '[ ! -e "$work/out_typo" ]'

"$vtb" run "$src/experiments/scenes/plate_step.toml" --dt -1 --out "$work/out_dt" 2> "$work/err"; rc=$?
check "negative dt exits 1 with a message" '[ $rc -eq 1 ] && grep -q "dt" "$work/err" && [ ! -e "$work/out_dt" ]'

# One check of a step from outside the scene (vtb/problem/overrides.hh); 0 is not "the scene's".
for args in "run --out $work/out_dt0" "compare --solvers filtered --out $work/out_dt0" "view --frames 1"; do
  "$vtb" ${args%% *} "$src/experiments/scenes/plate_step.toml" ${args#* } --dt 0 2> "$work/err"; rc=$?
  check "vtb ${args%% *} --dt 0: exit 1, the one line" '[ $rc -eq 1 ] && [ "$(cat "$work/err")" = "vtb: error: --dt must be a positive number" ] && [ ! -e "$work/out_dt0" ]'
done

"$vtb" run "$work/none.toml" 2> "$work/err"; rc=$?
check "missing scene" '[ $rc -eq 1 ] && grep -q "none.toml: cannot open scene file" "$work/err"'

printf 'not a mesh' > "$work/broken.msh"
sed "s#generate = .*#file = \"$work/broken.msh\"#" "$src/experiments/scenes/plate_step.toml" > "$work/broken.toml"
"$vtb" run "$work/broken.toml" --out "$work/out_broken" 2> "$work/err"; rc=$?
check "broken mesh exits 1 naming the file" '[ $rc -eq 1 ] && grep -q "broken.msh" "$work/err" && [ ! -e "$work/out_broken" ]'

"$vtb" run "$src/experiments/scenes/plate_step.toml" --duration 0.05 --out "$work/out_good" > "$work/out_good.txt"; rc=$?
check "good scene runs" '[ $rc -eq 0 ] && [ -s "$work/out_good/probes.csv" ] && [ -s "$work/out_good/reactions.csv" ] && [ -s "$work/out_good/summary.json" ]'
# The scene names Lloyd's springs: the run says how far they are from P1 FEM on its loads, in
# its line and in a line of its own past 5 %, and summary.json holds the number.
check "the run says how good its springs are on its loads, against the continuum and P1 on the mesh" 'grep -q "lloyd springs (.* from the continuum on the scene.s loads, static; P1 on this mesh .*)" "$work/out_good.txt" && grep -q "^vtb run: the lloyd springs are .* from the continuum .* above 5 %" "$work/out_good.txt" && grep -q "^vtb run: the springs. load check against the continuum (P2 refined" "$work/out_good.txt" && grep -q "\"calibration_load_error\"" "$work/out_good/summary.json" && grep -q "\"mesh_fem_load_error\"" "$work/out_good/summary.json" && grep -q "\"calibration_yardstick\": \"the continuum" "$work/out_good/summary.json"'

# A write that fails is an I/O error (exit 74), not bad input, named in one line; nothing is
# left behind. Root ignores permissions, so the unwritable folders are a path through a
# regular file and /proc (a file system that refuses new folders).
printf 'x' > "$work/afile"
"$vtb" run "$src/experiments/scenes/plate_step.toml" --duration 0.05 --out "$work/afile/out" > /dev/null 2> "$work/err"; rc=$?
check "output under a file exits 74 naming the folder" '[ $rc -eq 74 ] && grep -q "^vtb: I/O error: $work/afile/out: cannot create the folder" "$work/err" && [ $(wc -l < "$work/err") -eq 1 ] && [ "$(cat "$work/afile")" = x ]'
"$vtb" run "$src/experiments/scenes/plate_step.toml" --duration 0.05 --out /proc/vtb_contract_out > /dev/null 2> "$work/err"; rc=$?
check "output on a read-only file system exits 74" '[ $rc -eq 74 ] && grep -q "I/O error: /proc/vtb_contract_out" "$work/err" && [ ! -e /proc/vtb_contract_out ]'
"$vtb" mesh generate rectangle --size 1 1 --divisions 2 2 -o "$work/afile/m.msh" > /dev/null 2> "$work/err"; rc=$?
check "mesh written under a file exits 74" '[ $rc -eq 74 ] && grep -q "I/O error: $work/afile" "$work/err"'
"$vtb" compare "$src/experiments/scenes/plate_step.toml" --solvers filtered-full --reference cvode --out "$work/afile/cmp" > /dev/null 2> "$work/err"; rc=$?
check "compare into an unwritable folder exits 74" '[ $rc -eq 74 ] && [ "$(cat "$work/afile")" = x ]'
ls "$work" | grep -q "\.part" ; check "no .part file left anywhere" '[ $? -ne 0 ]'

"$vtb" run "$src/experiments/scenes/plate_step.toml" --solver explicit --dt 1e-3 --duration 0.2 --out "$work/out_unstable" > /dev/null 2> "$work/err"; rc=$?
check "unstable run exits 2 with stable=false" '[ $rc -eq 2 ] && grep -q "\"stable\": false" "$work/out_unstable/summary.json" && grep -q "unstable" "$work/err"'

"$vtb" run "$src/experiments/scenes/plate123_step.toml" --solver fem --duration 0.08 --frames --out "$work/out_frames" > /dev/null; rc=$?
check "fem run with frames" '[ $rc -eq 0 ] && [ -s "$work/out_frames/frames.pvd" ] && [ $(ls "$work/out_frames/frames" | wc -l) -eq 3 ]'

"$vtb" run "$src/experiments/scenes/plate123_step.toml" --duration 0.08 --frames --out "$work/out_sframes" > /dev/null; rc=$?
f="$work/out_sframes/frames/frame_0002.vtu"
check "spring run with frames: compressed VTU with displacement, velocity, strain, spring force" '[ $rc -eq 0 ] && [ $(ls "$work/out_sframes/frames" | wc -l) -eq 3 ] && grep -q vtkZLibDataCompressor "$f" && grep -q "Name=\"displacement\"" "$f" && grep -q "Name=\"velocity\"" "$f" && grep -q "Name=\"max_principal_strain\"" "$f" && grep -q "Name=\"spring_force\"" "$f" && [ ! -e "$f.part" ]'

"$vtb" compare "$src/experiments/scenes/plate123_step.toml" --solvers filtered,implicit-euler --reference cvode --dt 0.01 --out "$work/out_cmp" > "$work/cmp.txt" 2> /dev/null; rc=$?
check "compare writes compare.csv and a table" '[ $rc -eq 0 ] && [ $(wc -l < "$work/out_cmp/compare.csv") -eq 4 ] && grep -q "implicit-euler" "$work/cmp.txt"'

"$vtb" compare "$src/experiments/scenes/plate123_step.toml" --solvers filterd --out "$work/out_cmp2" 2> "$work/err"; rc=$?
check "compare refuses an unknown solver" '[ $rc -eq 1 ] && grep -q "unknown solver" "$work/err" && [ ! -e "$work/out_cmp2" ]'

"$vtb" haptics "$src/experiments/scenes/haptic_press.toml" --lockstep --fault nan@1.4 --out "$work/out_hap" > /dev/null; rc=$?
check "haptics writes haptics.csv and summary.json" '[ $rc -eq 0 ] && [ $(wc -l < "$work/out_hap/haptics.csv") -eq 3001 ] && grep -q "deadline_misses" "$work/out_hap/summary.json"'

"$vtb" haptics "$src/experiments/scenes/haptic_slab_press.toml" --lockstep --out "$work/out_hap3d" > /dev/null; rc=$?
check "haptics runs a 3D body (device plane in the slab)" '[ $rc -eq 0 ] && [ $(wc -l < "$work/out_hap3d/haptics.csv") -eq 3001 ] && grep -q "\"dim\": 3" "$work/out_hap3d/summary.json"'

"$vtb" haptics "$src/experiments/scenes/haptic_two_probes.toml" --lockstep --out "$work/out_hap_two" > /dev/null; rc=$?
check "haptics with two probes writes a column set per probe" '[ $rc -eq 0 ] && head -1 "$work/out_hap_two/haptics.csv" | grep -qx "t,hx,hy,fx,fy,hx_1,hy_1,fx_1,fy_1"'

sed 's/^y_axis = \[0.0, 0.0, 1.0\]/y_axis = [1.0, 0.0, 1.0]/' "$src/experiments/scenes/haptic_slab_press.toml" > "$work/bad_plane.toml"
sed -i 's|"\.\./\.\./meshes|"'"$src"'/meshes|' "$work/bad_plane.toml"
"$vtb" haptics "$work/bad_plane.toml" --out "$work/out_hap_bad" 2> "$work/err"; rc=$?
check "haptics refuses a device plane whose axes are not at right angles" '[ $rc -eq 1 ] && [ $(wc -l < "$work/err") -eq 1 ] && grep -q "\[haptics.plane\].y_axis: must be orthogonal" "$work/err" && [ ! -e "$work/out_hap_bad" ]'
sed 's/^max_force = 4.0/max_force = 4.0\ntip_radius = -0.002/' "$src/experiments/scenes/haptic_slab_press.toml" > "$work/bad_tip.toml"
sed -i 's|"\.\./\.\./meshes|"'"$src"'/meshes|' "$work/bad_tip.toml"
"$vtb" haptics "$work/bad_tip.toml" --out "$work/out_hap_tip" 2> "$work/err"; rc=$?
check "haptics refuses a negative tool tip radius, naming the key" '[ $rc -eq 1 ] && [ $(wc -l < "$work/err") -eq 1 ] && grep -q "tip_radius" "$work/err" && [ ! -e "$work/out_hap_tip" ]'

"$vtb" haptics "$src/experiments/scenes/plate_step.toml" --out "$work/out_hap2" 2> "$work/err"; rc=$?
check "haptics refuses a scene without [haptics]" '[ $rc -eq 1 ] && grep -q "\[haptics\] is missing" "$work/err"'

"$vtb" haptics "$src/experiments/scenes/haptic_press.toml" --fault melt@1 --out "$work/out_hap3" 2> "$work/err"; rc=$?
check "haptics refuses a bad fault" '[ $rc -eq 1 ] && grep -q "stall@T or nan@T" "$work/err"'

"$vtb" mesh generate rectangle --size 0.2 0.05 --divisions 4 2 -o "$work/r.msh" > /dev/null; rc=$?
check "mesh generate + info" '[ $rc -eq 0 ] && "$vtb" mesh info "$work/r.msh" | grep -q "nodes: 15"'

# A user's surface (docs/meshes.md): a good one meshes and lists its groups; each bad one exits 1
# with one line naming the file and the fault, and writes nothing.
"$vtb" mesh generate surface "$src/meshes/data/bean.off" --nodes 600 -o "$work/bean.msh" > /dev/null; rc=$?
check "mesh generate surface + info lists the surface group" '[ $rc -eq 0 ] && "$vtb" mesh info "$work/bean.msh" | grep -q "^group surface: "'
cube_v='0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n'
cube_f='3 0 2 1\n3 1 2 3\n3 4 5 6\n3 5 7 6\n3 0 1 4\n3 1 5 4\n3 2 6 3\n3 3 6 7\n3 0 4 2\n3 2 4 6\n3 1 3 5\n'
printf "OFF\n8 11 0\n${cube_v}${cube_f}" > "$work/open.off"   # 11 of the cube's 12 faces
printf "OFF\n16 24 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n.5 .5 .5\n1.5 .5 .5\n.5 1.5 .5\n1.5 1.5 .5\n.5 .5 1.5\n1.5 .5 1.5\n.5 1.5 1.5\n1.5 1.5 1.5\n${cube_f}3 3 7 5\n3 8 10 9\n3 9 10 11\n3 12 13 14\n3 13 15 14\n3 8 9 12\n3 9 13 12\n3 10 14 11\n3 11 14 15\n3 8 12 10\n3 10 12 14\n3 9 11 13\n3 11 15 13\n" > "$work/cross.off"
printf "OFF\n16 24 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n1 1 0\n2 1 0\n1 2 0\n2 2 0\n1 1 1\n2 1 1\n1 2 1\n2 2 1\n${cube_f}3 3 7 5\n3 8 10 9\n3 9 10 11\n3 12 13 14\n3 13 15 14\n3 8 9 12\n3 9 13 12\n3 10 14 11\n3 11 14 15\n3 8 12 10\n3 10 12 14\n3 9 11 13\n3 11 15 13\n" > "$work/edge.off"
: > "$work/empty.stl"
{ head -c 80 /dev/zero; printf '\x64\x00\x00\x00'; head -c 700 /dev/zero; } > "$work/cut.stl"   # 100 triangles declared, 14 present
for bad in open:not\ closed cross:self-intersecting edge:not\ manifold empty:empty cut:truncated; do
  name=${bad%%:*}; what=${bad#*:}; file=$(ls "$work/$name".*)
  "$vtb" mesh generate surface "$file" --nodes 600 -o "$work/bad_$name.msh" > /dev/null 2> "$work/err"; rc=$?
  check "a surface $what: exit 1, one line naming it, nothing written" '[ $rc -eq 1 ] && [ $(wc -l < "$work/err") -eq 1 ] && grep -q "$file: .*$what" "$work/err" && ! ls "$work" | grep -q "bad_$name"'
done

"$vtb" view --help >/dev/null; check "vtb view --help" '[ $? -eq 0 ]'
env -u DISPLAY -u WAYLAND_DISPLAY "$vtb" view "$src/experiments/scenes/plate_step.toml" --frames 2 --screenshot "$work/v.png" 2> "$work/err"; rc=$?
check "view without a display: exit 3, one line, no picture" '[ $rc -eq 3 ] && [ $(wc -l < "$work/err") -eq 1 ] && grep -q "xvfb-run" "$work/err" && [ ! -e "$work/v.png" ]'
env -u DISPLAY "$vtb" view "$work/typo.toml" --frames 2 2> "$work/err"; rc=$?
check "view of a bad scene is bad input before any window" '[ $rc -eq 1 ] && grep -q "youngs_modulus" "$work/err"'
env -u DISPLAY "$vtb" view "$src/experiments/scenes/plate_step.toml" --frames 2 --drag 1,2 2> "$work/err"; rc=$?
check "view refuses a malformed --drag" '[ $rc -eq 1 ] && grep -q "\-\-drag" "$work/err"'
env -u DISPLAY "$vtb" view "$src/experiments/scenes/plate_step.toml" --frames 2 --drag 700,0:700.1,0 --screenshot "$work/far.png" 2> "$work/err"; rc=$?
check "view refuses a pull that starts off the body (700 m from a 0.2 m plate), naming the point and distance" '[ $rc -eq 1 ] && [ $(wc -l < "$work/err") -eq 1 ] && grep -q "\[700, 0\]" "$work/err" && grep -q "m from the body" "$work/err" && [ ! -e "$work/far.png" ]'

"$vtb" study "$src/experiments/scenes/plate123_step.toml" --quick --solvers filtered-full,implicit-euler --reference cvode --out "$work/out_study" > "$work/study.txt" 2> /dev/null; rc=$?
check "study writes study.csv (header + 6 runs) and study_plot.tex" '[ $rc -eq 0 ] && [ $(wc -l < "$work/out_study/study.csv") -eq 7 ] && [ -s "$work/out_study/study_plot.tex" ] && grep -q "Pareto front" "$work/study.txt"'
# The plot draws whichever solvers ran (here neither bullet nor the paper's full set): a PNG, no
# "no plot" note, and the legend names exactly the solvers of the study.
check "study draws its plot for any solver set" '[ -s "$work/out_study/study_plot.png" ] && ! grep -q "no plot" "$work/study.txt" && pdftotext "$work/out_study/study_plot.pdf" - | grep -q "filtered-full" && ! pdftotext "$work/out_study/study_plot.pdf" - | grep -qi "bullet"'
"$vtb" study "$src/experiments/scenes/plate123_step.toml" --solvers fem --out "$work/out_study2" 2> "$work/err"; rc=$?
check "study refuses a solver it cannot ladder" '[ $rc -eq 1 ] && grep -q "not one to study" "$work/err" && [ ! -e "$work/out_study2" ]'

if [ $fail -eq 0 ]; then echo "cli contract: all checks passed"; fi
exit $fail
