# Sourced by the CLI test scripts (usage: SCRIPT VTB SRC_DIR): sets vtb, src, a scratch folder
# $work removed on exit, and check NAME CONDITION, which prints ok/FAIL and remembers a failure
# in $fail (the script ends with `exit $fail`).
set -u
vtb=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0
check() { # NAME CONDITION
  if eval "$2"; then echo "ok   $1"; else echo "FAIL $1"; fail=1; fi
}
