#include "dps/camera/valid_mask.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "dps/util/error.h"

namespace dps {

cv::Mat ModelValidMask(const CameraModel& model) {
  cv::Mat mask(model.height(), model.width(), CV_8U);
  cv::parallel_for_(cv::Range(0, mask.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      std::uint8_t* m = mask.ptr<std::uint8_t>(y);
      for (int x = 0; x < mask.cols; ++x) {
        Eigen::Vector3d ray;
        m[x] = model.Unproject(Eigen::Vector2d(x, y), &ray) ? 255 : 0;
      }
    }
  });
  return mask;
}

cv::Mat CameraValidMask(const RigCamera& camera) {
  cv::Mat mask = ModelValidMask(camera.model);
  if (!camera.mask.empty()) mask &= camera.mask;
  return mask;
}

cv::Mat ReadCameraMask(const std::string& path, const CameraModel& model) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) throw Error(Str(path, ": cannot read the mask image (no such file)"));
  const cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw Error(Str(path, ": cannot read the mask image"));
  if (image.cols != model.width() || image.rows != model.height()) {
    throw Error(Str(path, ": the mask is ", image.cols, "x", image.rows, ", the camera's images ", model.width(), "x",
                    model.height()));
  }
  return image > 127;
}

void FieldMaskOptions::Check() const {
  const OptionCheck Require("field mask");
  Require(dark_fraction > 0 && dark_fraction < 1, "dark_fraction", dark_fraction, "in (0, 1)");
  Require(edge_margin_fraction >= 0 && edge_margin_fraction <= 0.1, "edge_margin_fraction", edge_margin_fraction,
          "in [0, 0.1]");
}

namespace {

// The brightest grey value each pixel reaches over the frames.
cv::Mat Brightest(const std::vector<cv::Mat>& frames, const CameraModel& model) {
  cv::Mat brightest, grey;
  for (const cv::Mat& frame : frames) {
    if (frame.cols != model.width() || frame.rows != model.height()) {
      throw Error(Str("field mask: a frame is ", frame.cols, "x", frame.rows, ", the camera's images ", model.width(),
                      "x", model.height()));
    }
    if (frame.channels() == 3) {
      cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
    } else {
      grey = frame;
    }
    if (grey.type() != CV_8U) throw Error("field mask: frames must be 8-bit grey or BGR images");
    if (brightest.empty()) {
      brightest = grey.clone();
    } else {
      cv::max(brightest, grey, brightest);
    }
  }
  return brightest;
}

// The 75th percentile of `values` over the pixels where `where` is set (all pixels when none is).
double UpperQuartile(const cv::Mat& values, const cv::Mat& where) {
  int histogram[256] = {0};
  int total = 0;
  for (int y = 0; y < values.rows; ++y) {
    const std::uint8_t* v = values.ptr<std::uint8_t>(y);
    const std::uint8_t* w = where.ptr<std::uint8_t>(y);
    for (int x = 0; x < values.cols; ++x) {
      if (!w[x]) continue;
      ++histogram[v[x]];
      ++total;
    }
  }
  int seen = 0;
  for (int g = 0; g < 256; ++g) {
    seen += histogram[g];
    if (4 * seen >= 3 * total) return g;
  }
  return 255;
}

}  // namespace

cv::Mat EstimateFieldMask(const std::vector<cv::Mat>& frames, const CameraModel& model,
                          const FieldMaskOptions& options) {
  options.Check();
  if (frames.empty()) throw Error("field mask: no frames to estimate it from");
  const cv::Mat brightest = Brightest(frames, model);
  cv::Mat model_valid = ModelValidMask(model);
  if (cv::countNonZero(model_valid) == 0) model_valid.setTo(255);
  const double level = UpperQuartile(brightest, model_valid);
  // Dark, or unseen by the model: the candidates for "beyond the field".
  cv::Mat outside = (brightest <= options.dark_fraction * level) | (model_valid == 0);
  // Isolated dark pixels (noise, thin dark lines in the scene) do not make a field's edge.
  cv::morphologyEx(outside, outside, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3)));
  outside |= model_valid == 0;
  // Only what is connected to the image's border or to the model's unseen area.
  cv::Mat labels;
  const int count = cv::connectedComponents(outside, labels, 8, CV_32S);
  std::vector<std::uint8_t> keep(count, 0);
  for (int y = 0; y < labels.rows; ++y) {
    const int* l = labels.ptr<int>(y);
    const std::uint8_t* m = model_valid.ptr<std::uint8_t>(y);
    const bool border_row = y == 0 || y == labels.rows - 1;
    for (int x = 0; x < labels.cols; ++x) {
      if (l[x] != 0 && (border_row || x == 0 || x == labels.cols - 1 || !m[x])) keep[l[x]] = 1;
    }
  }
  cv::Mat beyond(labels.size(), CV_8U);
  for (int y = 0; y < labels.rows; ++y) {
    const int* l = labels.ptr<int>(y);
    std::uint8_t* b = beyond.ptr<std::uint8_t>(y);
    for (int x = 0; x < labels.cols; ++x) b[x] = keep[l[x]] ? 255 : 0;
  }
  const int margin = std::max(1, static_cast<int>(std::ceil(options.edge_margin_fraction * model.width())));
  cv::dilate(beyond, beyond, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * margin + 1, 2 * margin + 1)));
  return beyond == 0;
}

}  // namespace dps
