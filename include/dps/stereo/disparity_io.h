// dps — writing and reading disparity maps.
//
// - PNG: 16-bit, KITTI convention: value = round(d * 256), 0 = invalid; only for d in
//   (0, 255.996]; negative or larger disparities cannot be stored and are refused.
// - PFM: the portable float map (grey, "Pf"), little-endian, rows bottom to top; invalid = +inf.
// - A colour picture for people: disparities mapped with a colour map between the given limits,
//   invalid pixels black.
#pragma once

#include <string>

#include <opencv2/core.hpp>

namespace dps {

// Writes a CV_32F disparity map by extension (.png or .pfm), atomically. Throws dps::Error
// naming the file for another extension, a negative / too large disparity in a PNG, or a failed
// write.
void WriteDisparity(const std::string& path, const cv::Mat& disparity);

// Reads a disparity map written by WriteDisparity (.png or .pfm) back to CV_32F with
// kInvalidDisparity for invalid pixels.
cv::Mat ReadDisparity(const std::string& path);

// A BGR picture of the disparity (turbo-like colour map, near = warm), invalid black;
// min/max in pixels (max > min).
cv::Mat ColourDisparity(const cv::Mat& disparity, double min_disparity, double max_disparity);

}  // namespace dps
