#!/usr/bin/env bash
# The layers of docs/architecture.md, read from the includes: each folder may include vtb
# headers of the layers below it only, and no folder of sources holds more than 18 files.
# Usage: layers.sh SRC_DIR
set -u
cd "$1"
status=0

# folder | the vtb include folders (vtb/<name>/) it may use
rules=(
  "core/base|base"
  "meshes|meshes base"
  "core/linalg|linalg base"
  "core/problem|problem linalg meshes base"
  "core/springs|springs problem linalg meshes base"
  "core/solvers|solvers springs problem linalg meshes base"
  "core/stepper|stepper solvers springs problem linalg meshes base"
  "core/haptics|haptics solvers springs problem linalg meshes base"
  "reference_fem|fem problem meshes base"
  "experiments/harness|harness fem haptics solvers springs problem linalg meshes base"
  "experiments/reproduction|reproduction harness fem haptics solvers springs problem linalg meshes base"
)
for rule in "${rules[@]}"; do
  dir=${rule%%|*}
  allowed=" ${rule#*|} "
  [ -d "$dir" ] || { echo "layers: no folder $dir"; status=1; continue; }
  while IFS=: read -r file line inc; do
    layer=$(sed -E 's#.*"vtb/([a-z_]+)/.*#\1#' <<<"$inc")
    if [[ "$allowed" != *" $layer "* ]]; then
      echo "layers: $file:$line includes vtb/$layer/, which $dir may not (allowed:$allowed)"
      status=1
    fi
  done < <(grep -rnE '^#include "vtb/[a-z_]+/' --include=*.cc --include=*.hh "$dir")
done

# Small rooms: a folder of sources or headers over 18 files holds more than one concept.
while read -r d; do
  n=$(find "$d" -maxdepth 1 -type f | wc -l)
  if [ "$n" -gt 18 ]; then echo "layers: $d holds $n files (at most 18)"; status=1; fi
done < <(find core meshes reference_fem experiments -type d \( -name src -o -path '*/src/*' -o -path '*/include/vtb/*' -o -name cli -o -name viewer \))

[ $status -eq 0 ] && echo "layers: every include points down the layers; no folder over 18 files"
exit $status
