// dps — obstacles at the sides by motion stereo (Gandhi & Trivedi 2006, section V-B, eq. 17-18).
//
// One camera's side views of two consecutive frames form the stereo pair; the camera moved
// between them by the ego motion (from CAN speed and yaw rate). Both views lie in the vertical
// plane parallel to that displacement (section V-C: turning), so they are rectified with the
// displacement as baseline. Static things then have disparity f B / depth; vehicles moving with
// us have less, overtaking ones negative disparity, hence a disparity range shifted below zero
// (the paper's fixed offset). The road's disparity at every pixel follows from the geometry; the
// score counts distance from it in either direction. Column histograms give the components;
// each component's pixels are traced back in the disparity image (where a pixel sees the road,
// only if it stands out from the road's disparity: member_min_score) and, per column, the
// bottom-most one is taken as the object's contact with the ground: its ray meets the road
// plane (eq. 17-18, from the real view geometry); optionally, where that agrees with the depth a
// static object at its disparity has, the two are combined (static_gate), and a column where the
// road beyond shows between the contact and the object's height gives none. Points are reported
// in the vehicle frame of the current frame.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "dps/camera/ego_motion.h"
#include "dps/camera/rig.h"
#include "dps/detect/coverage.h"
#include "dps/detect/detection.h"
#include "dps/detect/disparity_histogram.h"
#include "dps/stereo/sad_stereo.h"
#include "dps/stereo/virtual_view.h"

namespace dps {

struct SideDetectorOptions {
  int view_width = 400;        // side view size, px (with back_ or forward_half_angle_deg, the other half twice)
  int view_height = 200;
  double focal_px = 170.0;
  // > 0: the view reaches this far behind its axis instead of as far as in front (the blind spot
  // behind the mirrors), its width growing by focal_px x tan of it; deg, 0 <= a < 80.
  double back_half_angle_deg = 0.0;
  // > 0: the view reaches this far in front of its axis instead (towards where the front pair does
  // not see: SideOptionsForRig), its width growing the same way; deg, 0 <= a < 80.
  double forward_half_angle_deg = 0.0;
  // The horizon's row as a fraction of the height: below it the view reaches 37 degrees down at
  // the defaults, so a camera 0.9 m high sees where objects 1.2 m away meet the road.
  double horizon_fraction = 0.35;
  StereoOptions stereo;        // default: 64 disparities from -16 (overtaking vehicles), coarse_same_rows
  HistogramOptions histogram;  // its range is the stereo range; scored two-sided
  double max_range_m = 40.0;   // points farther than this are dropped
  // ... and points deeper than this along the view's axis: motion stereo's depth error grows with
  // depth squared over f B, m
  double max_depth_m = 6.0;
  double own_car_height_m = 0.9;
  // Camera displacement below this: no motion stereo; nor below min_motion_disparity_px x
  // max_depth_m / f (the views' focal length f), where a static object as deep as the views keep
  // would shift less than min_motion_disparity_px (slow driving, high frame rates, coarse images).
  double min_baseline_m = 0.05;
  // Components lower than this (median), or whose top (the height three quarters of their columns
  // reach) is lower, are dropped, and with static_gate on, columns where the road beyond shows
  // within this height above the contact; m.
  double min_obstacle_height_m = 0.5;
  // At speed the camera moves far between frames, and a static object beside the car has the
  // disparity f B / D (D: its distance from the camera across the view). To keep objects down to
  // min_static_distance_m inside the disparity range, the views shrink (focal length and size
  // together, so the field of view stays) by f B / D <= the range's upper end, in steps of 1/16
  // and not below min_view_scale.
  double min_static_distance_m = 1.0;
  double min_view_scale = 0.5;
  // Columns whose depth times disparity differs from the component's median by more than this
  // fraction are dropped (see side_detection.cpp), unless the component's median |disparity| is
  // below min_motion_disparity_px.
  double motion_tolerance = 0.35;
  double min_motion_disparity_px = 3.0;
  // A column whose contact lies farther than this from both neighbouring columns' contacts on
  // the ground is dropped: its bottom-most pixel was a stray match, not where the object meets the
  // road. The depth x disparity test above cannot catch it for objects keeping pace with us
  // (disparity near zero), and one such point 3 m short becomes the detection's nearest point.
  // m, > 0.
  double max_contact_jump_m = 1.0;
  // Each contact a static object's disparity placed (static_gate) moved to the median depth of such
  // contacts within half a matching window of columns (side_detection.cpp, MedianContacts): the
  // component's nearest point is then not the extreme of its columns' scatter. false: every
  // column's contact as placed.
  bool median_contacts = true;
  double disparity_sigma_px = 1.0;    // matching noise: the velocity's uncertainty, a static depth's error
  // A contact whose depth agrees with the depth a static object at its disparity would have (f B /
  // d), within this many standard deviations of the two, is a static object's: its depth is the
  // two combined (see side_detection.cpp; 2 lets a static object's contact pass 95 % of the time).
  // With it on, columns past an object's end give no point (SolidAboveContact). >= 0; 0 = every
  // contact placed by its row alone.
  double static_gate = 2.0;
  // A pixel with a component's disparity that sees the road is a member of the component (its
  // bottom-most member is the contact) only when its score (eq. 14: its disparity's distance from
  // the road's, over the ramp) is at least this. Road pixels near an object's depth share its
  // disparity bins (the windows carry its disparity onto the road around its foot; at slow speed
  // the road's whole disparity range can form one component) and, as members, put contacts on the
  // road. Above the horizon any pixel that scores is a member (an object keeping pace has about the
  // background's disparity there). A fraction of the ramp, [0, 1]; 1: the full ramp.
  double member_min_score = 1.0;
  // Below the bottom-most matched pixel, pixels with no disparity (up to max_gap_below_m at the
  // object's depth) or with the object's disparity (within contact_tolerance_px) still count as
  // the object: the contact with the road is the lowest of them.
  double max_gap_below_m = 0.6;
  double contact_tolerance_px = 1.5;
  // Block matching carries the object's disparity up to half a window below its bottom edge
  // (vertical foreground fattening): the contact is taken this many rows above the lowest pixel,
  // >= 0. DefaultPipelineOptions: 2 with 9x9 windows, 0 with 7x7.
  int contact_trim_rows = 0;
  // An object keeping pace with us (|disparity| below min_motion_disparity_px) over road whose
  // disparity at the contact differs from the object's by more than this: the windows carry the
  // object's disparity down over the road by up to half a window, so the contact is taken half a
  // window above the lowest pixel. px, > 0.
  double pacing_road_contrast_px = 5.0;
  // An object keeping pace with us stays where it is in the vehicle frame from one frame to the
  // next (it moves by at most min_motion_disparity_px x depth / f, a few centimetres), while a
  // component that only looks still - a far band the video codec repeated, a verge too fine to
  // resolve - has its bottom-most pixels, and so its contact, wherever that frame's matching left
  // them. A component keeping pace is kept only when half its contact points lie within this
  // distance of a contact point of one of the previous frame's components (any, kept or not;
  // Persisting). m; 0 = no test.
  double pacing_persistence_m = 0.5;
  // Something keeping pace with us is a vehicle: its contacts span no more across the direction of
  // travel (their depths along the view's axis) than the widest road vehicle (trucks and buses are
  // 2.55 m wide). A band of road or verge that the matcher left at zero disparity spans metres.
  // m; 0 = no test.
  double max_vehicle_width_m = 2.6;
  // Something keeping pace with us stands up into the view above the horizon, the camera's height at
  // every distance: standing up from its contact through pixels at its disparity or without one, its
  // columns (three quarters of them) reach above the camera, while a band of road or verge lies on
  // the road and ends below the horizon (the sky above the horizon, also at zero disparity, does not
  // count: rows matched at other disparities or too many without one lie between). Road vehicles
  // stand taller than a camera in a side mirror; a car lower than the camera that keeps exactly our
  // speed is lost with this test (from one pair of frames it is the same picture as such a band).
  bool pacing_above_camera = true;

  SideDetectorOptions();
  // Throws dps::Error naming the field, its value and the violated constraint (the stereo and
  // histogram options included).
  void Check() const;
};

struct SideResult {
  bool skipped = false;        // no motion stereo this frame (see reason)
  std::string reason;
  cv::Mat reference_view, other_view;  // the pair as matched (reference = left image)
  cv::Mat disparity, score, histogram;
  cv::Mat obstacle;            // CV_8U reference-view image, 255 at the bottom-most pixels
  double baseline_m = 0.0;
  double view_scale = 1.0;     // the views' size and focal length relative to the options
  // The ground sector of the reference view's columns that motion stereo matched: the others
  // (a strip at either edge, where a match could fall outside the previous view) are not seen.
  // Empty name when skipped.
  Sector sector;
  // Where this pair's motion tells depth (MotionSight: the views' focal length, the baseline, the
  // matching noise disparity_sigma_px). Empty name when skipped.
  MotionSight motion;
  std::vector<Detection> detections;   // source = the camera's name
};

// The columns [first, last] of a side view `width` pixels wide that motion stereo matches with
// these stereo options (the left side's view is matched mirrored).
std::pair<int, int> SideMatchedColumns(Side side, int width, const StereoOptions& stereo);
// Whether ground points lie where earlier ones did: half of them (the median) within `distance_m`
// of a point of one of the `earlier` components (SideDetectorOptions::pacing_persistence_m).
bool Persisting(const std::vector<Eigen::Vector2d>& points, const std::vector<std::vector<Eigen::Vector2d>>& earlier,
                double distance_m);
// The topmost row that an object reaches standing up in column x of a side view's disparity
// (CV_32F, NaN where none) from its bottom-most pixel `bottom`, matched at `disparity_px`: upwards
// through the rows of its histogram component (`member`), rows within tolerance_px of its
// disparity (the component's neighbouring bins) and runs of at most max_gap_px rows without a
// disparity (an untextured body); a row matched at any other disparity ends it. A band of road
// that the matcher left at zero disparity shares its component with the sky above the horizon,
// but the rows between them end it (SideDetectorOptions::pacing_above_camera).
int ConnectedTop(const cv::Mat& disparity, int x, int bottom, double disparity_px, double tolerance_px, int max_gap_px,
                 const std::function<bool(int)>& member);
// The side view of these options with its size and focal length times `scale`, turned by yaw_rad.
ViewSpec SideDetectorViewSpec(Side side, const SideDetectorOptions& options, double scale = 1.0, double yaw_rad = 0.0);

class SideDetector {
 public:
  // `camera`: the rig camera looking to `side` ("left" camera, Side::kLeft, usually).
  SideDetector(const Rig& rig, const std::string& camera, Side side, const SideDetectorOptions& options);
  ~SideDetector();

  // Detects obstacles from the previous and the current omni image of the camera;
  // `current_in_previous` is the vehicle's pose at the current frame in the previous frame's
  // vehicle frame (MotionProfile::Integrate over the frame interval).
  // `interval_s` > 0 (the time between the frames): each detection also carries its ground
  // velocity along the camera's displacement (Detection::has_motion): a rigid object has depth x
  // disparity = f x (the camera's displacement relative to it) in every column, so its own
  // displacement is the camera's minus the median of depth x disparity / f.
  // `continuing`: previous_omni is the current_omni of the last call (consecutive frames); the
  // previous view is then the last call's current view whenever the two views are the same (same
  // scale and yaw, e.g. driving straight), and is taken as it was rendered and prefiltered then.
  SideResult Detect(const cv::Mat& previous_omni, const cv::Mat& current_omni,
                    const PlanarPose& current_in_previous, double interval_s = 0.0, bool continuing = false);
  size_t views_reused() const { return views_reused_; }  // calls that took the last current view

 private:
  RigCamera camera_;
  Side side_;
  Vehicle vehicle_;
  SideDetectorOptions options_;
  double camera_height_m_;  // above the road
  // Per view (by yaw grid index): pixels to ignore (no source, own car) and the inverse depth of
  // the road along the view axis (0 where there is no road); the road's disparity is f B times it.
  struct ViewGeometry {
    cv::Mat ignore, inverse_depth;
    cv::Mat valid;  // 255 where the view sees the world (mirrored for the left side, as matched)
  };
  const ViewGeometry& Geometry(const VirtualView& view, std::pair<int, long> key);
  // The matched pair of one call: the reference (current) view, its geometry, and the camera's
  // direction of travel in the current vehicle frame.
  struct Matched {
    const VirtualView* reference = nullptr;
    const ViewGeometry* geometry = nullptr;
    Eigen::Vector2d direction{0, 0};
  };
  // Renders both views parallel to the camera's displacement and matches them (the previous view
  // is the last call's current one when `continuing`); fills r's baseline, views, disparity,
  // sector and motion. False (r skipped) when the camera moved too little (min_baseline_m).
  bool MatchPair(const cv::Mat& previous_omni, const cv::Mat& current_omni, const PlanarPose& current_in_previous,
                 bool continuing, SideResult* r, Matched* m);
  // The view scale for a baseline, in sixteenths.
  int ScaleSixteenths(double baseline_m) const;
  SideViewCache& Views(int sixteenths);
  std::map<std::pair<int, long>, ViewGeometry> geometry_;   // by (scale, yaw grid index)
  std::map<int, std::unique_ptr<SideViewCache>> views_;     // by scale
  std::unique_ptr<SadStereoMatcher> matcher_;
  // The last call's current view as matched (rendered; prefiltered, mirrored for the left side)
  // and its (scale, yaw grid index); valid only after a call that matched. `prepared_` is the
  // current view's buffer of the next call.
  cv::Mat last_view_;
  SadStereoMatcher::PreparedView last_prepared_, prepared_;
  std::pair<int, long> last_key_{0, 0};
  bool last_valid_ = false;
  size_t views_reused_ = 0;
  // The ground points of the last call's components (before the pacing persistence test), for
  // the next call's test; empty when that call did not match.
  std::vector<std::vector<Eigen::Vector2d>> last_components_;
};

}  // namespace dps
