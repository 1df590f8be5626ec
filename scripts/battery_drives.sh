# The robustness battery's drives, rendered and scored one way for scripts/robustness_table.sh and
# scripts/battery_compare.sh (sourced by both). A drive is WORK/SIZE/drives/FAMILY_SEED.

# battery_render TOOLS ROOT SIZE DRIVE: renders the drive (dps-synth --randomize SEED of the shipped
# scene FAMILY) unless it is complete.
battery_render() {
  local tools=$1 root=$2 size=$3 drive=$4
  local name family seed
  name=$(basename "$drive")
  family=${name%_*}
  seed=${name##*_}
  if [ ! -f "$drive/truth.csv" ] || [ ! -d "$drive/truth_masks" ]; then
    "$tools/dps-synth" "$root/data/scenes/$family.yaml" --size "$size" --randomize "$seed" --out "$drive" --force --quiet
  fi
}

# battery_score TOOLS DRIVE OUT JSON: scores the drive's outputs in OUT (dps-eval within 20 m
# against its rendering rig and truth masks, and its lanes where it has lane truth) into JSON; no
# outputs (the drive failed): no JSON.
battery_score() {
  local tools=$1 drive=$2 out=$3 json=$4
  if [ ! -f "$out/detections.csv" ]; then
    rm -f "$json"
    return 0
  fi
  local lanes=()
  if [ -f "$drive/truth_lanes.csv" ]; then
    lanes=(--truth-lanes "$drive/truth_lanes.csv")
    [ -f "$out/lanes.csv" ] && lanes+=(--lanes "$out/lanes.csv")
    [ -f "$out/ego_lane.csv" ] && [ -f "$drive/truth_ego_lane.csv" ] &&
      lanes+=(--ego-lane "$out/ego_lane.csv" --truth-ego-lane "$drive/truth_ego_lane.csv")
  fi
  "$tools/dps-eval" --detections "$out/detections.csv" --tracks "$out/tracks.csv" --truth "$drive/truth.csv" \
    --frames "$drive/frames.csv" --rig "$drive/rig_true.yaml" --masks "$drive/truth_masks" ${lanes[@]+"${lanes[@]}"} \
    --json "$json" >/dev/null
}
