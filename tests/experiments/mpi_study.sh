#!/usr/bin/env bash
# Studies beyond one process (docs/harness.md): under `mpirun -np 2`
#  1. vtb study spreads its cells over the ranks and prints one table and writes one study.csv
#     whose error columns (solver, dt, rtol, stable, error_all, error_probes) equal the serial
#     run's (each cell is the same deterministic run against the same reference);
#  2. vtb sweep writes the serial stability.csv but for its timing column;
#  3. a command that does not spread (run with a spring solver, solvers) prints once.
# Usage: mpi_study.sh VTB SRC_DIR
source "$(dirname "$0")/check_lib.sh"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
mpi=(mpirun --allow-run-as-root --oversubscribe -np 2)
scene=$src/experiments/scenes/plate123_step.toml
args=(--quick --solvers filtered-full,implicit-euler,cvode --reference cvode)

"$vtb" study "$scene" "${args[@]}" --out "$work/serial" > "$work/serial.txt" 2> /dev/null
"${mpi[@]}" "$vtb" study "$scene" "${args[@]}" --out "$work/mpi" > "$work/mpi.txt" 2> "$work/mpi.err"
rc=$?
check "mpirun -np 2 vtb study exits 0" '[ $rc -eq 0 ]'
check "one table printed" '[ $(grep -c "^study of" "$work/mpi.txt") -eq 1 ] && [ $(grep -c "^outputs in" "$work/mpi.txt") -eq 1 ]'
errors() { cut -d, -f1-6 "$1"; }
check "study.csv error columns equal the serial run's" 'diff <(errors "$work/serial/study.csv") <(errors "$work/mpi/study.csv")'
check "the binding column names both ranks' cells" 'grep -q "rank 1/2" "$work/mpi/study.csv" && grep -q "serial" "$work/serial/study.csv"'
check "no part file left" '[ -z "$(find "$work/mpi" -name "*.part")" ]'

sweep=(--dt 1e-3,1e-2 --stiffness-scale 0.5,1 --solvers filtered-full,implicit-euler)
"$vtb" sweep "$scene" "${sweep[@]}" --out "$work/sweep_serial" > /dev/null 2>&1
"${mpi[@]}" "$vtb" sweep "$scene" "${sweep[@]}" --out "$work/sweep_mpi" > "$work/sweep.txt" 2> /dev/null
rc=$?
untimed() { cut -d, -f1-9,11- "$1"; } # all but step_median_seconds
check "mpirun -np 2 vtb sweep: the serial stability.csv but for its timing column" '[ $rc -eq 0 ] && diff <(untimed "$work/sweep_serial/stability.csv") <(untimed "$work/sweep_mpi/stability.csv")'
check "the sweep prints once" '[ $(grep -c "^criterion:" "$work/sweep.txt") -eq 1 ]'

"${mpi[@]}" "$vtb" run "$scene" --duration 0.05 --out "$work/run" > "$work/run.txt" 2> /dev/null
check "mpirun -np 2 vtb run (springs) prints once" '[ $(grep -c "^vtb run: .* with " "$work/run.txt") -eq 1 ]'
"${mpi[@]}" "$vtb" solvers > "$work/solvers_mpi.txt" 2> /dev/null
"$vtb" solvers > "$work/solvers.txt"
check "mpirun -np 2 vtb solvers prints once" 'diff "$work/solvers.txt" "$work/solvers_mpi.txt"'
exit $fail
