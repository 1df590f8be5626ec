// dps — reading and writing rig.yaml (DESIGN.md §3.1), and reading intrinsics from OpenCV's own
// calibration files (cv::fisheye, cv::omnidir), so that users can bring what they already have.
//
// rig.yaml, per camera: name, model (hyperbolic | unified | fisheye | ocam), width, height, K (3x3;
// not for ocam), a and b (hyperbolic), xi and optionally dist [k1, k2, p1, p2] (unified), dist
// [k1, k2, k3, k4] (fisheye), ss, optional invpol, center [xc, yc] and affine [c, d, e] (ocam,
// DESIGN.md §2; invpol is fitted when absent and always written), R (3x3, camera -> vehicle,
// orthonormal within 1e-6, det +1), t (3x1, metres, vehicle frame), and optionally rim_radius_px
// (pixels around the principal point that see the scene; 0 or absent = no rim) and mask (an 8-bit
// image of the camera's size, 255 = sees the world, relative to the rig file's folder; ReadRig
// loads it into RigCamera::mask). Matrices may be written as !!opencv-matrix or as plain row-major
// lists.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "dps/camera/rig.h"

namespace dps {

// Reads and validates a rig file. Throws dps::Error with a one-line message naming the file,
// the camera and the field (missing key, unknown model, wrong matrix size, R not a rotation,
// non-positive focal length or image size, duplicate camera name, ...).
Rig ReadRig(const std::string& path);

// Parses a rig from a node holding rig.yaml's fields (`vehicle`, `cameras`), e.g. a rig written
// inline in a scene file; `where` prefixes every error message (the file, and the key).
Rig ParseRig(const cv::FileNode& node, const std::string& where);

// The rig as rig.yaml text (cv::FileStorage YAML). Doubles are written with 17 significant
// digits, so ReadRig(WriteRig(rig)) reproduces the rig exactly.
std::string RigToYaml(const Rig& rig);

// Writes the rig atomically to `path`; throws dps::Error on failure.
void WriteRig(const Rig& rig, const std::string& path);

// Reads a cv::fisheye calibration file: `camera_matrix` (or `K`), `dist_coeffs` (or `D`,
// `distortion_coefficients`; 4 values) and the image size from `resolution` ([w, h]) or
// `image_width` / `image_height`; `size` overrides the file's size and is required when the file
// has none. Throws dps::Error naming the file and the field.
CameraModel ReadOpenCVFisheye(const std::string& path, cv::Size size = cv::Size());

// Reads a cv::omnidir calibration result (`K` or `camera_matrix`, `xi` or `Xi`, `D` or
// `distortion_coefficients` = [k1 k2 p1 p2], optional; the size also from `imageSize`) as a
// unified model with that distortion.
CameraModel ReadOpenCVOmnidir(const std::string& path, cv::Size size = cv::Size());
// The same from a node already parsed (`where` prefixes every error message).
CameraModel ParseOpenCVOmnidir(const cv::FileNode& root, const std::string& where, cv::Size size = cv::Size());

}  // namespace dps
