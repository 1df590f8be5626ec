#include "dps/surround_map.h"

#include <cmath>

#include <opencv2/imgproc.hpp>

namespace dps {

cv::Mat DrawSurroundMap(const std::vector<Detection>& detections, const Vehicle& vehicle,
                        const Coverage& coverage, const MapOptions& o, const std::string& caption) {
  const double scale = o.size_px / (2.0 * o.range_m);  // px per metre
  const cv::Point2d centre(o.size_px / 2.0, o.size_px / 2.0);
  auto to_px = [&](double x, double z) { return cv::Point(cvRound(centre.x + x * scale), cvRound(centre.y - z * scale)); };
  cv::Mat map(o.size_px, o.size_px, CV_8UC3, cv::Scalar(255, 255, 255));

  // Coverage: each sector lightly shaded.
  const cv::Scalar shades[] = {cv::Scalar(235, 245, 225), cv::Scalar(240, 230, 250), cv::Scalar(225, 240, 250)};
  int k = 0;
  for (const Sector& s : coverage.sectors) {
    std::vector<cv::Point> poly{to_px(s.apex.x(), s.apex.y())};
    for (int i = 0; i <= 24; ++i) {
      const double a = s.direction_rad - s.half_angle_rad + 2 * s.half_angle_rad * i / 24.0;
      poly.push_back(to_px(s.apex.x() + 2 * o.range_m * std::sin(a), s.apex.y() + 2 * o.range_m * std::cos(a)));
    }
    cv::Mat layer = map.clone();
    cv::fillPoly(layer, std::vector<std::vector<cv::Point>>{poly}, shades[k++ % 3]);
    cv::addWeighted(layer, 0.7, map, 0.3, 0, map);
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
  cv::rectangle(map, to_px(-vehicle.width_m / 2, vehicle.length_m / 2), to_px(vehicle.width_m / 2, -vehicle.length_m / 2),
                cv::Scalar(0, 0, 0), cv::FILLED);
  // Obstacles: ground points joined, closed in the picture.
  cv::Mat mask(map.size(), CV_8U, cv::Scalar(0));
  for (const Detection& d : detections) {
    std::vector<cv::Point> pts;
    for (const Eigen::Vector2d& p : d.points) pts.push_back(to_px(p.x(), p.y()));
    if (pts.empty()) pts.push_back(to_px(d.x_m, d.z_m));
    cv::polylines(mask, pts, false, cv::Scalar(255), std::max(2, cvRound(0.25 * scale)));
    for (const cv::Point& p : pts) cv::circle(mask, p, std::max(1, cvRound(0.15 * scale)), cv::Scalar(255), cv::FILLED);
  }
  cv::morphologyEx(mask, mask, cv::MORPH_CLOSE,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(cvRound(scale) | 1, cvRound(scale) | 1)));
  map.setTo(cv::Scalar(0, 0, 220), mask);
  for (const Detection& d : detections) cv::circle(map, to_px(d.x_m, d.z_m), 3, cv::Scalar(0, 0, 120), cv::FILLED, cv::LINE_AA);
  // Scale bar and caption.
  const cv::Point bar(12, o.size_px - 14);
  cv::line(map, bar, bar + cv::Point(cvRound(5 * scale), 0), cv::Scalar(0, 0, 0), 2);
  cv::putText(map, "5 m", bar + cv::Point(0, -6), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(map, caption, cv::Point(10, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return map;
}

}  // namespace dps
