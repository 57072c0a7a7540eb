#!/usr/bin/env bash
# pneumo optimize on the basic cushion rig: the robust against the nominal
# cushion throttle setting (impact speed over loads 2-8 kg and supplies
# 4-7 bar, the same 32 samples for both: docs/optimize_robust.png) and the
# Pareto front of impact speed against time in the cushioning zone over
# z_EC and the cushion length (docs/optimize_pareto.png).
# Usage: bash docs/plot_optimize.sh [PNEUMO_BINARY]   (from the repository root)
set -euo pipefail
bin="${1:-./build/pneumo}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
rig=netlists/cushion_rig.yaml
"$bin" optimize $rig --design z_EC=0:6 --minimize v_impact --constraint "t_cushion<=0.1s" -q -j 2 -o "$out/nominal.yaml"
z_nom=$(awk '/z_EC: \{value:/ {gsub(",", "", $3); print $3}' "$out/nominal.yaml")
common=(--design z_EC=0:6 --minimize v_impact --constraint "mean(t_cushion)<=0.1s"
        --uncertain m_load=uniform:2kg:8kg p_supply=uniform:4bar:7bar --robust quantile:0.95 --samples 32 -q -j 2)
"$bin" optimize $rig "${common[@]}" -o "$out/robust.yaml"
"$bin" optimize $rig "${common[@]}" --at "z_EC=$z_nom" -o "$out/nominal_on_samples.yaml"
z_rob=$(awk '/z_EC: \{value:/ {gsub(",", "", $3); print $3}' "$out/robust.yaml")
# The impact speeds of the 32 samples, sorted: an empirical distribution.
values() { awk '/^  v_impact:/ {f=1} f && /values:/ {sub(/.*values: \[/, ""); sub(/\]\}.*/, ""); gsub(",", "\n"); print; exit}' "$1" | sort -g; }
values "$out/robust.yaml" > "$out/robust.dat"
values "$out/nominal_on_samples.yaml" > "$out/nominal.dat"
for fmt in png svg; do
  if [ "$fmt" = png ]; then term="pngcairo size 800,480 font 'sans,10'"; else term="svg size 800,480"; fi
  gnuplot <<GP
set terminal $term
set output "docs/optimize_robust.$fmt"
set termoption noenhanced
set title "impact speed over loads 2-8 kg and supplies 4-7 bar (32 Latin hypercube samples)"
set xlabel "v_impact [m/s]"
set ylabel "share of the samples"
set grid
set key bottom right
set arrow from graph 0, first 0.95 to graph 1, first 0.95 nohead dt 2 lc rgb "#888888"
plot "$out/nominal.dat" using 1:(\$0/31.0) with steps lw 2 title sprintf("nominal optimum z_EC = %.3f rev", $z_nom), \
     "$out/robust.dat" using 1:(\$0/31.0) with steps lw 2 title sprintf("robust optimum z_EC = %.3f rev (95 %% quantile minimised)", $z_rob)
GP
done
"$bin" optimize $rig --design z_EC=0.3:6 cylinder.cushion_length=10mm:30mm --minimize v_impact,t_cushion --pareto -q -j 2 \
  -o "$out/pareto.yaml"
cp "$out/pareto.pareto.png" docs/optimize_pareto.png
cp "$out/pareto.pareto.svg" docs/optimize_pareto.svg
