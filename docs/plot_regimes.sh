#!/usr/bin/env bash
# The three cushioning regimes of paper [1] section 4 on the basic rig (5 bar
# absolute, 3.7 kg): z_EC = 0.1, 1.5 and 6 rev, position and cushion pressure
# over time, one figure (docs/cushion_regimes.png / .svg).
# Usage: bash docs/plot_regimes.sh [PNEUMO_BINARY]   (from the repository root)
set -euo pipefail
bin="${1:-./build/pneumo}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
for z in 0.1 1.5 6; do
  "$bin" simulate netlists/cushion_rig.yaml --set "z_EC=$z" -o "$out/z$z.csv" -q
done
for fmt in png svg; do
  if [ "$fmt" = png ]; then term="pngcairo size 900,700"; else term="svg size 900,700"; fi
  gnuplot <<GP
set terminal $term
set output "docs/cushion_regimes.$fmt"
set datafile separator ","
set termoption noenhanced
set key bottom right
set multiplot layout 2,1 title "basic cushion rig, 5 bar abs, 3.7 kg: the three regimes of paper [1]"
set xrange [0.25:0.9]
set ylabel "x [mm]"
set yrange [70:102]
set grid
plot "$out/z0.1.csv" using 1:(\$2*1000) with lines lw 2 title "z_EC = 0.1 rev (overdamped: springs back, creeps in)", \
     "$out/z1.5.csv" using 1:(\$2*1000) with lines lw 2 title "z_EC = 1.5 rev (well adjusted)", \
     "$out/z6.csv"   using 1:(\$2*1000) with lines lw 2 title "z_EC = 6 rev (hits the head)"
set ylabel "p_EC [bar abs]"
set key top right
set yrange [*:*]
set xlabel "t [s]"
plot "$out/z0.1.csv" using 1:(\$5/1e5) with lines lw 2 title "0.1 rev", \
     "$out/z1.5.csv" using 1:(\$5/1e5) with lines lw 2 title "1.5 rev", \
     "$out/z6.csv"   using 1:(\$5/1e5) with lines lw 2 title "6 rev"
unset multiplot
GP
done
echo "wrote docs/cushion_regimes.png and docs/cushion_regimes.svg"
