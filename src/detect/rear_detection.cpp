#include "dps/detect/rear_detection.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "dps/util/error.h"
#include "dps/util/math.h"

namespace dps {

void RearDetectorOptions::Check() const {
  const OptionCheck Require("rear detector");
  Require(focal_px > 0, "focal_px", focal_px, "> 0");
  Require(outer_deg > 0 && outer_deg <= 80, "outer_deg", outer_deg, "in (0, 80]");
  Require(inner_deg >= 0 && inner_deg <= 45, "inner_deg", inner_deg, "in [0, 45]");
  Require(up_deg > 0 && up_deg <= 60, "up_deg", up_deg, "in (0, 60]");
  Require(down_deg > 0 && down_deg <= 80, "down_deg", down_deg, "in (0, 80]");
  Require(max_range_m > 0, "max_range_m", max_range_m, "> 0");
  Require(min_road_shift_windows > 0, "min_road_shift_windows", min_road_shift_windows, "> 0");
  Require(max_interval_s > 0, "max_interval_s", max_interval_s, "> 0");
  Require(window_px >= 3 && window_px % 2 == 1, "window_px", window_px, "odd, >= 3");
  Require(max_road_zncc > -1 && max_road_zncc < 1, "max_road_zncc", max_road_zncc, "in (-1, 1)");
  Require(min_still_zncc > -1 && min_still_zncc < 1, "min_still_zncc", min_still_zncc, "in (-1, 1)");
  Require(min_contrast_sigmas > 0, "min_contrast_sigmas", min_contrast_sigmas, "> 0");
  Require(min_width_m > 0, "min_width_m", min_width_m, "> 0");
  Require(max_contact_jump_m > 0, "max_contact_jump_m", max_contact_jump_m, "> 0");
  Require(own_car_height_m > 0, "own_car_height_m", own_car_height_m, "> 0");
}

ViewSpec RearViewSpec(const Rig& rig, const std::string& camera, Side side, const RearDetectorOptions& o) {
  (void)rig.Camera(camera);  // names a missing camera
  // Bearings from +Z towards +X: straight back is 180 degrees, outward is +X on the right.
  const double sign = side == Side::kRight ? -1.0 : 1.0;
  const double outer = (180.0 + sign * o.outer_deg) * kRadPerDeg, inner = (180.0 - sign * o.inner_deg) * kRadPerDeg;
  const double axis = (outer + inner) / 2, half = std::abs(outer - inner) / 2;
  ViewSpec s;
  s.focal_px = o.focal_px;
  s.width = std::max(8, static_cast<int>(std::ceil(2 * o.focal_px * std::tan(half))));
  const double up = o.focal_px * std::tan(o.up_deg * kRadPerDeg), down = o.focal_px * std::tan(o.down_deg * kRadPerDeg);
  s.height = std::max(8, static_cast<int>(std::ceil(up + down)));
  s.cx = (s.width - 1) / 2.0;
  s.cy = up;
  const Eigen::Vector3d z(std::sin(axis), 0.0, std::cos(axis)), y(0.0, 1.0, 0.0);
  s.vehicle_from_view.col(0) = y.cross(z);
  s.vehicle_from_view.col(1) = y;
  s.vehicle_from_view.col(2) = z;
  return s;
}

RearDetector::RearDetector(const Rig& rig, const std::string& camera, Side side, const RearDetectorOptions& options)
    : camera_(rig.Camera(camera)),
      options_((options.Check(), options)),
      view_(camera_, RearViewSpec(rig, camera, side, options)) {
  const ViewSpec& s = view_.spec();
  cv::Mat ignore = OwnCarMask(view_, rig.vehicle, options_.own_car_height_m);
  if (!view_.own_car().empty()) ignore |= view_.own_car();
  ignore |= view_.mask() == 0;
  // A window touching an ignored pixel is not judged.
  const int half = options_.window_px / 2;
  cv::dilate(ignore, ignore_, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * half + 1, 2 * half + 1)));
  camera_height_m_ = std::max(0.1, -camera_.vehicle_from_camera.t.y());
  road_.create(s.height, s.width, CV_32FC3);
  rays_.create(s.height, s.width, CV_32FC3);
  const Eigen::Vector3d c = view_.viewpoint_vehicle();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < s.height; ++v) {
    for (int u = 0; u < s.width; ++u) {
      const Eigen::Vector3d ray = view_.RayVehicle(u, v);
      rays_.at<cv::Vec3f>(v, u) = cv::Vec3f(ray.x(), ray.y(), ray.z());
      Eigen::Vector3d g;
      road_.at<cv::Vec3f>(v, u) = RayMeetsRoad(c, ray, &g) ? cv::Vec3f(g.x(), g.y(), g.z()) : cv::Vec3f(nan, nan, nan);
    }
  }
}

namespace {

// A view's window means and standard deviations, computed once for every image it is compared
// with (as plane_sweep.cpp's Reference).
struct WindowStats {
  cv::Mat image, mean, sd;  // CV_32F
};

WindowStats MakeWindowStats(const cv::Mat& image, int window) {
  const cv::Size w(window, window);
  WindowStats st;
  image.convertTo(st.image, CV_32F);
  cv::Mat squares;
  cv::boxFilter(st.image, st.mean, CV_32F, w);
  cv::boxFilter(st.image.mul(st.image), squares, CV_32F, w);
  cv::Mat variance = squares - st.mean.mul(st.mean);
  cv::max(variance, 0.0, variance);
  cv::sqrt(variance, st.sd);
  return st;
}

// Zero-mean normalised cross-correlation of every window of `a` with b's, and b's standard
// deviations.
void WindowZncc(const WindowStats& a, const cv::Mat& b, int window, cv::Mat* zncc, cv::Mat* sd_b) {
  const WindowStats sb = MakeWindowStats(b, window);
  cv::Mat mab;
  cv::boxFilter(a.image.mul(sb.image), mab, CV_32F, cv::Size(window, window));
  const cv::Mat cab = mab - a.mean.mul(sb.mean);
  cv::Mat denominator = a.sd.mul(sb.sd) + 1e-6f;
  cv::divide(cab, denominator, *zncc);
  *sd_b = sb.sd;
}

}  // namespace

cv::Mat RearDetector::WarpEarlier(const Earlier& earlier, cv::Mat* invalid) const {
  const ViewSpec& s = view_.spec();
  const Pose rel = earlier.current_in_earlier.ToPose3();
  const Eigen::Vector3d c = view_.viewpoint_vehicle();
  cv::Mat map(s.height, s.width, CV_32FC2, cv::Scalar(-1, -1));
  for (int v = 0; v < s.height; ++v) {
    for (int u = 0; u < s.width; ++u) {
      const cv::Vec3f g = road_.at<cv::Vec3f>(v, u);
      Eigen::Vector3d p;
      if (std::isfinite(g[0])) {
        p = rel.Apply(Eigen::Vector3d(g[0], g[1], g[2]));
      } else {  // above the horizon: far away, only the rotation counts
        const cv::Vec3f r = rays_.at<cv::Vec3f>(v, u);
        p = rel.Apply(c + 1e4 * Eigen::Vector3d(r[0], r[1], r[2]));
      }
      Eigen::Vector2d px;
      if (view_.ProjectVehicle(p, &px) && px.x() >= 0 && px.y() >= 0 && px.x() <= s.width - 1 && px.y() <= s.height - 1) {
        map.at<cv::Vec2f>(v, u) = cv::Vec2f(static_cast<float>(px.x()), static_cast<float>(px.y()));
      }
    }
  }
  cv::Mat warped, ignored;
  cv::remap(earlier.view, warped, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
  cv::remap(ignore_, ignored, map, cv::noArray(), cv::INTER_NEAREST, cv::BORDER_CONSTANT, 255);
  *invalid = ignored;
  return warped;
}

RearResult RearDetector::Detect(const cv::Mat& omni, const PlanarPose* current_in_previous, double t_s) {
  RearResult r;
  const ViewSpec& s = view_.spec();
  const RearDetectorOptions& o = options_;
  r.view = view_.Render(omni);
  r.obstacle = cv::Mat::zeros(s.height, s.width, CV_8U);
  r.sector = ViewColumnsSector(camera_.name, {camera_.vehicle_from_camera.t.x(), camera_.vehicle_from_camera.t.z()}, s,
                               0, s.width - 1);
  if (current_in_previous == nullptr) {
    history_.clear();
  } else {
    for (Earlier& e : history_) e.current_in_earlier = Compose(e.current_in_earlier, *current_in_previous);
  }
  while (!history_.empty() && t_s - history_.back().t_s > o.max_interval_s) history_.pop_back();
  // Each pixel is judged against the two latest earlier frames in which the road at its distance
  // D (at most max_range_m) has moved by min_road_shift_windows windows (a camera displacement b
  // shifts it by about f H b / D^2), the second at least 1.5 times as far back as the first.
  const Eigen::Vector3d t = camera_.vehicle_from_camera.t;
  const auto remember = [&] { history_.push_front({r.view, PlanarPose{}, t_s}); };
  const int half = o.window_px / 2;
  const cv::Mat square = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * half + 1, 2 * half + 1));
  struct Warp {
    double baseline_m = 0.0;
    cv::Mat bad, image, zncc, sd;
  };
  std::vector<Warp> warps;
  const WindowStats current = MakeWindowStats(r.view, o.window_px);
  const cv::Mat& cur = current.image;
  const cv::Mat& sd_cur = current.sd;
  for (const Earlier& e : history_) {
    Warp w;
    const Eigen::Vector3d d = e.current_in_earlier.ToPose3().Apply(t) - t;
    w.baseline_m = std::hypot(d.x(), d.z());
    if (!warps.empty() && w.baseline_m < 1.2 * warps.back().baseline_m) continue;  // standing, or too alike
    cv::Mat invalid;
    WarpEarlier(e, &invalid).convertTo(w.image, CV_32F);
    cv::dilate(ignore_ | invalid, w.bad, square);
    WindowZncc(current, w.image, o.window_px, &w.zncc, &w.sd);
    warps.push_back(std::move(w));
  }
  if (warps.size() < 2) {
    r.skipped = true;
    r.reason = history_.size() < 2 ? "no earlier frames yet" : "the camera has not moved";
    remember();
    return r;
  }
  r.baseline_m = warps.front().baseline_m;
  // What holds still in the view while the road moves: the own car (a mirror housing's edge, the
  // body's flank) or something keeping pace with it exactly. The current view against the oldest
  // earlier one as it is (no warp).
  cv::Mat still, sd_still;
  WindowZncc(current, history_.back().view, o.window_px, &still, &sd_still);
  warps.front().image.convertTo(r.warped, CV_8U);
  // Per pixel, the two warps it is judged against (-1: none).
  cv::Mat pick(s.height, s.width, CV_32SC2, cv::Scalar(-1, -1));
  std::vector<float> diffs;
  // The displacement needed at distance D: D^2 / (f H / shift).
  const double f_h_per_shift = s.focal_px * camera_height_m_ / (o.min_road_shift_windows * o.window_px);
  const Eigen::Vector3d c = view_.viewpoint_vehicle();
  for (int v = 0; v < s.height; ++v) {
    for (int u = 0; u < s.width; ++u) {
      if (ignore_.at<uchar>(v, u)) continue;
      const cv::Vec3f g = road_.at<cv::Vec3f>(v, u);
      const double distance = std::isfinite(g[0]) ? std::min(o.max_range_m, std::hypot(g[0] - c.x(), g[2] - c.z())) : o.max_range_m;
      const double needed = distance * distance / f_h_per_shift;
      int a = -1, b = -1;
      for (int i = 0; i < static_cast<int>(warps.size()); ++i) {
        if (warps[i].baseline_m < needed || warps[i].bad.at<uchar>(v, u)) continue;
        if (a < 0) {
          a = i;
        } else if (warps[i].baseline_m >= 1.5 * warps[a].baseline_m) {
          b = i;
          break;
        }
      }
      if (b < 0) continue;
      pick.at<cv::Vec2i>(v, u) = cv::Vec2i(a, b);
      if (std::isfinite(g[0])) diffs.push_back(std::abs(cur.at<float>(v, u) - warps[a].image.at<float>(v, u)));
    }
  }
  if (diffs.size() < 100) {
    r.skipped = true;
    r.reason = "the rear view sees too little road that has moved enough";
    remember();
    return r;
  }
  // The images' noise: the robust spread of current minus warped over the road.
  std::nth_element(diffs.begin(), diffs.begin() + diffs.size() / 2, diffs.end());
  r.noise_sigma = std::max(0.5, 1.4826 * diffs[diffs.size() / 2] / std::sqrt(2.0));
  const float min_sd = static_cast<float>(o.min_contrast_sigmas * r.noise_sigma);
  // Per pixel: 0 ignored (own car, no source), 1 road, 2 not road, 3 untextured or holding still,
  // 4 not judged (the road there has not moved enough).
  cv::Mat state = cv::Mat::zeros(s.height, s.width, CV_8U);
  for (int v = 0; v < s.height; ++v) {
    for (int u = 0; u < s.width; ++u) {
      const cv::Vec2i ab = pick.at<cv::Vec2i>(v, u);
      if (ab[1] < 0) {
        if (!ignore_.at<uchar>(v, u)) state.at<uchar>(v, u) = 4;
        continue;
      }
      if (sd_cur.at<float>(v, u) < min_sd) {
        state.at<uchar>(v, u) = 3;
        continue;
      }
      // A flat earlier window against a textured current one disagrees.
      const auto off = [&](const Warp& w) { return w.sd.at<float>(v, u) < min_sd / 2 || w.zncc.at<float>(v, u) < o.max_road_zncc; };
      const bool held = sd_still.at<float>(v, u) >= min_sd / 2 && still.at<float>(v, u) >= o.min_still_zncc;
      if (!off(warps[ab[0]]) || !off(warps[ab[1]])) {
        state.at<uchar>(v, u) = 1;
      } else if (held) {
        state.at<uchar>(v, u) = 3;
      } else {
        state.at<uchar>(v, u) = 2;
        r.obstacle.at<uchar>(v, u) = 255;
      }
    }
  }
  // Per column, from the bottom up: the lowest not-road region that stands on road (half a
  // window's rows below it judged road or untextured: the features on a car's plain side have more
  // of its side below them) and is a region, not a speck (not-road pixels over half of the window's
  // rows above its bottom), meets the road at its bottom. Its height is not measured: an object's
  // parts near the camera's height move in the view as the road at the horizon does, and its plain
  // sides are not judged.
  const Eigen::Vector3d axis = s.vehicle_from_view.col(2);
  struct Contact {
    int column = 0;
    Eigen::Vector2d ground{0, 0};
    double row_depth_m = 0.0;
  };
  std::vector<Contact> contacts;
  const int horizon = static_cast<int>(std::ceil(s.cy));
  for (int u = 0; u < s.width; ++u) {
    int v = s.height - 1;
    while (v > horizon) {
      if (state.at<uchar>(v, u) != 2) {
        --v;
        continue;
      }
      const int low = v;
      int road_below = 0, flagged = 0;
      for (int w = low + 1; w <= std::min(s.height - 1, low + o.window_px); ++w) {
        road_below += state.at<uchar>(w, u) == 1 || state.at<uchar>(w, u) == 3;
      }
      for (int w = low; w >= std::max(0, low - o.window_px + 1); --w) flagged += state.at<uchar>(w, u) == 2;
      if (2 * road_below < o.window_px) break;  // on something else: not the object's bottom
      // The region's top: its highest not-road pixel before a window of road rows.
      int top = low;
      for (int w = low - 1, gap = 0; w >= 0 && state.at<uchar>(w, u) != 0; --w) {
        if (state.at<uchar>(w, u) == 2) {
          top = w;
          gap = 0;
        } else if (state.at<uchar>(w, u) == 1 && ++gap >= o.window_px) {
          break;
        }
      }
      v = top - 1;
      if (2 * flagged < o.window_px) continue;
      // The windows reach below the region's bottom edge, blurred over a few rows by the view's
      // resampling: back by a window.
      const int contact_row = low - (o.window_px - 1);
      if (contact_row <= horizon) break;
      const cv::Vec3f g = road_.at<cv::Vec3f>(contact_row, u);
      if (!std::isfinite(g[0])) break;
      const Eigen::Vector3d ground(g[0], g[1], g[2]);
      if (std::hypot(ground.x() - c.x(), ground.z() - c.z()) > o.max_range_m) break;
      // One row's depth at the contact: D^2 / (f H).
      const double depth = (ground - c).dot(axis);
      contacts.push_back({u, {ground.x(), ground.z()}, depth * depth / (s.focal_px * camera_height_m_)});
      r.obstacle.at<uchar>(contact_row, u) = 128;
      break;
    }
  }
  // Neighbouring columns with contacts close on the ground: one detection.
  const auto emit = [&](const std::vector<Contact>& run) {
    if (run.size() < 2) return;
    const double width = (run.front().ground - run.back().ground).norm();
    if (width < o.min_width_m) return;
    std::vector<Eigen::Vector2d> points;
    for (const Contact& k : run) points.push_back(k.ground);
    Detection d = DetectionFromPoints(points, camera_.name);
    for (const Contact* end : {&run.front(), &run.back()}) {
      const int col = end->column;
      if (col <= half || col >= s.width - 1 - half || ignore_.at<uchar>(s.height - 1, col)) d.clipped_ends.push_back(end->ground);
    }
    d.id = static_cast<int>(r.detections.size());
    r.detections.push_back(std::move(d));
  };
  std::vector<Contact> run;
  for (const Contact& k : contacts) {
    if (!run.empty()) {
      const Contact& last = run.back();
      const double tolerance = std::max(o.max_contact_jump_m, 2 * std::max(last.row_depth_m, k.row_depth_m));
      if (k.column - last.column > 2 || (k.ground - last.ground).norm() > tolerance) {
        emit(run);
        run.clear();
      }
    }
    run.push_back(k);
  }
  emit(run);
  remember();
  return r;
}

}  // namespace dps
