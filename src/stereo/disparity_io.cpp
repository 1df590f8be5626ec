#include "dps/stereo/disparity_io.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "dps/stereo/sad_stereo.h"
#include "dps/util/atomic_file.h"
#include "dps/util/error.h"
#include "dps/util/image.h"

namespace dps {
namespace {

std::string Extension(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

}  // namespace

void WriteDisparity(const std::string& path, const cv::Mat& disparity) {
  CV_Assert(disparity.type() == CV_32F);
  const std::string ext = Extension(path);
  if (ext == ".png") {
    cv::Mat out(disparity.size(), CV_16U);
    for (int y = 0; y < disparity.rows; ++y) {
      const float* d = disparity.ptr<float>(y);
      std::uint16_t* o = out.ptr<std::uint16_t>(y);
      for (int x = 0; x < disparity.cols; ++x) {
        if (!std::isfinite(d[x])) {
          o[x] = 0;
          continue;
        }
        const long v = std::lround(d[x] * 256.0);
        if (v < 0 || v > 65535) {
          throw Error(Str(path, ": disparity ", d[x], " at (", x, ", ", y, ") cannot be stored in a "
                          "KITTI 16-bit PNG (0..255.99); use .pfm"));
        }
        o[x] = static_cast<std::uint16_t>(std::max(1L, v));  // 0 means invalid
      }
    }
    WriteImageAtomically(path, out);
  } else if (ext == ".pfm") {
    AtomicOutputFile f(path);
    f.stream() << "Pf\n" << disparity.cols << " " << disparity.rows << "\n-1\n";
    for (int y = disparity.rows - 1; y >= 0; --y) {
      f.stream().write(reinterpret_cast<const char*>(disparity.ptr<float>(y)),
                       static_cast<std::streamsize>(disparity.cols * sizeof(float)));
    }
    f.Commit();
  } else {
    throw Error(Str(path, ": unknown disparity format '", ext, "' (use .png or .pfm)"));
  }
}

cv::Mat ReadDisparity(const std::string& path) {
  const std::string ext = Extension(path);
  if (ext == ".png") {
    const cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
    if (raw.empty() || raw.type() != CV_16U) throw Error(Str(path, ": not a 16-bit PNG"));
    cv::Mat d(raw.size(), CV_32F);
    for (int y = 0; y < raw.rows; ++y) {
      for (int x = 0; x < raw.cols; ++x) {
        const std::uint16_t v = raw.at<std::uint16_t>(y, x);
        d.at<float>(y, x) = v == 0 ? kInvalidDisparity : v / 256.0f;
      }
    }
    return d;
  }
  if (ext == ".pfm") {
    std::ifstream in(path, std::ios::binary);
    std::string magic;
    int w = 0, h = 0;
    double scale = 0;
    in >> magic >> w >> h >> scale;
    in.get();
    if (!in || magic != "Pf" || w <= 0 || h <= 0 || scale >= 0) {
      throw Error(Str(path, ": not a little-endian grey PFM"));
    }
    // The header's size is checked against the file before anything is allocated for it.
    const auto data_start = static_cast<std::uintmax_t>(in.tellg());
    const std::uintmax_t file_size = std::filesystem::file_size(path);
    const std::uintmax_t pixels = static_cast<std::uintmax_t>(w) * static_cast<std::uintmax_t>(h);
    if (data_start > file_size || pixels > (file_size - data_start) / sizeof(float)) {
      throw Error(Str(path, ": truncated PFM (header says ", w, " x ", h, ", the file holds ",
                      file_size > data_start ? (file_size - data_start) / sizeof(float) : 0, " values)"));
    }
    cv::Mat d(h, w, CV_32F);
    for (int y = h - 1; y >= 0; --y) {
      in.read(reinterpret_cast<char*>(d.ptr<float>(y)), static_cast<std::streamsize>(w * sizeof(float)));
    }
    if (!in) throw Error(Str(path, ": truncated PFM"));
    return d;
  }
  throw Error(Str(path, ": unknown disparity format '", ext, "' (use .png or .pfm)"));
}

cv::Mat ColourDisparity(const cv::Mat& disparity, double lo, double hi) {
  CV_Assert(disparity.type() == CV_32F && hi > lo);
  cv::Mat scaled(disparity.size(), CV_8U), colour;
  for (int y = 0; y < disparity.rows; ++y) {
    for (int x = 0; x < disparity.cols; ++x) {
      const float d = disparity.at<float>(y, x);
      scaled.at<std::uint8_t>(y, x) =
          std::isfinite(d) ? cv::saturate_cast<std::uint8_t>(255.0 * (d - lo) / (hi - lo)) : 0;
    }
  }
  cv::applyColorMap(scaled, colour, cv::COLORMAP_TURBO);
  colour.setTo(cv::Scalar::all(0), disparity == kInvalidDisparity);
  return colour;
}

}  // namespace dps
