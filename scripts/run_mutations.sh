#!/usr/bin/env bash
# A short mutation run: each mutation below is a deliberate bug (one sed on one file); the
# suite must fail at least one test for each. Builds in build-mut (separate from build/),
# restores every file it touched, and prints the failing tests per mutation. docs/testing.md
# lists the mutations and the tests that caught them. Takes about 10 minutes on 2 cores.
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${VTB_MUT_BUILD:-$root/build-mut}
cd "$root"
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DVTB_BUILD_BENCHMARKS=OFF > /dev/null
fi
# name | file | sed expression
mutations=(
  "spring force sign|core/springs/include/vtb/springs/spring_kernels.hh|s/return (k \* (l - rest_length) + c \* n.dot(vj - vi)) \* n;/return (k * (rest_length - l) + c * n.dot(vj - vi)) * n;/"
  "spring Jacobian sign (CVODE)|core/solvers/src/cvode_solver.cc|s/if (a >= 0) add(part, a, a, B, -1.0);/if (a >= 0) add(part, a, a, B, 1.0);/"
  "dashpot dropped from implicit Euler's matrix|core/solvers/src/implicit_euler.cc|s/const Mat<dim> B = dt \* dt \* K + dt \* dashpot_jacobian<dim>(xi, xj, net.damping\[sp\]);/const Mat<dim> B = dt * dt * K;/"
  "dashpot dropped from CVODE's Jacobian|core/solvers/src/cvode_solver.cc|s/const Mat<dim> C = dashpot_jacobian<dim>(xi, xj, net.damping\[s\]);/const Mat<dim> C = Mat<dim>::Zero();/"
  "saturation removed|core/haptics/src/force_shaping.cc|s/if (norm <= max_force) return f;/if (true) return f;/"
  "torque correction skipped|core/solvers/src/filtered/filtered.cc|s/if (m_correct) correct_momentum(s);/(void)m_correct;/"
  "FEM thickness scaling halved|reference_fem/src/grid.hh|s/const double t = dim == 2 ? mat.thickness : 1.0;/const double t = dim == 2 ? 0.5 * mat.thickness : 1.0;/"
  "strain limit skipped|core/solvers/src/filtered/filtered.cc|s/if (m_strain_limit > 0) limit_strain(s);/(void)m_strain_limit;/"
)
touched=()
restore() { for f in "${touched[@]}"; do git -C "$root" checkout -- "$f"; done; }
trap restore EXIT
survived=0
for m in "${mutations[@]}"; do
  IFS='|' read -r name file expr <<< "$m"
  cp "$file" "$file.orig"
  sed -i "$expr" "$file"
  touched+=("$file")
  if cmp -s "$file" "$file.orig"; then
    echo "MUTATION NOT APPLIED: $name ($file)"; rm "$file.orig"; survived=1; continue
  fi
  rm "$file.orig"
  if ! cmake --build "$build" -j "$(nproc)" > "$build/mutation.log" 2>&1; then
    echo "[$name] does not compile"; tail -5 "$build/mutation.log"; survived=1
  else
    # A mutation can make a solver crawl (CVODE with a wrong Jacobian): 120 s per test, a
    # time-out counts as caught.
    failed=$(cd "$build" && ctest -j "$(nproc)" --timeout 120 2>&1 | grep -E "^\s+[0-9]+ - " | sed -E 's/^\s+[0-9]+ - //; s/ \(.*//' )
    n=$(printf '%s' "$failed" | grep -c . || true)
    if [ "$n" -eq 0 ]; then echo "[$name] SURVIVED: no test failed"; survived=1
    else echo "[$name] caught by $n tests:"; printf '%s\n' "$failed" | sed 's/^/    /'; fi
  fi
  git checkout -- "$file"
done
cmake --build "$build" -j "$(nproc)" > /dev/null 2>&1
[ $survived -eq 0 ] && echo "mutations: every one caught"
exit $survived
