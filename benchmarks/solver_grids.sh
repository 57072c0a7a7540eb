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

# the cushion rig with the full cylinder model: p_supply 3-9 bar, load
# 1-20 kg, cushion throttle 0.2-3 rev, wall heat 10-200 W/(m2 K):
# 7 x 6 x 6 x 2 = 504 points.
grid cushion_rig_full "$here/../netlists/cushion_rig_full.yaml" \
  --grid "p_supply=3 bar:9 bar:7" --grid "m_load=1 kg:20 kg:6" --grid "z_EC=0.2 rev:3 rev:6" \
  --grid "wall_alpha=10 W/(m2*K):200 W/(m2*K):2"

# the five-cylinder assembly line: p_supply 4-8 bar, loads of A and C,
# flow controls of A and D: 5 x 4 x 4 x 3 x 3 = 720 points.
grid assembly_line "$here/../netlists/assembly_line.yaml" \
  --grid "p_supply=5 bar:9 bar:5" --grid "load_A.m=0.2 kg:5 kg:4" --grid "load_C.m=1 kg:20 kg:4" \
  --grid "flow_A_rod.C=0.03 dm3/(s*bar):0.3 dm3/(s*bar):3" --grid "flow_D_rod.C=0.1 dm3/(s*bar):1 dm3/(s*bar):3"

# the meter-out cylinder drawn as in FluidSIM, valve ports straight into the
# flow controls (junctions without volume): the grid of meter_out above.
grid meter_out_direct "$here/meter_out_direct_grid.yaml" \
  --grid p_s=501325:801325:7 --grid m_load=1:10:6 \
  --grid C_cap=0.5e-9:3e-9:6 --grid C_rod=0.5e-9:3e-9:6

# the cushion rig as shipped: p_supply 3-9 bar, load 1-20 kg, cushion
# throttle 0.2-3 rev, valve opening 5-50 ms: 5 x 5 x 5 x 4 = 500 points.
grid cushion_rig "$here/../netlists/cushion_rig.yaml" \
  --grid "p_supply=3 bar:9 bar:5" --grid "m_load=1 kg:20 kg:5" --grid "z_EC=0.2 rev:3 rev:5" \
  --grid "t_switch=5 ms:50 ms:4"

# tank filling: source 1.5-10 bar at -20-80 degC into 0.1-20 L:
# 10 x 5 x 10 = 500 points.
grid tank_filling "$here/../netlists/tank_filling.yaml" \
  --grid "p_source=1.5 bar:10 bar:10" --grid "T_source=253.15 K:353.15 K:5" --grid "V_tank=0.1 L:20 L:10"

# the energy-balance cylinder of paper [3]: inlet area, supply 2-8 bar g,
# load 0.2-5 kg, wall heat 5-100 W/(m2 K): 5 x 5 x 5 x 4 = 500 points.
grid bracha_cylinder "$here/../netlists/bracha_cylinder.yaml" \
  --grid "A_in=0.001 mm2:0.01 mm2:5" --grid "p_supply=2 barg:8 barg:5" --grid "m_load=0.2 kg:5 kg:5" \
  --grid "wall_alpha=5 W/(m2*K):100 W/(m2*K):4"

# the movement-time rig of paper [2]: supply 0.3-0.7 MPa g, load 0.5-10 kg,
# throttle 0.3-3 mm2 (impacts up to 3 m/s on the rubber bumper):
# 5 x 10 x 10 = 500 points.
grid movement_time_rig "$here/../netlists/movement_time_rig.yaml" \
  --grid "p_supply=0.3 MPag:0.7 MPag:5" --grid "m_load=0.5 kg:10 kg:10" --grid "A_throttle=0.3 mm2:3 mm2:10"
