#!/usr/bin/env bash
# Compares two builds on the robustness battery's drives, family by family, for the rule a change
# to the detectors is kept by: the report seeds improve and no scene family gets worse.
# Both builds process the same rendered drives (rendered once, by the base build, into the layout
# scripts/robustness_table.sh uses, so the two share renders); each drive is scored by dps-eval as
# there. Printed per family and size: detections' recall and precision pooled over the drives, the
# drives' median and 10th percentile of each, the tracks' velocity error (median and 90th
# percentile over the drives; and the median over the drives of the moving objects' own median,
# dps-eval's moving_velocity_error_median_mps), identity switches and the number of detections; a
# family is marked WORSE when any of these moved the wrong way (on the empty roads: more
# detections), and the exit status is 1 when any family is.
#
# Usage: scripts/battery_compare.sh BASE_BUILD_DIR CANDIDATE_BUILD_DIR [WORK_DIR]
#   (build dirs as DPS_BUILD_DIR gives them, with tools/ built; WORK_DIR default out/robustness)
#   SEEDS="1000 1001"   the seeds (default the report set 1000..1007; below 1000 the tuning set)
#   SIZES="320x240"     the image sizes (default "640x480 320x240")
#   FAMILIES="lead_car" the scenes (default every shipped drive scene)
#   ARGS="--rear"       extra dps-process options for both builds
set -euo pipefail
if [ $# -lt 2 ] || [ "$1" = --help ]; then
  sed -n '2,18p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
  [ "${1:-}" = --help ] && exit 0 || exit 2
fi
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=scripts/battery_drives.sh
. "$ROOT/scripts/battery_drives.sh"
BASE=$1 CAND=$2
WORK=${3:-$ROOT/out/robustness}
SEEDS=${SEEDS:-"1000 1001 1002 1003 1004 1005 1006 1007"}
SIZES=${SIZES:-"640x480 320x240"}
FAMILIES=${FAMILIES:-"lead_car overtaking overtaking_right following cut_in stop_and_go parked_cars parked_left left_turn truck_far empty_road empty_turn"}
for b in "$BASE" "$CAND"; do
  for t in dps-synth dps-process dps-eval; do
    [ -x "$b/tools/$t" ] || { echo "battery_compare.sh: $b/tools/$t: not built" >&2; exit 2; }
  done
done
start=$(date +%s)
for size in $SIZES; do
  drives=()
  for family in $FAMILIES; do
    for seed in $SEEDS; do drives+=("$WORK/$size/drives/${family}_$seed"); done
  done
  # Rendered by the base build; a complete drive is reused.
  for drive in "${drives[@]}"; do battery_render "$BASE/tools" "$ROOT" "$size" "$drive"; done
  echo "battery_compare.sh: $size rendered ($(( $(date +%s) - start )) s)" >&2
  for label in base candidate; do
    build=$BASE
    [ $label = candidate ] && build=$CAND
    out="$WORK/$size/compare/$label"
    rm -rf "$out"
    mkdir -p "$out"
    # shellcheck disable=SC2086
    "$build/tools/dps-process" "${drives[@]}" --out "$out" --force --quiet --no-video --jobs 2 ${ARGS:-} || true
    for drive in "${drives[@]}"; do
      battery_score "$build/tools" "$drive" "$out/$(basename "$drive")" "$out/$(basename "$drive").json"
    done
    echo "battery_compare.sh: $size $label processed and scored ($(( $(date +%s) - start )) s)" >&2
  done
done
python3 - "$WORK" "$SIZES" "$FAMILIES" "$SEEDS" <<'PY'
import json, os, sys
work, sizes, families, seeds = sys.argv[1], sys.argv[2].split(), sys.argv[3].split(), sys.argv[4].split()

def q(values, p):
    v = sorted(values)
    return v[min(len(v) - 1, int(p * (len(v) - 1) + 0.5))] if v else None

def family_figures(size, label, family):
    drives = []
    for seed in seeds:
        path = f"{work}/{size}/compare/{label}/{family}_{seed}.json"
        if os.path.exists(path):
            drives.append(json.load(open(path)))
    objects = sum(e["detections"]["overall"]["objects"] for e in drives)
    detections = sum(e["detections"]["overall"]["detections"] for e in drives)
    found = sum(e["detections"]["overall"]["recall"] * e["detections"]["overall"]["objects"] for e in drives)
    right = sum(e["detections"]["overall"]["precision"] * e["detections"]["overall"]["detections"] for e in drives)
    recalls = [e["detections"]["overall"]["recall"] for e in drives if e["detections"]["overall"]["objects"]]
    precisions = [e["detections"]["overall"]["precision"] for e in drives if e["detections"]["overall"]["detections"]]
    velocity = [e["tracks"]["overall"]["velocity_error_median_mps"] for e in drives
                if e.get("tracks") and e["tracks"]["overall"]["velocity_error_median_mps"] is not None]
    moving = [e["tracks"]["overall"].get("moving_velocity_error_median_mps") for e in drives if e.get("tracks")]
    moving = [v for v in moving if v is not None]
    # Higher is better for the first six, lower for the rest.
    return {"drives": len(drives), "detections": detections,
            "recall": found / objects if objects else None, "precision": right / detections if detections else None,
            "recall median": q(recalls, 0.5), "precision median": q(precisions, 0.5),
            "recall p10": q(recalls, 0.1), "precision p10": q(precisions, 0.1),
            "velocity median": q(velocity, 0.5), "velocity p90": q(velocity, 0.9),
            "moving velocity median": q(moving, 0.5),
            "switches": sum(e.get("id_switches") or 0 for e in drives)}

higher = ["recall", "precision", "recall median", "precision median", "recall p10", "precision p10"]
lower = ["velocity median", "velocity p90", "moving velocity median", "switches"]
fmt = lambda v: "-" if v is None else (str(v) if isinstance(v, int) else f"{v:.3f}")
worse_any = False
for size in sizes:
    print(f"\n{size}: base -> candidate")
    print("| family | drives | " + " | ".join(higher + lower) + " | detections | verdict |")
    print("| --- " * (len(higher) + len(lower) + 4) + "|")
    for family in families:
        a, b = family_figures(size, "base", family), family_figures(size, "candidate", family)
        # Ties: differences under 0.0005 in a fraction, 0.005 m/s in a velocity.
        worse = [k for k in higher if a[k] is not None and (b[k] is None or b[k] < a[k] - 5e-4)]
        worse += [k for k in lower if b[k] is not None and (a[k] is None or b[k] > a[k] + (0 if k == "switches" else 5e-3))]
        if family.startswith("empty"):  # no objects: any detection is false
            worse = ["detections"] if b["detections"] > a["detections"] else []
        cells = [f"{fmt(a[k])} -> {fmt(b[k])}" if a[k] != b[k] else fmt(a[k]) for k in higher + lower + ["detections"]]
        verdict = "WORSE: " + ", ".join(worse) if worse else "same or better"
        worse_any = worse_any or bool(worse)
        print(f"| {family} | {a['drives']} | " + " | ".join(cells) + f" | {verdict} |")
print("\nverdict: " + ("some family worse (not kept by the battery rule)" if worse_any else "no family worse"))
sys.exit(1 if worse_any else 0)
PY
