#!/usr/bin/env bash
# The main job on a built-in default: installs what is missing, builds (Release), synthesises a
# drive (two omni cameras, a lead car approaching and receding), processes it into the surround
# map and detections, scores them against the drive's ground truth, and says what is where.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${DPS_BUILD_DIR:-$ROOT/build}
OUT=${DPS_DEMO_OUT:-$ROOT/out}
SCENE=${1:-lead_car}
"$ROOT/scripts/build.sh"
T="$BUILD_DIR/tools"
mkdir -p "$OUT"
"$T/dps-synth" "$ROOT/data/scenes/$SCENE.yaml" --out "$OUT/drives/$SCENE" --force
"$T/dps-process" "$OUT/drives/$SCENE" --out "$OUT/results" --force --map-png
"$T/dps-eval" --detections "$OUT/results/$SCENE/detections.csv" --tracks "$OUT/results/$SCENE/tracks.csv" \
  --truth "$OUT/drives/$SCENE/truth.csv" --frames "$OUT/drives/$SCENE/frames.csv" \
  --lanes "$OUT/results/$SCENE/lanes.csv" --truth-lanes "$OUT/drives/$SCENE/truth_lanes.csv" \
  --ego-lane "$OUT/results/$SCENE/ego_lane.csv" --truth-ego-lane "$OUT/drives/$SCENE/truth_ego_lane.csv" \
  --rig "$OUT/drives/$SCENE/rig.yaml" --masks "$OUT/drives/$SCENE/truth_masks" --json "$OUT/results/$SCENE/scores.json" | tee "$OUT/results/$SCENE/scores.txt"
echo
echo "Drive (synthetic, with truth):  $OUT/drives/$SCENE/"
VIDEO="none (no encoder)"
for v in map.mp4 map.avi; do
  if [ -f "$OUT/results/$SCENE/$v" ]; then VIDEO="$OUT/results/$SCENE/$v"; break; fi
done
echo "Surround map video:             $VIDEO   (frames: $OUT/results/$SCENE/map/)"
echo "Detections / tracks / lanes:    $OUT/results/$SCENE/detections.csv, tracks.csv, lanes.csv, ego_lane.csv"
head -n 4 "$OUT/results/$SCENE/detections.csv" | column -t -s, 2>/dev/null || head -n 4 "$OUT/results/$SCENE/detections.csv"
echo "Scores (DESIGN.md §5):          $OUT/results/$SCENE/scores.txt, scores.json"
echo "Other scenes: $0 overtaking | parked_cars | parked_left | left_turn | truck_far | empty_road"
