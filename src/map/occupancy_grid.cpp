#include "dps/map/occupancy_grid.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "dps/util/error.h"
#include "dps/util/math.h"

namespace dps {
namespace {

// The map's colours for the grid (BGR): occupied cells grey, free ones light green.

constexpr int kShift = 4;  // fillPoly's fractional bits

// World (x, z) to grid cells (fractional: cell (c, r) spans [c, c + 1) x [r, r + 1)).
struct GridFrame {
  Eigen::Vector2d origin;
  double cell_m;
  Eigen::Vector2d Cell(const Eigen::Vector2d& w) const { return Eigen::Vector2d((w - origin) / cell_m); }
  // A fan's vertex for fillPoly: cell centres at whole numbers, kShift fractional bits.
  cv::Point Vertex(const Eigen::Vector2d& w) const {
    const Eigen::Vector2d c = (Cell(w) - Eigen::Vector2d::Constant(0.5)) * (1 << kShift);
    return cv::Point(static_cast<int>(std::lround(c.x())), static_cast<int>(std::lround(c.y())));
  }
};

// A bearing that hit something: from the apex (world) along dir, at range with its sigma.
struct Hit {
  Eigen::Vector2d apex, dir;
  double range, sigma;
};

// One frame's rays: per sector the free fan (apex and each bearing's free end) and the hits.
struct FrameRays {
  std::vector<Hit> hits;
  std::vector<std::vector<cv::Point>> fans;
};

// Per sector and bearing step, the nearest detection point: free up to two sigmas before it (or
// to free_range_m when none), occupied from there.
FrameRays Rays(const PlanarPose& pose, const Coverage& coverage, const std::vector<Detection>& detections,
               const GridFrame& frame, const OccupancyOptions& o) {
  const Eigen::Matrix2d rotation = BodyToWorldRotation(pose);  // one transform per bearing
  FrameRays rays;
  const double step_rad = o.bearing_step_deg * kPi / 180;
  for (const Sector& s : coverage.sectors) {
    const int bins = std::max(1, static_cast<int>(std::ceil(2 * s.half_angle_rad / step_rad)));
    std::vector<double> nearest(bins, std::numeric_limits<double>::infinity());
    const auto see = [&](const Eigen::Vector2d& p) {
      const Eigen::Vector2d rel = p - s.apex;
      const double a = std::remainder(std::atan2(rel.x(), rel.y()) - s.direction_rad, 2 * kPi);
      if (std::abs(a) > s.half_angle_rad) return;
      const int b = std::clamp(static_cast<int>((a + s.half_angle_rad) / step_rad), 0, bins - 1);
      nearest[b] = std::min(nearest[b], rel.norm());
    };
    for (const Detection& d : detections) {
      if (d.points.empty()) see({d.x_m, d.z_m});
      for (const Eigen::Vector2d& p : d.points) see(p);
    }
    const Eigen::Vector2d apex = BodyToWorld(pose, s.apex);
    std::vector<cv::Point> fan{frame.Vertex(apex)};
    for (int b = 0; b < bins; ++b) {
      const double angle = s.direction_rad - s.half_angle_rad + (b + 0.5) * step_rad;
      const Eigen::Vector2d dir = rotation * Eigen::Vector2d(std::sin(angle), std::cos(angle));
      const double r = nearest[b];
      const double sigma = std::isfinite(r) ? o.sigma0_m + o.sigma_per_m2 * r * r : 0.0;
      // Without a hit, free up to free_range_m, beyond a side view's depth limit too (ending the fan
      // there kept more phantoms and trails: docs/experiments/detection-history.md).
      const double free_end = std::isfinite(r) ? std::max(0.0, r - 2 * sigma) : o.free_range_m;
      fan.push_back(frame.Vertex(apex + std::min(free_end, o.free_range_m) * dir));
      if (std::isfinite(r)) rays.hits.push_back({apex, dir, r, sigma});
    }
    rays.fans.push_back(std::move(fan));
  }
  return rays;
}

// Only the cells this frame can touch (the fans' and the hits' bounding box, a cell of margin)
// hold evidence: the rest of the grid only decays.
cv::Rect TouchedCells(const FrameRays& rays, const GridFrame& frame, const OccupancyOptions& o, const cv::Rect& grid) {
  double lo_x = std::numeric_limits<double>::infinity(), lo_z = lo_x, hi_x = -lo_x, hi_z = -lo_x;
  const auto extend = [&](double cx, double cz) {
    lo_x = std::min(lo_x, cx), hi_x = std::max(hi_x, cx), lo_z = std::min(lo_z, cz), hi_z = std::max(hi_z, cz);
  };
  for (const std::vector<cv::Point>& fan : rays.fans) {
    for (const cv::Point& v : fan) extend(v.x / double(1 << kShift), v.y / double(1 << kShift));
  }
  for (const Hit& h : rays.hits) {
    const Eigen::Vector2d c = frame.Cell(h.apex + (h.range + o.thickness_m + o.cell_m) * h.dir);
    extend(c.x(), c.y());
  }
  if (!(lo_x <= hi_x)) return cv::Rect();
  const int x0 = static_cast<int>(std::floor(std::max(-1.0, lo_x))) - 1;
  const int z0 = static_cast<int>(std::floor(std::max(-1.0, lo_z))) - 1;
  const int x1 = static_cast<int>(std::ceil(std::min(grid.width + 1.0, hi_x))) + 2;
  const int z1 = static_cast<int>(std::ceil(std::min(grid.height + 1.0, hi_z))) + 2;
  return cv::Rect(x0, z0, x1 - x0, z1 - z0) & grid;
}

// sum = min(clamp, max(-clamp, sum * decay + evidence)) over columns [from, to) of a row, with the
// evidence (nullptr: none, +0), in vectors and a scalar tail of the same operations.
void DecayAndAdd(float* sum, const float* evidence, int from, int to, float decay, float clamp) {
  int col = from;
#if CV_SIMD
  const cv::v_float32 d = cv::vx_setall_f32(decay), hi = cv::vx_setall_f32(clamp), lo = cv::vx_setall_f32(-clamp);
  for (; col + cv::v_float32::nlanes <= to; col += cv::v_float32::nlanes) {
    const cv::v_float32 e = evidence ? cv::vx_load(evidence + col) : cv::vx_setzero_f32();
    cv::v_store(sum + col, cv::v_min(cv::v_max(cv::vx_load(sum + col) * d + e, lo), hi));
  }
#endif
  for (; col < to; ++col) {
    sum[col] = std::min(clamp, std::max(-clamp, sum[col] * decay + (evidence ? evidence[col] : 0.0f)));
  }
}

// The evidence as 8 bits (128 = unknown, 1 / 255 = clamped free / occupied) at each block, sampled
// at the nearest cell through the affine block -> cell map B as cv::warpAffine (INTER_NEAREST,
// WARP_INVERSE_MAP) does: coordinates in 10-bit fixed point, rounded; outside the grid unknown.
// (The same cells, at a fraction of its cost.)
cv::Mat NearestCellLevels(const cv::Mat& sum, double clamp, const cv::Matx23d& B, cv::Size blocks) {
  cv::Mat quantised;
  sum.convertTo(quantised, CV_8U, 127.0 / clamp, 128.0);
  constexpr int kBits = 10;
  const auto fixed = [](double v) { return cv::saturate_cast<int>(v * (1 << kBits)); };
  std::vector<int> column_step(blocks.width), row_step(blocks.width);
  for (int b = 0; b < blocks.width; ++b) {
    column_step[b] = fixed(B(0, 0) * b);
    row_step[b] = fixed(B(1, 0) * b);
  }
  cv::Mat level(blocks, CV_8U);
  for (int b = 0; b < blocks.height; ++b) {
    const int column0 = fixed(B(0, 1) * b + B(0, 2)) + (1 << (kBits - 1));
    const int row0 = fixed(B(1, 1) * b + B(1, 2)) + (1 << (kBits - 1));
    std::uint8_t* out = level.ptr<std::uint8_t>(b);
    for (int a = 0; a < blocks.width; ++a) {
      const int column = (column0 + column_step[a]) >> kBits, row = (row0 + row_step[a]) >> kBits;
      out[a] = static_cast<unsigned>(column) < static_cast<unsigned>(quantised.cols) &&
                       static_cast<unsigned>(row) < static_cast<unsigned>(quantised.rows)
                   ? quantised.at<std::uint8_t>(row, column)
                   : 128;
    }
  }
  return level;
}

// Each of `cols` levels repeated n times into out.
void RepeatColumns(const std::uint8_t* e, int cols, int n, std::uint8_t* out) {
  int b = 0;
#if CV_SIMD
  for (; n == 2 && b + cv::v_uint8::nlanes <= cols; b += cv::v_uint8::nlanes) {
    cv::v_uint8 lo, hi;
    const cv::v_uint8 x = cv::vx_load(e + b);
    cv::v_zip(x, x, lo, hi);
    cv::v_store(out + 2 * b, lo);
    cv::v_store(out + 2 * b + cv::v_uint8::nlanes, hi);
  }
#endif
  for (; b < cols; ++b) std::memset(out + b * n, e[b], n);
}

// One map row: pixel = background + (target - background) * |level - 128| / 128, the target grey
// for occupied and light green for free (unknown cells, level 128, leave the background as it is).
void BlendRow(const std::uint8_t* e, const std::uint8_t* bg, std::uint8_t* px, int cols) {
  int u = 0;
#if CV_SIMD
  const cv::v_uint8 unknown = cv::vx_setall_u8(128);
  const cv::v_int16 mid = cv::vx_setall_s16(128), grey = cv::vx_setall_s16(kGridOccupiedGrey);
  const cv::v_int16 free_bg = cv::vx_setall_s16(kGridFreeBlueRed), free_g = cv::vx_setall_s16(kGridFreeGreen);
  // One half of a register of pixels: the channel p (8 bits widened) towards its target.
  const auto blend = [&](const cv::v_uint16& level16, const cv::v_uint16& p16, const cv::v_int16& free_target) {
    const cv::v_int16 signed_level = cv::v_reinterpret_as_s16(level16) - mid;
    const cv::v_int16 weight = cv::v_reinterpret_as_s16(cv::v_abs(signed_level));
    const cv::v_int16 target = cv::v_select(signed_level > cv::vx_setzero_s16(), grey, free_target);
    const cv::v_int16 p = cv::v_reinterpret_as_s16(p16);
    return p + (cv::v_mul_wrap(target - p, weight) >> 7);
  };
  const auto channel = [&](const cv::v_uint16& e0, const cv::v_uint16& e1, const cv::v_uint8& c,
                           const cv::v_int16& free_target) {
    cv::v_uint16 c0, c1;
    cv::v_expand(c, c0, c1);
    return cv::v_pack_u(blend(e0, c0, free_target), blend(e1, c1, free_target));
  };
  for (; u + cv::v_uint8::nlanes <= cols; u += cv::v_uint8::nlanes) {
    const cv::v_uint8 levels = cv::vx_load(e + u);
    if (cv::v_check_all(levels == unknown)) {  // most of a map lies beyond the views
      if (px != bg) {
        const int lanes = cv::v_uint8::nlanes;
        for (int i = 0; i < 3; ++i) cv::v_store(px + 3 * u + i * lanes, cv::vx_load(bg + 3 * u + i * lanes));
      }
      continue;
    }
    cv::v_uint8 b, g, r;
    cv::v_load_deinterleave(bg + 3 * u, b, g, r);
    cv::v_uint16 e0, e1;
    cv::v_expand(levels, e0, e1);
    cv::v_store_interleave(px + 3 * u, channel(e0, e1, b, free_bg), channel(e0, e1, g, free_g),
                           channel(e0, e1, r, free_bg));
  }
#endif
  for (; u < cols; ++u) {
    const int a = std::abs(e[u] - 128);
    const bool occupied = e[u] > 128;
    const int targets[3] = {occupied ? kGridOccupiedGrey : kGridFreeBlueRed, occupied ? kGridOccupiedGrey : kGridFreeGreen,
                            occupied ? kGridOccupiedGrey : kGridFreeBlueRed};
    for (int k = 0; k < 3; ++k) {
      const int c = bg[3 * u + k];
      px[3 * u + k] = static_cast<std::uint8_t>(c + (((targets[k] - c) * a) >> 7));
    }
  }
}

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
  Require(half_life_s > 0, "half_life_s", half_life_s, "> 0");
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

cv::Mat OccupancyGrid::EvidenceImage() const {
  cv::Mat flipped, image;
  cv::flip(sum_, flipped, 0);  // row 0 = the largest z
  flipped.convertTo(image, CV_16U, EvidenceScale(), 32768.0);  // saturating, rounded
  return image;
}

double OccupancyGrid::AtVehicle(const Eigen::Vector2d& v) const { return At(BodyToWorld(pose_, v)); }

void OccupancyGrid::Update(double t_s, const PlanarPose& pose, const Coverage& coverage,
                           const std::vector<Detection>& detections) {
  // The first frame, or time not moving on: no decay.
  const double dt = std::isfinite(last_t_s_) && t_s > last_t_s_ ? t_s - last_t_s_ : 0.0;
  last_t_s_ = t_s;
  pose_ = pose;
  Recentre({pose.x_m, pose.z_m});
  const GridFrame frame{origin_, options_.cell_m};
  const FrameRays rays = Rays(pose, coverage, detections, frame, options_);
  const cv::Rect touched = TouchedCells(rays, frame, options_, cv::Rect(0, 0, sum_.cols, sum_.rows));
  // This frame's evidence per cell: occupied wins over free; each cell counts once per frame.
  // The free part of every sector is one fan polygon (the apex and each bearing's free end),
  // filled at once with the free weight; then the occupied evidence is walked along the bearings
  // that hit something, each cell keeping the largest weight.
  delta_.create(sum_.size(), CV_32F);
  cv::Mat evidence_roi = delta_(touched);
  evidence_roi.setTo(0);
  for (const std::vector<cv::Point>& fan : rays.fans) {
    cv::fillPoly(evidence_roi, std::vector<std::vector<cv::Point>>{fan}, cv::Scalar(options_.free_weight), cv::LINE_8,
                 kShift, -touched.tl() * (1 << kShift));
  }
  const cv::Rect grid(0, 0, sum_.cols, sum_.rows);
  const auto occupy = [&](const Eigen::Vector2d& w, double weight) {
    const Eigen::Vector2d c = frame.Cell(w);
    const cv::Point cell(static_cast<int>(std::floor(c.x())), static_cast<int>(std::floor(c.y())));
    if (!grid.contains(cell)) return;
    CV_DbgAssert(touched.contains(cell));
    float& d = delta_.at<float>(cell);
    d = std::max(d, static_cast<float>(weight));
  };
  const double walk = options_.cell_m / 2;
  for (const Hit& h : rays.hits) {
    for (double t = std::max(walk, h.range - 2 * h.sigma); t <= h.range + options_.thickness_m; t += walk) {
      const double w = t < h.range ? options_.occupied_weight * std::exp(-0.5 * std::pow((t - h.range) / h.sigma, 2))
                                   : options_.occupied_weight;
      occupy(h.apex + t * h.dir, w);
    }
  }
  // Decay, this frame's evidence, clamp: one pass (no evidence outside the touched cells).
  const float decay = static_cast<float>(std::pow(0.5, dt / options_.half_life_s));
  const float clamp = static_cast<float>(options_.clamp);
  for (int row = 0; row < sum_.rows; ++row) {
    float* sum = sum_.ptr<float>(row);
    const bool in_rows = row >= touched.y && row < touched.y + touched.height;
    const int a = in_rows ? touched.x : sum_.cols, b = in_rows ? touched.x + touched.width : sum_.cols;
    DecayAndAdd(sum, nullptr, 0, a, decay, clamp);
    DecayAndAdd(sum, delta_.ptr<float>(row), a, b, decay, clamp);
    DecayAndAdd(sum, nullptr, b, sum_.cols, decay, clamp);
  }
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

void OccupancyGrid::Draw(cv::Mat& map, double map_range_m) const { Draw(map, map, map_range_m); }

void OccupancyGrid::Draw(const cv::Mat& background, cv::Mat& map, double map_range_m) const {
  CV_Assert(background.type() == CV_8UC3);
  if (map.data != background.data) map.create(background.size(), CV_8UC3);
  // Map pixel (u, v) -> vehicle (vx, vz) -> world -> grid cell (column, row): one affine map, so
  // the grid is resampled by nearest cell instead of a lookup per pixel.
  const double scale = map.cols / (2.0 * map_range_m);
  const double c = std::cos(pose_.heading_rad), s = std::sin(pose_.heading_rad);
  const double k = 1.0 / (scale * options_.cell_m);
  // vx = (u - W/2) / scale, vz = (H/2 - v) / scale; world x = px + c vx + s vz, z = pz - s vx + c vz;
  // column = (x - ox) / cell - 0.5 (nearest-neighbour sampling rounds), row likewise.
  const double u0 = map.cols / 2.0, v0 = map.rows / 2.0;
  const double bx = (pose_.x_m - origin_.x()) / options_.cell_m - 0.5, bz = (pose_.z_m - origin_.y()) / options_.cell_m - 0.5;
  const cv::Matx23d M(c * k, -s * k, bx - c * k * u0 + s * k * v0,
                      -s * k, -c * k, bz + s * k * u0 + c * k * v0);
  // A cell spans `block` map pixels or more: resample one pixel per block x block square (at its
  // centre), which costs block^2 times less than every pixel and shows the same cells.
  const int block = std::max(1, static_cast<int>(std::floor(1.0 / k + 1e-9)));
  const double half = (block - 1) / 2.0;
  const cv::Matx23d B(M(0, 0) * block, M(0, 1) * block, M(0, 2) + (M(0, 0) + M(0, 1)) * half,
                      M(1, 0) * block, M(1, 1) * block, M(1, 2) + (M(1, 0) + M(1, 1)) * half);
  const cv::Size blocks((map.cols + block - 1) / block, (map.rows + block - 1) / block);
  const cv::Mat level = NearestCellLevels(sum_, options_.clamp, B, blocks);
  // Blend towards grey (occupied) or light green (free) by |evidence| / clamp, in 1/128 steps.
  cv::parallel_for_(cv::Range(0, map.rows), [&](const cv::Range& rows) {
    const int n = block;
    std::vector<std::uint8_t> expanded(n > 1 ? level.cols * n : 0);
    int expanded_row = -1;
    for (int v = rows.start; v < rows.end; ++v) {
      const std::uint8_t* e = level.ptr<std::uint8_t>(v / n);
      if (n > 1) {  // each block's level repeated over its n columns, once per n rows
        if (expanded_row != v / n) {
          expanded_row = v / n;
          RepeatColumns(e, level.cols, n, expanded.data());
        }
        e = expanded.data();
      }
      BlendRow(e, background.ptr<std::uint8_t>(v), map.ptr<std::uint8_t>(v), map.cols);
    }
  });
}

}  // namespace dps
