#include "dps/stereo/virtual_view.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "dps/camera/box.h"
#include "dps/util/error.h"

namespace dps {

void ViewSpec::Check() const {
  if (width <= 0 || height <= 0) throw Error(Str("view: size ", width, "x", height, ": violated constraint > 0"));
  if (!(focal_px > 0.0)) throw Error(Str("view: focal_px = ", focal_px, ": violated constraint > 0"));
  if (!std::isfinite(cx) || !std::isfinite(cy)) throw Error("view: principal point not finite");
  const std::string problem = RotationProblem(vehicle_from_view, 1e-6);
  if (!problem.empty()) throw Error("view: vehicle_from_view: " + problem);
}

namespace {

// A view with its principal point at the image centre and axes x, y, z (vehicle frame).
ViewSpec CentredSpec(int width, int height, double focal_px, const Eigen::Vector3d& x,
                     const Eigen::Vector3d& y, const Eigen::Vector3d& z) {
  ViewSpec s;
  s.width = width;
  s.height = height;
  s.focal_px = focal_px;
  s.cx = (width - 1) / 2.0;
  s.cy = (height - 1) / 2.0;
  s.vehicle_from_view << x, y, z;
  return s;
}

// True when the camera's mask (none: every pixel) marks all the pixels that bilinear sampling at
// `px` reads as seeing the world.
bool SeesWorld(const cv::Mat& mask, const Eigen::Vector2d& px) {
  if (mask.empty()) return true;
  const int x0 = static_cast<int>(std::floor(px.x())), y0 = static_cast<int>(std::floor(px.y()));
  for (int y = std::max(0, y0); y <= std::min(mask.rows - 1, y0 + 1); ++y) {
    for (int x = std::max(0, x0); x <= std::min(mask.cols - 1, x0 + 1); ++x) {
      if (!mask.at<std::uint8_t>(y, x)) return false;
    }
  }
  return true;
}

}  // namespace

ViewSpec FrontViewSpec(const Rig& rig, const std::string& left_camera,
                       const std::string& right_camera, int width, int height, double focal_px) {
  const Eigen::Vector3d baseline =
      rig.Camera(right_camera).vehicle_from_camera.t - rig.Camera(left_camera).vehicle_from_camera.t;
  if (baseline.norm() < 1e-3) throw Error(Str("front view: cameras '", left_camera, "' and '",
                                              right_camera, "' are at the same place"));
  const Eigen::Vector3d x = baseline.normalized();
  Eigen::Vector3d z = Eigen::Vector3d::UnitZ() - x.z() * x;
  if (z.norm() < 1e-3) throw Error("front view: the baseline points forward; no front pair");
  z.normalize();
  return CentredSpec(width, height, focal_px, x, z.cross(x), z);
}

ViewSpec SideViewSpec(Side side, int width, int height, double focal_px, double yaw_rad, double horizon_fraction,
                      double back_fraction) {
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const Eigen::Vector3d z = side == Side::kLeft ? Eigen::Vector3d(-c, 0, s) : Eigen::Vector3d(c, 0, s);
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY();
  ViewSpec spec = CentredSpec(width, height, focal_px, y.cross(z), y, z);
  spec.cy = horizon_fraction * (height - 1);
  // Image x runs backwards in a right view and forwards in a left one.
  if (back_fraction != 0.5) spec.cx = (side == Side::kRight ? 1.0 - back_fraction : back_fraction) * (width - 1);
  return spec;
}

VirtualView::VirtualView(const RigCamera& camera, const ViewSpec& spec)
    : spec_(spec), viewpoint_(camera.vehicle_from_camera.t) {
  spec.Check();
  const Eigen::Matrix3d camera_from_view = camera.vehicle_from_camera.R.transpose() * spec.vehicle_from_view;
  const CameraModel& model = camera.model;
  map_float_.create(spec.height, spec.width, CV_32FC2);
  mask_.create(spec.height, spec.width, CV_8U);
  if (!camera.own_car.empty()) own_car_.create(spec.height, spec.width, CV_8U);
  cv::parallel_for_(cv::Range(0, spec.height), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      cv::Vec2f* m = map_float_.ptr<cv::Vec2f>(y);
      std::uint8_t* k = mask_.ptr<std::uint8_t>(y);
      for (int x = 0; x < spec.width; ++x) {
        const Eigen::Vector3d ray((x - spec.cx) / spec.focal_px, (y - spec.cy) / spec.focal_px, 1.0);
        Eigen::Vector2d px;
        if (model.Project(camera_from_view * ray, &px) && model.InImage(px) && SeesWorld(camera.mask, px)) {
          m[x] = cv::Vec2f(static_cast<float>(px.x()), static_cast<float>(px.y()));
          k[x] = 255;
        } else {
          m[x] = cv::Vec2f(-1.0f, -1.0f);
          k[x] = 0;
        }
        if (!own_car_.empty()) {
          std::uint8_t own = 0;
          if (k[x]) {
            const int u = std::clamp(static_cast<int>(std::lround(px.x())), 0, camera.own_car.cols - 1);
            const int v = std::clamp(static_cast<int>(std::lround(px.y())), 0, camera.own_car.rows - 1);
            own = camera.own_car.at<std::uint8_t>(v, u) ? 255 : 0;
          }
          own_car_.at<std::uint8_t>(y, x) = own;
        }
      }
    }
  });
  // For cv::remap, pixels that see nothing point well outside the image: it fills those with the
  // border value at once, while points within a pixel of the image (such as (-1, -1)) take its
  // slow path that interpolates the border for every neighbour.
  cv::Mat remap_table = map_float_.clone();
  remap_table.setTo(cv::Scalar(-16, -16), mask_ == 0);
  cv::convertMaps(remap_table, cv::Mat(), map1_, map2_, CV_16SC2);
}

cv::Mat VirtualView::Render(const cv::Mat& omni) const {
  cv::Mat out;
  Render(omni, out);
  return out;
}

void VirtualView::Render(const cv::Mat& omni, cv::Mat& out) const {
  cv::remap(omni, out, map1_, map2_, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
}

Eigen::Vector3d VirtualView::RayVehicle(double x, double y) const {
  return (spec_.vehicle_from_view *
          Eigen::Vector3d((x - spec_.cx) / spec_.focal_px, (y - spec_.cy) / spec_.focal_px, 1.0))
      .normalized();
}

bool VirtualView::ProjectVehicle(const Eigen::Vector3d& p, Eigen::Vector2d* pixel) const {
  const Eigen::Vector3d v = spec_.vehicle_from_view.transpose() * (p - viewpoint_);
  if (v.z() <= 1e-9) return false;
  *pixel = Eigen::Vector2d(spec_.focal_px * v.x() / v.z() + spec_.cx,
                           spec_.focal_px * v.y() / v.z() + spec_.cy);
  return true;
}

SideViewCache::SideViewCache(const RigCamera& camera, Side side, int width, int height,
                             double focal_px, double yaw_step_rad, size_t capacity, double horizon_fraction,
                             double back_fraction)
    : camera_(camera), side_(side), width_(width), height_(height), focal_px_(focal_px),
      horizon_fraction_(horizon_fraction), back_fraction_(back_fraction), step_(yaw_step_rad), capacity_(capacity) {
  if (!(yaw_step_rad > 0.0)) throw Error(Str("side view cache: yaw step ", yaw_step_rad, ": violated constraint > 0"));
  if (capacity < 1) throw Error("side view cache: capacity must be >= 1");
}

long SideViewCache::Key(double yaw_rad) const { return std::lround(yaw_rad / step_); }

const VirtualView& SideViewCache::Get(double yaw_rad) {
  const long key = Key(yaw_rad);
  for (auto it = views_.begin(); it != views_.end(); ++it) {
    if (it->first == key) {
      views_.splice(views_.begin(), views_, it);  // most recently used first
      return *views_.front().second;
    }
  }
  views_.emplace_front(key, std::make_unique<VirtualView>(
                                camera_, SideViewSpec(side_, width_, height_, focal_px_, key * step_, horizon_fraction_, back_fraction_)));
  ++builds_;
  if (views_.size() > capacity_) views_.pop_back();
  return *views_.front().second;
}

cv::Mat OwnCarMask(const VirtualView& view, const Vehicle& vehicle, double height_m) {
  const ViewSpec& s = view.spec();
  const Eigen::Vector3d o = view.viewpoint_vehicle();
  const Eigen::Vector3d lo(-vehicle.width_m / 2, -height_m, -vehicle.length_m / 2);
  const Eigen::Vector3d hi(vehicle.width_m / 2, 0.0, vehicle.length_m / 2);
  cv::Mat mask(s.height, s.width, CV_8U, cv::Scalar(0));
  for (int y = 0; y < s.height; ++y) {
    for (int x = 0; x < s.width; ++x) {
      if (RayMeetsBox(o, view.RayVehicle(x, y), lo, hi, 0.0, 1e9)) mask.at<std::uint8_t>(y, x) = 255;
    }
  }
  return mask;
}

VerticalOffset EstimateVerticalOffset(const cv::Mat& left_in, const cv::Mat& right_in,
                                      int min_disparity, int num_disparities, double max_offset_px) {
  cv::Mat left = left_in, right = right_in;
  if (left.channels() == 3) cv::cvtColor(left_in, left, cv::COLOR_BGR2GRAY);
  if (right.channels() == 3) cv::cvtColor(right_in, right, cv::COLOR_BGR2GRAY);
  constexpr int kHalf = 7;              // template half size
  constexpr double kMinScore = 0.85;    // normalised correlation of a reliable match
  const int margin = static_cast<int>(std::ceil(max_offset_px)) + 1;
  const int d_max = min_disparity + num_disparities - 1;
  // Corners away from the borders and from pixels without a source (black).
  cv::Mat usable = left > 0;
  cv::erode(usable, usable, cv::Mat(), cv::Point(-1, -1), kHalf + 2);
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(left, corners, 300, 0.01, 6, usable);
  std::vector<double> shifts;
  for (const cv::Point2f& c : corners) {
    const int x = cvRound(c.x), y = cvRound(c.y);
    const int x0 = x - d_max - kHalf, x1 = x - min_disparity + kHalf + 1;
    const int y0 = y - kHalf - margin, y1 = y + kHalf + margin + 1;
    if (x - kHalf < 0 || x + kHalf >= left.cols || y0 < 0 || y1 > right.rows || x0 < 0 || x1 > right.cols) {
      continue;
    }
    const cv::Mat templ = left(cv::Rect(x - kHalf, y - kHalf, 2 * kHalf + 1, 2 * kHalf + 1));
    cv::Mat score;
    cv::matchTemplate(right(cv::Rect(x0, y0, x1 - x0, y1 - y0)), templ, score, cv::TM_CCOEFF_NORMED);
    double best = 0;
    cv::Point at;
    cv::minMaxLoc(score, nullptr, &best, nullptr, &at);
    if (best < kMinScore || at.y == 0 || at.y == score.rows - 1) continue;
    // A second peak a template width or more away, as good as the best, makes the match
    // ambiguous (repeated texture such as lane dashes).
    cv::Mat others = score.clone();
    cv::rectangle(others, cv::Rect(at.x - 2 * kHalf, 0, 4 * kHalf + 1, others.rows), cv::Scalar(-1),
                  cv::FILLED);
    double second = 0;
    cv::minMaxLoc(others, nullptr, &second);
    if (second > best - 0.05) continue;
    const double a = score.at<float>(at.y - 1, at.x), b = best, d = score.at<float>(at.y + 1, at.x);
    const double denom = a - 2 * b + d;
    const double sub = denom < 0 ? 0.5 * (a - d) / denom : 0.0;
    shifts.push_back(at.y + sub - margin);
  }
  VerticalOffset out;
  out.features = static_cast<int>(shifts.size());
  if (shifts.empty()) return out;
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  out.offset_px = median(shifts);
  std::vector<double> dev;
  for (double s : shifts) dev.push_back(std::abs(s - out.offset_px));
  out.spread_px = median(dev);
  return out;
}

}  // namespace dps
