#include "dps/map/surround_map.h"

#include "dps/util/error.h"
#include "dps/util/math.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>

namespace dps {

namespace {

// The obstacles' colour, their nearest points', the tracks'.
const cv::Scalar kObstacleColour(0, 0, 220), kNearestColour(0, 0, 120), kTrackColour(200, 80, 0);
const cv::Scalar kLaneColour(0, 170, 230);

// Vehicle-frame (x, z) to map pixels: the vehicle origin at the centre, +Z up.
struct MapProjection {
  double scale;  // px per metre
  cv::Point2d centre;
  explicit MapProjection(const MapOptions& o)
      : scale(o.size_px / (2.0 * o.range_m)), centre(o.size_px / 2.0, o.size_px / 2.0) {}
  cv::Point operator()(double x, double z) const {
    return cv::Point(cvRound(centre.x + x * scale), cvRound(centre.y - z * scale));
  }
};

// Each sector's shading: its colour blended over the white map.
const cv::Scalar kShades[] = {cv::Scalar(235, 245, 225), cv::Scalar(240, 230, 250), cv::Scalar(225, 240, 250)};
constexpr double kShadeWeight = 0.7;

cv::Scalar SectorShade(size_t k) { return kShades[k % 3] * kShadeWeight + cv::Scalar::all(255) * (1 - kShadeWeight); }

// A source keeps its colour whichever sources a frame measured with: the front pair, the left and
// the right camera; other names by their place.
size_t ShadeOf(const std::string& name, size_t k) {
  if (name == "front") return 0;
  if (name == "left") return 1;
  if (name == "right") return 2;
  return k;
}

// The legend's box at the bottom right (room for three sources; empty on maps too small for it).
constexpr int kLegendLine = 14, kLegendLines = 11;
cv::Rect LegendRect(const cv::Size& map) {
  const int width = 190, height = kLegendLine * kLegendLines + 8;
  const cv::Rect box(map.width - width - 6, map.height - height - 6, width, height);
  return box.x < map.width / 2 || box.y < map.height / 2 ? cv::Rect() : box;
}

// What the colours mean, in LegendRect: each source's ground, what no source measures, obstacles
// and their nearest points, tracks, the grid, the own car.
void DrawLegend(cv::Mat& map, const Coverage& coverage) {
  struct Entry {
    cv::Scalar colour;
    std::string text;
  };
  std::vector<Entry> entries;
  std::vector<std::string> named;
  for (size_t k = 0; k < coverage.sectors.size() && named.size() < 3; ++k) {
    const std::string& n = coverage.sectors[k].name;
    if (std::find(named.begin(), named.end(), n) != named.end()) continue;  // a camera's rear view
    named.push_back(n);
    entries.push_back({SectorShade(ShadeOf(n, k)), n == "front" ? "front: stereo pair" : n + ": motion stereo"});
  }
  entries.push_back({cv::Scalar::all(255), "not measured"});
  entries.push_back({kObstacleColour, "obstacle"});
  entries.push_back({kNearestColour, "its nearest point"});
  entries.push_back({kTrackColour, "track: id class lane"});
  entries.push_back({kLaneColour, "lane boundary, ego LP"});
  entries.push_back({cv::Scalar::all(kGridOccupiedGrey), "grid: occupied"});
  entries.push_back({cv::Scalar(kGridFreeBlueRed, kGridFreeGreen, kGridFreeBlueRed), "grid: free"});
  entries.push_back({cv::Scalar(0, 0, 0), "own car"});
  const cv::Rect box = LegendRect(map.size());
  if (box.empty()) return;
  map(box).setTo(cv::Scalar::all(255));
  cv::rectangle(map, box, cv::Scalar::all(120), 1);
  for (size_t i = 0; i < entries.size(); ++i) {
    const cv::Point at(box.x + 6, box.y + 5 + kLegendLine * static_cast<int>(i));
    cv::rectangle(map, cv::Rect(at, cv::Size(16, 10)), entries[i].colour, cv::FILLED);
    cv::rectangle(map, cv::Rect(at, cv::Size(16, 10)), cv::Scalar::all(160), 1);
    cv::putText(map, entries[i].text, at + cv::Point(22, 9), cv::FONT_HERSHEY_SIMPLEX, 0.35, cv::Scalar::all(0), 1,
                cv::LINE_AA);
  }
}

}  // namespace

void DrawOwnCar(cv::Mat& map, const Vehicle& vehicle, const MapOptions& o) {
  const MapProjection to_px(o);
  cv::rectangle(map, to_px(-vehicle.width_m / 2, vehicle.length_m / 2), to_px(vehicle.width_m / 2, -vehicle.length_m / 2),
                cv::Scalar(0, 0, 0), cv::FILLED);
}

cv::Mat DrawMapBackground(const Vehicle& vehicle, const Coverage& coverage, const MapOptions& o) {
  const MapProjection to_px(o);
  const double scale = to_px.scale;
  cv::Mat map(o.size_px, o.size_px, CV_8UC3, cv::Scalar(255, 255, 255));

  // Coverage: each sector lightly shaded.
  size_t k = 0;
  for (const Sector& s : coverage.sectors) {
    // As far as the sector sees: beyond the map, or a side view's depth limit (from its apex).
    const Eigen::Vector2d v = s.Vertex(), from = s.max_depth_m > 0 ? s.apex : v;
    std::vector<cv::Point> poly{to_px(v.x(), v.y())};
    for (int i = 0; i <= 24; ++i) {
      const double a = s.direction_rad - s.half_angle_rad + 2 * s.half_angle_rad * i / 24.0;
      const double r = std::min(s.Reach(a), 2 * o.range_m);
      poly.push_back(to_px(from.x() + r * std::sin(a), from.y() + r * std::cos(a)));
    }
    cv::Mat layer = map.clone();
    cv::fillPoly(layer, std::vector<std::vector<cv::Point>>{poly}, kShades[ShadeOf(s.name, k++) % 3]);
    cv::addWeighted(layer, kShadeWeight, map, 1 - kShadeWeight, 0, map);
  }
  // Range rings and their labels.
  for (double r = o.ring_step_m; r <= o.range_m * 1.42; r += o.ring_step_m) {
    cv::circle(map, to_px(0, 0), cvRound(r * scale), cv::Scalar(200, 200, 200), 1, cv::LINE_AA);
    if (std::fmod(r, 2 * o.ring_step_m) < 1e-9 && r <= o.range_m) {
      cv::putText(map, std::to_string(static_cast<int>(r)) + " m", to_px(0.3, r + 0.3), cv::FONT_HERSHEY_SIMPLEX,
                  0.35, cv::Scalar(120, 120, 120), 1, cv::LINE_AA);
    }
  }
  // The own car.
  DrawOwnCar(map, vehicle, o);
  const cv::Point bar(12, o.size_px - 14);
  cv::line(map, bar, bar + cv::Point(cvRound(5 * scale), 0), cv::Scalar(0, 0, 0), 2);
  cv::putText(map, "5 m", bar + cv::Point(0, -6), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  DrawLegend(map, coverage);
  return map;
}

MapBackgrounds::MapBackgrounds(const Vehicle& vehicle, const MapOptions& options, size_t capacity)
    : vehicle_(vehicle), options_(options), capacity_(std::max<size_t>(1, capacity)) {}

const cv::Mat& MapBackgrounds::For(const Coverage& coverage) {
  // Sectors alike to a tenth of a degree and a centimetre draw alike.
  std::string key;
  char part[160];
  for (const Sector& s : coverage.sectors) {
    std::snprintf(part, sizeof(part), "%s %ld %ld %ld %ld %ld %ld %ld;", s.name.c_str(), std::lround(s.apex.x() * 100),
                  std::lround(s.apex.y() * 100), std::lround(s.direction_rad / kRadPerDeg * 10),
                  std::lround(s.half_angle_rad / kRadPerDeg * 10), std::lround(s.start_m * 100),
                  std::lround(s.max_depth_m * 100), std::lround(s.depth_direction_rad / kRadPerDeg * 10));
    key += part;
  }
  const auto it = pictures_.find(key);
  if (it != pictures_.end()) return it->second;
  if (pictures_.size() >= capacity_) {
    pictures_.erase(order_.front());
    order_.pop_front();
  }
  order_.push_back(key);
  return pictures_.emplace(key, DrawMapBackground(vehicle_, coverage, options_)).first->second;
}

namespace {

// Draws the obstacles and the caption onto a map picture (DrawSurroundMap on a copy,
// DrawFrameMap on its own layers).
void DrawObstacles(cv::Mat& map, const std::vector<Detection>& detections, const MapOptions& o,
                   const std::string& caption) {
  const MapProjection to_px(o);
  const double scale = to_px.scale;
  // Obstacles: ground points joined, closed in the picture (each within its own bounding box;
  // a square closing, which OpenCV runs separably, costs a fraction of a disc's).
  const int close = cvRound(scale) | 1;
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(close, close));
  const cv::Rect picture(0, 0, map.cols, map.rows);
  const int pad = 2 * close + std::max(2, cvRound(0.25 * scale));
  for (const Detection& d : detections) {
    std::vector<cv::Point> pts;
    for (const Eigen::Vector2d& p : d.points) pts.push_back(to_px(p.x(), p.y()));
    if (pts.empty()) pts.push_back(to_px(d.x_m, d.z_m));
    const cv::Rect bounds = cv::boundingRect(pts);
    const cv::Rect box = cv::Rect(bounds.tl() - cv::Point(pad, pad), bounds.br() + cv::Point(pad, pad)) & picture;
    if (box.empty()) continue;
    cv::Mat mask(box.size(), CV_8U, cv::Scalar(0));
    for (cv::Point& p : pts) p -= box.tl();
    cv::polylines(mask, pts, false, cv::Scalar(255), std::max(2, cvRound(0.25 * scale)));
    for (const cv::Point& p : pts) cv::circle(mask, p, std::max(1, cvRound(0.15 * scale)), cv::Scalar(255), cv::FILLED);
    cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, kernel);
    map(box).setTo(kObstacleColour, mask);
  }
  for (const Detection& d : detections) cv::circle(map, to_px(d.x_m, d.z_m), 3, kNearestColour, cv::FILLED, cv::LINE_AA);
  cv::putText(map, caption, cv::Point(10, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
}

}  // namespace

cv::Mat DrawSurroundMap(const cv::Mat& background, const std::vector<Detection>& detections, const MapOptions& o,
                        const std::string& caption) {
  cv::Mat map = background.clone();
  DrawObstacles(map, detections, o, caption);
  return map;
}

void DrawLanes(cv::Mat& map, const std::vector<LaneBoundaryRow>& lanes, const MapOptions& o) {
  const MapProjection to_px(o);
  for (const LaneBoundaryRow& b : lanes) {
    const double slope = std::tan(b.heading_deg * kRadPerDeg);
    const int thickness = b.boundary == "left" || b.boundary == "right" ? 2 : 1;
    // Dashes of 3 m every 9 m for dashed lines, one segment for solid ones.
    const double step = b.type == "dashed" ? 9.0 : 2 * o.range_m, length = b.type == "dashed" ? 3.0 : 2 * o.range_m;
    for (double z = -o.range_m; z < o.range_m; z += step) {
      const double z1 = std::min(o.range_m, z + length);
      cv::line(map, to_px(b.offset_m + slope * z, z), to_px(b.offset_m + slope * z1, z1), kLaneColour, thickness, cv::LINE_AA);
    }
  }
}

void DrawEgoLane(cv::Mat& map, const EgoLaneRow& ego) {
  char text[96];
  // Rounded first, and + 0.0 turns -0 into 0: no "-0.0".
  const double lp = std::round(ego.lp_m * 100) / 100 + 0.0, heading = std::round(ego.heading_deg * 10) / 10 + 0.0;
  std::snprintf(text, sizeof(text), "LP %+.2f m in a %.2f m lane, heading %+.1f deg", lp, ego.lane_width_m, heading);
  cv::putText(map, text, cv::Point(10, 40), cv::FONT_HERSHEY_SIMPLEX, 0.45, kLaneColour, 1, cv::LINE_AA);
}

void DrawTracks(cv::Mat& map, const std::vector<TrackState>& tracks, const MapOptions& o) {
  const MapProjection to_px(o);
  for (const TrackState& t : tracks) {
    if (!t.confirmed) continue;
    const cv::Point at = to_px(t.x_m, t.z_m), ahead = to_px(t.predicted.x(), t.predicted.y());
    // The prediction's 1-sigma ellipse (map y points against z).
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(t.predicted_cov);
    const Eigen::Vector2d axis = eig.eigenvectors().col(1);
    const double angle = std::atan2(-axis.y(), axis.x()) * kDegPerRad;
    const cv::Size axes(std::max(1, cvRound(std::sqrt(std::max(0.0, eig.eigenvalues()(1))) * to_px.scale)),
                        std::max(1, cvRound(std::sqrt(std::max(0.0, eig.eigenvalues()(0))) * to_px.scale)));
    cv::ellipse(map, ahead, axes, angle, 0, 360, cv::Scalar(200, 120, 0), 1, cv::LINE_AA);
    cv::arrowedLine(map, at, ahead, kTrackColour, 2, cv::LINE_AA, 0, 0.2);
    // Id, class and lane (object_attributes.h), e.g. "7 vehicle L-1".
    std::string label = std::to_string(t.id);
    if (!t.object_class.empty() && t.object_class != "unknown") label += " " + t.object_class;
    if (t.lane) label += " L" + std::string(*t.lane > 0 ? "+" : "") + std::to_string(*t.lane);
    cv::putText(map, label, at + cv::Point(6, -6), cv::FONT_HERSHEY_SIMPLEX, 0.45, kTrackColour, 1, cv::LINE_AA);
  }
}

cv::Mat DrawFrameMap(const cv::Mat& background, const OccupancyGrid& grid, const Vehicle& vehicle,
                     const std::vector<Detection>& detections, const std::vector<TrackState>& tracks,
                     const MapOptions& options, const std::string& caption) {
  cv::Mat map;
  DrawFrameMap(background, grid, vehicle, detections, tracks, options, caption, map);
  return map;
}

void DrawFrameMap(const cv::Mat& background, const OccupancyGrid& grid, const Vehicle& vehicle,
                  const std::vector<Detection>& detections, const std::vector<TrackState>& tracks,
                  const MapOptions& options, const std::string& caption, cv::Mat& map) {
  grid.Draw(background, map, options.range_m);
  const cv::Rect legend = LegendRect(map.size());
  if (!legend.empty()) background(legend).copyTo(map(legend));  // over the grid
  DrawOwnCar(map, vehicle, options);
  DrawObstacles(map, detections, options, caption);
  DrawTracks(map, tracks, options);
}

namespace {

cv::Mat Panel(const cv::Mat& image, cv::Size size, const std::string& label) {
  cv::Mat out(size, CV_8UC3, cv::Scalar(60, 60, 60));
  if (!image.empty()) {
    cv::Mat bgr = image;
    if (image.channels() == 1) cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
    cv::resize(bgr, out, size, 0, 0, cv::INTER_NEAREST);
  }
  cv::putText(out, label, cv::Point(6, 16), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 255, 255), 1, cv::LINE_AA);
  return out;
}

}  // namespace

cv::Mat DrawDiagnostics(const std::string& title, const cv::Mat& reference, const cv::Mat& other,
                        const cv::Mat& disparity, const cv::Mat& histogram, const cv::Mat& obstacle,
                        double min_d, double max_d, cv::Size panel) {
  cv::Mat composite, disp_colour, hist_colour, obst_colour;
  if (!reference.empty() && !other.empty()) {
    std::vector<cv::Mat> ch = {other, other, reference};  // B, G from the right / later view, R from the left
    cv::merge(ch, composite);
  }
  if (!disparity.empty()) {
    cv::Mat scaled(disparity.size(), CV_8U);
    for (int y = 0; y < disparity.rows; ++y) {
      for (int x = 0; x < disparity.cols; ++x) {
        const float d = disparity.at<float>(y, x);
        scaled.at<std::uint8_t>(y, x) = std::isfinite(d) ? cv::saturate_cast<std::uint8_t>(255.0 * (d - min_d) / (max_d - min_d)) : 0;
      }
    }
    cv::applyColorMap(scaled, disp_colour, cv::COLORMAP_TURBO);
    disp_colour.setTo(cv::Scalar::all(0), disparity == std::numeric_limits<float>::infinity());
  }
  if (!histogram.empty()) {
    cv::Mat h8, flipped;
    double hi = 0;
    cv::minMaxLoc(histogram, nullptr, &hi);
    histogram.convertTo(h8, CV_8U, hi > 0 ? 255.0 / hi : 0);
    cv::flip(h8, flipped, 0);  // larger disparity (nearer) up
    cv::applyColorMap(flipped, hist_colour, cv::COLORMAP_HOT);
  }
  if (!obstacle.empty()) {
    cv::Mat o8;
    if (obstacle.type() == CV_32F) {
      cv::Mat flipped;
      cv::flip(obstacle > 0, flipped, 0);
      o8 = flipped;
    } else {
      o8 = obstacle;
    }
    cv::dilate(o8, o8, cv::Mat());
    cv::cvtColor(o8, obst_colour, cv::COLOR_GRAY2BGR);
  }
  cv::Mat top, middle, bottom, out;
  cv::hconcat(Panel(reference, panel, title + ": reference"), Panel(other, panel, "matched"), top);
  cv::hconcat(Panel(composite, panel, "composite"), Panel(disp_colour, panel, "disparity"), middle);
  cv::hconcat(Panel(hist_colour, panel, "column histogram"), Panel(obst_colour, panel, "obstacles"), bottom);
  cv::vconcat(std::vector<cv::Mat>{top, middle, bottom}, out);
  return out;
}

void MapOptions::Check() const {
  const OptionCheck Require("map");
  Require(size_px >= 16 && size_px <= 8192, "size_px", size_px, "16..8192");
  Require(range_m > 0 && range_m <= 1000, "range_m", range_m, "0 < range <= 1000 m");
  Require(ring_step_m > 0 && range_m / ring_step_m <= 1000, "ring_step_m", ring_step_m, "> 0, at most 1000 rings");
}

}  // namespace dps
