#include "dps/camera/rig_report.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "dps/camera/valid_mask.h"
#include "dps/util/error.h"
#include "dps/util/math.h"

namespace dps {
namespace {

const cv::Scalar kLaneOverlayColour(255, 0, 255);  // magenta (BGR)
const cv::Scalar kCameraColours[] = {{60, 60, 230}, {230, 120, 40}, {60, 200, 60}, {200, 60, 200}, {40, 200, 220}, {150, 150, 150}};

// What deciding whether a camera sees a point needs, computed once per camera.
struct Sight {
  explicit Sight(const RigCamera& c)
      : camera(c), camera_from_vehicle(c.vehicle_from_camera.Inverse()), valid(CameraValidMask(c)) {}

  // True when the camera-frame point projects inside the image onto a valid pixel.
  bool SeesCameraPoint(const Eigen::Vector3d& p, Eigen::Vector2d* pixel) const {
    Eigen::Vector2d px;
    if (!camera.model.Project(p, &px) || !camera.model.InImage(px)) return false;
    const int u = static_cast<int>(std::lround(px.x())), v = static_cast<int>(std::lround(px.y()));
    if (u < 0 || v < 0 || u >= valid.cols || v >= valid.rows || valid.at<std::uint8_t>(v, u) == 0) return false;
    if (pixel) *pixel = px;
    return true;
  }
  // A point of the vehicle frame, or a direction (a point at infinity: only the rotation matters).
  bool Sees(const Eigen::Vector3d& p, Eigen::Vector2d* pixel = nullptr) const {
    return SeesCameraPoint(camera_from_vehicle.Apply(p), pixel);
  }
  bool SeesDirection(const Eigen::Vector3d& d, Eigen::Vector2d* pixel) const {
    return SeesCameraPoint(camera_from_vehicle.Rotate(d), pixel);
  }

  const RigCamera& camera;
  Pose camera_from_vehicle;
  cv::Mat valid;
};

// Draws the polyline of vehicle-frame points (or directions) as the camera sees them, broken where
// a point is not seen or where two neighbours land far apart (a wrap around the image).
void DrawCurve(cv::Mat& image, const Sight& sight, const std::vector<Eigen::Vector3d>& points, const cv::Scalar& colour,
               int thickness, bool directions = false) {
  const double jump = 0.1 * std::max(image.cols, image.rows);
  bool have_last = false;
  Eigen::Vector2d last;
  for (const Eigen::Vector3d& p : points) {
    Eigen::Vector2d px;
    const bool seen = directions ? sight.SeesDirection(p, &px) : sight.Sees(p, &px);
    if (seen && have_last && (px - last).norm() < jump) {
      cv::line(image, cv::Point2d(last.x(), last.y()), cv::Point2d(px.x(), px.y()), colour, thickness, cv::LINE_AA);
    }
    have_last = seen;
    if (seen) last = px;
  }
}

std::vector<Eigen::Vector3d> Segment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double step) {
  const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i <= n; ++i) out.push_back(a + (b - a) * (static_cast<double>(i) / n));
  return out;
}

}  // namespace

std::string RigSummary(const Rig& rig, double range_m) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(2);
  out << "vehicle: " << rig.vehicle.length_m << " m x " << rig.vehicle.width_m << " m\n";
  for (const RigCamera& c : rig.cameras) {
    const Sight sight(c);
    const Eigen::Vector3d t = c.vehicle_from_camera.t, axis = c.vehicle_from_camera.R.col(2);
    const double azimuth = std::atan2(axis.x(), axis.z()) * kDegPerRad;
    const double elevation = -std::asin(std::max(-1.0, std::min(1.0, axis.y()))) * kDegPerRad;
    // The share of the road within range_m (outside the car) that the camera sees, on a 10 cm grid.
    int road = 0, seen = 0;
    for (double x = -range_m; x <= range_m; x += 0.1) {
      for (double z = -range_m; z <= range_m; z += 0.1) {
        if (std::hypot(x, z) > range_m) continue;
        if (std::abs(x) < rig.vehicle.width_m / 2 && std::abs(z) < rig.vehicle.length_m / 2) continue;
        ++road;
        seen += sight.Sees(Eigen::Vector3d(x, 0, z));
      }
    }
    out.precision(1);
    out << c.name << ": " << ModelName(c.model.type()) << " " << c.model.width() << "x" << c.model.height()
        << ", field to " << c.model.max_theta_rad() * kDegPerRad << " deg from the axis, at (" << t.x() << ", " << t.y()
        << ", " << t.z() << ") m (" << -t.y() << " m above the road), axis azimuth " << azimuth << " deg (+ = right), elevation "
        << elevation << " deg; sees " << 100.0 * seen / std::max(road, 1) << " % of the road within " << range_m << " m\n";
  }
  return out.str();
}

cv::Mat DrawRigFootprints(const Rig& rig, double range_m, double px_per_m) {
  if (!(range_m > 0.0 && px_per_m > 0.0 && range_m * px_per_m <= 4000.0)) {
    throw Error(Str("footprints: range ", range_m, " m at ", px_per_m, " px/m: expected positive and at most 8000 px across"));
  }
  const int size = static_cast<int>(std::lround(2.0 * range_m * px_per_m));
  cv::Mat image(size, size, CV_8UC3, cv::Scalar(40, 40, 40));
  auto to_ground = [&](int u, int v) { return Eigen::Vector3d((u + 0.5) / px_per_m - range_m, 0.0, range_m - (v + 0.5) / px_per_m); };
  auto to_image = [&](double x, double z) { return cv::Point2d((x + range_m) * px_per_m, (range_m - z) * px_per_m); };
  std::vector<std::vector<std::vector<cv::Point>>> outlines;
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    const RigCamera& c = rig.cameras[i];
    const Sight sight(c);
    const cv::Scalar colour = kCameraColours[i % 6];
    cv::Mat seen(size, size, CV_8U, cv::Scalar(0));
    cv::parallel_for_(cv::Range(0, size), [&](const cv::Range& rows) {
      for (int v = rows.start; v < rows.end; ++v) {
        for (int u = 0; u < size; ++u) seen.at<std::uint8_t>(v, u) = sight.Sees(to_ground(u, v)) ? 255 : 0;
      }
    });
    cv::Mat layer(size, size, CV_8UC3, colour);
    cv::Mat blended;
    cv::addWeighted(image, 0.7, layer, 0.3, 0.0, blended);
    blended.copyTo(image, seen);
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(seen, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
    outlines.push_back(contours);
  }
  for (size_t i = 0; i < outlines.size(); ++i) cv::drawContours(image, outlines[i], -1, kCameraColours[i % 6], 2, cv::LINE_AA);
  for (int m = -static_cast<int>(range_m); m <= static_cast<int>(range_m); ++m) {
    const cv::Scalar grid = m == 0 ? cv::Scalar(130, 130, 130) : cv::Scalar(75, 75, 75);
    cv::line(image, to_image(m, -range_m), to_image(m, range_m), grid, 1);
    cv::line(image, to_image(-range_m, m), to_image(range_m, m), grid, 1);
  }
  const double hl = rig.vehicle.length_m / 2, hw = rig.vehicle.width_m / 2;
  cv::rectangle(image, to_image(-hw, hl), to_image(hw, -hl), cv::Scalar(255, 255, 255), 2);
  cv::arrowedLine(image, to_image(0, 0), to_image(0, hl), cv::Scalar(255, 255, 255), 2, cv::LINE_AA, 0, 0.2);
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    const RigCamera& c = rig.cameras[i];
    const Eigen::Vector3d t = c.vehicle_from_camera.t, axis = c.vehicle_from_camera.R.col(2);
    const cv::Scalar colour = kCameraColours[i % 6];
    cv::circle(image, to_image(t.x(), t.z()), 6, colour, cv::FILLED, cv::LINE_AA);
    if (std::hypot(axis.x(), axis.z()) > 1e-3) {
      const Eigen::Vector2d d = Eigen::Vector2d(axis.x(), axis.z()).normalized();
      cv::line(image, to_image(t.x(), t.z()), to_image(t.x() + d.x(), t.z() + d.y()), colour, 2, cv::LINE_AA);
    }
    cv::putText(image, c.name, cv::Point(10, 24 + 22 * static_cast<int>(i)), cv::FONT_HERSHEY_SIMPLEX, 0.6, colour, 2, cv::LINE_AA);
  }
  cv::putText(image, Str("1 m grid, ", range_m, " m around the car, forward = up"), cv::Point(10, size - 12),
              cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(200, 200, 200), 1, cv::LINE_AA);
  return image;
}

cv::Mat DrawRigCheck(const RigCamera& camera, const Vehicle& vehicle, const cv::Mat& image, double range_m, double grid_m) {
  if (image.cols != camera.model.width() || image.rows != camera.model.height()) {
    throw Error(Str("camera '", camera.name, "': the image is ", image.cols, "x", image.rows, ", the calibration is for ",
                    camera.model.width(), "x", camera.model.height()));
  }
  if (!(range_m > 0.0 && grid_m > 0.0 && range_m / grid_m <= 1000.0)) {
    throw Error(Str("check: range ", range_m, " m, grid ", grid_m, " m: expected positive, at most 1000 lines"));
  }
  cv::Mat out;
  if (image.channels() == 1) cv::cvtColor(image, out, cv::COLOR_GRAY2BGR); else out = image.clone();
  const Sight sight(camera);
  const cv::Mat& valid = sight.valid;
  const int thick = std::max(1, out.cols / 600);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(valid.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  cv::drawContours(out, contours, -1, cv::Scalar(60, 220, 60), thick, cv::LINE_AA);
  const double step = grid_m / 20.0;
  for (double g = -range_m; g <= range_m + 1e-9; g += grid_m) {
    DrawCurve(out, sight, Segment({g, 0, -range_m}, {g, 0, range_m}, step), cv::Scalar(220, 200, 40), thick);
    DrawCurve(out, sight, Segment({-range_m, 0, g}, {range_m, 0, g}, step), cv::Scalar(220, 200, 40), thick);
  }
  const double hl = vehicle.length_m / 2, hw = vehicle.width_m / 2;
  const Eigen::Vector3d corners[] = {{-hw, 0, -hl}, {hw, 0, -hl}, {hw, 0, hl}, {-hw, 0, hl}, {-hw, 0, -hl}};
  for (int i = 0; i < 4; ++i) DrawCurve(out, sight, Segment(corners[i], corners[i + 1], 0.02), cv::Scalar(40, 40, 230), 2 * thick);
  std::vector<Eigen::Vector3d> horizon;
  for (int a = 0; a <= 1440; ++a) horizon.emplace_back(std::sin(a * kPi / 720), 0.0, std::cos(a * kPi / 720));
  DrawCurve(out, sight, horizon, cv::Scalar(40, 230, 230), 2 * thick, true);
  return out;
}

void DrawLaneBoundaries(const RigCamera& camera, const std::vector<LaneBoundaryRow>& boundaries, double range_m,
                        cv::Mat* image) {
  if (!(range_m > 0.0 && range_m <= 1000.0)) throw Error(Str("lanes: range ", range_m, " m: expected 0 < range <= 1000"));
  if (image->cols != camera.model.width() || image->rows != camera.model.height() || image->type() != CV_8UC3) {
    throw Error(Str("camera '", camera.name, "': lanes are drawn on a BGR image of the model's size"));
  }
  const Sight sight(camera);
  const int thick = std::max(2, image->cols / 320);
  for (const LaneBoundaryRow& b : boundaries) {
    const double slope = std::tan(b.heading_deg * kPi / 180.0);
    std::vector<Eigen::Vector3d> points;
    for (double z = -range_m; z <= range_m + 1e-9; z += 0.05) {
      points.emplace_back(b.offset_m + slope * z + 0.5 * b.curvature * z * z, 0.0, z);
    }
    DrawCurve(*image, sight, points, kLaneOverlayColour, thick);
    // The name beside the seen point nearest to the car.
    double nearest = std::numeric_limits<double>::infinity();
    Eigen::Vector2d at;
    for (const Eigen::Vector3d& p : points) {
      Eigen::Vector2d px;
      if (p.norm() < nearest && sight.Sees(p, &px)) nearest = p.norm(), at = px;
    }
    if (std::isfinite(nearest)) {
      cv::putText(*image, b.boundary, cv::Point2d(at.x() + 2 * thick, at.y()), cv::FONT_HERSHEY_SIMPLEX, 0.4 * thick,
                  kLaneOverlayColour, thick, cv::LINE_AA);
    }
  }
}

}  // namespace dps
