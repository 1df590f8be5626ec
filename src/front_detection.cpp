#include "dps/front_detection.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "dps/error.h"

namespace dps {
StereoOptions DetectionStereoOptions() {
  StereoOptions o;
  o.num_disparities = 64;
  o.texture_threshold = 4.5;
  return o;
}

FrontDetector::FrontDetector(const Rig& rig, const FrontDetectorOptions& options) : options_(options), rig_(rig) {
  options_.histogram.min_disparity = options.stereo.min_disparity;
  options_.histogram.max_disparity = options.stereo.min_disparity + options.stereo.num_disparities;
  options_.histogram.two_sided = false;
  options_.histogram.link_max_gap = options.link_max_gap;
  options_.histogram.Check();
  const ViewSpec spec = FrontViewSpec(rig, "left", "right", options.view_width, options.view_height, options.focal_px);
  spec_ = spec;
  if (options.temporal_max_variance_px2 > 0) {
    temporal_ = std::make_unique<TemporalConsistencyFilter>(options.temporal_forgetting, options.temporal_max_variance_px2);
  }
  left_ = std::make_unique<VirtualView>(rig.Camera("left"), spec);
  right_ = std::make_unique<VirtualView>(rig.Camera("right"), spec);
  matcher_ = std::make_unique<SadStereoMatcher>(options.stereo);
  baseline_m_ = (rig.Camera("right").vehicle_from_camera.t - rig.Camera("left").vehicle_from_camera.t).norm();
  cv::Mat own = OwnCarMask(*left_, rig.vehicle, options.own_car_height_m);
  cv::bitwise_or(own, OwnCarMask(*right_, rig.vehicle, options.own_car_height_m), own);
  cv::bitwise_or(own, left_->mask() == 0, ignore_);
  // The road's disparity at every pixel of the left view (the reference).
  road_ = cv::Mat(spec.height, spec.width, CV_32F, cv::Scalar(kInvalidDisparity));
  const Eigen::Vector3d origin = left_->viewpoint_vehicle();
  for (int y = 0; y < spec.height; ++y) {
    for (int x = 0; x < spec.width; ++x) {
      const Eigen::Vector3d ray = left_->RayVehicle(x, y);
      if (ray.y() <= 1e-9 || origin.y() >= 0) continue;  // looks up: no road
      const Eigen::Vector3d ground = origin + (-origin.y() / ray.y()) * ray;
      const double depth = (spec.vehicle_from_view.transpose() * (ground - origin)).z();
      if (depth > 0) road_.at<float>(y, x) = static_cast<float>(spec.focal_px * baseline_m_ / depth);
    }
  }
  ramp_ = RoadRamp(road_, options.stereo.block_height / 2 + 1);
}

FrontDetector::~FrontDetector() = default;


bool FrontDetector::ColumnToGround(double x, double disparity, Eigen::Vector2d* ground) const {
  if (!(disparity > 0)) return false;
  const ViewSpec& s = left_->spec();
  const double depth = s.focal_px * baseline_m_ / disparity;
  const double lateral = (x - s.cx) * depth / s.focal_px;
  // The view-frame point (lateral, h, depth) whose vehicle-frame height is 0 (the ground): the
  // vertical line of the column at that depth, dropped onto the road (eq. 16).
  const Eigen::Matrix3d& R = s.vehicle_from_view;
  const Eigen::Vector3d& t = left_->viewpoint_vehicle();
  const double h = std::abs(R(1, 1)) > 1e-9 ? -(t.y() + R(1, 0) * lateral + R(1, 2) * depth) / R(1, 1) : 0.0;
  const Eigen::Vector3d p = t + R * Eigen::Vector3d(lateral, h, depth);
  *ground = Eigen::Vector2d(p.x(), p.z());
  return true;
}

bool FrontDetector::OuterPoint(const HistogramComponent& c, bool last, Eigen::Vector2d* ground) const {
  const int n = static_cast<int>(c.column_disparity.size());
  for (int i = 0; i < n; ++i) {
    const int at = last ? n - 1 - i : i;
    if (std::isfinite(c.column_disparity[at])) return ColumnToGround(c.x_begin + at, c.column_disparity[at], ground);
  }
  return false;
}

bool FrontDetector::InComponent(const FrontResult& r, const cv::Mat& labels, int label, int x, int y) const {
  const float v = r.disparity.at<float>(y, x);
  if (!std::isfinite(v) || r.score.at<float>(y, x) <= 0) return false;
  const int bin = static_cast<int>(std::floor((v - options_.histogram.min_disparity) / options_.histogram.bin_px));
  return bin >= 0 && bin < labels.rows && labels.at<int>(bin, x) == label;
}

double FrontDetector::TopHeight(const FrontResult& r, const cv::Mat& labels, const HistogramComponent& c) const {
  const ViewSpec& s = left_->spec();
  const Eigen::Vector3d& t = left_->viewpoint_vehicle();
  std::vector<double> tops;
  for (int x = c.x_begin; x < c.x_end; ++x) {
    for (int y = 0; y < r.disparity.rows; ++y) {
      if (!InComponent(r, labels, c.label, x, y)) continue;
      // The highest pixel of the column in the component (its score > 0 puts its disparity
      // above the road's, so > 0): its point's height above the road.
      const float v = r.disparity.at<float>(y, x);
      const double depth = s.focal_px * baseline_m_ / v;
      const Eigen::Vector3d view((x - s.cx) * depth / s.focal_px, (y - s.cy) * depth / s.focal_px, depth);
      tops.push_back(-(t + s.vehicle_from_view * view).y());
      break;
    }
  }
  if (tops.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t k = tops.size() / 4;  // three quarters of the columns reach at least this high
  std::nth_element(tops.begin(), tops.begin() + k, tops.end(), std::greater<double>());
  return tops[k];
}

FrontResult FrontDetector::Detect(const cv::Mat& left_omni, const cv::Mat& right_omni) {
  FrontResult r;
  left_->Render(GreyImage(left_omni), r.left_view);
  right_->Render(GreyImage(right_omni), r.right_view);
  // Drift: measure the rows' misalignment now and then, and rebuild the right view to cancel it.
  if (options_.drift_interval > 0 && frames_ % options_.drift_interval == 0) {
    const VerticalOffset off = EstimateVerticalOffset(r.left_view, r.right_view, options_.stereo.min_disparity,
                                                      options_.stereo.num_disparities);
    r.drift_measured = true;
    if (off.features >= options_.drift_min_features && std::abs(off.offset_px) > options_.drift_min_px) {
      vertical_offset_px_ += off.offset_px;
      ViewSpec shifted = spec_;
      shifted.cy -= vertical_offset_px_;
      right_ = std::make_unique<VirtualView>(rig_.Camera("right"), shifted);
      right_->Render(GreyImage(right_omni), r.right_view);
    }
  }
  r.vertical_offset_px = vertical_offset_px_;
  ++frames_;
  r.disparity = matcher_->Compute(r.left_view, r.right_view);
  r.disparity.setTo(kInvalidDisparity, ignore_);
  if (temporal_) r.disparity = temporal_->Apply(r.disparity);
  r.score = ScoreImage(r.disparity, road_, options_.histogram, ramp_);
  cv::Mat moments, labels;
  r.histogram = ColumnHistogram(r.disparity, r.score, options_.histogram, &moments);
  // Parts of one surface are linked when the gap between them on the ground is short, a wider
  // gap only within one vehicle's length, and when their tops are level (a pole beyond the end of
  // a car's side is twice as tall).
  const auto link = [&](const HistogramComponent& a, int x0, float d0, const HistogramComponent& b, int x1, float d1) {
    Eigen::Vector2d ga, gb;
    if (!ColumnToGround(x0, d0, &ga) || !ColumnToGround(x1, d1, &gb) || (ga - gb).norm() > options_.link_max_gap_m) {
      return false;
    }
    // Parts apart on the ground are one object only if together they fit one vehicle's length.
    Eigen::Vector2d first, last;
    if (options_.link_vehicle_length_m > 0 && (ga - gb).norm() > options_.link_free_gap_m &&
        OuterPoint(a, false, &first) && OuterPoint(b, true, &last) &&
        (first - last).norm() > options_.link_vehicle_length_m) {
      return false;
    }
    return !(options_.link_max_top_difference_m > 0 &&
             std::abs(TopHeight(r, labels, a) - TopHeight(r, labels, b)) > options_.link_max_top_difference_m);
  };
  const std::vector<HistogramComponent> components =
      LinkComponents(FindComponents(r.histogram, options_.histogram, &labels, moments), r.disparity, road_,
                     options_.histogram, &labels, link);
  r.obstacle = cv::Mat(r.histogram.size(), CV_32F, cv::Scalar(0));
  int id = 0;
  const auto [first_valid, last_valid] = ValidColumns(r.disparity);
  const int margin = options_.stereo.block_width;
  for (const HistogramComponent& c : components) {
    // An obstacle stands up from the road: in each column it fills many rows with its disparity
    // (rows ~ height * d / B). Flat things (lane markings, road matched wrongly) and stray matches
    // fill few. Height per column = contributing rows * B / d; the component's is the median.
    std::vector<double> heights;
    for (int x = c.x_begin; x < c.x_end; ++x) {
      const float d = c.column_disparity[x - c.x_begin];
      if (!std::isfinite(d) || d <= 0) continue;
      int rows = 0;
      for (int y = 0; y < r.disparity.rows; ++y) rows += InComponent(r, labels, c.label, x, y);
      heights.push_back(rows * baseline_m_ / d);
    }
    if (heights.empty()) continue;
    std::nth_element(heights.begin(), heights.begin() + heights.size() / 2, heights.end());
    if (heights[heights.size() / 2] < options_.min_obstacle_height_m &&
        !(c.x_end - c.x_begin >= options_.tall_min_columns && TopHeight(r, labels, c) >= options_.tall_min_top_m)) {
      continue;
    }
    // The outermost half window of columns is foreground fattening, not the object.
    const auto [first, last] = ProjectedColumns(c, options_.stereo.block_width / 2);
    std::vector<Eigen::Vector2d> points;
    for (int x = first; x <= last; ++x) {
      const float d = c.column_disparity[x - c.x_begin];
      Eigen::Vector2d g;
      if (!std::isfinite(d) || !ColumnToGround(x, d, &g) || g.norm() > options_.max_range_m) continue;
      points.push_back(g);
      const int row = static_cast<int>((d - options_.histogram.min_disparity) / options_.histogram.bin_px);
      if (row >= 0 && row < r.obstacle.rows) r.obstacle.at<float>(row, x) = d;
    }
    if (points.empty()) continue;
    Detection det = DetectionFromPoints(points, "front");
    if (c.x_begin <= first_valid + margin) det.clipped_ends.push_back(points.front());
    if (c.x_end - 1 >= last_valid - margin) det.clipped_ends.push_back(points.back());
    det.id = id++;
    r.detections.push_back(std::move(det));
  }
  return r;
}

}  // namespace dps
