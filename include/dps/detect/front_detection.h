// dps — obstacles in front by binocular stereo (Gandhi & Trivedi 2006, section V-A, eq. 14-16).
//
// The rectified front views of the two cameras (virtual_view.h) are matched (sad_stereo.h); the
// road's disparity d_bg at every view pixel comes from the rig's geometry (the ray meets the
// ground plane Y = 0 at depth Z_view, d_bg = f B / Z_view), so asymmetric rigs and calibrated
// rotations are handled exactly. Column histograms (disparity_histogram.h) give the obstacle
// components; each column of a component, with its centroid disparity d, is a point at depth
// Z_view = f B / d and lateral X_view = (x - cx) Z_view / f in the view, dropped vertically onto
// the ground in the vehicle frame (eq. 16, from the real view geometry rather than the paper's
// symmetric placement).
#pragma once

#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "dps/camera/rig.h"
#include "dps/detect/detection.h"
#include "dps/detect/disparity_histogram.h"
#include "dps/stereo/sad_stereo.h"
#include "dps/stereo/virtual_view.h"

namespace dps {

struct FrontDetectorOptions {
  int view_width = 400;        // front view size, px
  int view_height = 200;
  double focal_px = 170.0;     // front view focal length, px
  StereoOptions stereo = DetectionStereoOptions();  // its disparity range is the histogram's too
  HistogramOptions histogram;  // its disparity range is taken from `stereo`
  // Parts of one surface up to this angle of the view (the columns it spans at the view's centre,
  // focal_px x angle) and metres on the ground apart are linked (LinkComponents;
  // link_max_gap_deg = 0: never). Degrees, 0..180.
  double link_max_gap_deg = 20.2;  // 60 columns at f = 170 px (640x480 omni images)
  double link_max_gap_m = 6.0;
  // ... and whose tops differ by at most this (the height above the road three quarters of a
  // part's columns reach with their highest pixel), m; 0 = no such test. One car's parts reach
  // different heights (faces matched part way up), a pole beyond a car much higher.
  double link_max_top_difference_m = 1.2;
  // ... and, when more than link_free_gap_m apart on the ground, only if together (first column
  // to last) at most link_vehicle_length_m long: one vehicle's textureless stretch, not two
  // parked cars in a row (0 = no such test).
  double link_free_gap_m = 1.0;
  double link_vehicle_length_m = 5.5;
  // Detections of the two references whose points come this close are one object (see
  // FrontDetector), m.
  double reference_overlap_m = 0.5;
  double max_range_m = 60.0;   // points farther than this are dropped
  double own_car_height_m = 0.9;  // the own car's box for masking the bonnet (see OwnCarMask)
  // Components whose pixels reach less than this above the road (median over columns) are flat
  // (markings, mismatched road) and dropped, and so are those whose top (TopHeight less the half
  // window of fattening above it) is lower: a kerb or a raised pavement beside the road, matched
  // with the windows' fattening above and below it, reaches the height but is no obstacle (the side
  // views hold their components to the same); metres, >= 0.
  double min_obstacle_height_m = 0.5;
  // ... unless at least tall_min_width_deg of the view wide (columns as for link_max_gap_deg) with
  // a top (TopHeight) at least tall_min_top_m high: a car's long side seen at a grazing angle is
  // matched in a few rows per column (its body's bands have no texture), yet its highest pixels
  // reach its roof line. Degrees, 0..180.
  double tall_min_width_deg = 20.2;  // as link_max_gap_deg
  double tall_min_top_m = 0.8;
  // Drift correction: every `drift_interval` frames (0 = never) the rows of the two views are
  // compared (EstimateVerticalOffset); a shift of more than drift_min_px measured on at least
  // drift_min_features corners is compensated by rebuilding the right view.
  int drift_interval = 30;
  double drift_min_px = 0.25;
  int drift_min_features = 6;
  // Temporal consistency (the paper's variance check): pixels whose disparity varies over frames
  // by more than this variance are suppressed; 0 = off.
  double temporal_max_variance_px2 = 4.0;
  double temporal_forgetting = 0.5;
  // Disparities within this of either end of the search range are dropped: a cost minimum at the
  // range's edge is where a match beyond the range ends up, not a minimum. px; 0 = none kept out.
  double range_edge_px = 0.0;

  // Throws dps::Error naming the field, its value and the violated constraint (the stereo and
  // histogram options included).
  void Check() const;
};

// The matching with one view as the reference, in that view's columns.
struct FrontMatch {
  cv::Mat disparity;              // CV_32F, kInvalidDisparity where not matched
  cv::Mat score;                  // eq. 14
  cv::Mat histogram;              // eq. 15
  cv::Mat obstacle;               // CV_32F histogram-sized image of centroid disparities, 0 = none
};

// Everything one frame's front detection produced, for the map and the diagnostics.
struct FrontResult {
  cv::Mat left_view, right_view;  // rectified grey views
  // The left view as reference (most objects) and the right view as reference (objects wholly
  // beyond the left camera); see FrontDetector.
  FrontMatch by_left, by_right;
  std::vector<Detection> detections;  // one per component (frame and t left 0)
  double vertical_offset_px = 0.0;    // the right view's compensated row shift so far
  bool drift_measured = false;        // the offset was measured on this frame
};

enum class FrontReference { kLeftView, kRightView };

// Objects beside the road are matched with the farther camera's view as the reference: it sees
// them less obliquely, so that a nearer object hides less of the ones behind it (a row of parked
// cars on the left, with the left view as reference, lost the second car behind the first for ten
// frames). The right view (matched mirrored) is the reference for components lying wholly beyond
// the left camera (on the far side of the line through it, parallel to the view axis), the left
// view for all others: between the cameras both see alike, and the left view as before. A left
// view component wholly beyond the left camera still counts where no right view one lies within
// reference_overlap_m of it (an object near the line, put beyond it by matching noise); a right
// view component that close to a left view detection joins it. Each reference is matched over
// the columns that can show its objects (the left view from an eighth of the view before its
// centre, the right view up to 16 columns past its centre), with both views prefiltered once for
// the two, so the two cost less than twice one matching; their first d_max columns, which the
// other view cannot match, show only the other reference's objects.
class FrontDetector {
 public:
  // Builds both views and the road disparity image for the rig's "left" and "right" cameras.
  FrontDetector(const Rig& rig, const FrontDetectorOptions& options);
  ~FrontDetector();

  // Detects obstacles in one pair of omni images (grey or BGR, the cameras' sizes). Frames must
  // come in order: drift correction and the temporal filter keep state between them.
  FrontResult Detect(const cv::Mat& left_omni, const cv::Mat& right_omni);

  // Detect in three steps, so that the two references can run as concurrent tasks (Detect takes
  // them in turn): the views (and drift correction); the matching and components with one
  // reference (the two may run at once); the detections of both. Steps of one frame in this
  // order, frames in order.
  void RenderViews(const cv::Mat& left_omni, const cv::Mat& right_omni, FrontResult* r);
  // `claimed` (optional, the views' size): pixels another matching already gave a disparity,
  // left unmatched here (NearFrontOptions: the near pair fills what the full pair did not match).
  void MatchReference(FrontReference reference, FrontResult* r, const cv::Mat& claimed = cv::Mat());
  void CombineReferences(FrontResult* r) const;

  // The ground point (vehicle frame x, z) of left view column x at disparity d (eq. 16); false
  // when d is not positive.
  bool ColumnToGround(double x, double disparity, Eigen::Vector2d* ground) const;

  const cv::Mat& road_disparity() const { return by_left_.road; }  // left view; CV_32F, inf above the horizon
  const VirtualView& left_view() const { return *left_; }
  const VirtualView& right_view() const { return *right_; }
  double baseline_m() const { return baseline_m_; }

 private:
  // One view as the reference of the pair.
  struct Reference {
    const VirtualView* view = nullptr;   // the reference view (left_ or right_)
    bool mirrored = false;               // the right view: matched with both views mirrored
    cv::Mat road, ramp;                  // the road's disparity at its pixels; ScoreImage's ramp
    cv::Mat ignore;                      // CV_8U, 255 where it sees nothing or the own car
    std::unique_ptr<TemporalConsistencyFilter> temporal;
    int first = 0;                              // its first matched column (mirrored for the right view)
    std::unique_ptr<SadStereoMatcher> matcher;  // one per reference: the two run concurrently
    SadStereoMatcher::PreparedView mirrored_reference, mirrored_other;  // the right view's, mirrored
    std::vector<Detection> found;               // this frame's components on its side
    std::vector<Detection> beyond;              // the left view's wholly beyond the left camera
  };
  // Road, ramp and ignore mask of both references (after the views are built or rebuilt), and of
  // one, given the own car as both views see it.
  void PrepareReferences();
  void Prepare(const cv::Mat& own_car, Reference* ref) const;
  // Matches the pair with `ref` as reference over its columns, finds the components and keeps
  // those on its side in ref.found (the left view's wholly beyond the left camera in ref.beyond).
  // `claimed`: as MatchReference's (empty: none).
  void DetectWith(Reference& ref, const cv::Mat& claimed, FrontMatch* m);
  // The steps of DetectWith: the reference's disparity (masked, temporally filtered); whether two
  // parts of the histogram are one surface; whether a component stands up from the road; and a
  // component kept as a detection of `ref` when it lies on its side, with its height (TopHeight less
  // the half window the matcher carries its disparity above its top edge).
  cv::Mat MatchReference(Reference& ref, const cv::Mat& claimed);
  bool Linked(const VirtualView& view, const FrontMatch& m, const cv::Mat& labels, const HistogramComponent& a, int x0,
              float d0, const HistogramComponent& b, int x1, float d1) const;
  bool StandsUp(const VirtualView& view, const FrontMatch& m, const cv::Mat& labels, const HistogramComponent& c) const;
  std::vector<double> ColumnHeights(const FrontMatch& m, const cv::Mat& labels, const HistogramComponent& c) const;
  void Keep(const VirtualView& view, const HistogramComponent& c, std::pair<int, int> valid_columns, Reference& ref,
            FrontMatch* m, const cv::Mat& labels) const;
  // The ground point of a reference view's column x at disparity d (eq. 16).
  bool ColumnToGround(const VirtualView& view, double x, double disparity, Eigen::Vector2d* ground) const;
  // Whether pixel (x, y) votes for component `label`: a scored disparity in one of its bins.
  bool InComponent(const FrontMatch& m, const cv::Mat& labels, int label, int x, int y) const;
  // How high a component reaches above the road: of its columns' highest pixels (disparity in
  // the component's bins), each taken `below_rows` rows lower, the height three quarters of the
  // columns reach; NaN when none.
  double TopHeight(const VirtualView& view, const FrontMatch& m, const cv::Mat& labels, const HistogramComponent& c,
                   int below_rows = 0) const;
  // The ground point of a component's first (or last) column with a centroid; false if none.
  bool OuterPoint(const VirtualView& view, const HistogramComponent& c, bool last, Eigen::Vector2d* ground) const;

  FrontDetectorOptions options_;
  std::unique_ptr<VirtualView> left_, right_;
  Rig rig_;
  ViewSpec spec_;
  double vertical_offset_px_ = 0.0;
  int frames_ = 0;
  double baseline_m_ = 0.0;
  int tall_min_columns_ = 0;  // tall_min_width_deg in the views' columns
  Reference by_left_, by_right_;
  // This frame's views prefiltered for matching (RenderViews), shared by the two references.
  SadStereoMatcher::PreparedView left_prepared_, right_prepared_;
  Eigen::Vector2d left_camera_{0, 0}, across_{1, 0};  // the left camera and the baseline's direction (ground)
};

}  // namespace dps
