// dps — small image helpers shared by the stages.
#pragma once

#include <string>

#include <opencv2/core.hpp>

namespace dps {

// The image as one grey channel (BGR converted; grey returned as it is).
cv::Mat GreyImage(const cv::Mat& image);

// Writes an image (format by the name's extension) under a temporary name beside `path` and
// renames it into place when complete; throws dps::Error naming `path` when it cannot be written.
void WriteImageAtomically(const std::string& path, const cv::Mat& image);

}  // namespace dps
