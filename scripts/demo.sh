#!/usr/bin/env bash
# The main job on a built-in default: installs what is missing, builds (Release), synthesises a
# drive (a lead car approaching and receding, two omni cameras) and a calibration scene into out/,
# and says what is where.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${DPS_BUILD_DIR:-$ROOT/build}
OUT=${DPS_DEMO_OUT:-$ROOT/out}
"$ROOT/scripts/build.sh"
mkdir -p "$OUT"
"$BUILD_DIR/tools/dps-synth" "$ROOT/data/scenes/lead_car.yaml" --out "$OUT/lead_car" --video --force
"$BUILD_DIR/tools/dps-synth" "$ROOT/data/scenes/calibration.yaml" --out "$OUT/calibration" --force
echo
echo "Synthetic drive:     $OUT/lead_car  (left/, right/ PNGs, left.avi, right.avi, can.csv, truth.csv)"
echo "Calibration scene:   $OUT/calibration  (marks.csv, rig.yaml nominal, rig_true.yaml)"
echo "First truth rows:"
head -n 4 "$OUT/lead_car/truth.csv" | column -t -s, 2>/dev/null || head -n 4 "$OUT/lead_car/truth.csv"
echo "Look at: $OUT/lead_car/left/000045.png (the lead car is nearest at frame 45)"
