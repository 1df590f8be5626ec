#include "dps/camera/valid_mask.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <vector>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "dps/camera/box.h"
#include "dps/util/error.h"
#include "dps/util/image.h"

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

bool SeesRoadPoint(const RigCamera& camera, const Pose& camera_from_vehicle, const cv::Mat& valid,
                   const Eigen::Vector3d& box_lo, const Eigen::Vector3d& box_hi, bool own_car_blocks,
                   const Eigen::Vector3d& ground, Eigen::Vector2d* pixel) {
  const Eigen::Vector3d& t = camera.vehicle_from_camera.t;
  if ((own_car_blocks && RayMeetsBox(t, ground - t, box_lo, box_hi, 0.0, 1.0)) ||
      !camera.model.Project(camera_from_vehicle.Apply(ground), pixel) || !camera.model.InImage(*pixel)) {
    return false;
  }
  const int u = static_cast<int>(std::lround(pixel->x())), v = static_cast<int>(std::lround(pixel->y()));
  return u >= 0 && v >= 0 && u < valid.cols && v < valid.rows && valid.at<std::uint8_t>(v, u);
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

void OwnCarMaskOptions::Check() const {
  const OptionCheck Require("own car mask");
  Require(max_roof_height_m > 0, "max_roof_height_m", max_roof_height_m, "> 0");
  Require(window_fraction > 0 && window_fraction <= 0.1, "window_fraction", window_fraction, "in (0, 0.1]");
  Require(min_road_m > 0, "min_road_m", min_road_m, "> 0");
  Require(max_road_m > min_road_m, "max_road_m", max_road_m, "> min_road_m");
  Require(min_road_to_car > 1, "min_road_to_car", min_road_to_car, "> 1");
  Require(min_travel_m > 0, "min_travel_m", min_travel_m, "> 0");
}

namespace {

// A frame as 8-bit grey, checked against the model's size; `what` names the estimate.
cv::Mat Grey(const cv::Mat& frame, const CameraModel& model, const char* what) {
  if (frame.cols != model.width() || frame.rows != model.height()) {
    throw Error(Str(what, ": a frame is ", frame.cols, "x", frame.rows, ", the camera's images ", model.width(), "x",
                    model.height()));
  }
  if (frame.type() != CV_8UC1 && frame.type() != CV_8UC3) throw Error(Str(what, ": frames must be 8-bit grey or BGR images"));
  return GreyImage(frame);
}

// The brightest grey value each pixel reaches over the frames.
cv::Mat Brightest(const std::vector<cv::Mat>& frames, const CameraModel& model) {
  cv::Mat brightest;
  for (const cv::Mat& frame : frames) {
    const cv::Mat grey = Grey(frame, model, "field mask");
    if (brightest.empty()) {
      brightest = grey.clone();
    } else {
      cv::max(brightest, grey, brightest);
    }
  }
  return brightest;
}

// The 8-connected components of `mask` (CV_8U) that hold a pixel set in `touch`, 255.
cv::Mat ComponentsTouching(const cv::Mat& mask, const cv::Mat& touch) {
  cv::Mat labels;
  const int count = cv::connectedComponents(mask, labels, 8, CV_32S);
  std::vector<std::uint8_t> keep(static_cast<size_t>(count), 0);
  for (int y = 0; y < labels.rows; ++y) {
    const int* l = labels.ptr<int>(y);
    const std::uint8_t* t = touch.ptr<std::uint8_t>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (l[x] != 0 && t[x]) keep[static_cast<size_t>(l[x])] = 1;
    }
  }
  cv::Mat kept(labels.size(), CV_8U);
  for (int y = 0; y < labels.rows; ++y) {
    const int* l = labels.ptr<int>(y);
    std::uint8_t* k = kept.ptr<std::uint8_t>(y);
    for (int x = 0; x < labels.cols; ++x) k[x] = keep[static_cast<size_t>(l[x])] ? 255 : 0;
  }
  return kept;
}

// Median of the values where `where` is set; NaN when it is set nowhere.
double MedianWhere(const cv::Mat& values, const cv::Mat& where) {
  std::vector<float> v;
  for (int y = 0; y < values.rows; ++y) {
    const float* a = values.ptr<float>(y);
    const std::uint8_t* w = where.ptr<std::uint8_t>(y);
    for (int x = 0; x < values.cols; ++x) {
      if (w[x]) v.push_back(a[x]);
    }
  }
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
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
  cv::Mat touch = model_valid == 0;
  touch.row(0).setTo(255);
  touch.row(touch.rows - 1).setTo(255);
  touch.col(0).setTo(255);
  touch.col(touch.cols - 1).setTo(255);
  cv::Mat beyond = ComponentsTouching(outside, touch);
  const int margin = std::max(1, static_cast<int>(std::ceil(options.edge_margin_fraction * model.width())));
  cv::dilate(beyond, beyond, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * margin + 1, 2 * margin + 1)));
  return beyond == 0;
}

cv::Mat EstimateOwnCarMask(const std::vector<cv::Mat>& frames, const RigCamera& camera, const Vehicle& vehicle,
                           double travel_m, const OwnCarMaskOptions& options) {
  options.Check();
  const CameraModel& model = camera.model;
  if (frames.size() < 2 || !(travel_m >= options.min_travel_m)) return cv::Mat();
  // Each pixel's spread over the frames, smoothed: the noise averages out over the window.
  const int window = std::max(3, 2 * static_cast<int>(std::lround(options.window_fraction * model.width() / 2)) + 1);
  cv::Mat sum(model.height(), model.width(), CV_64F, cv::Scalar(0)), square = sum.clone(), smooth;
  for (const cv::Mat& frame : frames) {
    cv::boxFilter(Grey(frame, model, "own car mask"), smooth, CV_64F, cv::Size(window, window));
    sum += smooth;
    square += smooth.mul(smooth);
  }
  const double n = static_cast<double>(frames.size());
  const cv::Mat mean = sum / n;
  cv::Mat variance = square / n - mean.mul(mean), spread;
  cv::max(variance, 0.0, variance);
  cv::sqrt(variance, spread);
  // Relative to the pixel's brightness: the road's texture is as strong in the own car's shadow as
  // in the sun, relative to its brightness.
  cv::divide(spread, cv::max(mean, 1.0), spread);
  spread.convertTo(spread, CV_32F);

  // What each pixel's ray may meet of the own car: the body over the footprint up to the
  // camera's height, the cabin behind the camera up to the roof, and below the camera's level
  // anything behind it (the mirror's housing reaches from the camera back to the body). Rays that
  // do not descend to the road: the cabin only (the sky and the distance hold still too). The
  // pixels whose rays reach the road inside the footprint must see the car; the others that reach
  // it min_road_m .. max_road_m beside the camera are the road's reference.
  const Eigen::Vector3d c = camera.vehicle_from_camera.t;
  const double hw = vehicle.width_m / 2, hl = vehicle.length_m / 2;
  const Eigen::Vector3d body_lo(-hw, std::min(c.y(), 0.0), -hl), body_hi(hw, 0, hl);
  const Eigen::Vector3d cabin_lo(-hw, -options.max_roof_height_m, -hl), cabin_hi(hw, 0, std::clamp(c.z(), -hl, hl));
  const cv::Mat valid = CameraValidMask(camera);
  cv::Mat candidate(valid.size(), CV_8U, cv::Scalar(0)), seed = candidate.clone(), reference = candidate.clone();
  cv::Mat outer = candidate.clone();  // the reference's outer half, by distance
  // Each road pixel's footprint on the road (m): how far its neighbours' rays meet the road from
  // its own. Far off, or seen at a grazing angle, the road's texture is not resolved and holds
  // still as the car does.
  cv::Mat footprint(valid.size(), CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
  // Every pixel's ray in the vehicle frame and where it meets the road (NaN: nowhere), one column
  // and row beyond the image for the last pixels' neighbours.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  cv::Mat rays(valid.rows + 1, valid.cols + 1, CV_64FC3, cv::Scalar::all(nan)), grounds = rays.clone();
  cv::parallel_for_(cv::Range(0, rays.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      for (int x = 0; x < rays.cols; ++x) {
        Eigen::Vector3d ray, ground;
        if (!model.Unproject(Eigen::Vector2d(x, y), &ray)) continue;
        const Eigen::Vector3d d = camera.vehicle_from_camera.R * ray;
        rays.at<cv::Vec3d>(y, x) = cv::Vec3d(d.x(), d.y(), d.z());
        if (RayMeetsRoad(c, d, &ground)) grounds.at<cv::Vec3d>(y, x) = cv::Vec3d(ground.x(), ground.y(), ground.z());
      }
    }
  });
  const auto at = [](const cv::Mat& m, int x, int y) {
    const cv::Vec3d v = m.at<cv::Vec3d>(y, x);
    return Eigen::Vector3d(v[0], v[1], v[2]);
  };
  const Pose camera_from_vehicle = camera.vehicle_from_camera.Inverse();
  cv::parallel_for_(cv::Range(0, valid.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      for (int x = 0; x < valid.cols; ++x) {
        const Eigen::Vector3d d = at(rays, x, y), ground = at(grounds, x, y);
        if (!valid.at<std::uint8_t>(y, x) || std::isnan(d.x())) continue;
        const bool cabin = RayMeetsBox(c, d, cabin_lo, cabin_hi);
        if (std::isnan(ground.x())) {
          candidate.at<std::uint8_t>(y, x) = cabin ? 255 : 0;
          footprint.at<float>(y, x) = 0.0f;  // no road to resolve
          continue;
        }
        const Eigen::Vector3d right = at(grounds, x + 1, y), below = at(grounds, x, y + 1);
        if (!std::isnan(right.x()) && !std::isnan(below.x())) {
          footprint.at<float>(y, x) = static_cast<float>(std::max((right - ground).norm(), (below - ground).norm()));
        }
        if (std::abs(ground.x()) < hw && std::abs(ground.z()) < hl) seed.at<std::uint8_t>(y, x) = 255;
        if (!cabin && !RayMeetsBox(c, d, body_lo, body_hi) && d.z() >= 0) {
          const double beside = std::hypot(ground.x() - c.x(), ground.z() - c.z());
          if (beside >= options.min_road_m && beside <= options.max_road_m) {
            reference.at<std::uint8_t>(y, x) = 255;
            if (beside >= (options.min_road_m + options.max_road_m) / 2) outer.at<std::uint8_t>(y, x) = 255;
          }
          continue;
        }
        // Were it the road, would it have moved far enough to change? (Not far off towards the
        // motion's epipoles, where the road holds still too.)
        Eigen::Vector2d moved;
        const Eigen::Vector3d later = camera_from_vehicle.Apply(ground - Eigen::Vector3d(0, 0, travel_m));
        candidate.at<std::uint8_t>(y, x) = !model.Project(later, &moved) || (moved - Eigen::Vector2d(x, y)).norm() >= window ? 255 : 0;
      }
    }
  });
  const double road_spread = MedianWhere(spread, reference);
  if (!(road_spread > 0)) return cv::Mat();
  // The road must move clearly more than the car: else nothing tells them apart.
  const double car_spread = MedianWhere(spread, seed);
  if (!(road_spread >= options.min_road_to_car * car_spread)) return cv::Mat();
  // Road pixels coarser than the reference's outer half (its median footprint) cannot be told from
  // the car by holding still (beyond the bonnet, a smooth verge far off holds still too, and a
  // vehicle stopping close ahead later stands there); a pixel holds still below the geometric mean
  // of the car's and the road's spread.
  const double coarsest = MedianWhere(footprint, outer);
  if (!(coarsest > 0)) return cv::Mat();
  const cv::Mat still = candidate & (spread < std::sqrt(car_spread * road_spread)) & (footprint <= coarsest);
  cv::Mat own = ComponentsTouching(still, seed);
  // Specks of noise inside the car; then back by half a window: the window that smooths the spread
  // reaches that far beyond the car, where the road moves less on average and holds still with it
  // (an object's bottom next to the bonnet must stay).
  const cv::Mat disc = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(window, window));
  cv::morphologyEx(own, own, cv::MORPH_CLOSE, disc);
  cv::erode(own, own, disc);
  return own & valid;
}

}  // namespace dps
