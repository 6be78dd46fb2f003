#!/usr/bin/env bash
# Builds the paper from a reproduction (paper/README.md):
#   scripts/build_paper.sh [REPRODUCE_DIR] [OUT_DIR]     (defaults out/reproduce, out/paper)
# 1. `vtb paper-data` turns REPRODUCE_DIR's CSV files into OUT_DIR/data (numbers.tex, table
#    rows, .dat series; every string escaped, every number computed, none typed in the LaTeX);
# 2. each paper/figures/NAME.tex is drawn alone by pgfplots (standalone class) into
#    OUT_DIR/figures/NAME.pdf and REPRODUCE_DIR/figures/NAME.png (report.md shows them);
# 3. paper/vtb.tex is built into OUT_DIR/vtb.pdf with latexmk (BibTeX for paper/references.bib), shell
#    escape off. LaTeX's by-products (aux, logs, the figures' standalone sources) stay in OUT_DIR/build.
# Without LaTeX: one line naming what to install, exit 3, the reproduction's data untouched.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
in=$(realpath -m "${1:-$root/out/reproduce}")
out=$(realpath -m "${2:-$root/out/paper}")
vtb=${VTB_BUILD:-$root/build}/bin/vtb

for tool in latexmk pdflatex pdftoppm; do
  if ! command -v "$tool" >/dev/null; then
    echo "build_paper: $tool not found; install texlive-latex-extra texlive-pictures texlive-latex-recommended" \
      "texlive-fonts-recommended latexmk poppler-utils (scripts/setup.sh does); the data in $in is kept" >&2
    exit 3
  fi
done
[ -f "$in/timing_table.csv" ] || { echo "build_paper: $in/timing_table.csv: no reproduction there (run vtb reproduce)" >&2; exit 1; }

mkdir -p "$out/figures" "$out/build" "$in/figures"
"$vtb" paper-data "$in" "$out/data" >/dev/null
# LaTeX runs in OUT_DIR/build and finds data/ and figures/ in OUT_DIR through TEXINPUTS.
export TEXINPUTS="$root/paper:$out:" BIBINPUTS="$root/paper:"
latex=(latexmk -pdf -interaction=nonstopmode -halt-on-error -quiet
  "-pdflatex=pdflatex -no-shell-escape %O %S")

build() { # JOBNAME: runs latexmk in OUT_DIR/build, prints the log's errors if it fails
  if ! (cd "$out/build" && "${latex[@]}" "$1.tex" >"$1.latexmk.log" 2>&1); then
    echo "build_paper: LaTeX failed on $1; from $out/build/$1.log:" >&2
    grep -A6 '^!' "$out/build/$1.log" >&2 || tail -20 "$out/build/$1.latexmk.log" >&2
    exit 1
  fi
}

for src in "$root"/paper/figures/*.tex; do
  name=$(basename "$src" .tex)
  printf '%s\n' '\documentclass[border=4pt]{standalone}' '\input{preamble.tex}' '\begin{document}' \
    "\\input{figures/$name.tex}" '\end{document}' >"$out/build/figure_$name.tex"
  build "figure_$name"
  mv "$out/build/figure_$name.pdf" "$out/figures/$name.pdf"
  pdftoppm -png -r 130 -singlefile "$out/figures/$name.pdf" "$in/figures/$name"
done
cp "$root/paper/vtb.tex" "$out/build/vtb.tex"
build vtb
mv "$out/build/vtb.pdf" "$out/vtb.pdf"
echo "$out/vtb.pdf"
