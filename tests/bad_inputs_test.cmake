# cmake -DTOOLS=<dir with the tools> -DSOURCE=<project source> -DWORK=<scratch dir> -P bad_inputs_test.cmake
# The catalogue of bad inputs (docs/reliability.md): each case breaks one thing in a good drive,
# scene, rig, marks or detections file, or asks for an output that would destroy an input, and
# asserts what a user must get: a non-zero exit within a time limit (no hang), one line on stderr
# naming the file and the field, line or frame, and nothing under the final output name.
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")

# (A batch of drives reports one line per failed drive: cases named batch_*.)
# bad(<name> <regex the one-line error must match> <output folder that must not appear or "-"> COMMAND ...)
function(bad name regex absent)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
  string(STRIP "${err}" line)
  if(rc EQUAL 0)
    message(FATAL_ERROR "${name}: expected failure: ${ARGN}\n${out}\n${err}")
  elseif(NOT rc MATCHES "^[0-9]+$")
    message(FATAL_ERROR "${name}: no clean exit (${rc}): ${ARGN}\n${err}")
  elseif(line MATCHES "\n" AND NOT name MATCHES "^batch_")
    message(FATAL_ERROR "${name}: the error is not one line:\n${err}")
  elseif(NOT line MATCHES "${regex}")
    message(FATAL_ERROR "${name}: the error does not match '${regex}':\n${err}")
  elseif(NOT absent STREQUAL "-" AND EXISTS "${absent}")
    message(FATAL_ERROR "${name}: ${absent} was written")
  endif()
  set_property(GLOBAL APPEND PROPERTY refused "${name}")
  message(STATUS "ok ${name}: ${line}")
endfunction()

# A good drive to break: 3 frames at 320x240.
execute_process(COMMAND "${TOOLS}/dps-synth" "${SOURCE}/data/scenes/lead_car.yaml" --size 320x240 --frames 3
                        --out "${WORK}/good" --quiet RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "dps-synth could not write the good drive")
endif()
file(READ "${WORK}/good/rig.yaml" good_rig)
file(READ "${WORK}/good/can.csv" good_can)

# A copy of the good drive named <name> under cases/, then the change; processed into out/.
function(broken name)
  file(REMOVE_RECURSE "${WORK}/cases/${name}")
  file(MAKE_DIRECTORY "${WORK}/cases")
  file(COPY "${WORK}/good/" DESTINATION "${WORK}/cases/${name}")
endfunction()
function(process_bad name regex)
  bad(${name} "${regex}" "${WORK}/out/${name}" "${TOOLS}/dps-process" "${WORK}/cases/${name}" --out "${WORK}/out"
      --no-video --quiet ${ARGN})
endfunction()

# rig.yaml
broken(rig_missing)
file(REMOVE "${WORK}/cases/rig_missing/rig.yaml")
process_bad(rig_missing "rig_missing/rig.yaml: file not found")
broken(rig_empty)
file(WRITE "${WORK}/cases/rig_empty/rig.yaml" "")
process_bad(rig_empty "rig_empty/rig.yaml")
broken(rig_endless)
file(WRITE "${WORK}/cases/rig_endless/rig.yaml" "%YAML:1.\n h:0\n:  -\n")
process_bad(rig_endless "rig_endless/rig.yaml")
broken(rig_width_text)
string(REPLACE "width: 320" "width: wide" text "${good_rig}")
file(WRITE "${WORK}/cases/rig_width_text/rig.yaml" "${text}")
process_bad(rig_width_text "rig_width_text/rig.yaml: camera 'left': field 'width'")
broken(rig_model)
string(REPLACE "model: hyperbolic" "model: pinhole" text "${good_rig}")
file(WRITE "${WORK}/cases/rig_model/rig.yaml" "${text}")
process_bad(rig_model "rig_model/rig.yaml: camera 'left': field 'model'")
broken(rig_no_cameras)
file(WRITE "${WORK}/cases/rig_no_cameras/rig.yaml" "%YAML:1.0\n---\nvehicle:\n   length: 4.8\n   width: 1.8\n")
process_bad(rig_no_cameras "rig_no_cameras/rig.yaml.*cameras")
broken(rig_mask_missing)
string(REPLACE "model: hyperbolic" "mask: masks/none.png\n      model: hyperbolic" text "${good_rig}")
file(WRITE "${WORK}/cases/rig_mask_missing/rig.yaml" "${text}")
process_bad(rig_mask_missing "none.png: cannot read the mask image")

# masks/
broken(mask_size)
file(MAKE_DIRECTORY "${WORK}/cases/mask_size/masks")
file(COPY "${SOURCE}/data/real/fisheye_car/images/left.png" DESTINATION "${WORK}/cases/mask_size/masks")
process_bad(mask_size "masks/left.png: the mask is 960x640, the camera's images 320x240")

# can.csv
broken(can_missing)
file(REMOVE "${WORK}/cases/can_missing/can.csv")
process_bad(can_missing "can_missing/can.csv")
broken(can_no_speed)
string(REPLACE "speed" "velocity" text "${good_can}")
file(WRITE "${WORK}/cases/can_no_speed/can.csv" "${text}")
process_bad(can_no_speed "can_no_speed/can.csv: missing column 'speed'")
broken(can_text)
file(WRITE "${WORK}/cases/can_text/can.csv" "t,speed,yaw_rate\n0,10,0\n0.1,fast,0\n")
process_bad(can_text "can_text/can.csv:3: column 'speed'")
broken(can_backwards)
file(WRITE "${WORK}/cases/can_backwards/can.csv" "t,speed,yaw_rate\n0,10,0\n1,10,0\n0.5,10,0\n")
process_bad(can_backwards "can_backwards/can.csv:4")
broken(can_fields)
file(WRITE "${WORK}/cases/can_fields/can.csv" "t,speed,yaw_rate\n0,10,0\n0.1,10\n")
process_bad(can_fields "can_fields/can.csv:3: 2 fields, the header has 3")

# frames.csv
broken(frames_nan)
file(WRITE "${WORK}/cases/frames_nan/frames.csv" "frame,t\n0,0\n1,nan\n2,0.2\n")
process_bad(frames_nan "frames_nan/frames.csv:3: frame 1 has no finite time")
broken(frames_inf)
file(WRITE "${WORK}/cases/frames_inf/frames.csv" "frame,t\n0,0\n1,0.1\n2,inf\n")
process_bad(frames_inf "frames_inf/frames.csv:4")
broken(frames_backwards)
file(WRITE "${WORK}/cases/frames_backwards/frames.csv" "frame,t\n0,0\n1,0.2\n2,0.1\n")
process_bad(frames_backwards "frames_backwards/frames.csv:4: frame 2 at t = 0.1 s does not come after")
broken(frames_all_zero)
file(WRITE "${WORK}/cases/frames_all_zero/frames.csv" "frame,t\n0,0\n1,0\n2,0\n")
process_bad(frames_all_zero "frames_all_zero/frames.csv:3")
broken(frames_numbering)
file(WRITE "${WORK}/cases/frames_numbering/frames.csv" "frame,t\n0,0\n2,0.1\n3,0.2\n")
process_bad(frames_numbering "frames_numbering/frames.csv:3: expected frame 1, got 2")
broken(frames_gap)
file(WRITE "${WORK}/cases/frames_gap/frames.csv" "frame,t\n0,0\n1,0.1\n2,0.3\n")
process_bad(frames_gap "frames_gap/frames.csv: frames 1 and 2 are 0.2 s apart")
broken(frames_short)
file(WRITE "${WORK}/cases/frames_short/frames.csv" "frame,t\n0,0\n1,0.1\n")
process_bad(frames_short "frames_short/frames.csv: 2 frames listed, the images have 3")
broken(frames_huge)
file(WRITE "${WORK}/cases/frames_huge/frames.csv" "frame,t\n0,0\n1e300,0.1\n2,0.2\n")
process_bad(frames_huge "frames_huge/frames.csv:3")

# Images
broken(no_left)
file(REMOVE_RECURSE "${WORK}/cases/no_left/left")
process_bad(no_left "no 'left/'")
broken(image_garbage)
file(WRITE "${WORK}/cases/image_garbage/left/000001.png" "not a png")
process_bad(image_garbage "000001.png")
broken(image_size)
file(REMOVE "${WORK}/cases/image_size/left/000001.png")
file(COPY "${SOURCE}/data/real/fisheye_car/images/left.png" DESTINATION "${WORK}/cases/image_size/left")
file(RENAME "${WORK}/cases/image_size/left/left.png" "${WORK}/cases/image_size/left/000001.png")
process_bad(image_size "image_size: frame 1: left is 960x640 but rig.yaml.s camera is 320x240")
broken(right_short)
file(REMOVE "${WORK}/cases/right_short/right/000002.png")
process_bad(right_short "left/ has frames 0..2, .*right/ has 0..1 \\(--truncate")
broken(left_gap)
file(REMOVE "${WORK}/cases/left_gap/left/000001.png")
process_bad(left_gap "left_gap/left: frame 1 missing \\(000000.png is followed by 000002.png\\)")
broken(left_twice)
file(COPY_FILE "${WORK}/cases/left_twice/left/000001.png" "${WORK}/cases/left_twice/left/1.png")
process_bad(left_twice "left_twice/left: frame 1 twice")
broken(left_unnumbered)
file(COPY_FILE "${WORK}/cases/left_unnumbered/left/000001.png" "${WORK}/cases/left_unnumbered/left/cover.png")
process_bad(left_unnumbered "left_unnumbered/left/cover.png: not a numbered frame")
broken(truncate_disjoint)
foreach(i 0 1 2)
  file(RENAME "${WORK}/cases/truncate_disjoint/right/00000${i}.png" "${WORK}/cases/truncate_disjoint/right/00001${i}.png")
endforeach()
process_bad(truncate_disjoint "right/ has 10..12: no frame number in both" --truncate)

# can.csv that cannot be right: another clock or unit, speeds and yaw rates no car has
broken(can_nanoseconds)
file(WRITE "${WORK}/cases/can_nanoseconds/can.csv" "t,speed,yaw_rate\n1000000000,10,0\n2000000000,10,0\n")
process_bad(can_nanoseconds "can_nanoseconds/can.csv: its times 1000000000..2000000000 s do not overlap the frames'")
broken(can_speed_absurd)
file(WRITE "${WORK}/cases/can_speed_absurd/can.csv" "t,speed,yaw_rate\n0,10,0\n0.05,1e300,0\n0.1,10,0\n")
process_bad(can_speed_absurd "can_speed_absurd/can.csv:3: column 'speed': 1e\\+300 m/s is no road vehicle's speed")
broken(can_yaw_degrees)
file(WRITE "${WORK}/cases/can_yaw_degrees/can.csv" "t,speed,yaw_rate\n0,10,30\n0.1,10,30\n")
process_bad(can_yaw_degrees "can_yaw_degrees/can.csv:2: column 'yaw_rate': 30 rad/s is no road vehicle's yaw rate")
broken(rig_matrix_huge)
string(REGEX REPLACE "rows: 3\n( *)cols: 3" "rows: 100000\n\\1cols: 100000" text "${good_rig}")
file(WRITE "${WORK}/cases/rig_matrix_huge/rig.yaml" "${text}")
process_bad(rig_matrix_huge "rig_matrix_huge/rig.yaml: camera 'left': field 'K': expected a 3x3 matrix, got 100000x100000")

# Paths with spaces and non-ASCII names: the error names them as they are.
broken("drive with spåce")
file(REMOVE "${WORK}/cases/drive with spåce/can.csv")
process_bad("drive with spåce" "cases/drive with spåce/can.csv")
broken(yaw_file_missing)
process_bad(yaw_file_missing "no_such_gyro.csv" --yaw-file "${WORK}/cases/yaw_file_missing/no_such_gyro.csv")
broken(left_video_garbage)
file(REMOVE_RECURSE "${WORK}/cases/left_video_garbage/left")
file(WRITE "${WORK}/cases/left_video_garbage/left.avi" "not a video")
process_bad(left_video_garbage "left_video_garbage/left.avi: cannot open video")

# Outputs that would destroy inputs, and options
broken(out_is_drive)
bad(out_is_drive "would be, contain or lie inside the input" "-" "${TOOLS}/dps-process" "${WORK}/cases/out_is_drive"
    --out "${WORK}/cases" --no-video --quiet)
if(NOT EXISTS "${WORK}/cases/out_is_drive/rig.yaml")
  message(FATAL_ERROR "out_is_drive: the drive lost its rig.yaml")
endif()
bad(out_inside_drive "would be, contain or lie inside the input" "${WORK}/cases/out_is_drive/out_is_drive"
    "${TOOLS}/dps-process" "${WORK}/cases/out_is_drive" --out "${WORK}/cases/out_is_drive" --no-video --quiet)
broken(out_not_ours)
file(WRITE "${WORK}/out_foreign/out_not_ours/thesis.tex" "mine")
bad(out_not_ours "left alone" "-" "${TOOLS}/dps-process" "${WORK}/cases/out_not_ours" --out "${WORK}/out_foreign"
    --no-video --quiet --force)
if(NOT EXISTS "${WORK}/out_foreign/out_not_ours/thesis.tex")
  message(FATAL_ERROR "out_not_ours: a folder dps did not write was replaced")
endif()
file(MAKE_DIRECTORY "${WORK}/twins/a" "${WORK}/twins/b")
file(COPY "${WORK}/good" DESTINATION "${WORK}/twins/a")
file(COPY "${WORK}/good" DESTINATION "${WORK}/twins/b")
bad(batch_twins "two drives of one folder name" "${WORK}/out_twins/good" "${TOOLS}/dps-process" "${WORK}/twins/a/good"
    "${WORK}/twins/b/good" --out "${WORK}/out_twins" --no-video --quiet --jobs 1)
bad(jobs_zero "--jobs" "-" "${TOOLS}/dps-process" "${WORK}/good" --out "${WORK}/out" --jobs 0)
bad(shard_bad "shard" "-" "${TOOLS}/dps-process" "${WORK}/good" --out "${WORK}/out" --shard 3/2)
bad(image_fps_zero "--image-fps" "-" "${TOOLS}/dps-process" "${WORK}/good" --out "${WORK}/out" --image-fps 0)
bad(mask_seconds "--mask-seconds" "-" "${TOOLS}/dps-process" "${WORK}/good" --out "${WORK}/out" --mask-seconds -1)
bad(list_missing "absent.txt" "-" "${TOOLS}/dps-process" --list "${WORK}/absent.txt" --out "${WORK}/out")

# dps-synth
bad(scene_missing "absent.yaml: file not found" "${WORK}/synth_out" "${TOOLS}/dps-synth" "${WORK}/absent.yaml"
    --out "${WORK}/synth_out")
file(WRITE "${WORK}/endless_scene.yaml" "%YAML:1.\n h:0\n:  -\n")
bad(scene_endless "endless_scene.yaml" "${WORK}/synth_out" "${TOOLS}/dps-synth" "${WORK}/endless_scene.yaml"
    --out "${WORK}/synth_out")
bad(synth_size "--size" "${WORK}/synth_out" "${TOOLS}/dps-synth" "${SOURCE}/data/scenes/lead_car.yaml" --size 3x2
    --out "${WORK}/synth_out")
file(WRITE "${WORK}/out_foreign/synth_target/notes.txt" "mine")
bad(synth_not_ours "left alone" "-" "${TOOLS}/dps-synth" "${SOURCE}/data/scenes/lead_car.yaml" --frames 1 --force
    --out "${WORK}/out_foreign/synth_target")
bad(synth_into_scene_folder "would be, contain or lie inside the input" "-" "${TOOLS}/dps-synth"
    "${WORK}/cases/rig_missing/../../endless_scene.yaml" --force --out "${WORK}")

# dps-calibrate, dps-eval, dps-stereo
file(WRITE "${WORK}/marks_huge.csv" "camera,line,axis,u,v\nleft,1e300,X,10,10\n")
bad(marks_huge "marks_huge.csv:2: column 'line'" "${WORK}/cal.yaml" "${TOOLS}/dps-calibrate" --rig "${WORK}/good/rig.yaml"
    --marks "${WORK}/marks_huge.csv" --out "${WORK}/cal.yaml")
bad(calibrate_rig_endless "rig_endless/rig.yaml" "${WORK}/cal.yaml" "${TOOLS}/dps-calibrate"
    --rig "${WORK}/cases/rig_endless/rig.yaml" --marks "${WORK}/marks_huge.csv" --out "${WORK}/cal.yaml")
file(WRITE "${WORK}/marks_same_point.csv" "camera,line,axis,u,v\nleft,1,Z,100,150\nleft,1,Z,100,150\nleft,1,Z,100,150\n")
bad(marks_same_point "marks_same_point.csv: camera 'left': line 1: its 3 points span 0 px" "${WORK}/cal.yaml"
    "${TOOLS}/dps-calibrate" --rig "${WORK}/good/rig.yaml" --marks "${WORK}/marks_same_point.csv" --out "${WORK}/cal.yaml")
file(WRITE "${WORK}/det_nan.csv" "frame,t,source,id,x,z,range,x_min,x_max,z_min,z_max,n_points\n0,0,front,0,nan,5,5,-1,1,4,6,10\n")
bad(detections_nan "det_nan.csv:2: column 'x': not a finite number" "-" "${TOOLS}/dps-eval" --detections "${WORK}/det_nan.csv"
    --truth "${WORK}/good/truth.csv")
file(WRITE "${WORK}/truth_empty.csv" "frame,t,id,kind,x,z,heading_deg,length,width,height,vx,vz\n")
file(WRITE "${WORK}/det_other.csv" "frame,t,source,id,x,z,range,x_min,x_max,z_min,z_max,n_points\n1,7.5,front,0,0,5,5,-1,1,4,6,10\n")
bad(detections_other_drive "det_other.csv: frame 1 is at t = 7.5 s, in .*truth.csv at .*not the same drive" "-"
    "${TOOLS}/dps-eval" --detections "${WORK}/det_other.csv" --truth "${WORK}/good/truth.csv")
file(WRITE "${WORK}/det_huge.csv" "frame,t,source,id,x,z,range,x_min,x_max,z_min,z_max,n_points\n1e300,0,front,0,0,5,5,-1,1,4,6,10\n")
bad(detections_huge "det_huge.csv:2: column 'frame'" "-" "${TOOLS}/dps-eval" --detections "${WORK}/det_huge.csv"
    --truth "${WORK}/good/truth.csv" --rig "${WORK}/good/rig.yaml")
file(WRITE "${WORK}/frames_short.csv" "frame,t\n0,0\n")
bad(detections_beyond_frames "det_other.csv: frame 1 but .*frames_short.csv lists 1 frames" "-" "${TOOLS}/dps-eval"
    --detections "${WORK}/det_other.csv" --truth "${WORK}/truth_empty.csv" --frames "${WORK}/frames_short.csv")
file(WRITE "${WORK}/truth_bad.csv" "frame,t,id\n0,0,1\n")
bad(truth_columns "truth_bad.csv: missing column" "-" "${TOOLS}/dps-eval" --detections "${WORK}/det_huge.csv"
    --truth "${WORK}/truth_bad.csv" --rig "${WORK}/good/rig.yaml")
file(WRITE "${WORK}/lanes_bad.csv" "frame,t,boundary,offset,heading_deg,curvature,type,confidence\n0,0,middle,0,0,0,solid,1\n")
bad(lanes_boundary "lanes_bad.csv:2: column 'boundary': 'middle' is not one of left2, left, right, right2" "-"
    "${TOOLS}/dps-eval" --lanes "${WORK}/lanes_bad.csv" --truth-lanes "${WORK}/lanes_bad.csv")
bad(lanes_alone "--lanes needs --truth-lanes" "-" "${TOOLS}/dps-eval" --lanes "${WORK}/lanes_bad.csv")
bad(truth_lanes_alone "missing --detections, --tracks or --lanes" "-" "${TOOLS}/dps-eval"
    --truth-lanes "${WORK}/lanes_bad.csv")
file(WRITE "${WORK}/det_class.csv" "frame,t,source,id,x,z,range,x_min,x_max,z_min,z_max,n_points,height,lane,class\n0,0,front,0,0,5,5,-1,1,4,6,10,1.5,0,lorry\n")
bad(detections_class "det_class.csv:2: column 'class': 'lorry' is not one of" "-" "${TOOLS}/dps-eval" --detections
    "${WORK}/det_class.csv" --truth "${WORK}/good/truth.csv")
bad(stereo_disparities "num_disparities" "${WORK}/disp.pfm" "${TOOLS}/dps-stereo" "${WORK}/good/left/000000.png"
    "${WORK}/good/right/000000.png" --num-disparities 2147483647 --out "${WORK}/disp.pfm")
bad(stereo_missing "absent.png" "${WORK}/disp.pfm" "${TOOLS}/dps-stereo" "${WORK}/absent.png"
    "${WORK}/good/right/000000.png" --num-disparities 16 --out "${WORK}/disp.pfm")

# dps-rig
bad(rig_import_format "unknown calibration format 'matlab'" "${WORK}/imported.yaml" "${TOOLS}/dps-rig" import --format matlab
    "${WORK}/good/rig.yaml" --out "${WORK}/imported.yaml")
file(WRITE "${WORK}/calib_results.txt" "#polynomial\n\n5 -266.588 0 1.22e-03 -5.78e-07 2.0e-09\n")
bad(rig_import_truncated "calib_results.txt: field 'invpol \\(world2cam polynomial\\)': missing" "${WORK}/imported.yaml"
    "${TOOLS}/dps-rig" import --format ocam "${WORK}/calib_results.txt" --out "${WORK}/imported.yaml")
bad(rig_view_size "000000.png: 320x240, the calibration is for" "${WORK}/view.png" "${TOOLS}/dps-rig" view
    "${SOURCE}/data/rigs/omni_pair.yaml" --camera left --image "${WORK}/good/left/000000.png" --out "${WORK}/view.png")

# No temporary folder of a failed run is left behind.
file(GLOB leftovers "${WORK}/out/.*" "${WORK}/.*tmp*")
if(leftovers)
  message(FATAL_ERROR "temporary files left behind: ${leftovers}")
endif()
get_property(refused GLOBAL PROPERTY refused)
list(LENGTH refused cases)
message(STATUS "${cases} bad inputs refused as they should be")
