#!/usr/bin/env bash
# The robustness battery: every shipped drive scene (the scene families) rendered with randomised
# cameras, mountings, calibration errors, appearance and objects (dps-synth --randomize SEED),
# processed (dps-process) with the rig the drive comes with (the calibration error included) and
# scored (dps-eval, within 20 m, every object a camera of the rendering rig sees, DESIGN.md §5),
# then summarised per family, per zone and per camera family into docs/robustness.md.
#
# Seeds: the report set is 1000 and up; seeds below 1000 are the tuning set, free to look at while
# changing the code. Only report seeds go into docs/robustness.md.
#
# Usage: scripts/robustness_table.sh [WORK_DIR]       (default out/robustness; builds first)
#   SEEDS="1000 1001"   the seeds (default 1000..1007)
#   SIZES="320x240"     the image sizes (default "640x480 320x240")
#   FAMILIES="lead_car" the scenes (default every shipped drive scene)
#   DOC=path            where the table goes (default docs/robustness.md; "-" = stdout)
#   CALIBRATE_SIZES="320x240"  sizes whose drives are also processed with their rendering rig
#                       and with the rig dps-calibrate estimates from marks of a calibration scene
#                       rendered with the drive's own rig (default both sizes; "" = none)
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${DPS_BUILD_DIR:-$ROOT/build}
WORK=${1:-$ROOT/out/robustness}
SEEDS=${SEEDS:-"1000 1001 1002 1003 1004 1005 1006 1007"}
SIZES=${SIZES:-"640x480 320x240"}
FAMILIES=${FAMILIES:-"lead_car overtaking overtaking_right following cut_in stop_and_go parked_cars parked_left left_turn truck_far empty_road empty_turn"}
DOC=${DOC:-$ROOT/docs/robustness.md}
CALIBRATE_SIZES=${CALIBRATE_SIZES-"640x480 320x240"}
"$ROOT/scripts/build.sh" >/dev/null
T="$BUILD_DIR/tools"
# shellcheck source=scripts/battery_drives.sh
. "$ROOT/scripts/battery_drives.sh"
mkdir -p "$WORK"
for seed in $SEEDS; do
  if [ "$seed" -lt 1000 ] && [ "$DOC" = "$ROOT/docs/robustness.md" ]; then
    echo "robustness_table.sh: seed $seed is a tuning seed; docs/robustness.md takes report seeds (>= 1000) only" >&2
    exit 2
  fi
done
start=$(date +%s)
for size in $SIZES; do
  drives=()
  for family in $FAMILIES; do
    for seed in $SEEDS; do
      drive="$WORK/$size/drives/${family}_$seed"
      battery_render "$T" "$ROOT" "$size" "$drive"
      drives+=("$drive")
    done
    echo "robustness_table.sh: $size $family rendered ($(( $(date +%s) - start )) s)" >&2
  done
  # Rig variants: the drive processed with its rendering rig (no calibration error), and with the
  # rig dps-calibrate estimates from marks of the parking-lot scene seen by the drive's own rig,
  # starting from the rig the drive came with.
  calibrated=()
  if [[ " $CALIBRATE_SIZES " == *" $size "* ]]; then
    for drive in "${drives[@]}"; do
      name=$(basename "$drive")
      cal="$WORK/$size/calibration/$name" cdrive="$WORK/$size/drives/${name}_calibrated"
      tdrive="$WORK/$size/drives/${name}_true"
      rm -rf "$cdrive" "$tdrive"
      mkdir -p "$tdrive"
      for f in "$drive"/*; do [ "$(basename "$f")" = rig.yaml ] || ln -s "$f" "$tdrive/"; done
      cp "$drive/rig_true.yaml" "$tdrive/rig.yaml"
      calibrated+=("$tdrive")
      # Rendered once, as the drives are (a rerun with other code reuses both).
      if [ ! -f "$cal/marks.csv" ]; then
        "$T/dps-synth" "$ROOT/data/scenes/calibration.yaml" --rig "$drive/rig_true.yaml" \
          --processing-rig "$drive/rig.yaml" --frames 1 --out "$cal" --force --quiet
      fi
      if "$T/dps-calibrate" --rig "$drive/rig.yaml" --marks "$cal/marks.csv" --out "$cal/rig_calibrated.yaml" \
           > "$cal/report.txt" 2>&1; then
        mkdir -p "$cdrive"
        for f in "$drive"/*; do [ "$(basename "$f")" = rig.yaml ] || ln -s "$f" "$cdrive/"; done
        cp "$cal/rig_calibrated.yaml" "$cdrive/rig.yaml"
        calibrated+=("$cdrive")
      fi
    done
  fi
  # A drive that fails to process is reported by dps-process and scored as nothing detected.
  "$T/dps-process" "${drives[@]}" ${calibrated[@]+"${calibrated[@]}"} --out "$WORK/$size/out" --force --quiet \
    --no-video --jobs 2 || true
  for drive in "${drives[@]}" ${calibrated[@]+"${calibrated[@]}"}; do
    name=$(basename "$drive")
    battery_score "$T" "$drive" "$WORK/$size/out/$name" "$WORK/$size/$name.json"
  done
  echo "robustness_table.sh: $size processed and scored ($(( $(date +%s) - start )) s)" >&2
done
target=$DOC
[ "$DOC" = "-" ] && target=/dev/stdout
python3 - "$WORK" "$SIZES" "$FAMILIES" "$SEEDS" "$CALIBRATE_SIZES" > "$target" <<'PY'
import json, os, sys
work, sizes, families, seeds = sys.argv[1], sys.argv[2].split(), sys.argv[3].split(), sys.argv[4].split()
calibrate_sizes = sys.argv[5].split()

def q(values, p):
    v = sorted(x for x in values if x is not None)
    if not v: return None
    return v[min(len(v) - 1, int(p * (len(v) - 1) + 0.5))]

def fmt(v, pct=False):
    if v is None: return "-"
    if isinstance(v, int): return str(v)
    return f"{100 * v:.1f} %" if pct else f"{v:.2f}"

rows = []
for size in sizes:
    for family in families:
        for seed in seeds:
            name = f"{family}_{seed}"
            drive = f"{work}/{size}/drives/{name}"
            r = json.load(open(f"{drive}/randomization.json"))
            codec_file = f"{drive}/video_codec.txt"
            images = open(codec_file).read().strip() if os.path.exists(codec_file) else "PNG"
            row = {"size": size, "family": family, "seed": seed, "camera": r["camera_family"],
                   "images": images, "mirrored": r["mirrored"], "failed": False}
            path = f"{work}/{size}/{name}.json"
            if not os.path.exists(path):
                row["failed"] = True
                rows.append(row)
                continue
            e = json.load(open(path))
            d, t = e["detections"], e.get("tracks")
            o = d["overall"]
            row.update(objects=o["objects"], recall=o["recall"] if o["objects"] else None,
                       precision=o["precision"] if o["detections"] else None,
                       range_error=o["range_error_median_relative"], detections=o["detections"],
                       frames=d["frames"], frames_with=d["frames_with_detections"])
            for z in d.get("zones", []):
                row["zone_" + z["band"]] = z["recall"] if z["objects"] else None
            row["kinds"] = {k["band"]: (k["objects"], k["matched_objects"]) for k in d.get("kinds", [])}
            row["false_causes"] = {s["source"]: s.get("false_causes", {}) for s in d.get("sources", [])}
            for attribute in ("classes", "lanes"):
                a = d.get(attribute) or {}
                row[attribute] = (a.get("correct", 0), a.get("judged", 0))
            lane = e.get("lanes")
            if lane:
                for b in lane["boundaries"]:
                    if b["boundary"] in ("left", "right") and b["truth_frames"]:
                        row["lane_found_" + b["boundary"]] = b["found"] / b["truth_frames"]
                        row["lane_median_" + b["boundary"]] = b["offset_error_median_m"]
                        row["lane_p90_" + b["boundary"]] = b["offset_error_p90_m"]
                row.update(lane_lp=lane["lp_error_median_m"], lane_changes=lane["lane_changes"],
                           lane_changes_found=lane["lane_changes_found"],
                           lane_changes_invented=lane["lane_changes_invented"])
                # The drive's ego lane: the lower found rate and the larger errors of left and right.
                row["lane_found"] = min(row.get("lane_found_left", 0), row.get("lane_found_right", 0))
                row["lane_median"] = max(row.get("lane_median_left") or 0, row.get("lane_median_right") or 0)
                row["lane_p90"] = max(row.get("lane_p90_left") or 0, row.get("lane_p90_right") or 0)
            if t:
                row.update(track_velocity=t["overall"]["velocity_error_median_mps"],
                           moving_velocity=t["overall"]["moving_velocity_error_median_mps"],
                           track_recall=t["overall"]["recall"] if t["overall"]["objects"] else None,
                           track_precision=t["overall"]["precision"] if t["overall"]["detections"] else None,
                           switches=e.get("id_switches"))
            rows.append(row)

def stats(group, key, pct=False, worst_low=True):
    v = [r.get(key) for r in group if not r["failed"]]
    v = [x for x in v if x is not None]
    if not v: return "-"
    lo = q(v, 0.1) if worst_low else q(v, 0.9)
    extreme = min(v) if worst_low else max(v)
    return f"{fmt(q(v, 0.5), pct)} / {fmt(lo, pct)} / {fmt(extreme, pct)}"

print("# Robustness battery\n")
report = all(int(s) >= 1000 for s in seeds)
kind = "**report seeds**" if report else "seeds of the **tuning set** (not for reporting)"
print("Generated by `scripts/robustness_table.sh` from " + kind + " (" + ", ".join(seeds) + "): each")
print("shipped drive scene rendered with `dps-synth --randomize SEED` — a drawn camera family and model,")
print("field of view, mounting, calibration error of up to 0.5° per camera in the rig processed with,")
print("appearance, road detail (repair patches, cracks, kerbs with a raised pavement, grass or gravel")
print("verges), the own car's sill and mirror housings, the story's objects and up to three poles, walls or")
print("pedestrians beside the road, the story mirrored half of the time, MJPG or H.264 video half of the")
print("time (the ranges: `include/dps/synth/randomize.h`) — processed by dps-process and scored by dps-eval within")
print("20 m, every object that a camera of the rendering rig sees counted (DESIGN.md §5: 5 % of its box in")
print("the camera's valid pixels, not hidden by the own car or other objects; the rear and the wedges")
print("between the pipeline's views included). Seeds below 1000 are the tuning set, free to look at while")
print("changing the code; docs/robustness.md shows report seeds only. Rerun one drive: `dps-synth data/scenes/FAMILY.yaml --size WxH --randomize SEED --out d`,")
print("then `dps-process d --out o` and `dps-eval` as in the script.\n")
print("Each cell: median / 10th percentile / worst over the drives (for range and velocity errors the")
print("90th percentile and the largest). Track velocity errors: each drive's median over every matched")
print("object; moving objects': over the objects moving at 0.5 m/s or more (dps-eval's")
print("`moving_velocity_error_median_mps`; the static ones' near-zero errors hide the passing cars'). Targets")
print("(next issue): recall and precision ≥ 0.95, range error ≤ 5 %, no detection on empty roads, moving")
print("objects' velocity error ≤ 0.5 m/s.\n")
def scores(size, name):
    path = f"{work}/{size}/{name}.json"
    if not os.path.exists(path): return None
    o = json.load(open(path))["detections"]["overall"]
    return (o["recall"] if o["objects"] else None, o["precision"] if o["detections"] else None)

for size in sizes:
    group = [r for r in rows if r["size"] == size]
    print(f"## {size}\n")
    print("| family | drives | failed | recall | precision | range error | track velocity error (m/s) | moving objects' velocity error (m/s) | identity switches |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for family in families:
        g = [r for r in group if r["family"] == family]
        failed = sum(r["failed"] for r in g)
        if family.startswith("empty"):
            ok = [r for r in g if not r["failed"]]
            per_frame = [r["detections"] / max(1, r["frames"]) for r in ok]
            share = [r["frames_with"] / max(1, r["frames"]) for r in ok]
            print(f"| {family} (false detections per frame; frames with any) | {len(g)} | {failed} | "
                  f"{fmt(q(per_frame, 0.5))} / {fmt(q(per_frame, 0.9))} / {fmt(max(per_frame) if per_frame else None)} | "
                  f"{fmt(q(share, 0.5), True)} / {fmt(q(share, 0.9), True)} / {fmt(max(share) if share else None, True)} | - | - | - | - |")
            continue
        print(f"| {family} | {len(g)} | {failed} | {stats(g, 'recall')} | {stats(g, 'precision')} | "
              f"{stats(g, 'range_error', True, False)} | {stats(g, 'track_velocity', False, False)} | "
              f"{stats(g, 'moving_velocity', False, False)} | {stats(g, 'switches', False, False)} |")
    print()
    print("Recall by zone (the object's near point ahead of the own car's front, beside it, behind its back):\n")
    print("| family | front | side | rear |")
    print("| --- | --- | --- | --- |")
    for family in families:
        if family.startswith("empty"): continue
        g = [r for r in group if r["family"] == family]
        print(f"| {family} | {stats(g, 'zone_front')} | {stats(g, 'zone_side')} | {stats(g, 'zone_rear')} |")
    print()
    print("False detections within 20 m by what they are (dps-eval's causes, pooled over the family's")
    print("drives; front pair / left camera / right camera): a duplicate of an object another detection")
    print("matched, misplaced near an object none matched (within twice the matching distance), or a")
    print("phantom with no object near:\n")
    print("| family | false detections | duplicate | misplaced | phantom |")
    print("| --- | --- | --- | --- | --- |")
    for family in families:
        g = [r for r in group if r["family"] == family and not r["failed"]]
        counts = [[sum(r.get("false_causes", {}).get(src, {}).get(cause, 0) for r in g) for src in ("front", "left", "right")]
                  for cause in ("duplicate", "misplaced", "phantom")]
        cells = [f"{sum(n)} ({n[0]} / {n[1]} / {n[2]})" for n in counts]
        print(f"| {family} | {sum(map(sum, counts))} | {cells[0]} | {cells[1]} | {cells[2]} |")
    print()
    kinds = sorted({k for r in group if not r["failed"] for k in r.get("kinds", {})})
    if kinds:
        print("Recall by the object's kind (object-frames of every drive pooled; the drives' medians):\n")
        print("| kind | drives | object-frames | recall pooled | recall median / 10th percentile / worst |")
        print("| --- | --- | --- | --- | --- |")
        for kind in kinds:
            g = [r for r in group if not r["failed"] and r.get("kinds", {}).get(kind, (0, 0))[0] > 0]
            n = sum(r["kinds"][kind][0] for r in g)
            m = sum(r["kinds"][kind][1] for r in g)
            for r in g: r["kind_recall"] = r["kinds"][kind][1] / r["kinds"][kind][0]
            print(f"| {kind} | {len(g)} | {n} | {fmt(m / n)} | {stats(g, 'kind_recall')} |")
        print()
    print("Object attributes of the matched detections (object_attributes.h; pooled over the family's")
    print("drives): the class fitting the object's kind (car: vehicle, truck: truck, pedestrian: pedestrian,")
    print("motorbike: pedestrian, pole: pole, wall: unknown), the lane the object's (drives rendered with")
    print("lane truth only):\n")
    print("| family | class right | lane right |")
    print("| --- | --- | --- |")
    for family in families:
        if family.startswith("empty"): continue
        g = [r for r in group if r["family"] == family and not r["failed"]]
        cells = []
        for attribute in ("classes", "lanes"):
            right = sum(r.get(attribute, (0, 0))[0] for r in g)
            judged = sum(r.get(attribute, (0, 0))[1] for r in g)
            cells.append(f"{fmt(right / judged)} of {judged}" if judged else "-")
        print(f"| {family} | {cells[0]} | {cells[1]} |")
    print()
    laned = [r for r in group if not r["failed"] and "lane_lp" in r]
    if laned:
        print("Lanes (lanes.csv and ego_lane.csv against the drive's lane truth, `dps-eval --lanes`; drives")
        print("with lane truth only): the ego lane's left and right boundaries found in the frames where the")
        print("truth has them, their offset errors (each drive's median and 90th percentile), the lateral")
        print("position's median error, and lane changes (found of the truth's; invented), summed:\n")
        print("| family | drives | left / right found | offset error median (m) | offset error p90 (m) | lp error median (m) | lane changes found; invented |")
        print("| --- | --- | --- | --- | --- | --- | --- |")
        for family in families:
            g = [r for r in laned if r["family"] == family]
            if not g: continue
            changes = sum(r["lane_changes"] for r in g)
            print(f"| {family} | {len(g)} | {stats(g, 'lane_found')} | {stats(g, 'lane_median', False, False)} | "
                  f"{stats(g, 'lane_p90', False, False)} | {stats(g, 'lane_lp', False, False)} | "
                  f"{sum(r['lane_changes_found'] for r in g)} of {changes}; {sum(r['lane_changes_invented'] for r in g)} |")
        print("\n(found: the lower of left and right per drive; offset errors: the larger of the two.)\n")
    print("By camera family (every scene but the empty roads):\n")
    print("| camera | drives | recall | precision | range error |")
    print("| --- | --- | --- | --- | --- |")
    for camera in ["hyperbolic", "unified", "fisheye_down", "fisheye_side"]:
        g = [r for r in group if r["camera"] == camera and not r["family"].startswith("empty")]
        if not g: continue
        print(f"| {camera} | {len(g)} | {stats(g, 'recall')} | {stats(g, 'precision')} | {stats(g, 'range_error', True, False)} |")
    print()
    scored = [r for r in group if not r["failed"] and not r["family"].startswith("empty") and r.get("recall") is not None]
    worst = sorted(scored, key=lambda r: min(r["recall"], r["precision"] if r["precision"] is not None else 1))[:8]
    print("Worst drives (lowest of recall and precision):\n")
    print("| family | seed | camera | images | mirrored | recall | precision |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for r in worst:
        print(f"| {r['family']} | {r['seed']} | {r['camera']} | {r['images']} | "
              f"{'yes' if r['mirrored'] else 'no'} | {fmt(r['recall'])} | {fmt(r['precision'])} |")
    if size in calibrate_sizes:
        print("\nThe same drives processed with the rendering rig (no calibration error) and with the rig")
        print("dps-calibrate estimates from marks of the parking-lot scene seen by the drive's own rig")
        print("(starting from the rig with the drawn error); medians over the family's drives:\n")
        print("| family | recall: drawn error / true rig / dps-calibrate | precision: drawn error / true rig / dps-calibrate | calibrations failed |")
        print("| --- | --- | --- | --- |")
        for family in families:
            if family.startswith("empty"): continue
            cols = {"": [], "_true": [], "_calibrated": []}
            cal_failed = 0
            for seed in seeds:
                for suffix in cols:
                    sc = scores(size, f"{family}_{seed}{suffix}")
                    if sc is None and suffix == "_calibrated": cal_failed += 1
                    cols[suffix].append(sc)
            med = lambda k, i: fmt(q([x[i] for x in cols[k] if x is not None], 0.5))
            print(f"| {family} | {med('', 0)} / {med('_true', 0)} / {med('_calibrated', 0)} | "
                  f"{med('', 1)} / {med('_true', 1)} / {med('_calibrated', 1)} | {cal_failed} |")
    failed = [r for r in group if r["failed"]]
    if failed:
        print("\nDrives dps-process could not process: " + ", ".join(f"{r['family']} {r['seed']}" for r in failed))
    print()
PY
echo "robustness_table.sh: wrote $DOC ($(( $(date +%s) - start )) s)" >&2
