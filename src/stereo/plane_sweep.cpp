#include "dps/stereo/plane_sweep.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "dps/util/error.h"

namespace dps {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr double kSameSurfacePx = 1.5;  // warps this close together are the same surface

// The rays of the pixels of the region's bounding box (vehicle frame; NaN where the pixel sees
// nothing) and their distances to the road plane (+inf above the horizon).
struct Rays {
  cv::Mat dirs;    // CV_32FC3
  cv::Mat road_m;  // CV_32F
};

// Where each current pixel (of the box) lands in the earlier image if it lies at `distance_m`
// along its ray (distance < 0: on the road). (-1, -1) where it leaves the earlier image or its
// valid pixels.
cv::Mat WarpMap(const CameraModel& model, const Pose& vehicle_from_camera, const Pose& previous_from_current,
                const Rays& rays, const cv::Mat& valid, double distance_m) {
  const Pose camera_from_previous = vehicle_from_camera.Inverse() * previous_from_current;
  const Eigen::Vector3d& o = vehicle_from_camera.t;
  cv::Mat map(rays.dirs.size(), CV_32FC2);
  cv::parallel_for_(cv::Range(0, map.rows), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      for (int u = 0; u < map.cols; ++u) {
        const cv::Vec3f d = rays.dirs.at<cv::Vec3f>(v, u);
        const double s = distance_m < 0 ? rays.road_m.at<float>(v, u) : distance_m;
        cv::Vec2f& out = map.at<cv::Vec2f>(v, u);
        out = cv::Vec2f(-1, -1);
        if (std::isnan(d[0]) || !std::isfinite(s)) continue;
        const Eigen::Vector3d p = o + s * Eigen::Vector3d(d[0], d[1], d[2]);
        Eigen::Vector2d px;
        if (!model.Project(camera_from_previous.Apply(p), &px)) continue;
        const int pu = static_cast<int>(std::lround(px.x())), pv = static_cast<int>(std::lround(px.y()));
        if (pu < 0 || pv < 0 || pu >= model.width() || pv >= model.height()) continue;
        if (!valid.empty() && valid.at<std::uint8_t>(pv, pu) == 0) continue;
        out = cv::Vec2f(static_cast<float>(px.x()), static_cast<float>(px.y()));
      }
    }
  });
  return map;
}

// How far apart a pixel's ray warps at the nearest and the farthest hypothesis: about the motion's
// epipoles every distance warps alike.
cv::Mat Parallax(const CameraModel& model, const Pose& vehicle_from_camera, const Pose& previous_from_current,
                 const Rays& rays, const PlaneSweepOptions& o) {
  const Pose camera_from_previous = vehicle_from_camera.Inverse() * previous_from_current;
  const Eigen::Vector3d& origin = vehicle_from_camera.t;
  cv::Mat parallax(rays.dirs.size(), CV_32F, cv::Scalar(0));
  cv::parallel_for_(cv::Range(0, parallax.rows), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      for (int u = 0; u < parallax.cols; ++u) {
        const cv::Vec3f d = rays.dirs.at<cv::Vec3f>(v, u);
        if (std::isnan(d[0])) continue;
        const Eigen::Vector3d dir(d[0], d[1], d[2]);
        Eigen::Vector2d a, b;
        if (model.Project(camera_from_previous.Apply(origin + o.min_distance_m * dir), &a) &&
            model.Project(camera_from_previous.Apply(origin + o.max_distance_m * dir), &b)) {
          parallax.at<float>(v, u) = static_cast<float>((a - b).norm());
        }
      }
    }
  });
  return parallax;
}

// Box means over the window.
cv::Mat Mean(const cv::Mat& a, int window) {
  cv::Mat m;
  cv::boxFilter(a, m, CV_32F, cv::Size(window, window), cv::Point(-1, -1), true, cv::BORDER_REPLICATE);
  return m;
}

// The current image's window statistics, shared by every hypothesis.
struct Reference {
  cv::Mat image, mean, variance, inside;  // CV_32F; inside: the window's share of valid pixels
};

Reference MakeReference(const cv::Mat& current, const Rays& rays, int window) {  // current: the box
  Reference r;
  current.convertTo(r.image, CV_32F);
  r.mean = Mean(r.image, window);
  r.variance = Mean(r.image.mul(r.image), window) - r.mean.mul(r.mean);
  cv::Mat seen(rays.dirs.size(), CV_32F);
  for (int v = 0; v < seen.rows; ++v) {
    for (int u = 0; u < seen.cols; ++u) seen.at<float>(v, u) = std::isnan(rays.dirs.at<cv::Vec3f>(v, u)[0]) ? 0.0f : 1.0f;
  }
  r.inside = Mean(seen, window);
  return r;
}

// ZNCC of the reference window with the warped earlier image's; NaN where a window is not whole.
cv::Mat Zncc(const Reference& ref, const cv::Mat& previous, const cv::Mat& map, int window) {
  cv::Mat warped, coverage;
  cv::remap(previous, warped, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::Mat landed = cv::Mat(map.size(), CV_32F);
  for (int v = 0; v < map.rows; ++v) {
    const cv::Vec2f* m = map.ptr<cv::Vec2f>(v);
    float* l = landed.ptr<float>(v);
    for (int u = 0; u < map.cols; ++u) l[u] = m[u][0] >= 0 ? 1.0f : 0.0f;
  }
  coverage = Mean(landed, window);
  const cv::Mat mb = Mean(warped, window);
  const cv::Mat vb = Mean(warped.mul(warped), window) - mb.mul(mb);
  const cv::Mat cov = Mean(ref.image.mul(warped), window) - ref.mean.mul(mb);
  cv::Mat score(map.size(), CV_32F);
  for (int v = 0; v < map.rows; ++v) {
    const float *c = cov.ptr<float>(v), *va = ref.variance.ptr<float>(v), *vbp = vb.ptr<float>(v);
    const float *in = ref.inside.ptr<float>(v), *cv_ = coverage.ptr<float>(v);
    float* s = score.ptr<float>(v);
    for (int u = 0; u < map.cols; ++u) {
      const float denominator = std::sqrt(std::max(va[u], 0.0f) * std::max(vbp[u], 0.0f));
      s[u] = in[u] > 0.999f && cv_[u] > 0.999f && denominator > 1e-3f ? c[u] / denominator : kNaN;
    }
  }
  return score;
}

// The surface a pixel's best score says, with the uniqueness test against surfaces that warp it
// elsewhere; the label and distance follow.
struct PixelChoice {
  const cv::Mat& measured;             // the region's pixels
  const std::vector<cv::Mat>& scores;  // per hypothesis; the last is the road
  const std::vector<cv::Mat>& maps;
  const std::vector<double>& distances;
  const cv::Mat& parallax;
  const PlaneSweepOptions& o;
};

void Choose(const PixelChoice& c, const Rays& rays, const Reference& ref, int u, int v, SweepResult* out) {
  const int n = static_cast<int>(c.scores.size());
  float& distance = out->distance_m.at<float>(v, u);
  std::uint8_t& label = out->label.at<std::uint8_t>(v, u);
  if (!c.measured.at<std::uint8_t>(v, u) || std::isnan(rays.dirs.at<cv::Vec3f>(v, u)[0])) {
    label = kSweepNoRay;
    return;
  }
  if (c.parallax.at<float>(v, u) < c.o.min_parallax_px) {
    label = kSweepUnobservable;
    return;
  }
  int best = -1;
  float best_score = -2.0f;
  for (int k = 0; k < n; ++k) {
    const float s = c.scores[k].at<float>(v, u);
    if (s > best_score) best_score = s, best = k;
  }
  out->score.at<float>(v, u) = best < 0 ? kNaN : best_score;
  label = kSweepAmbiguous;
  if (best < 0 || best_score < c.o.min_zncc || ref.variance.at<float>(v, u) < c.o.min_contrast * c.o.min_contrast) return;
  const cv::Vec2f at = c.maps[best].at<cv::Vec2f>(v, u);
  for (int k = 0; k < n; ++k) {
    const float s = c.scores[k].at<float>(v, u);
    if (k != best && s > best_score - c.o.uniqueness && cv::norm(c.maps[k].at<cv::Vec2f>(v, u) - at) > kSameSurfacePx) return;
  }
  const float road = rays.road_m.at<float>(v, u);
  // A distance that warps where the road does cannot be told from the road: the road it is.
  const cv::Vec2f on_road = c.maps[n - 1].at<cv::Vec2f>(v, u);
  if (best != n - 1 && on_road[0] >= 0 && cv::norm(on_road - at) <= kSameSurfacePx) best = n - 1;
  double d = best == n - 1 ? road : c.distances[best];
  if (best > 0 && best < n - 2) {  // (not the road, n - 1)
    // Parabola through the neighbours' scores, in inverse distance (the hypotheses' spacing).
    const double sl = c.scores[best - 1].at<float>(v, u), sr = c.scores[best + 1].at<float>(v, u);
    const double curvature = sl - 2 * best_score + sr;
    if (std::isfinite(sl) && std::isfinite(sr) && curvature < 0) {
      const double offset = std::clamp(0.5 * (sl - sr) / curvature, -0.5, 0.5);
      const double inv = 1 / c.distances[best], step = 1 / c.distances[best + 1] - inv;
      d = 1 / (inv + offset * step);
    }
  }
  distance = static_cast<float>(d);
  if (std::isfinite(road) && std::abs(d - road) <= c.o.road_tolerance * road) {
    label = kSweepRoad;
  } else if (!std::isfinite(road) || d < road) {
    label = kSweepObstacle;
  } else {
    distance = kNaN;  // beyond the road: no static surface explains it
  }
}

}  // namespace

void PlaneSweepOptions::Check() const {
  const OptionCheck Require("plane_sweep");
  Require(min_distance_m > 0, "min_distance_m", min_distance_m, "> 0");
  Require(max_distance_m > min_distance_m, "max_distance_m", max_distance_m, "> min_distance_m");
  Require(distances >= 2 && distances <= 1024, "distances", distances, "2..1024");
  Require(window_px >= 3 && window_px % 2 == 1 && window_px <= 63, "window_px", window_px, "odd, 3..63");
  Require(min_zncc > -1 && min_zncc < 1, "min_zncc", min_zncc, "-1 < z < 1");
  Require(uniqueness >= 0 && uniqueness < 2, "uniqueness", uniqueness, "0..2");
  Require(min_parallax_px >= 0, "min_parallax_px", min_parallax_px, ">= 0");
  Require(min_contrast >= 0, "min_contrast", min_contrast, ">= 0");
  Require(road_tolerance > 0 && road_tolerance < 1, "road_tolerance", road_tolerance, "0 < t < 1");
}

PlaneSweeper::PlaneSweeper(const CameraModel& model, const Pose& vehicle_from_camera, const cv::Mat& valid,
                           const cv::Mat& region, const PlaneSweepOptions& options)
    : model_(model), vehicle_from_camera_(vehicle_from_camera), valid_(valid), options_(options) {
  options_.Check();
  const cv::Size size(model.width(), model.height());
  for (const cv::Mat* m : {&valid, &region}) {
    if (!m->empty() && (m->type() != CV_8U || m->size() != size)) {
      throw Error("plane sweep: the valid-pixel and region masks must be CV_8U of the camera's size");
    }
  }
  const cv::Rect whole(0, 0, size.width, size.height);
  const int half = options_.window_px / 2;
  roi_ = region.empty() ? whole : cv::boundingRect(region);
  roi_ = cv::Rect(roi_.x - half, roi_.y - half, roi_.width + 2 * half, roi_.height + 2 * half) & whole;
  dirs_.create(roi_.size(), CV_32FC3);
  road_m_.create(roi_.size(), CV_32F);
  measured_.create(roi_.size(), CV_8U);
  const Eigen::Vector3d& o = vehicle_from_camera.t;
  cv::parallel_for_(cv::Range(0, roi_.height), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      for (int u = 0; u < roi_.width; ++u) {
        const int x = u + roi_.x, y = v + roi_.y;
        Eigen::Vector3d ray;
        cv::Vec3f& dir = dirs_.at<cv::Vec3f>(v, u);
        float& road = road_m_.at<float>(v, u);
        const bool sees = (valid.empty() || valid.at<std::uint8_t>(y, x)) && model.Unproject({x, y}, &ray);
        measured_.at<std::uint8_t>(v, u) = sees && (region.empty() || region.at<std::uint8_t>(y, x)) ? 255 : 0;
        if (!sees) {
          dir = cv::Vec3f(kNaN, kNaN, kNaN);
          road = kNaN;
          continue;
        }
        const Eigen::Vector3d d = vehicle_from_camera.R * ray;
        dir = cv::Vec3f(static_cast<float>(d.x()), static_cast<float>(d.y()), static_cast<float>(d.z()));
        road = d.y() > 1e-6 && o.y() < 0 ? static_cast<float>(-o.y() / d.y()) : std::numeric_limits<float>::infinity();
      }
    }
  });
}

SweepResult PlaneSweeper::Sweep(const cv::Mat& previous, const cv::Mat& current, const Pose& previous_from_current) const {
  return Sweep(std::vector<EarlierFrame>{{previous, previous_from_current}}, current);
}

SweepResult PlaneSweeper::Sweep(const std::vector<EarlierFrame>& earlier, const cv::Mat& current) const {
  const cv::Size size(model_.width(), model_.height());
  if (earlier.empty()) throw Error("plane sweep: no earlier frame");
  for (const cv::Mat* m : {&earlier.front().image, &current}) {
    if (m->type() != CV_8U || m->size() != size) throw Error("plane sweep: images must be grey and the camera's size");
  }
  const PlaneSweepOptions& o = options_;
  const Rays rays{dirs_, road_m_};
  const Reference ref = MakeReference(current(roi_), rays, o.window_px);
  std::vector<double> distances;
  const double inv_near = 1 / o.min_distance_m, inv_far = 1 / o.max_distance_m;
  for (int k = 0; k < o.distances; ++k) distances.push_back(1 / (inv_near + (inv_far - inv_near) * k / (o.distances - 1)));
  // The longest baseline first: its warps are the ones kept.
  std::vector<const EarlierFrame*> frames;
  for (const EarlierFrame& e : earlier) {
    if (e.image.type() != CV_8U || e.image.size() != size) throw Error("plane sweep: images must be grey and the camera's size");
    frames.push_back(&e);
  }
  const Eigen::Vector3d& c = vehicle_from_camera_.t;
  std::stable_sort(frames.begin(), frames.end(), [&](const EarlierFrame* a, const EarlierFrame* b) {
    return (a->previous_from_current.Apply(c) - c).norm() > (b->previous_from_current.Apply(c) - c).norm();
  });
  std::vector<cv::Mat> maps(distances.size() + 1), scores(distances.size() + 1);
  for (const EarlierFrame* e : frames) {
    cv::Mat image;
    e->image.convertTo(image, CV_32F);
    for (size_t k = 0; k <= distances.size(); ++k) {
      const double d = k < distances.size() ? distances[k] : -1.0;  // the last: the road
      cv::Mat map = WarpMap(model_, vehicle_from_camera_, e->previous_from_current, rays, valid_, d);
      const cv::Mat score = Zncc(ref, image, map, o.window_px);
      if (scores[k].empty()) {
        maps[k] = map;
        scores[k] = score;
      } else {
        scores[k] += score;  // NaN where either is
      }
    }
  }
  for (cv::Mat& s : scores) s *= 1.0 / static_cast<double>(frames.size());
  SweepResult box;
  box.distance_m = cv::Mat(roi_.size(), CV_32F, cv::Scalar(kNaN));
  box.label = cv::Mat(roi_.size(), CV_8U, cv::Scalar(kSweepNoRay));
  box.score = cv::Mat(roi_.size(), CV_32F, cv::Scalar(kNaN));
  const cv::Mat parallax = Parallax(model_, vehicle_from_camera_, frames.front()->previous_from_current, rays, o);
  const PixelChoice choice{measured_, scores, maps, distances, parallax, o};
  cv::parallel_for_(cv::Range(0, roi_.height), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      for (int u = 0; u < roi_.width; ++u) Choose(choice, rays, ref, u, v, &box);
    }
  });
  SweepResult out;
  out.distance_m = cv::Mat(size, CV_32F, cv::Scalar(kNaN));
  out.label = cv::Mat(size, CV_8U, cv::Scalar(kSweepNoRay));
  out.score = cv::Mat(size, CV_32F, cv::Scalar(kNaN));
  box.distance_m.copyTo(out.distance_m(roi_));
  box.label.copyTo(out.label(roi_));
  box.score.copyTo(out.score(roi_));
  return out;
}

SweepResult PlaneSweep(const CameraModel& model, const Pose& vehicle_from_camera, const cv::Mat& previous,
                       const cv::Mat& current, const Pose& previous_from_current, const cv::Mat& valid,
                       const PlaneSweepOptions& options) {
  return PlaneSweeper(model, vehicle_from_camera, valid, cv::Mat(), options).Sweep(previous, current, previous_from_current);
}

cv::Mat SweepPicture(const cv::Mat& image, const SweepResult& sweep, double min_distance_m, double max_distance_m) {
  if (image.type() != CV_8U || image.size() != sweep.label.size() || sweep.distance_m.size() != image.size()) {
    throw Error("SweepPicture: a grey image and a sweep of its size expected");
  }
  if (!(min_distance_m > 0 && max_distance_m > min_distance_m)) {
    throw Error(Str("SweepPicture: distances ", min_distance_m, "..", max_distance_m, " m: expected 0 < min < max"));
  }
  // Turbo colours: index 0 (blue) far, 255 (red) near, even in inverse distance.
  cv::Mat ramp(1, 256, CV_8U), turbo;
  for (int i = 0; i < 256; ++i) ramp.at<std::uint8_t>(0, i) = static_cast<std::uint8_t>(i);
  cv::applyColorMap(ramp, turbo, cv::COLORMAP_TURBO);
  const double near_inv = 1.0 / min_distance_m, far_inv = 1.0 / max_distance_m;
  cv::Mat out(image.size(), CV_8UC3);
  for (int y = 0; y < image.rows; ++y) {
    const std::uint8_t* g = image.ptr<std::uint8_t>(y);
    const std::uint8_t* l = sweep.label.ptr<std::uint8_t>(y);
    const float* d = sweep.distance_m.ptr<float>(y);
    cv::Vec3b* o = out.ptr<cv::Vec3b>(y);
    for (int x = 0; x < image.cols; ++x) {
      const std::uint8_t v = g[x];
      switch (l[x]) {
        case kSweepObstacle: {
          const double f = std::isfinite(d[x]) ? (1.0 / d[x] - far_inv) / (near_inv - far_inv) : 0.0;
          o[x] = turbo.at<cv::Vec3b>(0, std::clamp(static_cast<int>(std::lround(255 * f)), 0, 255));
          break;
        }
        case kSweepRoad: o[x] = cv::Vec3b(static_cast<std::uint8_t>(v / 2), static_cast<std::uint8_t>(v / 2 + 100),
                                          static_cast<std::uint8_t>(v / 2)); break;
        case kSweepUnobservable: o[x] = cv::Vec3b(static_cast<std::uint8_t>(v / 2 + 90), static_cast<std::uint8_t>(v / 2),
                                                  static_cast<std::uint8_t>(v / 2 + 90)); break;
        case kSweepAmbiguous: o[x] = cv::Vec3b(v, v, v); break;
        default: o[x] = cv::Vec3b(0, 0, 0);
      }
    }
  }
  // Legend: the colour ramp with its distances, and the labels' tints.
  const double scale = std::max(0.35, image.cols / 1600.0);
  const int line = static_cast<int>(std::lround(28 * scale / 0.5)), bar = std::max(64, image.cols / 4);
  const cv::Rect box(0, 0, bar + 2 * line, 5 * line);
  out(box & cv::Rect(0, 0, out.cols, out.rows)).setTo(cv::Scalar(30, 30, 30));
  for (int i = 0; i < bar && line + i < out.cols; ++i) {
    const cv::Vec3b c = turbo.at<cv::Vec3b>(0, 255 - 255 * i / std::max(1, bar - 1));
    cv::line(out, {line / 2 + i, line / 3}, {line / 2 + i, line}, cv::Scalar(c[0], c[1], c[2]));
  }
  const auto text = [&](const std::string& s, int row, const cv::Scalar& colour) {
    cv::putText(out, s, {line / 2, line * (row + 1) + line / 2}, cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv::LINE_AA);
  };
  text(Str("obstacle ", min_distance_m, " m .. ", max_distance_m, " m"), 1, cv::Scalar(255, 255, 255));
  text("road (free)", 2, cv::Scalar(60, 200, 60));
  text("unobservable (epipole)", 3, cv::Scalar(220, 90, 220));
  return out;
}

}  // namespace dps
