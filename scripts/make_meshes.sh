#!/usr/bin/env bash
# Regenerates the canonical meshes in meshes/data bit for bit (CGAL; deterministic):
#   plate_517.msh, plate_123.msh  the paper's plate (exact node counts, angles >= 20 deg)
#   slab_500.msh, slab_2000.msh, sphere_500.msh, sphere_2000.msh   3D Mesh_3 solids
# Larger 3D meshes (about 10k, 50k nodes) are generated on demand, e.g.
#   build/bin/vtb mesh generate slab --nodes 50000 -o out/slab_50000.msh
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
data="$VTB_ROOT/meshes/data"
vtb="$VTB_BUILD/bin/vtb"
for n in 517 123; do "$vtb" mesh generate plate --nodes "$n" -o "$data/plate_$n.msh"; done
for shape in slab sphere; do
  for n in 500 2000; do "$vtb" mesh generate "$shape" --nodes "$n" -o "$data/${shape}_$n.msh"; done
done
