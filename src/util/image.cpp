#include "dps/util/image.h"

#include <filesystem>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "dps/util/atomic_file.h"
#include "dps/util/error.h"

namespace dps {

cv::Mat GreyImage(const cv::Mat& image) {
  if (image.channels() == 1) return image;
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  return grey;
}

void WriteImageAtomically(const std::string& path, const cv::Mat& image) {
  const std::string tmp = TemporaryPathFor(path);
  bool written = false;
  try {
    written = cv::imwrite(tmp, image);
  } catch (const cv::Exception&) {  // e.g. an extension no encoder knows
  }
  if (!written) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw Error(Str(path, ": cannot write image (does its folder exist, and is it an image file name?)"));
  }
  RenameReplacing(tmp, path);
}

}  // namespace dps
