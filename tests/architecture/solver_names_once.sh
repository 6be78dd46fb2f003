#!/usr/bin/env bash
# The solver registry is the one place solver names are written (docs/architecture.md): a quoted
# solver name anywhere else in the sources fails this test. Usage: solver_names_once.sh SRC_DIR
set -u
cd "$1"
hits=$(grep -rnE '"(explicit|filtered|filtered-full|filtered-neighbors|implicit-euler|cvode|fem)"' \
  --include=*.cc --include=*.hh core reference_fem experiments meshes | grep -v '^core/problem/include/vtb/problem/solver_names.hh:')
if [ -n "$hits" ]; then
  echo "solver names written outside core/problem/include/vtb/problem/solver_names.hh:"
  echo "$hits"
  exit 1
fi
echo "solver names: only in the registry"
