// dps — bringing real cameras' calibrations in: the files other toolboxes write, read into dps's
// camera models and vehicle frame (`dps-rig import`).
//
// Formats and the conventions each one is read with (docs/camera_models.md shows the formulas):
// - ocam: OCamCalib's calib_results.txt (data lines after `#` comments: `N a0..a(N-1)` = ss,
//   `M p0..p(M-1)` = invpol, `xc yc` (row, column, 0-based), `c d e`, `height width`; lines after
//   these are ignored), or the same numbers in YAML (`ss`, `invpol` with the count first, `xy`,
//   `cde`, `shape` = [height, width]). Intrinsics only.
// - omnidir: a cv::omnidir result (K or camera_matrix, xi or Xi, D or distortion_coefficients,
//   imageSize); opencv-fisheye: a cv::fisheye result. Intrinsics only.
// - kitti360: the camodocal-style MEI YAML of KITTI-360's fisheyes (mirror_parameters xi,
//   distortion_parameters k1 k2 p1 p2, projection_parameters gamma1 gamma2 u0 v0), as the unified
//   model with that distortion (cv::omnidir's formula; KITTI-360's devkit drops p1, p2), plus
//   `calib_cam_to_pose.txt` (`image_0N: ` 3x4 [R t] row-major, X_pose = R X_cam + t). The pose
//   frame is x forward, y right, z down; dps's vehicle frame is X right, Y down, Z forward, so
//   (X, Y, Z) = (y, z, x) + the pose origin's position in the vehicle frame (`source_origin`).
// - pjlab-ocam: PJLab SensorsCalibration's surround-view JSON: intrinsic `cam_K` = [[c, d, u0],
//   [e, 1, v0], [0, 0, 1]] with u0 a column, `cam_dist` = rho(theta) ascending, its x axis along
//   the image's columns (transposed from OCamCalib: converted exactly, c' = 1/c, d' = e/c,
//   e' = d/c, invpol' = c invpol, xc = v0, yc = u0; ss fitted); extrinsic `bev-to-<camera>-extrinsic`
//   T with P_camera = T P_bev, the bird's-eye camera looking down from `bev_height_m` above the
//   ground with its image x to the right and image up forward: (X, Y, Z) = (x, z - h, -y). Its
//   files do not state their unit (the sample's cameras come out 3.6 units apart across the car,
//   which suggests about half a metre): `source_unit_m` scales every translation.
// Cameras without extrinsics in their files get a nominal mount (`NominalMount`) that dps-calibrate
// then refines.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dps/camera/rig.h"

namespace dps {

enum class CalibrationFormat { kOCam, kOmnidir, kOpenCVFisheye, kKitti360, kPJLabOCam };

// "ocam", "omnidir", "opencv-fisheye", "kitti360", "pjlab-ocam"; throws dps::Error naming the
// known ones for any other string.
CalibrationFormat CalibrationFormatFromName(const std::string& name);

// One format's readers. Each throws dps::Error naming the file and the field (or line).
CameraModel ReadOCamCalibResults(const std::string& path);
// A cv::omnidir result (ReadOpenCVOmnidir), or the same keys in plain YAML that OpenCV's parser
// refuses (K as 9 numbers row-major, D, Xi); `size` where the file has none.
CameraModel ReadOmnidirCalibration(const std::string& path, cv::Size size = cv::Size());
CameraModel ReadKitti360Fisheye(const std::string& path, std::string* camera_name = nullptr);
std::map<std::string, Pose> ReadKitti360CamToPose(const std::string& path);
CameraModel ReadPJLabOCamIntrinsic(const std::string& path, std::string* camera_name = nullptr);
Pose ReadPJLabExtrinsic(const std::string& path, std::string* camera_name = nullptr);  // camera_from_bev

// How a camera without extrinsics is placed: at a side mirror (x = +-(vehicle width / 2 + 0.1),
// forward 1 m of the vehicle centre, `height_m` above the road), its axis down (omni cameras) or
// looking out sideways (fisheyes in the mirrors).
enum class NominalAxis { kDown, kOut };
Pose NominalMount(const Vehicle& vehicle, bool left, NominalAxis axis, double height_m);

struct ImportOptions {
  CalibrationFormat format = CalibrationFormat::kOCam;
  std::vector<std::string> files;
  std::vector<std::string> names;      // the cameras' names in import order; empty: the source's
  Vehicle vehicle;
  cv::Size size;                       // omnidir / opencv-fisheye files without an image size
  Eigen::Vector3d source_origin = Eigen::Vector3d::Zero();  // kitti360: the pose frame's origin, vehicle frame
  // pjlab-ocam: the bird's-eye camera's height above the road (files' units), per source camera
  // name ("front_camera"), else bev_height_m for all.
  std::map<std::string, double> bev_height_by_camera;
  double bev_height_m = 0.0;
  double source_unit_m = 1.0;          // metres per unit of the files' translations (pjlab states none)
  NominalAxis nominal_axis = NominalAxis::kDown;  // cameras without extrinsics
  double nominal_height_m = 1.0;

  void Check() const;
};

// The rig of the files: one camera per intrinsics file, named after `names`, else the source's
// name (kitti360: image_02, ...; pjlab: front_camera, ...), else left, right, camera2, ...; the
// extrinsics converted into the vehicle frame, or nominal. `notes` gets one line per camera that
// says where its pose came from.
Rig ImportRig(const ImportOptions& options, std::vector<std::string>* notes = nullptr);

}  // namespace dps
