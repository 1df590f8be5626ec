#include "dps/side_detection.h"

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "dps/error.h"
#include "dps/front_detection.h"

namespace dps {
namespace {

// Where a view pixel's ray meets the road, in the vehicle frame of the view; false above the
// horizon.
bool PixelToGround(const VirtualView& view, double x, double y, Eigen::Vector3d* ground) {
  const Eigen::Vector3d o = view.viewpoint_vehicle();
  const Eigen::Vector3d r = view.RayVehicle(x, y);
  if (r.y() <= 1e-9 || o.y() >= 0) return false;
  *ground = o + (-o.y() / r.y()) * r;
  return true;
}

}  // namespace

SideDetectorOptions::SideDetectorOptions() {
  stereo = DetectionStereoOptions();
  stereo.min_disparity = -16;
  histogram.two_sided = true;
  histogram.min_columns = 10;  // nearby vehicles fill much of a side view; small blobs are road
}

SideDetector::SideDetector(const Rig& rig, const std::string& camera, Side side,
                           const SideDetectorOptions& options)
    : camera_(rig.Camera(camera)), side_(side), vehicle_(rig.vehicle), options_(options) {
  options_.histogram.min_disparity = options.stereo.min_disparity;
  options_.histogram.max_disparity = options.stereo.min_disparity + options.stereo.num_disparities;
  options_.histogram.two_sided = true;
  options_.histogram.Check();
  views_ = std::make_unique<SideViewCache>(camera_, side, options.view_width, options.view_height, options.focal_px);
  matcher_ = std::make_unique<SadStereoMatcher>(options.stereo);
}

SideDetector::~SideDetector() = default;

const SideDetector::ViewGeometry& SideDetector::Geometry(const VirtualView& view, long key) {
  const auto it = geometry_.find(key);
  if (it != geometry_.end()) return it->second;
  if (geometry_.size() > 64) geometry_.clear();  // a long turn through many yaws
  const ViewSpec& spec = view.spec();
  ViewGeometry g;
  g.ignore = OwnCarMask(view, vehicle_, options_.own_car_height_m);
  cv::bitwise_or(g.ignore, view.mask() == 0, g.ignore);
  g.inverse_depth = cv::Mat(spec.height, spec.width, CV_32F, cv::Scalar(0));
  for (int y = 0; y < spec.height; ++y) {
    for (int x = 0; x < spec.width; ++x) {
      Eigen::Vector3d p;
      if (!PixelToGround(view, x, y, &p)) continue;
      const double depth = (spec.vehicle_from_view.transpose() * (p - view.viewpoint_vehicle())).z();
      if (depth > 0) g.inverse_depth.at<float>(y, x) = static_cast<float>(1.0 / depth);
    }
  }
  return geometry_.emplace(key, std::move(g)).first->second;
}

SideResult SideDetector::Detect(const cv::Mat& previous_omni, const cv::Mat& current_omni,
                                const PlanarPose& current_in_previous) {
  SideResult r;
  // The camera's displacement, in the previous frame's vehicle frame.
  const Pose rel = current_in_previous.ToPose3();
  const Eigen::Vector3d t = camera_.vehicle_from_camera.t;
  const Eigen::Vector3d delta = rel.Apply(t) - t;
  r.baseline_m = std::hypot(delta.x(), delta.z());
  if (r.baseline_m < options_.min_baseline_m) {
    r.skipped = true;
    r.reason = Str("camera moved ", r.baseline_m, " m (< ", options_.min_baseline_m, " m)");
    return r;
  }
  // Both views parallel to the displacement: heading alpha in the previous frame, alpha - dh in
  // the current one. SideViewSpec's yaw turns towards the front on either side.
  const double alpha = std::atan2(delta.x(), delta.z());
  const double sign = side_ == Side::kLeft ? 1.0 : -1.0;
  const VirtualView& previous_view = views_->Get(sign * alpha);
  const cv::Mat previous = previous_view.Render(GreyImage(previous_omni));
  const VirtualView& current_view = views_->Get(sign * (alpha - current_in_previous.heading_rad));
  const cv::Mat current = current_view.Render(GreyImage(current_omni));
  // The camera moves along +x of a left view (static things move left in the image: the earlier
  // image is the reference) and along -x of a right view (the later one is).
  const bool previous_is_reference = side_ == Side::kLeft;
  const VirtualView& reference = previous_is_reference ? previous_view : current_view;
  r.reference_view = previous_is_reference ? previous : current;
  r.other_view = previous_is_reference ? current : previous;
  const ViewSpec& spec = reference.spec();

  const double reference_yaw = previous_is_reference ? sign * alpha : sign * (alpha - current_in_previous.heading_rad);
  const ViewGeometry& geometry = Geometry(reference, views_->Key(reference_yaw));
  const cv::Mat& ignore = geometry.ignore;
  r.disparity = matcher_->Compute(r.reference_view, r.other_view);
  r.disparity.setTo(kInvalidDisparity, ignore);
  // The road's disparity: f B / depth of the ground point along the view axis.
  cv::Mat road = geometry.inverse_depth * (spec.focal_px * r.baseline_m);
  road.setTo(kInvalidDisparity, geometry.inverse_depth == 0);
  const HistogramOptions& ho = options_.histogram;
  r.score = ScoreImage(r.disparity, road, ho, RoadRamp(road, options_.stereo.block_height / 2 + 1));
  cv::Mat moments, labels;
  r.histogram = ColumnHistogram(r.disparity, r.score, ho, &moments);
  const std::vector<HistogramComponent> components = FindComponents(r.histogram, ho, &labels, moments);
  r.obstacle = cv::Mat(spec.height, spec.width, CV_8U, cv::Scalar(0));
  const Pose to_current = previous_is_reference ? rel.Inverse() : Pose();
  int id = 0;
  for (const HistogramComponent& c : components) {
    std::vector<Eigen::Vector2d> points;
    std::vector<double> heights;
    for (int x = c.x_begin; x < c.x_end; ++x) {
      // The component's pixels in this column; the bottom-most is the contact with the road.
      int bottom = -1, rows = 0;
      for (int y = 0; y < spec.height; ++y) {
        const float v = r.disparity.at<float>(y, x);
        if (!std::isfinite(v) || r.score.at<float>(y, x) <= 0) continue;
        const int bin = static_cast<int>(std::floor((v - ho.min_disparity) / ho.bin_px));
        if (bin >= 0 && bin < labels.rows && labels.at<int>(bin, x) == c.label) {
          bottom = y;
          ++rows;
        }
      }
      Eigen::Vector3d g;
      if (bottom < 0 || !PixelToGround(reference, x, bottom, &g)) continue;
      const double depth = (spec.vehicle_from_view.transpose() * (g - reference.viewpoint_vehicle())).z();
      heights.push_back(rows * depth / spec.focal_px);
      const Eigen::Vector3d p = to_current.Apply(g);
      const Eigen::Vector2d ground(p.x(), p.z());
      if (ground.norm() > options_.max_range_m) continue;
      points.push_back(ground);
      r.obstacle.at<std::uint8_t>(bottom, x) = 255;
    }
    if (points.empty() || heights.empty()) continue;
    std::nth_element(heights.begin(), heights.begin() + heights.size() / 2, heights.end());
    if (heights[heights.size() / 2] < options_.min_obstacle_height_m) continue;
    Detection det = DetectionFromPoints(points, camera_.name);
    det.id = id++;
    r.detections.push_back(std::move(det));
  }
  return r;
}

}  // namespace dps
