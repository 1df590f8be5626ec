#include "dps/occupancy_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "dps/error.h"

namespace dps {
namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

void OccupancyOptions::Check() const {
  const OptionCheck Require("occupancy");
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
  // The free part of every sector is one fan polygon (the apex and each bearing's free end),
  // filled at once; the occupied evidence is walked along the bearings that hit something.
  cv::Mat delta(sum_.size(), CV_32F, cv::Scalar(0));
  cv::Mat free(sum_.size(), CV_8U, cv::Scalar(0));
  const Eigen::Matrix2d rotation = BodyToWorldRotation(pose);  // one transform per bearing
  const auto cell_of = [&](const Eigen::Vector2d& w) { return Eigen::Vector2d((w - origin_) / options_.cell_m); };
  constexpr int kShift = 4;  // fillPoly's fractional bits
  const auto vertex = [&](const Eigen::Vector2d& w) {
    const Eigen::Vector2d c = (cell_of(w) - Eigen::Vector2d::Constant(0.5)) * (1 << kShift);  // cell centres
    return cv::Point(static_cast<int>(std::lround(c.x())), static_cast<int>(std::lround(c.y())));
  };
  const auto occupy = [&](const Eigen::Vector2d& w, double weight) {
    const Eigen::Vector2d c = cell_of(w);
    const int col = static_cast<int>(std::floor(c.x())), row = static_cast<int>(std::floor(c.y()));
    if (col < 0 || row < 0 || col >= options_.cells || row >= options_.cells) return;
    float& d = delta.at<float>(row, col);
    d = std::max(d, static_cast<float>(weight));
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
    const Eigen::Vector2d apex = BodyToWorld(pose, s.apex);
    std::vector<cv::Point> fan{vertex(apex)};
    for (int b = 0; b < bins; ++b) {
      const double angle = s.direction_rad - s.half_angle_rad + (b + 0.5) * step_rad;
      const Eigen::Vector2d dir = rotation * Eigen::Vector2d(std::sin(angle), std::cos(angle));
      const double r = nearest[b];
      const double sigma = std::isfinite(r) ? options_.sigma0_m + options_.sigma_per_m2 * r * r : 0.0;
      const double free_end = std::isfinite(r) ? std::max(0.0, r - 2 * sigma) : options_.free_range_m;
      fan.push_back(vertex(apex + std::min(free_end, options_.free_range_m) * dir));
      if (!std::isfinite(r)) continue;
      for (double t = std::max(walk, r - 2 * sigma); t <= r + options_.thickness_m; t += walk) {
        const double w = t < r ? options_.occupied_weight * std::exp(-0.5 * std::pow((t - r) / sigma, 2))
                               : options_.occupied_weight;
        occupy(apex + t * dir, w);
      }
    }
    cv::fillPoly(free, std::vector<std::vector<cv::Point>>{fan}, cv::Scalar(255), cv::LINE_8, kShift);
  }
  cv::Mat unoccupied = delta <= 0;
  cv::bitwise_and(free, unoccupied, free);
  delta.setTo(options_.free_weight, free);
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
  CV_Assert(map.type() == CV_8UC3);
  // Map pixel (u, v) -> vehicle (vx, vz) -> world -> grid cell (column, row): one affine map, so
  // the grid is resampled with warpAffine (nearest cell) instead of a lookup per pixel.
  const double scale = map.cols / (2.0 * map_range_m);
  const double c = std::cos(pose_.heading_rad), s = std::sin(pose_.heading_rad);
  const double k = 1.0 / (scale * options_.cell_m);
  // vx = (u - W/2) / scale, vz = (H/2 - v) / scale; world x = px + c vx + s vz, z = pz - s vx + c vz;
  // column = (x - ox) / cell - 0.5 (nearest-neighbour sampling rounds), row likewise.
  const double u0 = map.cols / 2.0, v0 = map.rows / 2.0;
  const double bx = (pose_.x_m - origin_.x()) / options_.cell_m - 0.5, bz = (pose_.z_m - origin_.y()) / options_.cell_m - 0.5;
  const cv::Matx23d M(c * k, -s * k, bx - c * k * u0 + s * k * v0,
                      -s * k, -c * k, bz + s * k * u0 + c * k * v0);
  // The evidence as 8 bits (128 = unknown, 1 / 255 = clamped free / occupied) resamples fast.
  cv::Mat quantised, level;
  sum_.convertTo(quantised, CV_8U, 127.0 / options_.clamp, 128.0);
  cv::warpAffine(quantised, level, M, map.size(), cv::INTER_NEAREST | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT,
                 cv::Scalar(128));
  // Blend towards grey (occupied) or light green (free) by |evidence| / clamp, in 1/256 steps.
  int weight[256];
  for (int q = 0; q < 256; ++q) weight[q] = std::min(256, std::abs(q - 128) * 256 / 127);
  cv::parallel_for_(cv::Range(0, map.rows), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      const std::uint8_t* e = level.ptr<std::uint8_t>(v);
      std::uint8_t* px = map.ptr<std::uint8_t>(v);
      for (int u = 0; u < map.cols; ++u, px += 3) {
        if (e[u] == 128) continue;
        const int a = weight[e[u]];
        const bool occupied = e[u] > 128;
        const int t0 = occupied ? 90 : 215, t1 = occupied ? 90 : 240, t2 = occupied ? 90 : 215;
        px[0] = static_cast<std::uint8_t>(px[0] + (((t0 - px[0]) * a) >> 8));
        px[1] = static_cast<std::uint8_t>(px[1] + (((t1 - px[1]) * a) >> 8));
        px[2] = static_cast<std::uint8_t>(px[2] + (((t2 - px[2]) * a) >> 8));
      }
    }
  });
}

}  // namespace dps
