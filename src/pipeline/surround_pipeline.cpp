#include "dps/pipeline/surround_pipeline.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <tuple>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "dps/stereo/virtual_view.h"
#include "dps/util/error.h"
#include "dps/util/image.h"

namespace dps {
namespace {

constexpr double kMaxViewScale = 1.25;

// The matching window for views `scale` times the 400x200 ones: 9x9 from three quarters of that
// size on, 7x7 below (fewer pixels per window as the views shrink).
int WindowForViewScale(double scale) { return scale >= 0.75 ? 9 : 7; }

// Runs each task once on up to cv::getNumThreads() workers, each taking the next task until none
// is left; returns each task's milliseconds, and rethrows the first failed task's exception (in
// task order) once all have run. Each task's own cv::parallel_for_ then runs serially inside it
// (OpenCV does not nest parallel regions): on 2 cores this costs less than splitting every stage
// into stripes, whose synchronisation dominates at the paper's 320x240 (docs/performance.md).
std::vector<double> RunTasks(const std::vector<std::function<void()>>& tasks) {
  const int n = static_cast<int>(tasks.size());
  std::vector<double> task_ms(n, 0.0);
  std::vector<std::exception_ptr> failure(n);
  std::atomic<int> next{0};
  const int workers = std::max(1, std::min<int>(cv::getNumThreads(), n));
  cv::parallel_for_(cv::Range(0, workers), [&](const cv::Range& range) {
    for (int w = range.start; w < range.end; ++w) {
      for (int i = next++; i < n; i = next++) {
        const auto start = std::chrono::steady_clock::now();
        try {
          tasks[i]();
        } catch (...) {
          failure[i] = std::current_exception();
        }
        task_ms[i] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      }
    }
  }, workers);
  for (const std::exception_ptr& f : failure) {
    if (f) std::rethrow_exception(f);
  }
  return task_ms;
}

}  // namespace

PipelineOptions DefaultPipelineOptions(const Rig& rig) {
  PipelineOptions o;
  // Views scale with the omni image up to 1.25 times the 640 px settings: larger views cost the
  // cube of their scale (width, height, disparities) while the mirror's resolution near the
  // horizon, where the views look, grows more slowly (docs/performance.md).
  const double s = std::min(kMaxViewScale, rig.Camera("left").model.width() / 640.0);
  const int w = std::max(64, static_cast<int>(std::lround(400 * s))), h = std::max(32, static_cast<int>(std::lround(200 * s)));
  // 96 disparities at 640 px: with a 2 m baseline and f = 170 px the front pair then sees down to
  // 3.5 m, and the side pairs cover vehicles passing at up to about 7 m/s relative speed (15 fps).
  const int d = std::max(16, static_cast<int>(std::lround(96 * s / 16.0)) * 16);
  const int block = WindowForViewScale(s);
  for (StereoOptions* st : {&o.front.stereo, &o.side.stereo}) {
    st->num_disparities = d;
    st->block_width = st->block_height = block;
  }
  o.side.stereo.min_disparity = -(d * 5) / 12;  // -40 of 96
  o.front.histogram.far_reference_px = d / 3.0;  // fewer votes needed below (disparity_histogram.h)
  o.side.contact_trim_rows = block >= 9 ? 2 : 0;  // side_detection.h
  o.front.view_width = o.side.view_width = w;
  o.front.view_height = o.side.view_height = h;
  o.front.focal_px = o.side.focal_px = o.rear.focal_px = 170.0 * s;
  o.rear.window_px = block >= 9 ? 7 : 5;
  return o;
}

namespace {
// A disparity within this of either end of a search range is where a match beyond the range ends
// up, not a cost minimum (NearFrontOptions, ClaimedAtHalf); px.
constexpr double kRangeEdgePx = 1.0;

// The pixels of a half-size front view where the full-size view has a disparity below upper_px
// (its range's end less kRangeEdgePx) in any of the 2x2 pixels under it: matched within that
// range, nothing for the near pair (which would otherwise match what the full pair found too weak
// to match, e.g. faint clouds, at its own nearer disparities).
cv::Mat ClaimedAtHalf(const cv::Mat& disparity, double upper_px, cv::Size half) {
  const cv::Mat matched = disparity < upper_px;  // kInvalidDisparity (+inf) is not
  cv::Mat area;
  cv::resize(matched, area, half, 0, 0, cv::INTER_AREA);
  return area > 0;
}
}  // namespace

FrontDetectorOptions NearFrontOptions(const FrontDetectorOptions& front) {
  FrontDetectorOptions o = front;
  o.view_width = std::max(32, front.view_width / 2);
  o.view_height = std::max(16, front.view_height / 2);
  o.focal_px = front.focal_px * o.view_width / front.view_width;
  const int end = front.stereo.min_disparity + front.stereo.num_disparities;
  // One below half the end: past the edge dropped, the first kept disparity continues the range.
  o.stereo.min_disparity = static_cast<int>(std::floor(end * o.focal_px / front.focal_px)) - 1;
  o.stereo.num_disparities = std::max(16, (front.stereo.num_disparities / 2 + 15) / 16 * 16);
  o.stereo.block_width = o.stereo.block_height = WindowForViewScale(o.view_width / 400.0);
  o.range_edge_px = kRangeEdgePx;
  o.drift_interval = 0;
  return o;
}

namespace {
// Where the front pair sees: its views' columns that both have a source that is not the own car on
// the horizon's row, the outermost on the left and on the right (-1 when none), with their rays.
struct FrontSight {
  int width = 0;
  int first = -1, last = -1;
  Eigen::Vector3d first_ray{0, 0, 1}, last_ray{0, 0, 1};  // vehicle frame
};

FrontSight FrontPairSight(const Rig& rig, const PipelineOptions& o) {
  const ViewSpec spec = FrontViewSpec(rig, "left", "right", o.front.view_width, o.front.view_height, o.front.focal_px);
  const VirtualView left(rig.Camera("left"), spec), right(rig.Camera("right"), spec);
  const int y = static_cast<int>(std::lround(spec.cy));
  auto sees = [y](const VirtualView& v, int x) {
    return v.mask().at<std::uint8_t>(y, x) != 0 && (v.own_car().empty() || v.own_car().at<std::uint8_t>(y, x) == 0);
  };
  FrontSight f;
  f.width = spec.width;
  for (int x = 0; x < spec.width; ++x) {
    if (!sees(left, x) || !sees(right, x)) continue;
    if (f.first < 0) f.first = x;
    f.last = x;
  }
  if (f.first >= 0) {
    f.first_ray = left.RayVehicle(f.first, y);
    f.last_ray = left.RayVehicle(f.last, y);
  }
  return f;
}

// A ray's bearing on the ground, from +Z towards +X.
double Bearing(const Eigen::Vector3d& ray) { return std::atan2(ray.x(), ray.z()); }

// How far in front of its axis a side view reaches with these options, degrees.
double GivenForwardDeg(const SideDetectorOptions& s) {
  return s.forward_half_angle_deg > 0.0 ? s.forward_half_angle_deg
                                        : std::atan((s.view_width - 1) / 2.0 / s.focal_px) / kRadPerDeg;
}

// Whether the side views may reach further forward than options.side gives them.
bool MayReachForward(const PipelineOptions& o) { return o.side_forward_max_deg > GivenForwardDeg(o.side); }

// SideOptionsForRig with the front pair's sight.
SideDetectorOptions SideOptionsForSight(const PipelineOptions& o, Side side, const FrontSight& sight) {
  SideDetectorOptions s = o.side;
  if (!MayReachForward(o)) return s;
  // The bearing of the pair's outermost seen column on the side, from straight ahead towards the
  // side (negative: beyond straight ahead); none seen: the side view reaches as far as it may.
  double edge_deg = -90.0;
  if (sight.first >= 0) {
    edge_deg = (side == Side::kLeft ? -Bearing(sight.first_ray) : Bearing(sight.last_ray)) / kRadPerDeg;
  }
  const double reach_deg = std::min(90.0 - edge_deg, o.side_forward_max_deg);
  if (reach_deg > GivenForwardDeg(s)) s.forward_half_angle_deg = reach_deg;
  return s;
}
}  // namespace

SideDetectorOptions SideOptionsForRig(const Rig& rig, const PipelineOptions& o, Side side) {
  return MayReachForward(o) ? SideOptionsForSight(o, side, FrontPairSight(rig, o)) : o.side;
}

Coverage PipelineCoverage(const Rig& rig, const PipelineOptions& o) {
  Coverage c;
  const Eigen::Vector3d l = rig.Camera("left").vehicle_from_camera.t, r = rig.Camera("right").vehicle_from_camera.t;
  const ViewSpec front = FrontViewSpec(rig, "left", "right", o.front.view_width, o.front.view_height, o.front.focal_px);
  const Eigen::Vector3d dir = front.vehicle_from_view.col(2);
  // Binocular stereo sees what both views see. They share the axis and the half-angle, so their
  // overlap is a sector from where the left view's right edge crosses the right view's left edge:
  // each edge closes tan(half) across the axis per metre along it, so they meet half the cameras'
  // separation across the axis, over tan(half), ahead of the midpoint (0.85 m for cameras 2 m
  // apart and +-49.6 degrees), whatever their offset along the axis.
  const double axis = std::atan2(dir.x(), dir.z()), half = std::atan(o.front.view_width / 2.0 / o.front.focal_px);
  const Eigen::Vector2d lg(l.x(), l.z()), rg(r.x(), r.z()), across(std::cos(axis), -std::sin(axis));
  const Eigen::Vector2d apex = (lg + rg) / 2;
  const FrontSight sight = FrontPairSight(rig, o);
  if (sight.first == 0 && sight.last == sight.width - 1) {
    c.sectors.push_back({"front", apex, axis, half, across.dot(rg - lg) / 2 / std::tan(half)});
  } else if (sight.first < 0) {
    c.sectors.push_back({"front", apex, axis, 0.0, 0.0});  // the pair sees nothing
  } else {
    // Where the cameras' fields or the own car end the pair's sight within the views: between the
    // bearings of its outermost seen columns, from where the right camera's ray along the first
    // meets the left camera's along the last (the inner edges, as for the views' own edges).
    const double lo = Bearing(sight.first_ray), hi = Bearing(sight.last_ray);
    const double direction = (lo + hi) / 2;
    const Eigen::Vector2d a(std::sin(lo), std::cos(lo)), b(std::sin(hi), std::cos(hi));
    // rg + s a = lg + t b
    const double det = a.x() * (-b.y()) - a.y() * (-b.x());
    double start = 0.0;
    if (std::abs(det) > 1e-9) {
      const Eigen::Vector2d d = lg - rg;
      const double s = (d.x() * (-b.y()) - d.y() * (-b.x())) / det;
      start = std::max(0.0, (rg + s * a - apex).dot(Eigen::Vector2d(std::sin(direction), std::cos(direction))));
    }
    c.sectors.push_back({"front", apex, direction, (hi - lo) / 2, start});
  }
  if (o.sides) {
    // Each side view's columns that motion stereo matches, at the views' full size (at speed the
    // views shrink and their matched columns span less: SideResult::sector is each frame's).
    for (const auto& [name, side, at] : {std::make_tuple("left", Side::kLeft, l), std::make_tuple("right", Side::kRight, r)}) {
      const SideDetectorOptions options = SideOptionsForSight(o, side, sight);
      const ViewSpec view = SideDetectorViewSpec(side, options);
      const auto [first, last] = SideMatchedColumns(side, view.width, options.stereo);
      c.sectors.push_back(ViewColumnsSector(name, {at.x(), at.z()}, view, first, last, options.max_depth_m));
    }
  }
  if (o.rears) {
    for (const auto& [name, side, at] : {std::make_tuple("left", Side::kLeft, l), std::make_tuple("right", Side::kRight, r)}) {
      const ViewSpec view = RearViewSpec(rig, name, side, o.rear);
      c.sectors.push_back(ViewColumnsSector(name, {at.x(), at.z()}, view, 0, view.width - 1));
    }
  }
  return c;
}

void PipelineOptions::Check() const {
  const OptionCheck Require("pipeline");
  Require(side_forward_max_deg >= 0 && side_forward_max_deg < 80, "side_forward_max_deg", side_forward_max_deg,
          "0 <= a < 80");
  Require(merge_distance_m >= 0, "merge_distance_m", merge_distance_m, ">= 0");
  Require(vehicle_length_m >= 0, "vehicle_length_m", vehicle_length_m, ">= 0 (0 = no merging)");
  Require(vehicle_width_m >= 0, "vehicle_width_m", vehicle_width_m, ">= 0");
  Require(vehicle_disparity_slack_px >= 0, "vehicle_disparity_slack_px", vehicle_disparity_slack_px, ">= 0");
  front.Check();
  side.Check();
  rear.Check();
  lane.Check();
  lane_tracking.Check();
  classes.Check();
}

namespace {
// The options once they pass their Check() (before anything is built from them).
const PipelineOptions& Checked(const PipelineOptions& options) {
  options.Check();
  return options;
}
}  // namespace

SurroundPipeline::SurroundPipeline(const Rig& rig, const PipelineOptions& options)
    : rig_(rig), options_(Checked(options)), coverage_(PipelineCoverage(rig, options)) {
  // Where each source looks from (the sectors' apexes), for MergeVehicleParts' see-through test.
  for (const Sector& s : coverage_.sectors) viewpoints_[s.name] = s.apex;
  front_ = std::make_unique<FrontDetector>(rig, options.front);
  if (options.front_near) front_near_ = std::make_unique<FrontDetector>(rig, NearFrontOptions(options.front));
  // ... and the front pair's depth error there (the sides' changes with the speed every frame).
  depth_error_per_m2_["front"] = options.vehicle_disparity_slack_px / (options.front.focal_px * front_->baseline_m());
  // The front pair looks from its cameras' midpoint (DropHidden).
  const Eigen::Vector3d eye = (rig.Camera("left").vehicle_from_camera.t + rig.Camera("right").vehicle_from_camera.t) / 2;
  front_eye_ = Eigen::Vector2d(eye.x(), eye.z());
  front_eye_height_m_ = -eye.y();
  if (options.sides) {
    const FrontSight sight = MayReachForward(options) ? FrontPairSight(rig, options) : FrontSight{};
    left_ = std::make_unique<SideDetector>(rig, "left", Side::kLeft, SideOptionsForSight(options, Side::kLeft, sight));
    right_ = std::make_unique<SideDetector>(rig, "right", Side::kRight, SideOptionsForSight(options, Side::kRight, sight));
  }
  if (options.rears) {
    left_rear_ = std::make_unique<RearDetector>(rig, "left", Side::kLeft, options.rear);
    right_rear_ = std::make_unique<RearDetector>(rig, "right", Side::kRight, options.rear);
  }
  if (options.lanes) lanes_ = std::make_unique<LaneDetector>(rig, options.lane);
  if (options.lanes && options.track_lanes) lane_tracker_ = std::make_unique<LaneTracker>(options.lane_tracking);
}

SurroundPipeline::~SurroundPipeline() = default;

FrameOutput SurroundPipeline::Process(const FrameInput& in, const std::vector<std::function<void()>>& alongside) {
  FrameOutput out;
  auto now = [] { return std::chrono::steady_clock::now(); };
  auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
  const auto t0 = now();
  // The first frame has nothing to compare the side views with.
  const bool sides = options_.sides && !previous_left_.empty() && in.motion_known;
  // The side detectors' last frame is the previous one only if that frame went through (an
  // exception leaves previous_left_ as it was).
  const bool continuing = sides_last_;
  sides_last_ = false;
  if (options_.sides && !previous_left_.empty() && !in.motion_known) {
    out.warnings.push_back(Str("frame ", in.frame, ": no known motion (CAN); side detection skipped"));
  }
  // Grey images of our own, once per frame (every view samples grey images; the side views keep
  // the previous frame's, and the caller may reuse the input's buffers).
  cv::Mat grey[2];
  cv::parallel_for_(cv::Range(0, 2), [&](const cv::Range& images) {
    for (int i = images.start; i < images.end; ++i) {
      const cv::Mat& image = i == 0 ? in.left : in.right;
      grey[i] = image.channels() == 1 ? image.clone() : GreyImage(image);
    }
  }, 2);
  // The front views first (both references match them).
  const auto front_start = now();
  front_->RenderViews(grey[0], grey[1], &out.front);
  const double front_views_ms = ms(front_start, now());
  // The sources share nothing but the input, so they run as concurrent tasks with the caller's
  // `alongside` work, in the order front (its two references), alongside..., left, right (the
  // front pair is the largest).
  const double dt = in.t_s - previous_t_s_;
  std::vector<std::function<void()>> tasks{
      [&] { front_->MatchReference(FrontReference::kLeftView, &out.front); },
      [&] { front_->MatchReference(FrontReference::kRightView, &out.front); }};
  tasks.insert(tasks.end(), alongside.begin(), alongside.end());
  if (sides) {
    tasks.push_back([&] { out.left = left_->Detect(previous_left_, grey[0], in.current_in_previous, dt, continuing); });
    tasks.push_back([&] { out.right = right_->Detect(previous_right_, grey[1], in.current_in_previous, dt, continuing); });
  }
  if (left_rear_) {
    const PlanarPose* motion = in.motion_known ? &in.current_in_previous : nullptr;
    tasks.push_back([&, motion] {
      out.left_rear = left_rear_->Detect(grey[0], motion, in.t_s);
      out.right_rear = right_rear_->Detect(grey[1], motion, in.t_s);
    });
  }
  if (lanes_) {
    tasks.push_back([&] {
      out.lanes = lanes_->Detect(grey[0], grey[1]);
      if (lane_tracker_) out.lanes = lane_tracker_->Update(out.lanes, in.motion_known ? &in.current_in_previous : nullptr, in.t_s);
    });
  }
  const std::vector<double> task_ms = RunTasks(tasks);
  front_->CombineReferences(&out.front);
  double near_ms = 0.0;
  if (front_near_) {
    // After the full-size pair: it fills only the pixels that pair did not match.
    const auto near_start = now();
    const double upper = options_.front.stereo.min_disparity + options_.front.stereo.num_disparities - 1 - kRangeEdgePx;
    FrontResult near;
    front_near_->RenderViews(grey[0], grey[1], &near);
    const cv::Size half = near.left_view.size();
    const cv::Mat claimed[2] = {ClaimedAtHalf(out.front.by_left.disparity, upper, half),
                                ClaimedAtHalf(out.front.by_right.disparity, upper, half)};
    RunTasks({[&] { front_near_->MatchReference(FrontReference::kLeftView, &near, claimed[0]); },
              [&] { front_near_->MatchReference(FrontReference::kRightView, &near, claimed[1]); }});
    front_near_->CombineReferences(&near);
    for (const Detection& d : near.detections) out.front.detections.push_back(d);
    near_ms = ms(near_start, now());
  }
  out.front_ms = front_views_ms + task_ms[0] + task_ms[1] + near_ms;
  const size_t sides_end = tasks.size() - (lanes_ ? 1 : 0) - (left_rear_ ? 1 : 0);
  out.rears_ms = left_rear_ ? task_ms[tasks.size() - (lanes_ ? 2 : 1)] : 0.0;
  out.sides_ms = sides ? task_ms[sides_end - 2] + task_ms[sides_end - 1] : 0.0;
  out.lanes_ms = lanes_ ? task_ms.back() : 0.0;
  out.detect_ms = ms(t0, now());
  Collect(in, sides, grey, &out);
  return out;
}

void SurroundPipeline::Collect(const FrameInput& in, bool sides, const cv::Mat grey[2], FrameOutput* out) {
  // What the front pair reports behind a nearer object of its own.
  out->detections = DropHidden(out->front.detections, "front", front_eye_, front_eye_height_m_,
                               depth_error_per_m2_.at("front"));
  out->coverage.sectors.push_back(coverage_.sectors.front());
  for (const SideResult* s : {&out->left, &out->right}) {
    if (!sides || s->skipped) continue;
    out->coverage.sectors.push_back(s->sector);
    if (!s->motion.name.empty()) out->coverage.motion.push_back(s->motion);
    for (const Detection& d : s->detections) out->detections.push_back(d);
  }
  for (const RearResult* s : {&out->left_rear, &out->right_rear}) {
    if (!left_rear_ || s->skipped) continue;
    out->coverage.sectors.push_back(s->sector);
    for (const Detection& d : s->detections) out->detections.push_back(d);
  }
  sides_last_ = sides;  // the side detectors saw this frame as their current one
  if (options_.sides) {
    previous_left_ = grey[0];
    previous_right_ = grey[1];
    previous_t_s_ = in.t_s;
  }
  for (Detection& d : out->detections) {
    d.frame = in.frame;
    d.t_s = in.t_s;
  }
  out->detections = FuseDetections(out->detections, options_.merge_distance_m);
  if (options_.vehicle_length_m > 0) {
    out->detections = MergeVehicleParts(std::move(out->detections), options_.vehicle_length_m,
                                        options_.vehicle_width_m, options_.vehicle_across_sources_only, viewpoints_,
                                        depth_error_per_m2_);
  }
  for (Detection& d : out->detections) SetAttributes(out->lanes.boundaries, options_.classes, &d);
}

}  // namespace dps
