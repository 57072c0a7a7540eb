#!/bin/sh
# Robustness grids of everyday circuits (issue 36), run on demand, never in
# CI: every point of each grid must run to t_end. Prints the failures of
# each grid; the sweep CSVs (status and reason per run) stay in OUTDIR.
#   benchmarks/solver_grids.sh [PNEUMO] [OUTDIR] [THREADS]
set -eu
here=$(cd "$(dirname "$0")" && pwd)
pneumo=${1:-$here/../build/pneumo}
out=${2:-solver_grids}
threads=${3:-2}
mkdir -p "$out"

grid() {  # NAME NETLIST GRID...
  name=$1 netlist=$2
  shift 2
  start=$(date +%s)
  "$pneumo" sweep "$netlist" -q -j "$threads" -o "$out/$name.csv" "$@" || true
  runs=$(($(wc -l < "$out/$name.csv") - 1))
  failed=$(grep -c ',failed,' "$out/$name.csv" || true)
  echo "$name: $failed of $runs runs failed ($(($(date +%s) - start)) s)"
  grep ',failed,' "$out/$name.csv" | head -3 | cut -c1-300
}

# meter-out cylinder: 4-7 bar gauge, 1-10 kg, both flow controls' C
# 0.05-0.3 dm3/(s*bar): 7 x 6 x 6 x 6 = 1512 points.
grid meter_out "$here/meter_out_grid.yaml" \
  --grid p_s=501325:801325:7 --grid m_load=1:10:6 \
  --grid C_cap=0.5e-9:3e-9:6 --grid C_rod=0.5e-9:3e-9:6

# sequence A+ B+ B- A-: p_supply 3-9 bar, load A 0.5-30 kg, flow_A_rod's C
# 0.05-1 dm3/(s*bar): 7 x 8 x 8 = 448 points.
grid sequence_ab "$here/../netlists/sequence_ab.yaml" \
  --grid p_supply=3e5:9e5:7 --grid load_A.m=0.5:30:8 --grid flow_A_rod.C=0.5e-9:1e-8:8
