#include "dps/map/surround_map.h"

#include "dps/camera/valid_mask.h"
#include "dps/util/error.h"
#include "dps/util/math.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>

namespace dps {

namespace {

// The obstacles' colours by their lane (the ego lane's, the lanes to the left, to the right,
// unknown), their nearest points', the tracks'.
const cv::Scalar kEgoLaneColour(0, 0, 220), kLeftLanesColour(0, 150, 255), kRightLanesColour(160, 30, 140),
    kUnknownLaneColour(90, 110, 130), kNearestColour(0, 0, 120), kTrackColour(200, 80, 0);

cv::Scalar LaneColour(const std::optional<int>& lane) {
  if (!lane) return kUnknownLaneColour;
  return *lane == 0 ? kEgoLaneColour : *lane < 0 ? kLeftLanesColour : kRightLanesColour;
}
const cv::Scalar kLaneColour(0, 170, 230);
// Hatching: where motion stereo tells no depth (the sweep's colour for the epipoles' wedges,
// plane_sweep.h), the road no camera sees.
const cv::Scalar kMotionBlindColour(220, 90, 220), kUnseenColour(110, 110, 110);
constexpr int kHatchPx = 8;  // the hatching's line spacing

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

// Diagonal lines kHatchPx apart (and the crossing ones when `crossed`) in `colour` over the pixels
// of `picture` where `where` is set; `origin`: the picture's place in the map, so that hatching
// drawn in pieces lines up.
void Hatch(cv::Mat picture, const cv::Mat& where, const cv::Scalar& colour, bool crossed, cv::Point origin = {}) {
  const cv::Vec3b c(cv::saturate_cast<uchar>(colour[0]), cv::saturate_cast<uchar>(colour[1]),
                    cv::saturate_cast<uchar>(colour[2]));
  const auto mod = [](int a) { return (a % kHatchPx + kHatchPx) % kHatchPx; };
  for (int v = 0; v < picture.rows; ++v) {
    // Every kHatchPx-th column from the first one on a line.
    const auto line = [&](int first) {
      for (int u = first; u < picture.cols; u += kHatchPx) {
        if (where.at<uchar>(v, u)) picture.at<cv::Vec3b>(v, u) = c;
      }
    };
    // The lines where the map's u + v is a multiple of the spacing, and u - v when crossed.
    const int y = v + origin.y;
    line(mod(-origin.x - y));
    if (crossed) line(mod(y - origin.x));
  }
}

// The legend's box at the bottom right (room for three sources; empty on maps too small for it).
constexpr int kLegendLine = 14, kLegendLines = 16;
cv::Rect LegendRect(const cv::Size& map) {
  const int width = 190, height = kLegendLine * kLegendLines + 8;
  const cv::Rect box(map.width - width - 6, map.height - height - 6, width, height);
  return box.x < map.width / 2 || box.y < map.height / 2 ? cv::Rect() : box;
}

// What the colours mean, in LegendRect: each source's ground, what no source measures, where the
// motion tells no depth and the road no camera sees (when drawn), obstacles by lane and their
// nearest points, tracks, the grid, the own car.
void DrawLegend(cv::Mat& map, const Coverage& coverage, bool unseen) {
  struct Entry {
    cv::Scalar colour;
    std::string text;
    int hatch = 0;  // 0: a filled swatch; 1: diagonal lines; 2: crossed
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
  if (!coverage.motion.empty()) entries.push_back({kMotionBlindColour, "no depth from motion", 1});
  if (unseen) entries.push_back({kUnseenColour, "no camera sees the road", 2});
  entries.push_back({kEgoLaneColour, "obstacle in the ego lane"});
  entries.push_back({kLeftLanesColour, "... in a lane to the left"});
  entries.push_back({kRightLanesColour, "... in a lane to the right"});
  entries.push_back({kUnknownLaneColour, "... lane unknown"});
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
    const cv::Rect swatch(at, cv::Size(16, 10));
    if (entries[i].hatch == 0) {
      cv::rectangle(map, swatch, entries[i].colour, cv::FILLED);
    } else {
      Hatch(map(swatch), cv::Mat(swatch.size(), CV_8U, cv::Scalar(255)), entries[i].colour, entries[i].hatch == 2, at);
    }
    cv::rectangle(map, swatch, cv::Scalar::all(160), 1);
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

cv::Mat RoadNoCameraSees(const Rig& rig, double own_car_height_m, const MapOptions& o) {
  o.Check();
  if (!(own_car_height_m >= 0)) throw Error(Str("map: own_car_height_m = ", own_car_height_m, " (must be >= 0)"));
  const MapProjection to_px(o);
  const Eigen::Vector3d lo(-rig.vehicle.width_m / 2, -own_car_height_m, -rig.vehicle.length_m / 2);
  const Eigen::Vector3d hi(rig.vehicle.width_m / 2, 0.0, rig.vehicle.length_m / 2);
  struct Camera {
    const RigCamera* camera;
    cv::Mat valid;
    Pose camera_from_vehicle;
    bool inside;  // the viewpoint lies inside the own car's box: its mask says what the car hides
  };
  std::vector<Camera> cameras;
  for (const RigCamera& c : rig.cameras) {
    const Eigen::Vector3d t = c.vehicle_from_camera.t;
    cameras.push_back({&c, CameraValidMask(c), c.vehicle_from_camera.Inverse(),
                       (t.array() >= lo.array()).all() && (t.array() <= hi.array()).all()});
  }
  cv::Mat unseen(o.size_px, o.size_px, CV_8U, cv::Scalar(0));
  cv::parallel_for_(cv::Range(0, o.size_px), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      for (int u = 0; u < o.size_px; ++u) {
        const Eigen::Vector3d p((u - to_px.centre.x) / to_px.scale, 0.0, (to_px.centre.y - v) / to_px.scale);
        bool seen = false;
        for (const Camera& c : cameras) {
          Eigen::Vector2d px;
          if (!SeesRoadPoint(*c.camera, c.camera_from_vehicle, c.valid, lo, hi, !c.inside, p, &px)) continue;
          if (!c.camera->own_car.empty() &&
              c.camera->own_car.at<uchar>(static_cast<int>(std::lround(px.y())), static_cast<int>(std::lround(px.x())))) {
            continue;
          }
          seen = true;
          break;
        }
        if (!seen) unseen.at<uchar>(v, u) = 255;
      }
    }
  });
  return unseen;
}

cv::Mat DrawMapBackground(const Vehicle& vehicle, const Coverage& coverage, const MapOptions& o, const cv::Mat& unseen) {
  const MapProjection to_px(o);
  const double scale = to_px.scale;
  cv::Mat map(o.size_px, o.size_px, CV_8UC3, cv::Scalar(255, 255, 255));
  if (!unseen.empty() && (unseen.size() != map.size() || unseen.type() != CV_8U)) {
    throw Error(Str("map: the unseen road is ", unseen.cols, "x", unseen.rows, ", not the map's ", o.size_px, "x",
                    o.size_px, " CV_8U"));
  }

  // Coverage: each sector lightly shaded.
  std::vector<std::vector<cv::Point>> polygons;
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
    // Blended over the polygon's bounding box only.
    const cv::Rect box = cv::boundingRect(poly) & cv::Rect(0, 0, map.cols, map.rows);
    if (!box.empty()) {
      cv::Mat layer = map(box).clone();
      std::vector<cv::Point> shifted = poly;
      for (cv::Point& q : shifted) q -= box.tl();
      cv::fillPoly(layer, std::vector<std::vector<cv::Point>>{shifted}, kShades[ShadeOf(s.name, k) % 3]);
      cv::addWeighted(layer, kShadeWeight, map(box), 1 - kShadeWeight, 0, map(box));
    }
    ++k;
    polygons.push_back(std::move(poly));
  }
  // Where this frame's motion stereo tells no depth (outside every sight's two discs), outside what
  // a sector measured and where a camera sees the road; the road no camera sees.
  if (!coverage.motion.empty()) {
    cv::Mat blind(map.size(), CV_8U, cv::Scalar(255));
    for (const MotionSight& m : coverage.motion) {
      const Eigen::Vector2d across(std::cos(m.direction_rad), -std::sin(m.direction_rad));
      for (const double side : {-1.0, 1.0}) {
        const Eigen::Vector2d c = m.viewpoint + side * m.diameter_m / 2 * across;
        // A quarter-pixel grid (shift 2) for the discs' centres and radii.
        const cv::Point2d at(4 * (to_px.centre.x + c.x() * scale), 4 * (to_px.centre.y - c.y() * scale));
        const double radius = std::min(4 * m.diameter_m / 2 * scale, 4e8);
        cv::circle(blind, cv::Point(cvRound(at.x), cvRound(at.y)), cvRound(radius), cv::Scalar(0), cv::FILLED, cv::LINE_8, 2);
      }
    }
    if (!polygons.empty()) cv::fillPoly(blind, polygons, cv::Scalar(0));
    if (!unseen.empty()) blind.setTo(0, unseen);
    Hatch(map, blind, kMotionBlindColour, false);
  }
  if (!unseen.empty()) Hatch(map, unseen, kUnseenColour, true);
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
  DrawLegend(map, coverage, !unseen.empty());
  return map;
}

MapBackgrounds::MapBackgrounds(const Vehicle& vehicle, const MapOptions& options, size_t capacity, const cv::Mat& unseen)
    : vehicle_(vehicle), options_(options), capacity_(std::max<size_t>(1, capacity)), unseen_(unseen) {}

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
  for (const MotionSight& m : coverage.motion) {
    std::snprintf(part, sizeof(part), "m %s %ld %ld %ld %ld;", m.name.c_str(), std::lround(m.viewpoint.x() * 100),
                  std::lround(m.viewpoint.y() * 100), std::lround(m.direction_rad / kRadPerDeg),
                  m.diameter_m > 0 ? std::lround(std::log(m.diameter_m) / std::log(1.05)) : -1000L);
    key += part;
  }
  const auto it = pictures_.find(key);
  if (it != pictures_.end()) return it->second;
  if (pictures_.size() >= capacity_) {
    pictures_.erase(order_.front());
    order_.pop_front();
  }
  order_.push_back(key);
  return pictures_.emplace(key, DrawMapBackground(vehicle_, coverage, options_, unseen_)).first->second;
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
    map(box).setTo(LaneColour(d.lane), mask);
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
