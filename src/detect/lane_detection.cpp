#include "dps/detect/lane_detection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "dps/camera/valid_mask.h"
#include "dps/util/error.h"
#include "dps/util/math.h"

namespace dps {
namespace {

// A line found in the bird's-eye view: x = offset + slope z (vehicle frame, metres).
struct Line {
  double offset = 0.0, slope = 0.0;
  int votes = 0, seen_rows = 0;
  LaneStretch evidence{};  // where along the car its evidence lies
  double Support() const { return seen_rows > 0 ? static_cast<double>(votes) / seen_rows : 0.0; }
};

// Each cell's stripe response: its core mean less the brighter of the means just beyond the
// widest marking on either side, in grey levels times `scale` (an integer: the core's and the
// band's sums over the least common multiple of their widths; `view` CV_8U); *seen (CV_8U) is 255
// where all of that is seen.
cv::Mat StripeResponse(const cv::Mat& view, const cv::Mat& valid, const LaneDetectorOptions& o, cv::Mat* seen,
                       int* scale) {
  const int core = std::max(0, static_cast<int>(std::lround(o.min_marking_width_m / o.cell_m / 2)));
  const int beyond = static_cast<int>(std::ceil(o.max_marking_width_m / o.cell_m / 2)), band = 2;
  const int core_n = 2 * core + 1;
  *scale = core_n * band;  // core mean - band mean = (band core_sum - core_n band_sum) / scale
  cv::Mat response(view.size(), CV_32S, cv::Scalar(0));
  *seen = cv::Mat(view.size(), CV_8U, cv::Scalar(0));
  const int reach = beyond + band, n = view.cols - 2 * reach, whole = 2 * reach + 1;
  if (n <= 0) return response;
  // Prefix sums of a row and of its valid cells; the cells' loops without branches, so that the
  // compiler vectorises them.
  std::vector<int> sum(view.cols + 1, 0), count(view.cols + 1, 0);
  for (int r = 0; r < view.rows; ++r) {
    const std::uint8_t* v = view.ptr<std::uint8_t>(r);
    const std::uint8_t* ok = valid.ptr<std::uint8_t>(r);
    for (int c = 0; c < view.cols; ++c) sum[c + 1] = sum[c] + v[c], count[c + 1] = count[c] + (ok[c] != 0);
    int* out = response.ptr<int>(r) + reach;
    std::uint8_t* all = seen->ptr<std::uint8_t>(r) + reach;
    const int* s0 = sum.data() + reach;  // s0[i] = sum[c] for c = reach + i
    const int* k0 = count.data() + reach;
    for (int i = 0; i < n; ++i) {
      const int left = s0[i - beyond] - s0[i - reach], right = s0[i + reach + 1] - s0[i + beyond + 1];
      out[i] = band * (s0[i + core + 1] - s0[i - core]) - core_n * std::max(left, right);
    }
    for (int i = 0; i < n; ++i) all[i] = k0[i + reach + 1] - k0[i - reach] == whole ? 255 : 0;
  }
  return response;
}

// The value at sorted position values.size() / 2 of integers within +-bound, by counting.
int MedianByCount(const std::vector<int>& values, int bound, std::vector<int>* counts) {
  counts->assign(2 * static_cast<size_t>(bound) + 1, 0);
  for (const int x : values) ++(*counts)[x + bound];
  size_t seen = 0;
  for (int k = 0; k <= 2 * bound; ++k) {
    seen += (*counts)[k];
    if (seen > values.size() / 2) return k - bound;
  }
  return bound;
}

// Evidence: responses far above the view's own where seen (median + 4 robust sigmas, at least 1
// grey level; the statistics from every second row and column). `scale`: the response's units
// per grey level.
cv::Mat Evidence(const cv::Mat& response, const cv::Mat& seen, int scale) {
  std::vector<int> v;
  v.reserve(static_cast<size_t>(response.rows / 2 + 1) * (response.cols / 2 + 1));
  for (int r = 0; r < response.rows; r += 2) {
    const int* row = response.ptr<int>(r);
    const std::uint8_t* ok = seen.ptr<std::uint8_t>(r);
    for (int c = 0; c < response.cols; c += 2) {
      if (ok[c]) v.push_back(row[c]);
    }
  }
  if (v.size() < 100) return cv::Mat(response.size(), CV_8U, cv::Scalar(0));
  // |response| <= 255 scale: the median and the median deviation by counting.
  const int bound = 255 * scale;
  std::vector<int> counts;
  const int median = MedianByCount(v, bound, &counts);
  for (int& x : v) x = std::abs(x - median);
  const int deviation = MedianByCount(v, 2 * bound, &counts);
  const double threshold = median + std::max(1.0 * scale, 4.0 * 1.4826 * deviation);
  cv::Mat evidence;
  cv::compare(response, threshold, evidence, cv::CMP_GT);
  return evidence & seen;
}

// The distance across two lines (perpendicular to their mean heading), m.
double Across(const LaneLine& a, const LaneLine& b) {
  return std::abs(a.offset_m - b.offset_m) * std::cos(std::atan((a.slope + b.slope) / 2));
}

}  // namespace

void LaneDetectorOptions::Check() const {
  const OptionCheck Require("lane detector");
  Require(cell_m > 0 && cell_m <= 1, "cell_m", cell_m, "0 < cell <= 1 m");
  Require(lateral_m > 0 && lateral_m / cell_m <= 4096, "lateral_m", lateral_m, "> 0, at most 4096 cells");
  Require(behind_m >= 0 && ahead_m > 0 && (behind_m + ahead_m) / cell_m <= 4096, "ahead_m", ahead_m,
          "> 0, behind_m >= 0, at most 4096 cells in all");
  Require(min_marking_width_m > 0 && min_marking_width_m < max_marking_width_m, "min_marking_width_m",
          min_marking_width_m, "0 < min < max_marking_width_m");
  Require(max_heading_deg >= 0 && max_heading_deg <= 60, "max_heading_deg", max_heading_deg, "0..60");
  Require(max_heading_spread_deg > 0, "max_heading_spread_deg", max_heading_spread_deg, "> 0 deg");
  Require(min_support > 0 && min_support <= 1, "min_support", min_support, "0 < share <= 1");
  Require(solid_support >= min_support && solid_support <= 1, "solid_support", solid_support, "min_support..1");
  Require(min_lane_width_m > 0, "min_lane_width_m", min_lane_width_m, "> 0");
  Require(own_car_height_m >= 0, "own_car_height_m", own_car_height_m, ">= 0");
}

LaneDetector::LaneDetector(const Rig& rig, const LaneDetectorOptions& options) : options_(options) {
  options_.Check();
  if (rig.cameras.size() < 2) throw Error("lane detector: the rig needs two cameras");
  const RigCamera* cams[2] = {rig.Has("left") ? &rig.Camera("left") : &rig.cameras[0],
                              rig.Has("right") ? &rig.Camera("right") : &rig.cameras[1]};
  const LaneDetectorOptions& o = options_;
  width_ = static_cast<int>(std::lround(2 * o.lateral_m / o.cell_m));
  height_ = static_cast<int>(std::lround((o.ahead_m + o.behind_m) / o.cell_m));
  const Eigen::Vector3d lo(-rig.vehicle.width_m / 2, -o.own_car_height_m, -rig.vehicle.length_m / 2);
  const Eigen::Vector3d hi(rig.vehicle.width_m / 2, 0.0, rig.vehicle.length_m / 2);
  cv::Mat seen[2];
  for (int i = 0; i < 2; ++i) {
    const RigCamera& cam = *cams[i];
    const cv::Mat valid = CameraValidMask(cam);
    const Pose camera_from_vehicle = cam.vehicle_from_camera.Inverse();
    map_[i].create(height_, width_, CV_32FC2);
    seen[i] = cv::Mat(height_, width_, CV_8U, cv::Scalar(0));
    for (int r = 0; r < height_; ++r) {
      for (int c = 0; c < width_; ++c) {
        const Eigen::Vector3d p(-o.lateral_m + (c + 0.5) * o.cell_m, 0.0, o.ahead_m - (r + 0.5) * o.cell_m);
        Eigen::Vector2d px;
        map_[i].at<cv::Vec2f>(r, c) = cv::Vec2f(-1, -1);
        if (!SeesRoadPoint(cam, camera_from_vehicle, valid, lo, hi, true, p, &px)) continue;
        map_[i].at<cv::Vec2f>(r, c) = cv::Vec2f(static_cast<float>(px.x()), static_cast<float>(px.y()));
        seen[i].at<std::uint8_t>(r, c) = 255;
      }
    }
  }
  // Each cell from the camera on its side, else from the other.
  for (int i = 0; i < 2; ++i) use_[i] = cv::Mat(height_, width_, CV_8U, cv::Scalar(0));
  for (int r = 0; r < height_; ++r) {
    for (int c = 0; c < width_; ++c) {
      const int own = (c < width_ / 2) ? 0 : 1, other = 1 - own;
      if (seen[own].at<std::uint8_t>(r, c)) {
        use_[own].at<std::uint8_t>(r, c) = 255;
      } else if (seen[other].at<std::uint8_t>(r, c)) {
        use_[other].at<std::uint8_t>(r, c) = 255;
      }
    }
  }
  // Fixed-point tables for remap (several times faster than float ones); cells a camera does not
  // give point inside its image, so that remap never takes its border path.
  for (int i = 0; i < 2; ++i) {
    map_[i].setTo(cv::Scalar(0, 0), ~use_[i]);
    cv::Mat fixed;
    cv::convertMaps(map_[i], cv::noArray(), fixed, fraction_[i], CV_16SC2);
    map_[i] = fixed;
  }
  valid_ = use_[0] | use_[1];
  for (int i = 0; i < 2; ++i) used_[i] = cv::boundingRect(use_[i]);
  const int slopes = 2 * static_cast<int>(std::ceil(o.max_heading_deg / 2.0)) + 1;
  for (int k = 0; k < slopes; ++k) slopes_.push_back(std::tan((k - slopes / 2) * 2.0 * kRadPerDeg));
  // x = -lateral + (c + 0.5) cell meets offset cell floor((x - slope z + lateral) / cell).
  shift_.resize(static_cast<size_t>(height_) * slopes);
  for (int r = 0; r < height_; ++r) {
    const double z = o.ahead_m - (r + 0.5) * o.cell_m;
    for (int k = 0; k < slopes; ++k) {
      shift_[static_cast<size_t>(r) * slopes + k] = static_cast<int>(std::floor(0.5 - slopes_[k] * z / o.cell_m));
    }
  }
}

LaneFrame LaneDetector::Detect(const cv::Mat& left_grey, const cv::Mat& right_grey) {
  const LaneDetectorOptions& o = options_;
  cv::Mat view(height_, width_, CV_8U, cv::Scalar(0));
  const cv::Mat* images[2] = {&left_grey, &right_grey};
  for (int i = 0; i < 2; ++i) {
    if (used_[i].empty()) continue;
    cv::Mat sampled;
    cv::remap(*images[i], sampled, map_[i](used_[i]), fraction_[i](used_[i]), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    sampled.copyTo(view(used_[i]), use_[i](used_[i]));
  }
  const cv::Mat& valid = valid_;
  cv::Mat seen;
  int scale = 1;
  const cv::Mat response = StripeResponse(view, valid, o, &seen, &scale);
  const cv::Mat evidence = Evidence(response, seen, scale);
  // Votes per (slope, offset cell), one per row and line.
  const int slopes = static_cast<int>(slopes_.size());
  const auto slope_of = [&](int k) { return slopes_[k]; };
  const auto z_of = [&](int r) { return o.ahead_m - (r + 0.5) * o.cell_m; };
  // Cell c of row r votes for offset cell c + shift_[r][k] at slope k (the line through its centre).
  std::vector<int> votes(static_cast<size_t>(slopes) * width_, 0);
  for (int r = 0; r < height_; ++r) {
    const std::uint8_t* e = evidence.ptr<std::uint8_t>(r);
    const int* shift = &shift_[static_cast<size_t>(r) * slopes];
    for (int c = 0; c < width_; ++c) {
      if (!e[c]) continue;
      for (int k = 0; k < slopes; ++k) {
        const int a = c + shift[k];
        if (a >= 0 && a < width_) ++votes[static_cast<size_t>(k) * width_ + a];
      }
    }
  }
  // Per offset cell its best slope; lines: local maxima over +-min_lane_width / 4 with support.
  std::vector<Line> best(width_);
  for (int a = 0; a < width_; ++a) {
    for (int k = 0; k < slopes; ++k) {
      const int n = votes[static_cast<size_t>(k) * width_ + a];
      if (n > best[a].votes) best[a] = {-o.lateral_m + (a + 0.5) * o.cell_m, slope_of(k), n, 0};
    }
  }
  const int suppress = std::max(1, static_cast<int>(o.min_lane_width_m / 4 / o.cell_m));
  std::vector<Line> lines;
  // A boundary is seen over a metre at least, with min_support of it voting.
  const int min_votes = std::max(1, static_cast<int>(std::ceil(o.min_support / o.cell_m)));
  for (int a = 0; a < width_; ++a) {
    if (best[a].votes < min_votes) continue;
    bool peak = true;
    for (int b = std::max(0, a - suppress); b <= std::min(width_ - 1, a + suppress) && peak; ++b) {
      peak = b == a || best[b].votes < best[a].votes || (best[b].votes == best[a].votes && b > a);
    }
    if (!peak) continue;
    Line l = best[a];
    // Its rows where the view sees the road under it; then least squares on its evidence.
    double sz = 0, sx = 0, szz = 0, szx = 0;
    double near = std::numeric_limits<double>::infinity(), far = -near;
    int n = 0;
    const int reach = static_cast<int>(std::ceil(o.max_marking_width_m / o.cell_m));
    for (int r = 0; r < height_; ++r) {
      const double z = z_of(r), x = l.offset + l.slope * z;
      const int c = static_cast<int>(std::floor((x + o.lateral_m) / o.cell_m));
      if (c < 0 || c >= width_ || !valid.at<std::uint8_t>(r, c)) continue;
      ++l.seen_rows;
      for (int d = std::max(0, c - reach); d <= std::min(width_ - 1, c + reach); ++d) {
        if (!evidence.at<std::uint8_t>(r, d)) continue;
        const double xd = -o.lateral_m + (d + 0.5) * o.cell_m;
        sz += z, sx += xd, szz += z * z, szx += z * xd, ++n;
        near = std::min(near, z), far = std::max(far, z);
      }
    }
    if (l.Support() < o.min_support || l.seen_rows * o.cell_m < 1.0) continue;
    const double det = n * szz - sz * sz;
    if (n >= 5 && std::abs(det) > 1e-9) {
      l.slope = (n * szx - sz * sx) / det;
      l.offset = (sx - l.slope * sz) / n;
    }
    if (n > 0) l.evidence = {near, far};
    lines.push_back(l);
  }
  std::vector<double> line_slopes, line_votes;
  for (const Line& l : lines) line_slopes.push_back(l.slope), line_votes.push_back(l.votes);
  const std::vector<bool> parallel = ParallelLines(line_slopes, line_votes, o.max_heading_spread_deg);
  std::vector<LaneLine> found;
  for (size_t i = 0; i < lines.size(); ++i) {
    const Line& l = lines[i];
    if (!parallel[i]) continue;
    found.push_back({l.offset, l.slope, l.Support() >= o.solid_support ? "solid" : "dashed",
                     std::min(1.0, l.votes * o.cell_m / 3.0), l.evidence});
  }
  return NameLaneLines(found, o.min_lane_width_m, &previous_lp_);
}

std::vector<bool> ParallelLines(const std::vector<double>& slopes, const std::vector<double>& weights,
                                double max_spread_deg) {
  const size_t n = std::min(slopes.size(), weights.size());
  const auto parallel = [&](size_t a, size_t b) {
    return std::abs(std::atan(slopes[a]) - std::atan(slopes[b])) * kDegPerRad <= max_spread_deg;
  };
  // The frame's heading: the line's whose parallel lines weigh the most.
  size_t frame = 0;
  double most = -1;
  for (size_t i = 0; i < n; ++i) {
    double w = 0;
    for (size_t k = 0; k < n; ++k) w += parallel(i, k) ? weights[k] : 0.0;
    if (w > most) most = w, frame = i;
  }
  std::vector<bool> out(n);
  for (size_t i = 0; i < n; ++i) out[i] = parallel(i, frame);
  return out;
}

LaneFrame NameLaneLines(const std::vector<LaneLine>& lines, double min_lane_width_m,
                        std::optional<double>* previous_lp) {
  LaneFrame out;
  // Two boundaries lie a lane apart at least: a line closer than the narrowest lane (across them)
  // to a more confident one is not one (lines as confident as each other are named by where they
  // lie, below).
  std::vector<LaneLine> apart;
  for (const LaneLine& l : lines) {
    bool alone = true;
    for (const LaneLine& k : lines) {
      alone = alone && !(k.confidence > l.confidence && Across(l, k) < min_lane_width_m);
    }
    if (alone) apart.push_back(l);
  }
  // The ego lane's boundaries and its neighbours' outer ones.
  const LaneLine* left = nullptr;
  const LaneLine* right = nullptr;
  for (const LaneLine& l : apart) {
    if (l.offset_m < 0 && (!left || l.offset_m > left->offset_m)) left = &l;
    if (l.offset_m > 0 && (!right || l.offset_m < right->offset_m)) right = &l;
  }
  // No lane is wider than two of the narrowest, and the car is inside its own: a line farther out
  // is a neighbour's (the ego lane's line on that side missed, e.g. under a car beside us).
  const double widest = 2 * min_lane_width_m;
  if (left && right && right->offset_m - left->offset_m > widest) {
    if (-left->offset_m > right->offset_m) {
      left = nullptr;
    } else {
      right = nullptr;
    }
  }
  if (left && -left->offset_m > widest) left = nullptr;
  if (right && right->offset_m > widest) right = nullptr;
  // The neighbours' outer boundaries: at least a lane beyond the ego lane's boundary on their side
  // or, without it, two lanes beyond the other side's.
  const double infinity = std::numeric_limits<double>::infinity();
  const double left2_below = left ? left->offset_m - min_lane_width_m : right ? right->offset_m - widest : -infinity;
  const double right2_above = right ? right->offset_m + min_lane_width_m : left ? left->offset_m + widest : infinity;
  const LaneLine* left2 = nullptr;
  const LaneLine* right2 = nullptr;
  for (const LaneLine& l : apart) {
    if (l.offset_m < left2_below && (!left2 || l.offset_m > left2->offset_m)) left2 = &l;
    if (l.offset_m > right2_above && (!right2 || l.offset_m < right2->offset_m)) right2 = &l;
  }
  const std::pair<const char*, const LaneLine*> named[] = {{"left2", left2}, {"left", left}, {"right", right}, {"right2", right2}};
  for (const auto& [name, l] : named) {
    if (!l) continue;
    out.boundaries.push_back({0, 0.0, name, l->offset_m, std::atan(l->slope) * kDegPerRad, 0.0, l->type, l->confidence});
    out.seen.push_back(l->seen);
  }
  // A lane narrower than the narrowest is no lane (a line that is not a boundary, e.g. an edge on
  // the road the car is turning onto).
  const double heading = left && right ? std::atan((left->slope + right->slope) / 2) : 0.0;
  if (left && right && Across(*left, *right) >= min_lane_width_m) {
    out.has_ego = true;
    out.ego.lp_m = -(left->offset_m + right->offset_m) / 2;
    out.ego.lane_width_m = Across(*left, *right);
    out.ego.heading_deg = -heading * kDegPerRad;
    if (*previous_lp && std::abs(out.ego.lp_m - **previous_lp) > out.ego.lane_width_m / 2) {
      out.ego.event = out.ego.lp_m > **previous_lp ? "left" : "right";
    }
    *previous_lp = out.ego.lp_m;
  }
  return out;
}

}  // namespace dps
