#include "dps/occupancy_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "dps/error.h"

namespace dps {
namespace {

constexpr double kPi = 3.14159265358979323846;

void Require(bool ok, const char* field, double value, const char* constraint) {
  if (!ok) throw Error(Str("occupancy option ", field, " = ", value, ": violated constraint ", constraint));
}

}  // namespace

void OccupancyOptions::Check() const {
  Require(cell_m > 0, "cell_m", cell_m, "> 0");
  Require(cells >= 16, "cells", cells, ">= 16");
  Require(bearing_step_deg > 0, "bearing_step_deg", bearing_step_deg, "> 0");
  Require(free_range_m > 0, "free_range_m", free_range_m, "> 0");
  Require(free_weight < 0, "free_weight", free_weight, "< 0");
  Require(occupied_weight > 0, "occupied_weight", occupied_weight, "> 0");
  Require(thickness_m >= 0, "thickness_m", thickness_m, ">= 0");
  Require(decay > 0 && decay <= 1, "decay", decay, "0 < decay <= 1");
  Require(clamp > 0, "clamp", clamp, "> 0");
}

OccupancyGrid::OccupancyGrid(const OccupancyOptions& options) : options_(options) {
  options_.Check();
  sum_ = cv::Mat(options.cells, options.cells, CV_32F, cv::Scalar(0));
  origin_ = Eigen::Vector2d::Constant(-options.cells * options.cell_m / 2);
}

void OccupancyGrid::Recentre(const Eigen::Vector2d& world) {
  const double half = options_.cells * options_.cell_m / 2;
  const Eigen::Vector2d centre = origin_ + Eigen::Vector2d::Constant(half);
  if ((world - centre).cwiseAbs().maxCoeff() < half / 2) return;
  // Shift by whole cells so that the vehicle is at the centre again; keep what overlaps.
  const int dx = static_cast<int>(std::lround((world.x() - centre.x()) / options_.cell_m));
  const int dz = static_cast<int>(std::lround((world.y() - centre.y()) / options_.cell_m));
  cv::Mat shifted(sum_.size(), CV_32F, cv::Scalar(0));
  const int n = options_.cells;
  const cv::Rect src(std::max(0, dx), std::max(0, dz), n - std::abs(dx), n - std::abs(dz));
  if (src.width > 0 && src.height > 0) {
    sum_(src).copyTo(shifted(cv::Rect(std::max(0, -dx), std::max(0, -dz), src.width, src.height)));
  }
  sum_ = shifted;
  origin_ += Eigen::Vector2d(dx, dz) * options_.cell_m;
}

double OccupancyGrid::At(const Eigen::Vector2d& w) const {
  const int c = static_cast<int>(std::floor((w.x() - origin_.x()) / options_.cell_m));
  const int r = static_cast<int>(std::floor((w.y() - origin_.y()) / options_.cell_m));
  if (c < 0 || r < 0 || c >= options_.cells || r >= options_.cells) return 0.0;
  return sum_.at<float>(r, c);
}

double OccupancyGrid::AtVehicle(const Eigen::Vector2d& v) const { return At(BodyToWorld(pose_, v)); }

void OccupancyGrid::Update(const PlanarPose& pose, const Coverage& coverage, const std::vector<Detection>& detections) {
  pose_ = pose;
  Recentre({pose.x_m, pose.z_m});
  sum_ *= options_.decay;
  // This frame's evidence per cell: occupied wins over free; each cell counts once per frame.
  cv::Mat delta(sum_.size(), CV_32F, cv::Scalar(0));
  auto add = [&](const Eigen::Vector2d& vehicle_point, double weight) {
    const Eigen::Vector2d w = BodyToWorld(pose, vehicle_point);
    const int c = static_cast<int>(std::floor((w.x() - origin_.x()) / options_.cell_m));
    const int r = static_cast<int>(std::floor((w.y() - origin_.y()) / options_.cell_m));
    if (c < 0 || r < 0 || c >= options_.cells || r >= options_.cells) return;
    float& d = delta.at<float>(r, c);
    if (weight > 0) d = std::max(d, static_cast<float>(weight));
    else if (d <= 0) d = std::min(d, static_cast<float>(weight));
  };
  const double step_rad = options_.bearing_step_deg * kPi / 180;
  const double walk = options_.cell_m / 2;
  for (const Sector& s : coverage.sectors) {
    const int bins = std::max(1, static_cast<int>(std::ceil(2 * s.half_angle_rad / step_rad)));
    std::vector<double> nearest(bins, std::numeric_limits<double>::infinity());
    for (const Detection& d : detections) {
      const std::vector<Eigen::Vector2d> pts = d.points.empty() ? std::vector<Eigen::Vector2d>{{d.x_m, d.z_m}} : d.points;
      for (const Eigen::Vector2d& p : pts) {
        const Eigen::Vector2d rel = p - s.apex;
        const double a = std::remainder(std::atan2(rel.x(), rel.y()) - s.direction_rad, 2 * kPi);
        if (std::abs(a) > s.half_angle_rad) continue;
        const int b = std::clamp(static_cast<int>((a + s.half_angle_rad) / step_rad), 0, bins - 1);
        nearest[b] = std::min(nearest[b], rel.norm());
      }
    }
    for (int b = 0; b < bins; ++b) {
      const double angle = s.direction_rad - s.half_angle_rad + (b + 0.5) * step_rad;
      const Eigen::Vector2d dir(std::sin(angle), std::cos(angle));
      const double r = nearest[b];
      const double sigma = std::isfinite(r) ? options_.sigma0_m + options_.sigma_per_m2 * r * r : 0.0;
      const double free_end = std::isfinite(r) ? std::max(0.0, r - 2 * sigma) : options_.free_range_m;
      for (double t = walk; t < std::min(free_end, options_.free_range_m); t += walk) add(s.apex + t * dir, options_.free_weight);
      if (!std::isfinite(r)) continue;
      for (double t = std::max(walk, r - 2 * sigma); t <= r + options_.thickness_m; t += walk) {
        const double w = t < r ? options_.occupied_weight * std::exp(-0.5 * std::pow((t - r) / sigma, 2))
                               : options_.occupied_weight;
        add(s.apex + t * dir, w);
      }
    }
  }
  sum_ += delta;
  cv::min(sum_, options_.clamp, sum_);
  cv::max(sum_, -options_.clamp, sum_);
}

std::vector<Eigen::Vector2d> OccupancyGrid::ObstacleCells() const {
  std::vector<Eigen::Vector2d> out;
  for (int r = 0; r < sum_.rows; ++r) {
    for (int c = 0; c < sum_.cols; ++c) {
      if (sum_.at<float>(r, c) > options_.strength_threshold) {
        out.push_back(origin_ + Eigen::Vector2d(c + 0.5, r + 0.5) * options_.cell_m);
      }
    }
  }
  return out;
}

void OccupancyGrid::Draw(cv::Mat& map, double map_range_m) const {
  const double scale = map.cols / (2.0 * map_range_m);
  // Map pixel -> vehicle -> world, with the pose's rotation taken once.
  const double c = std::cos(pose_.heading_rad), s = std::sin(pose_.heading_rad);
  for (int v = 0; v < map.rows; ++v) {
    const double vz = (map.rows / 2.0 - v) / scale;
    for (int u = 0; u < map.cols; ++u) {
      const double vx = (u - map.cols / 2.0) / scale;
      const double e = At({pose_.x_m + c * vx + s * vz, pose_.z_m - s * vx + c * vz});
      if (e == 0) continue;
      cv::Vec3b& px = map.at<cv::Vec3b>(v, u);
      const double a = std::min(1.0, std::abs(e) / options_.clamp);
      const cv::Vec3b target = e > 0 ? cv::Vec3b(90, 90, 90) : cv::Vec3b(215, 240, 215);
      for (int k = 0; k < 3; ++k) px[k] = cv::saturate_cast<std::uint8_t>(px[k] + a * (target[k] - px[k]));
    }
  }
}

}  // namespace dps
