#include "dps/detect/detection.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <utility>

#include <opencv2/imgproc.hpp>

namespace dps {

Detection DetectionFromPoints(const std::vector<Eigen::Vector2d>& points, const std::string& source) {
  Detection d;
  d.source = source;
  d.points = points;
  d.n_points = static_cast<int>(points.size());
  d.x_min_m = d.z_min_m = std::numeric_limits<double>::infinity();
  d.x_max_m = d.z_max_m = -std::numeric_limits<double>::infinity();
  d.range_m = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector2d& p : points) {
    d.x_min_m = std::min(d.x_min_m, p.x());
    d.x_max_m = std::max(d.x_max_m, p.x());
    d.z_min_m = std::min(d.z_min_m, p.y());
    d.z_max_m = std::max(d.z_max_m, p.y());
    const double r = p.norm();
    if (r < d.range_m) {
      d.range_m = r;
      d.x_m = p.x();
      d.z_m = p.y();
    }
  }
  return d;
}

namespace {

std::vector<Eigen::Vector2d> PointsOf(const Detection& d) {
  return d.points.empty() ? std::vector<Eigen::Vector2d>{{d.x_m, d.z_m}} : d.points;
}

// One detection from two parts of the same frame: all points; the source of the part holding the
// nearest point.
Detection Merged(const Detection& a, const Detection& b) {
  std::vector<Eigen::Vector2d> points = PointsOf(a);
  const std::vector<Eigen::Vector2d> extra = PointsOf(b);
  points.insert(points.end(), extra.begin(), extra.end());
  Detection m = DetectionFromPoints(points, b.range_m < a.range_m ? b.source : a.source);
  m.frame = a.frame;
  m.t_s = a.t_s;
  m.clipped_ends = a.clipped_ends;
  m.clipped_ends.insert(m.clipped_ends.end(), b.clipped_ends.begin(), b.clipped_ends.end());
  // The higher top of the two (either may have seen only part of the object).
  m.height_m = std::isnan(a.height_m) ? b.height_m : std::isnan(b.height_m) ? a.height_m : std::max(a.height_m, b.height_m);
  // The motion measurement of the part with more points (only motion stereo has one).
  const Detection* motion = a.has_motion && (!b.has_motion || a.n_points >= b.n_points) ? &a : b.has_motion ? &b : nullptr;
  if (motion) {
    m.has_motion = true;
    m.motion_direction = motion->motion_direction;
    m.motion_mps = motion->motion_mps;
    m.motion_sigma_mps = motion->motion_sigma_mps;
  }
  return m;
}

// Ids numbered per frame and source.
void Renumber(std::vector<Detection>* d) {
  std::map<std::pair<int, std::string>, int> next_id;
  for (Detection& e : *d) e.id = next_id[{e.frame, e.source}]++;
}

}  // namespace

bool Near(const Detection& a, const Detection& b, double distance_m) {
  for (const Eigen::Vector2d& p : PointsOf(a)) {
    for (const Eigen::Vector2d& q : PointsOf(b)) {
      if ((p - q).norm() <= distance_m) return true;
    }
  }
  return false;
}

std::vector<Detection> FuseDetections(const std::vector<Detection>& in, double merge_distance_m) {
  const size_t n = in.size();
  std::vector<size_t> parent(n);
  for (size_t i = 0; i < n; ++i) parent[i] = i;
  std::function<size_t(size_t)> root = [&](size_t i) { return parent[i] == i ? i : parent[i] = root(parent[i]); };
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      if (in[i].frame == in[j].frame && Near(in[i], in[j], merge_distance_m)) parent[root(i)] = root(j);
    }
  }
  std::vector<Detection> out;
  std::vector<int> slot(n, -1);
  for (size_t i = 0; i < n; ++i) {
    const size_t r = root(i);
    if (slot[r] < 0) {
      slot[r] = static_cast<int>(out.size());
      out.push_back(in[i]);
      out.back().points = PointsOf(in[i]);
      continue;
    }
    out[slot[r]] = Merged(out[slot[r]], in[i]);
  }
  Renumber(&out);
  return out;
}

namespace {

// What one source saw, as (bearing from its viewpoint, range) of its points, sorted by bearing.
struct Sightings {
  Eigen::Vector2d viewpoint;
  std::vector<std::pair<double, double>> seen;
};

// Whether a source saw through the stretch between two parts: along the segment joining their
// closest points, at least three of five samples have a point of the source behind them on the
// same bearing (within 0.01 rad, farther by more than 0.5 m) — the stretch is free space, not an
// unseen part of one surface. Bearings are atan2(x, z) without wrapping (no view looks straight
// back).
bool SeenBetween(const Detection& a, const Detection& b, const Sightings& source) {
  Eigen::Vector2d pa = a.points.front(), pb = b.points.front();
  for (const Eigen::Vector2d& p : a.points) {
    for (const Eigen::Vector2d& q : b.points) {
      if ((p - q).squaredNorm() < (pa - pb).squaredNorm()) pa = p, pb = q;
    }
  }
  int seen = 0;
  for (int k = 1; k <= 5; ++k) {
    const Eigen::Vector2d s = pa + (pb - pa) * (k / 6.0) - source.viewpoint;
    const double bearing = std::atan2(s.x(), s.y()), range = s.norm();
    auto it = std::lower_bound(source.seen.begin(), source.seen.end(), std::make_pair(bearing - 0.01, 0.0));
    for (; it != source.seen.end() && it->first <= bearing + 0.01; ++it) {
      if (it->second > range + 0.5) {
        ++seen;
        break;
      }
    }
  }
  return seen >= 3;
}

}  // namespace

std::vector<Detection> MergeVehicleParts(std::vector<Detection> d, double max_length_m, double max_width_m,
                                         bool across_sources_only,
                                         const std::map<std::string, Eigen::Vector2d>& viewpoints,
                                         const std::map<std::string, double>& depth_error_per_m2) {
  for (Detection& e : d) e.points = PointsOf(e);
  // A part's depth error at its farthest point from its source (0 without the source's k).
  const auto slack = [&](const Detection& e) {
    const auto k = depth_error_per_m2.find(e.source);
    const auto v = viewpoints.find(e.source);
    if (k == depth_error_per_m2.end() || v == viewpoints.end()) return 0.0;
    double far2 = 0.0;
    for (const Eigen::Vector2d& p : e.points) far2 = std::max(far2, (p - v->second).squaredNorm());
    return k->second * far2;
  };
  // Merged parts' slack: the larger of theirs (the union's ends are theirs).
  std::vector<double> slacks;
  for (const Detection& e : d) slacks.push_back(slack(e));
  // Each source's sightings, once: merging only regroups the points.
  std::map<std::string, Sightings> sightings;
  for (const auto& [source, viewpoint] : viewpoints) {
    Sightings& v = sightings[source];
    v.viewpoint = viewpoint;
    for (const Detection& e : d) {
      if (e.source != source) continue;
      for (const Eigen::Vector2d& p : e.points) {
        const Eigen::Vector2d r = p - viewpoint;
        v.seen.emplace_back(std::atan2(r.x(), r.y()), r.norm());
      }
    }
    std::sort(v.seen.begin(), v.seen.end());
  }
  for (;;) {
    size_t bi = 0, bj = 0;
    // Parts of different sources first (each source has kept its own parts apart), then the
    // smallest union: (same source, length), lowest first.
    std::pair<bool, double> best{true, std::numeric_limits<double>::infinity()};
    for (size_t i = 0; i < d.size(); ++i) {
      for (size_t j = i + 1; j < d.size(); ++j) {
        if (d[i].frame != d[j].frame || (across_sources_only && d[i].source == d[j].source)) continue;
        std::vector<cv::Point2f> points;
        for (const Detection* e : {&d[i], &d[j]}) {
          for (const Eigen::Vector2d& p : e->points) points.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()));
        }
        const cv::RotatedRect box = cv::minAreaRect(points);
        const double length = std::max(box.size.width, box.size.height), width = std::min(box.size.width, box.size.height);
        const std::pair<bool, double> key{d[i].source == d[j].source, length};
        if (length > max_length_m + slacks[i] + slacks[j] || width > max_width_m || !(key < best)) continue;
        const auto source = sightings.find(d[i].source);
        if (d[i].source == d[j].source && source != sightings.end() && SeenBetween(d[i], d[j], source->second)) continue;
        best = key;
        bi = i;
        bj = j;
      }
    }
    if (!std::isfinite(best.second)) break;
    d[bi] = Merged(d[bi], d[bj]);
    slacks[bi] = std::max(slacks[bi], slacks[bj]);
    d.erase(d.begin() + static_cast<std::ptrdiff_t>(bj));
    slacks.erase(slacks.begin() + static_cast<std::ptrdiff_t>(bj));
  }
  Renumber(&d);
  return d;
}

std::vector<Detection> DropHidden(std::vector<Detection> detections, const std::string& source,
                                  const Eigen::Vector2d& eye, double eye_height_m, double depth_error_per_m2) {
  // Each detection's bearings from eye (atan2(x, z), no view looks straight back) and ranges.
  struct Seen {
    bool counts = false;
    double first = std::numeric_limits<double>::infinity(), last = -first, near = first, far = 0.0;
  };
  std::vector<Seen> seen(detections.size());
  for (size_t i = 0; i < detections.size(); ++i) {
    const Detection& d = detections[i];
    Seen& s = seen[i];
    s.counts = d.source == source && std::isfinite(d.height_m);
    for (const Eigen::Vector2d& p : PointsOf(d)) {
      const Eigen::Vector2d v = p - eye;
      const double bearing = std::atan2(v.x(), v.y()), range = v.norm();
      s.first = std::min(s.first, bearing);
      s.last = std::max(s.last, bearing);
      s.near = std::min(s.near, range);
      s.far = std::max(s.far, range);
    }
  }
  const auto hides = [&](size_t front, size_t behind) {
    const Seen &a = seen[front], &b = seen[behind];
    if (!(a.first <= b.first && b.last <= a.last)) return false;
    if (b.near - a.far <= depth_error_per_m2 * (a.far * a.far + b.near * b.near)) return false;
    // The sight line over a's top, at b's nearest point.
    const double sight = eye_height_m + (detections[front].height_m - eye_height_m) * b.near / a.far;
    return detections[behind].height_m < sight;
  };
  std::vector<char> hidden(detections.size(), 0);
  for (size_t i = 0; i < detections.size(); ++i) {
    for (size_t j = 0; j < detections.size() && seen[i].counts && !hidden[i]; ++j) {
      hidden[i] = j != i && seen[j].counts && hides(j, i);
    }
  }
  std::vector<Detection> kept;
  for (size_t i = 0; i < detections.size(); ++i) {
    if (!hidden[i]) kept.push_back(std::move(detections[i]));
  }
  return kept;
}

}  // namespace dps
