#!/usr/bin/env bash
# Builds libFuzzer harnesses for dps's readers with clang (build-fuzz/, -DDPS_FUZZ=ON: ASan + UBSan,
# coverage-guided) and runs each for SECONDS (default 60) from a seed corpus of the project's own
# files. A crash, a sanitizer report, a hang (> 20 s) or an exception other than dps::Error is a
# finding: its input is written to build-fuzz/findings/ and the script fails.
#   scripts/fuzz.sh [SECONDS]        readers: csv rig scene marks disparity ocam
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
FUZZ_DIR=${DPS_FUZZ_BUILD_DIR:-$ROOT/build-fuzz}
SECONDS_EACH=${1:-60}
READERS=(csv rig scene marks disparity ocam)
if ! command -v clang++ >/dev/null 2>&1; then
  echo "fuzz: clang++ not found (install it with: sudo apt-get install -y clang)" >&2
  exit 1
fi
CC=clang CXX=clang++ cmake -S "$ROOT" -B "$FUZZ_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DDPS_FUZZ=ON \
  -DDPS_BUILD_TESTS=OFF -DDPS_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build "$FUZZ_DIR" -j "$(nproc 2>/dev/null || echo 2)" --target "${READERS[@]/#/fuzz_}"

# Seeds: the project's own files of each kind, and the inputs of earlier findings.
seeds="$FUZZ_DIR/seeds"
rm -rf "$seeds" && mkdir -p "$seeds"/{csv,rig,scene,marks,disparity,ocam} "$FUZZ_DIR/findings"
cp "$ROOT"/data/rigs/*.yaml "$seeds/rig/"
cp "$ROOT"/data/scenes/*.yaml "$seeds/scene/"
find "$ROOT/data/real/calibrations" -name 'calib_results*.txt' -exec cp {} "$seeds/ocam/" \;
head -c 4000 "$ROOT/data/real/can_logs/comma2k19/can_speed.csv" > "$seeds/csv/can.csv"
printf 'frame,t\n0,0\n1,0.033\n2,0.067\n' > "$seeds/csv/frames.csv"
printf 'frame,t,source,id,x,z,range,x_min,x_max,z_min,z_max,n_points\n0,0,front,0,0.5,8,8.02,-0.4,1.3,8,12,40\n' > "$seeds/csv/detections.csv"
printf 'frame,t,track,x,z,vx,vz,sigma_x,sigma_z,age\n0,0,1,0.5,8,0,-1,0.1,0.2,3\n' > "$seeds/csv/tracks.csv"
printf 'frame,t,id,kind,x,z,heading_deg,length,width,height,vx,vz\n0,0,1,car,0,10,0,4.5,1.8,1.5,0,0\n' > "$seeds/csv/truth.csv"
printf 'frame,t,boundary,offset,heading_deg,curvature,type,confidence\n0,0,left,-1.75,0,0,dashed,1\n' > "$seeds/csv/lanes.csv"
printf 'frame,t,lp,lane_width,heading_deg,event\n0,0,0.1,3.5,0,\n1,0.07,0.2,3.5,1,right\n' > "$seeds/csv/ego_lane.csv"
printf 'camera,line,axis,u,v\nleft,1,Z,100,150\nleft,1,Z,120,170\nleft,1,Z,140,190\n' > "$seeds/marks/marks.csv"
printf 'Pf\n4 2\n-1.0\n' > "$seeds/disparity/d.pfm" && head -c 32 /dev/zero >> "$seeds/disparity/d.pfm"
for r in "${READERS[@]}"; do
  [ -d "$ROOT/tests/fuzz/regressions/$r" ] && cp "$ROOT/tests/fuzz/regressions/$r"/* "$seeds/$r/" 2>/dev/null || true
done

status=0
for r in "${READERS[@]}"; do
  corpus="$FUZZ_DIR/corpus/$r"
  mkdir -p "$corpus"
  echo "fuzz_$r: ${SECONDS_EACH} s" >&2
  # The YAML readers give OpenCV's parser 10 s (util/yaml_guard.cpp); a file it loops on is
  # refused and the parser's thread left running, its memory in use: no leak check for them.
  case $r in rig|scene) leaks=0 ;; *) leaks=1 ;; esac
  if ! ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=$leaks" \
       "$FUZZ_DIR/fuzz_$r" -max_total_time="$SECONDS_EACH" -timeout=20 -rss_limit_mb=4096 -print_final_stats=1 \
       -detect_leaks=$leaks \
       -artifact_prefix="$FUZZ_DIR/findings/$r-" "$corpus" "$seeds/$r" 2> "$FUZZ_DIR/fuzz_$r.log"; then
    echo "fuzz_$r: FINDING (see $FUZZ_DIR/fuzz_$r.log and $FUZZ_DIR/findings/)" >&2
    status=1
  fi
  grep -E "^(Done|stat::number_of_executed_units)" "$FUZZ_DIR/fuzz_$r.log" | tail -1 >&2 || true
  echo "fuzz_$r: corpus $(ls "$corpus" | wc -l) inputs" >&2
done
exit $status
