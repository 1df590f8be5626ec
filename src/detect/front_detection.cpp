#include "dps/detect/front_detection.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "dps/detect/ground_projection.h"
#include "dps/util/error.h"
#include "dps/util/image.h"
#include "dps/util/math.h"

namespace dps {
namespace {

// The columns an angle of a view spans at its centre (focal_px x angle).
int ViewColumns(double degrees, double focal_px) {
  return static_cast<int>(std::lround(focal_px * degrees * kRadPerDeg));
}

}  // namespace

void FrontDetectorOptions::Check() const {
  const OptionCheck Require("front detector");
  Require(view_width > 0 && view_width <= 8192, "view_width", view_width, "1..8192 px");
  Require(view_height > 0 && view_height <= 8192, "view_height", view_height, "1..8192 px");
  Require(focal_px > 0 && focal_px <= 100.0 * view_width, "focal_px", focal_px, "> 0 and at most 100 view widths");
  Require(link_max_gap_deg >= 0 && link_max_gap_deg <= 180, "link_max_gap_deg", link_max_gap_deg, "0..180 degrees");
  Require(link_max_gap_m >= 0, "link_max_gap_m", link_max_gap_m, ">= 0");
  Require(link_max_top_difference_m >= 0, "link_max_top_difference_m", link_max_top_difference_m, ">= 0");
  Require(link_free_gap_m >= 0, "link_free_gap_m", link_free_gap_m, ">= 0");
  Require(link_vehicle_length_m >= 0, "link_vehicle_length_m", link_vehicle_length_m, ">= 0 (0 = no test)");
  Require(reference_overlap_m >= 0, "reference_overlap_m", reference_overlap_m, ">= 0");
  Require(max_range_m > 0, "max_range_m", max_range_m, "> 0");
  Require(own_car_height_m >= 0, "own_car_height_m", own_car_height_m, ">= 0");
  Require(min_obstacle_height_m >= 0, "min_obstacle_height_m", min_obstacle_height_m, ">= 0");
  Require(tall_min_width_deg >= 0 && tall_min_width_deg <= 180, "tall_min_width_deg", tall_min_width_deg, "0..180 degrees");
  Require(tall_min_top_m >= 0, "tall_min_top_m", tall_min_top_m, ">= 0");
  Require(drift_interval >= 0, "drift_interval", drift_interval, ">= 0 (0 = never)");
  Require(drift_min_px >= 0, "drift_min_px", drift_min_px, ">= 0");
  Require(drift_min_features >= 1, "drift_min_features", drift_min_features, ">= 1");
  Require(temporal_max_variance_px2 >= 0, "temporal_max_variance_px2", temporal_max_variance_px2, ">= 0 (0 = off)");
  Require(temporal_forgetting > 0 && temporal_forgetting <= 1, "temporal_forgetting", temporal_forgetting, "0 < f <= 1");
  Require(range_edge_px >= 0, "range_edge_px", range_edge_px, ">= 0");
  stereo.Check();
}

FrontDetector::FrontDetector(const Rig& rig, const FrontDetectorOptions& options) : options_(options), rig_(rig) {
  options.Check();
  options_.histogram.min_disparity = options.stereo.min_disparity;
  options_.histogram.max_disparity = options.stereo.min_disparity + options.stereo.num_disparities;
  options_.histogram.two_sided = false;
  options_.histogram.link_max_gap = ViewColumns(options.link_max_gap_deg, options.focal_px);
  tall_min_columns_ = ViewColumns(options.tall_min_width_deg, options.focal_px);
  options_.histogram.Check();
  spec_ = FrontViewSpec(rig, "left", "right", options.view_width, options.view_height, options.focal_px);
  left_ = std::make_unique<VirtualView>(rig.Camera("left"), spec_);
  right_ = std::make_unique<VirtualView>(rig.Camera("right"), spec_);
  const Eigen::Vector3d l = rig.Camera("left").vehicle_from_camera.t, r = rig.Camera("right").vehicle_from_camera.t;
  baseline_m_ = (r - l).norm();
  left_camera_ = Eigen::Vector2d(l.x(), l.z());
  across_ = Eigen::Vector2d(r.x() - l.x(), r.z() - l.z()).normalized();
  // The columns each reference matches (in matching coordinates: the right view mirrored).
  // What reaches beyond the left camera lies right of the left view's centre: the left view
  // matches from an eighth of the view before its centre, which keeps the parts of wide objects
  // that stretch farther. What lies wholly beyond it lies left of the right view's centre, by
  // f B / 60 m (6 px at 640x480) or more: the right view matches up to 16 columns past its centre.
  const int w = spec_.width;
  by_left_.first = std::max(0, w / 2 - w / 8);
  by_right_.first = std::max(0, w / 2 - 16);
  by_left_.view = left_.get();
  by_right_.view = right_.get();
  by_right_.mirrored = true;
  PrepareReferences();
  for (Reference* ref : {&by_left_, &by_right_}) {
    ref->matcher = std::make_unique<SadStereoMatcher>(options.stereo);
    if (options.temporal_max_variance_px2 > 0) {
      ref->temporal = std::make_unique<TemporalConsistencyFilter>(options.temporal_forgetting,
                                                                   options.temporal_max_variance_px2);
    }
  }
}

FrontDetector::~FrontDetector() = default;

void FrontDetector::PrepareReferences() {
  cv::Mat own = OwnCarMask(*left_, rig_.vehicle, options_.own_car_height_m);
  cv::bitwise_or(own, OwnCarMask(*right_, rig_.vehicle, options_.own_car_height_m), own);
  for (Reference* ref : {&by_left_, &by_right_}) Prepare(own, ref);
}

void FrontDetector::Prepare(const cv::Mat& own_car, Reference* ref) const {
  const VirtualView& view = *ref->view;
  cv::bitwise_or(own_car, view.mask() == 0, ref->ignore);
  // The reference camera's own car as estimated from the drive (its pixels only: the other view's
  // pixels at the same coordinates see other things).
  if (!view.own_car().empty()) ref->ignore |= view.own_car();
  ref->road = RoadDisparity(view, baseline_m_);
  ref->ramp = RoadRamp(ref->road, options_.stereo.block_height / 2 + 1);
}

bool FrontDetector::ColumnToGround(double x, double disparity, Eigen::Vector2d* ground) const {
  return ColumnToGround(*left_, x, disparity, ground);
}

bool FrontDetector::ColumnToGround(const VirtualView& view, double x, double disparity, Eigen::Vector2d* ground) const {
  return dps::ColumnToGround(view, x, disparity, baseline_m_, ground);
}

bool FrontDetector::OuterPoint(const VirtualView& view, const HistogramComponent& c, bool last,
                               Eigen::Vector2d* ground) const {
  const int n = static_cast<int>(c.column_disparity.size());
  for (int i = 0; i < n; ++i) {
    const int at = last ? n - 1 - i : i;
    if (std::isfinite(c.column_disparity[at])) return ColumnToGround(view, c.x_begin + at, c.column_disparity[at], ground);
  }
  return false;
}

bool FrontDetector::InComponent(const FrontMatch& m, const cv::Mat& labels, int label, int x, int y) const {
  const float v = m.disparity.at<float>(y, x);
  if (!std::isfinite(v) || m.score.at<float>(y, x) <= 0) return false;
  const int bin = static_cast<int>(std::floor((v - options_.histogram.min_disparity) / options_.histogram.bin_px));
  return bin >= 0 && bin < labels.rows && labels.at<int>(bin, x) == label;
}

double FrontDetector::TopHeight(const VirtualView& view, const FrontMatch& m, const cv::Mat& labels,
                                const HistogramComponent& c, int below_rows) const {
  const ViewSpec& s = view.spec();
  const Eigen::Vector3d& t = view.viewpoint_vehicle();
  std::vector<double> tops;
  for (int x = c.x_begin; x < c.x_end; ++x) {
    for (int y = 0; y < m.disparity.rows; ++y) {
      if (!InComponent(m, labels, c.label, x, y)) continue;
      // The highest pixel of the column in the component (its score > 0 puts its disparity
      // above the road's, so > 0): its point's height above the road.
      const float v = m.disparity.at<float>(y, x);
      const double depth = s.focal_px * baseline_m_ / v;
      const Eigen::Vector3d p((x - s.cx) * depth / s.focal_px, (y + below_rows - s.cy) * depth / s.focal_px, depth);
      tops.push_back(-(t + s.vehicle_from_view * p).y());
      break;
    }
  }
  if (tops.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t k = tops.size() / 4;  // three quarters of the columns reach at least this high
  std::nth_element(tops.begin(), tops.begin() + k, tops.end(), std::greater<double>());
  return tops[k];
}

FrontResult FrontDetector::Detect(const cv::Mat& left_omni, const cv::Mat& right_omni) {
  FrontResult r;
  RenderViews(left_omni, right_omni, &r);
  MatchReference(FrontReference::kLeftView, &r);
  MatchReference(FrontReference::kRightView, &r);
  CombineReferences(&r);
  return r;
}

void FrontDetector::RenderViews(const cv::Mat& left_omni, const cv::Mat& right_omni, FrontResult* out) {
  FrontResult& r = *out;
  // Each view rendered and prefiltered for matching at once (the pipeline calls this before its
  // concurrent tasks; OpenCV runs the filters inside serially then).
  const SadStereoMatcher& matcher = *by_left_.matcher;  // Prepare is const: safe from both
  cv::parallel_for_(cv::Range(0, 2), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      cv::Mat& view = i == 0 ? r.left_view : r.right_view;
      (i == 0 ? *left_ : *right_).Render(GreyImage(i == 0 ? left_omni : right_omni), view);
      matcher.Prepare(view, i == 0 ? &left_prepared_ : &right_prepared_, (i == 0 ? left_ : right_)->mask());
    }
  });
  // Drift: measure the rows' misalignment now and then, and rebuild the right view to cancel it.
  if (options_.drift_interval > 0 && frames_ % options_.drift_interval == 0) {
    const VerticalOffset off = EstimateVerticalOffset(r.left_view, r.right_view, options_.stereo.min_disparity,
                                                      options_.stereo.num_disparities);
    r.drift_measured = true;
    if (off.features >= options_.drift_min_features && std::abs(off.offset_px) > options_.drift_min_px) {
      vertical_offset_px_ += off.offset_px;
      ViewSpec shifted = spec_;
      shifted.cy -= vertical_offset_px_;
      right_ = std::make_unique<VirtualView>(rig_.Camera("right"), shifted);
      by_right_.view = right_.get();
      PrepareReferences();
      right_->Render(GreyImage(right_omni), r.right_view);
      matcher.Prepare(r.right_view, &right_prepared_, right_->mask());
    }
  }
  r.vertical_offset_px = vertical_offset_px_;
  ++frames_;
}

void FrontDetector::MatchReference(FrontReference reference, FrontResult* r, const cv::Mat& claimed) {
  const bool left = reference == FrontReference::kLeftView;
  DetectWith(left ? by_left_ : by_right_, claimed, left ? &r->by_left : &r->by_right);
}

void FrontDetector::CombineReferences(FrontResult* r) const {
  r->detections = by_left_.found;
  // A component wholly beyond the left camera may be a part of an object reaching past it that the
  // left view saw whole (its back fell apart in the right view): it joins that object.
  for (const Detection& d : by_right_.found) {
    bool joined = false;
    for (Detection& e : r->detections) {
      const std::vector<Detection> fused = FuseDetections({e, d}, options_.reference_overlap_m);
      if (fused.size() == 1) {
        e = fused.front();
        joined = true;
        break;
      }
    }
    if (!joined) r->detections.push_back(d);
  }
  // What the left view saw wholly beyond the left camera, where the right view found nothing
  // (an object near that line whose parts the matching noise put on either side).
  for (const Detection& e : by_left_.beyond) {
    const bool covered = std::any_of(by_right_.found.begin(), by_right_.found.end(), [&](const Detection& d) {
      return FuseDetections({e, d}, options_.reference_overlap_m).size() == 1;
    });
    if (!covered) r->detections.push_back(e);
  }
  for (size_t i = 0; i < r->detections.size(); ++i) r->detections[i].id = static_cast<int>(i);
}

cv::Mat FrontDetector::MatchReference(Reference& ref, const cv::Mat& claimed) {
  // The reference's columns that can show its objects, from ref.first on (the right view's
  // mirrored), against the whole other view.
  const SadStereoMatcher::PreparedView* reference = &left_prepared_;
  const SadStereoMatcher::PreparedView* other = &right_prepared_;
  if (ref.mirrored) {
    // Into the reference's own copies: the prepared views are shared with the other task.
    SadStereoMatcher::Mirror(right_prepared_, &ref.mirrored_reference);
    SadStereoMatcher::Mirror(left_prepared_, &ref.mirrored_other);
    reference = &ref.mirrored_reference;
    other = &ref.mirrored_other;
  }
  // Matched from 16 columns earlier, which are then dropped: the left-right check of the first
  // columns then weighs the matches of the columns before them too, as when the whole view is
  // matched.
  const int first = ref.first;
  cv::Mat disparity = ref.matcher->Compute(*reference, *other, std::max(0, first - 16));
  disparity.colRange(0, first).setTo(kInvalidDisparity);
  if (ref.mirrored) cv::flip(disparity, disparity, 1);
  disparity.setTo(kInvalidDisparity, ref.ignore);
  if (!claimed.empty()) disparity.setTo(kInvalidDisparity, claimed);
  if (options_.range_edge_px > 0) {
    const double lo = options_.stereo.min_disparity + options_.range_edge_px;
    const double hi = options_.stereo.min_disparity + options_.stereo.num_disparities - 1 - options_.range_edge_px;
    disparity.setTo(kInvalidDisparity, (disparity < lo) | (disparity > hi));
  }
  if (ref.temporal) disparity = ref.temporal->Apply(disparity);
  return disparity;
}

// Parts of one surface are linked when the gap between them on the ground is short, a wider gap
// only within one vehicle's length, and when their tops are level (a pole beyond the end of a
// car's side is twice as tall).
bool FrontDetector::Linked(const VirtualView& view, const FrontMatch& m, const cv::Mat& labels,
                           const HistogramComponent& a, int x0, float d0, const HistogramComponent& b, int x1,
                           float d1) const {
  Eigen::Vector2d ga, gb;
  if (!ColumnToGround(view, x0, d0, &ga) || !ColumnToGround(view, x1, d1, &gb) ||
      (ga - gb).norm() > options_.link_max_gap_m) {
    return false;
  }
  // Parts apart on the ground are one object only if together they fit one vehicle's length.
  Eigen::Vector2d first_point, last_point;
  if (options_.link_vehicle_length_m > 0 && (ga - gb).norm() > options_.link_free_gap_m &&
      OuterPoint(view, a, false, &first_point) && OuterPoint(view, b, true, &last_point) &&
      (first_point - last_point).norm() > options_.link_vehicle_length_m) {
    return false;
  }
  return !(options_.link_max_top_difference_m > 0 &&
           std::abs(TopHeight(view, m, labels, a) - TopHeight(view, m, labels, b)) > options_.link_max_top_difference_m);
}

// Per column of a component with a centroid, its rows times B / d: an obstacle fills rows ~ height
// x d / B with its disparity, so this is its height there.
std::vector<double> FrontDetector::ColumnHeights(const FrontMatch& m, const cv::Mat& labels,
                                                 const HistogramComponent& c) const {
  std::vector<double> heights;
  for (int x = c.x_begin; x < c.x_end; ++x) {
    const float d = c.column_disparity[x - c.x_begin];
    if (!std::isfinite(d) || d <= 0) continue;
    int rows = 0;
    for (int y = 0; y < m.disparity.rows; ++y) rows += InComponent(m, labels, c.label, x, y);
    heights.push_back(rows * baseline_m_ / d);
  }
  return heights;
}

// An obstacle stands up from the road: in each column it fills many rows with its disparity.
// Flat things (lane markings, road matched wrongly) and stray matches fill few. The component's
// height is the median of its columns'.
bool FrontDetector::StandsUp(const VirtualView& view, const FrontMatch& m, const cv::Mat& labels,
                             const HistogramComponent& c) const {
  std::vector<double> heights = ColumnHeights(m, labels, c);
  if (heights.empty()) return false;
  std::nth_element(heights.begin(), heights.begin() + heights.size() / 2, heights.end());
  return heights[heights.size() / 2] >= options_.min_obstacle_height_m ||
         (c.x_end - c.x_begin >= tall_min_columns_ && TopHeight(view, m, labels, c) >= options_.tall_min_top_m);
}

void FrontDetector::Keep(const VirtualView& view, const HistogramComponent& c, std::pair<int, int> valid_columns,
                         Reference& ref, FrontMatch* m, const cv::Mat& labels) const {
  // The outermost half window of columns is foreground fattening, not the object.
  const auto [from, to] = ProjectedColumns(c, options_.stereo.block_width / 2);
  std::vector<Eigen::Vector2d> points;
  std::vector<std::pair<int, float>> columns;
  // The farthest point towards the right camera, along the baseline from the left camera.
  double reach = -std::numeric_limits<double>::infinity();
  for (int x = from; x <= to; ++x) {
    const float d = c.column_disparity[x - c.x_begin];
    Eigen::Vector2d g;
    if (!std::isfinite(d) || !ColumnToGround(view, x, d, &g) || g.norm() > options_.max_range_m) continue;
    points.push_back(g);
    columns.emplace_back(x, d);
    reach = std::max(reach, (g - left_camera_).dot(across_));
  }
  // The right view keeps what lies wholly beyond the left camera, the left view the rest (and
  // what it sees beyond, in case the right view finds nothing there).
  if (points.empty()) return;
  const bool beyond = reach < 0;
  if (ref.mirrored && !beyond) return;
  // The object's top above the road (object_attributes.h classes by it), less the half window the
  // matcher carries the object's disparity above its top edge. An obstacle's top stands
  // min_obstacle_height_m above the road as the side views require (a kerb or a raised pavement
  // beside the road, matched at its own disparity with the windows' fattening, does not).
  const double top = TopHeight(view, *m, labels, c, options_.stereo.block_height / 2);
  if (top < options_.min_obstacle_height_m) return;
  for (const auto& [x, d] : columns) {
    const int row = static_cast<int>((d - options_.histogram.min_disparity) / options_.histogram.bin_px);
    if (row >= 0 && row < m->obstacle.rows) m->obstacle.at<float>(row, x) = d;
  }
  Detection det = DetectionFromPoints(points, "front");
  det.height_m = std::isfinite(top) ? std::max(0.0, top) : top;
  const int margin = options_.stereo.block_width;
  if (c.x_begin <= valid_columns.first + margin) det.clipped_ends.push_back(points.front());
  if (c.x_end - 1 >= valid_columns.second - margin) det.clipped_ends.push_back(points.back());
  std::vector<Detection>& into = beyond && !ref.mirrored ? ref.beyond : ref.found;
  det.id = static_cast<int>(into.size());
  into.push_back(std::move(det));
}

void FrontDetector::DetectWith(Reference& ref, const cv::Mat& claimed, FrontMatch* m) {
  const VirtualView& view = *ref.view;
  m->disparity = MatchReference(ref, claimed);
  m->score = ScoreImage(m->disparity, ref.road, options_.histogram, ref.ramp);
  cv::Mat moments, labels;
  m->histogram = ColumnHistogram(m->disparity, m->score, options_.histogram, &moments);
  const auto link = [&](const HistogramComponent& a, int x0, float d0, const HistogramComponent& b, int x1, float d1) {
    return Linked(view, *m, labels, a, x0, d0, b, x1, d1);
  };
  const std::vector<HistogramComponent> components =
      LinkComponents(FindComponents(m->histogram, options_.histogram, &labels, moments), m->disparity, ref.road,
                     options_.histogram, &labels, link);
  m->obstacle = cv::Mat(m->histogram.size(), CV_32F, cv::Scalar(0));
  ref.found.clear();
  ref.beyond.clear();
  const std::pair<int, int> valid = ValidColumns(m->disparity);
  for (const HistogramComponent& c : components) {
    if (StandsUp(view, *m, labels, c)) Keep(view, c, valid, ref, m, labels);
  }
}

}  // namespace dps
