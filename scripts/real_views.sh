#!/usr/bin/env bash
# Regenerates the pictures of docs/camera_models.md from the real calibrations and their images
# with dps-rig: perspective views, a check overlay and the cameras' footprints; and the lane
# finder's boundaries on the surround rig's left and right stills (docs/detection.md).
#   scripts/real_views.sh [OUT_DIR]     (default docs/images; uses ${DPS_BUILD_DIR:-build}/tools/dps-rig)
# The shared images whose licence keeps them out of the project (KITTI-360, the GPL fisheye) are
# drawn only when OUT_DIR is not inside docs/.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
out="$(realpath -m "${1:-$here/docs/images}")"
rig_tool="${DPS_BUILD_DIR:-$here/build}/tools/dps-rig"
data="$here/data/real/calibrations"
shared="$here/../shared/data/real_calibrations"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"
quiet() { local log; log=$("$@" 2>&1) || { echo "failed: $*" >&2; echo "$log" >&2; return 1; }; }

# The mirror camera (its calibration is for columns 300..1599 of the 1920x1080 frame).
quiet "$rig_tool" import --format ocam "$data/ocam_catadioptric_kuanli/calib_results.txt" --name left --out "$work/mirror.yaml"
quiet "$rig_tool" view "$work/mirror.yaml" --camera left --image "$data/ocam_catadioptric_kuanli/example.jpg" --crop 300,0 \
  --yaw-deg 125 --pitch-deg 5 --fov-deg 70 --size 640x480 --out "$out/real_mirror_view.jpg"

# The OCamCalib toolbox's sample wide-angle camera, looking along its axis.
quiet "$rig_tool" import --format ocam "$data/ocam_fisheye_ocamcalib_sample/calib_results_fisheye.txt" --name left --axis out \
  --out "$work/sample.yaml"
quiet "$rig_tool" view "$work/sample.yaml" --camera left --image "$data/ocam_fisheye_ocamcalib_sample/test_fisheye.jpg" \
  --yaw-deg -90 --fov-deg 110 --size 640x480 --out "$out/real_ocam_sample_view.jpg"

# The four surround fisheyes of one car (PJLab), with their extrinsics; a unit of their files is
# taken as 0.5 m (the cameras come out 1.8 m apart across the car).
pj="$data/ocam_surround_pjlab"
quiet "$rig_tool" import --format pjlab-ocam "$pj"/intrinsic/*.json "$pj"/extrinsic/*.json --unit-m 0.5 \
  --bev-height front_camera=6.07826,left_camera=6.25217,back_camera=6.31014,right_camera=6.28116 --out "$work/surround.yaml"
quiet "$rig_tool" show "$work/surround.yaml" --out "$out/real_surround_footprints.png" --range 8
if [ -d "$shared/ocam_surround_pjlab/imgs" ]; then
  imgs="$shared/ocam_surround_pjlab/imgs"
  quiet "$rig_tool" check "$work/surround.yaml" --images "front_camera=$imgs/Front.png" --range 10 --ext jpg --out "$work/check"
  cp "$work/check/check_front_camera.jpg" "$out/real_surround_check_front.jpg"
  for cam in front:0 left:-90 back:180 right:90; do
    name="${cam%%:*}"; yaw="${cam##*:}"
    file="$(tr '[:lower:]' '[:upper:]' <<< "${name:0:1}")${name:1}"
    quiet "$rig_tool" view "$work/surround.yaml" --camera "${name}_camera" --image "$imgs/$file.png" --yaw-deg "$yaw" \
      --pitch-deg 15 --fov-deg 100 --size 480x360 --out "$out/real_surround_${name}_view.jpg"
  done
  # The lane finder on the left and right cameras' stills (docs/detection.md): a drive of one frame
  # with the car standing, dps-process, and its lanes.csv drawn over both images.
  process_tool="${DPS_BUILD_DIR:-$here/build}/tools/dps-process"
  mkdir -p "$work/lanes_drive/left" "$work/lanes_drive/right"
  quiet "$rig_tool" import --format pjlab-ocam "$pj"/intrinsic/*.json "$pj"/extrinsic/*.json --unit-m 0.5 \
    --bev-height front_camera=6.07826,left_camera=6.25217,back_camera=6.31014,right_camera=6.28116 \
    --name back,front,left,right --out "$work/lanes_drive/rig.yaml"
  cp "$imgs/Left.png" "$work/lanes_drive/left/000000.png"
  cp "$imgs/Right.png" "$work/lanes_drive/right/000000.png"
  printf 't,speed,yaw_rate\n0,0,0\n1,0,0\n' > "$work/lanes_drive/can.csv"
  quiet "$process_tool" "$work/lanes_drive" --out "$work/lanes_out" --no-video --quiet
  quiet "$rig_tool" check "$work/lanes_drive/rig.yaml" --images "left=$imgs/Left.png,right=$imgs/Right.png" \
    --lanes "$work/lanes_out/lanes_drive/lanes.csv" --range 8 --ext jpg --out "$work/lanes_check"
  cp "$work/lanes_check/check_left.jpg" "$out/real_lanes_left.jpg"
  cp "$work/lanes_check/check_right.jpg" "$out/real_lanes_right.jpg"
fi

# Not for docs/: KITTI-360's left fisheye (CC BY-NC-SA) and the GPL fisheye.
case "$out" in
  "$here"/docs*) ;;
  *)
    if [ -d "$shared/kitti360_fisheye" ]; then
      k="$shared/kitti360_fisheye"
      quiet "$rig_tool" import --format kitti360 "$k/image_02.yaml" "$k/image_03.yaml" "$k/calib_cam_to_pose.txt" \
        --name left,right --out "$work/kitti.yaml"
      quiet "$rig_tool" view "$work/kitti.yaml" --camera left --image "$k/kitti360_rgb.png" --yaw-deg -60 --fov-deg 100 \
        --out "$out/kitti360_left_view.jpg"
    fi
    ;;
esac
ls "$out"
