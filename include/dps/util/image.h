// dps — small image helpers shared by the stages.
#pragma once

#include <opencv2/core.hpp>

namespace dps {

// The image as one grey channel (BGR converted; grey returned as it is).
cv::Mat GreyImage(const cv::Mat& image);

}  // namespace dps
