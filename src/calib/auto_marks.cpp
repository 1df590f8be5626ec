#include "dps/calib/auto_marks.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>

#include "dps/calib/vanishing_points.h"
#include "dps/camera/box.h"
#include "dps/util/error.h"
#include "dps/util/image.h"
#include "dps/util/math.h"

namespace dps {
namespace {

// A paint pixel: where it is in the image, its ray (camera frame) and where that ray meets the
// road, relative to the camera's footprint (nominal geometry).
struct Paint {
  Eigen::Vector2d pixel;
  Eigen::Vector3d ray;
  Eigen::Vector2d ground;
};

std::vector<Paint> FindPaint(const cv::Mat& image, const Rig& rig, const RigCamera& cam, const AutoMarkOptions& o) {
  const cv::Mat grey = GreyImage(image);
  cv::Mat tophat;
  cv::morphologyEx(grey, tophat, cv::MORPH_TOPHAT,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(o.tophat_px, o.tophat_px)));
  const Eigen::Matrix3d& R = cam.vehicle_from_camera.R;
  const Eigen::Vector3d& t = cam.vehicle_from_camera.t;
  const double m = o.own_car_margin_m;
  const Eigen::Vector3d lo(-rig.vehicle.width_m / 2 - m, -o.own_car_height_m, -rig.vehicle.length_m / 2 - m);
  const Eigen::Vector3d hi(rig.vehicle.width_m / 2 + m, 0.0, rig.vehicle.length_m / 2 + m);
  std::vector<Paint> paint;
  for (int v = 0; v < tophat.rows; ++v) {
    const std::uint8_t* row = tophat.ptr<std::uint8_t>(v);
    for (int u = 0; u < tophat.cols; ++u) {
      if (row[u] < o.tophat_threshold) continue;
      Paint p;
      p.pixel = Eigen::Vector2d(u, v);
      if (!cam.model.Unproject(p.pixel, &p.ray)) continue;
      const Eigen::Vector3d d = R * p.ray;
      Eigen::Vector3d g;
      if (!RayMeetsRoad(t, d, &g)) continue;  // at or above the horizon
      const double s = -t.y() / d.y();        // g = t + s d
      p.ground = Eigen::Vector2d(g.x() - t.x(), g.z() - t.z());
      if (p.ground.norm() > o.max_range_m || RayMeetsBox(t, d, lo, hi, 0.0, s)) continue;
      paint.push_back(p);
    }
  }
  return paint;
}

// A line on the road plane: unit direction and offset along its normal (relative to the
// camera's footprint).
struct GroundLine {
  Eigen::Vector2d direction{0, 1};
  double offset = 0.0;
  Eigen::Vector2d normal() const { return {direction.y(), -direction.x()}; }
  double Distance(const Eigen::Vector2d& p) const { return std::abs(normal().dot(p) - offset); }
};

// The strongest line of the family whose direction is within max_angle of `base` (radians from
// +Z towards +X), among the points not yet used. Votes = 0 when nothing qualifies.
GroundLine HoughPeak(const std::vector<Paint>& paint, const std::vector<bool>& used, double base,
                     const AutoMarkOptions& o, int* votes) {
  const int n_angles = 2 * static_cast<int>(std::ceil(o.max_angle_deg / o.angle_step_deg)) + 1;
  const int n_offsets = 2 * static_cast<int>(std::ceil(o.max_range_m / o.offset_step_m)) + 1;
  cv::Mat acc(n_angles, n_offsets, CV_32S, cv::Scalar(0));
  std::vector<Eigen::Vector2d> normals(n_angles);
  for (int a = 0; a < n_angles; ++a) {
    const double angle = base + (a - n_angles / 2) * o.angle_step_deg * kPi / 180.0;
    normals[a] = Eigen::Vector2d(std::cos(angle), -std::sin(angle));  // direction (sin, cos)
  }
  for (size_t i = 0; i < paint.size(); ++i) {
    if (used[i]) continue;
    for (int a = 0; a < n_angles; ++a) {
      const int k = static_cast<int>(std::lround(normals[a].dot(paint[i].ground) / o.offset_step_m)) + n_offsets / 2;
      if (k >= 0 && k < n_offsets) ++acc.at<int>(a, k);
    }
  }
  // Lines are a paint stripe wide: sum neighbouring offsets so the peak does not split.
  const int band = std::max(1, static_cast<int>(std::lround(o.inlier_m / o.offset_step_m)));
  cv::Mat summed;
  cv::boxFilter(acc, summed, CV_32S, cv::Size(2 * band + 1, 1), cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  double best = 0;
  cv::Point at;
  cv::minMaxLoc(summed, nullptr, &best, nullptr, &at);
  *votes = static_cast<int>(best);
  GroundLine line;
  const double angle = base + (at.y - n_angles / 2) * o.angle_step_deg * kPi / 180.0;
  line.direction = Eigen::Vector2d(std::sin(angle), std::cos(angle));
  line.offset = (at.x - n_offsets / 2) * o.offset_step_m;
  return line;
}

// Least-squares line through points (principal direction), keeping the orientation of `near`.
GroundLine FitLine(const std::vector<Eigen::Vector2d>& points, const GroundLine& near) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
  for (const Eigen::Vector2d& p : points) C += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(C);
  GroundLine line;
  line.direction = eig.eigenvectors().col(1).normalized();
  if (line.direction.dot(near.direction) < 0) line.direction = -line.direction;
  line.offset = line.normal().dot(mean);
  return line;
}

}  // namespace

void AutoMarkOptions::Check() const {
  const OptionCheck Require("auto-mark");
  Require(tophat_px >= 3 && tophat_px % 2 == 1, "tophat_px", tophat_px, "odd, >= 3");
  Require(tophat_threshold > 0, "tophat_threshold", tophat_threshold, "> 0");
  Require(max_range_m > 0, "max_range_m", max_range_m, "> 0");
  Require(own_car_margin_m >= 0, "own_car_margin_m", own_car_margin_m, ">= 0");
  Require(own_car_height_m >= 0, "own_car_height_m", own_car_height_m, ">= 0");
  Require(max_angle_deg > 0 && max_angle_deg < 45, "max_angle_deg", max_angle_deg, "in (0, 45)");
  Require(angle_step_deg > 0, "angle_step_deg", angle_step_deg, "> 0");
  Require(offset_step_m > 0, "offset_step_m", offset_step_m, "> 0");
  Require(inlier_m > 0, "inlier_m", inlier_m, "> 0");
  Require(min_points >= 3, "min_points", min_points, ">= 3");
  Require(min_length_m > 0, "min_length_m", min_length_m, "> 0");
  Require(min_offset_m >= 0, "min_offset_m", min_offset_m, ">= 0");
  Require(max_marks_per_line >= 3, "max_marks_per_line", max_marks_per_line, ">= 3");
}

AutoMarkOptions AutoMarkOptions::ScaledTo(int width) const {
  const double s = width / 640.0;
  AutoMarkOptions o = *this;
  o.tophat_px = std::max(3, 2 * static_cast<int>(std::lround((tophat_px * s - 1) / 2)) + 1);
  o.min_points = std::max(3, static_cast<int>(std::lround(min_points * s * s)));
  return o;
}

std::vector<Mark> DetectMarks(const cv::Mat& image, const Rig& nominal, const std::string& camera,
                              const AutoMarkOptions& options, int first_line, std::vector<AutoMarkLine>* lines_out) {
  options.Check();
  const RigCamera& cam = nominal.Camera(camera);
  if (image.cols != cam.model.width() || image.rows != cam.model.height()) {
    throw Error(Str("camera '", camera, "': image is ", image.cols, "x", image.rows, ", the model ",
                    cam.model.width(), "x", cam.model.height()));
  }
  const AutoMarkOptions o = options.ScaledTo(image.cols);
  const std::vector<Paint> paint = FindPaint(image, nominal, cam, o);
  std::vector<bool> used(paint.size(), false);
  std::vector<Mark> marks;
  int line_id = first_line;
  // Z lines run along the vehicle's Z (direction angle 0), X lines along X (90 degrees).
  for (const std::pair<char, double>& family : {std::pair<char, double>{'Z', 0.0}, {'X', kPi / 2}}) {
    for (;;) {
      int votes = 0;
      const GroundLine peak = HoughPeak(paint, used, family.second, o, &votes);
      if (votes < o.min_points) break;
      // Refine on the peak's pixels, then take the pixels of the refined line.
      std::vector<size_t> members;
      auto collect = [&](const GroundLine& line) {
        members.clear();
        std::vector<Eigen::Vector2d> points;
        for (size_t i = 0; i < paint.size(); ++i) {
          if (!used[i] && line.Distance(paint[i].ground) <= o.inlier_m) {
            members.push_back(i);
            points.push_back(paint[i].ground);
          }
        }
        return points;
      };
      std::vector<Eigen::Vector2d> points = collect(peak);
      const GroundLine line = points.size() >= 3 ? FitLine(points, peak) : peak;
      points = collect(line);
      for (size_t i : members) used[i] = true;  // taken, whether the line is kept or not
      if (static_cast<int>(members.size()) < o.min_points) continue;
      // Extent along the line; radial lines (through the camera's footprint) are not road lines.
      std::vector<std::pair<double, size_t>> along;
      for (size_t i : members) along.emplace_back(line.direction.dot(paint[i].ground), i);
      std::sort(along.begin(), along.end());
      const double length = along.back().first - along.front().first;
      if (length < o.min_length_m || std::abs(line.offset) < o.min_offset_m) continue;
      std::vector<Eigen::Vector3d> rays;
      for (size_t i : members) rays.push_back(paint[i].ray);
      double rms = 0.0;
      FitGreatCircle(rays, &rms);
      const size_t n = std::min(along.size(), static_cast<size_t>(o.max_marks_per_line));
      for (size_t k = 0; k < n; ++k) {
        const Paint& p = paint[along[k * (along.size() - 1) / std::max<size_t>(1, n - 1)].second];
        Mark m;
        m.camera = camera;
        m.line = line_id;
        m.axis = family.first;
        m.u = p.pixel.x();
        m.v = p.pixel.y();
        marks.push_back(m);
      }
      if (lines_out) {
        lines_out->push_back({line_id, family.first, static_cast<int>(members.size()), length, rms * 180.0 / kPi});
      }
      ++line_id;
    }
  }
  return marks;
}

cv::Mat DrawMarks(const cv::Mat& image, const std::vector<Mark>& marks) {
  cv::Mat out;
  if (image.channels() == 1) cv::cvtColor(image, out, cv::COLOR_GRAY2BGR);
  else out = image.clone();
  std::map<int, cv::Point> label_at;
  for (const Mark& m : marks) {
    const cv::Scalar colour = m.axis == 'Z' ? cv::Scalar(0, 200, 0) : m.axis == 'X' ? cv::Scalar(0, 0, 255)
                                                                                    : cv::Scalar(255, 80, 0);
    const cv::Point p(static_cast<int>(std::lround(m.u)), static_cast<int>(std::lround(m.v)));
    cv::circle(out, p, 1, colour, cv::FILLED);
    label_at.emplace(m.line, p);
  }
  for (const auto& [line, p] : label_at) {
    cv::putText(out, std::to_string(line), p + cv::Point(3, -3), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(255, 255, 0), 1,
                cv::LINE_AA);
  }
  return out;
}

}  // namespace dps
