#include "dps/detect/side_detection.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "dps/detect/ground_projection.h"
#include "dps/util/error.h"
#include "dps/util/image.h"
#include "dps/util/math.h"

namespace dps {
namespace {

// The bottom-most matched pixel of an object often sits above its contact with the road: the
// lowest part of a vehicle (wheels, the shadow under it) is dark and untextured, so it has no
// disparity, and near the contact the road's own disparity approaches the object's, so the score
// fades. From `bottom` down, pixels with no disparity or with the object's disparity (within
// `tolerance`) still belong to the object; the walk stops at the first pixel that shows something
// else (the road at its own disparity), at an ignored pixel (own car, no source), or after
// `max_gap` rows with no disparity. Returns the lowest object row (the row of the last pixel with
// the object's disparity; a trailing run with no disparity is not taken).
int ExtendToContact(const cv::Mat& disparity, const cv::Mat& ignore, int x, int bottom, float object_disparity,
                    double tolerance, int max_gap) {
  int lowest = bottom, gap = 0;
  for (int y = bottom + 1; y < disparity.rows; ++y) {
    if (ignore.at<std::uint8_t>(y, x)) break;
    const float d = disparity.at<float>(y, x);
    if (!std::isfinite(d)) {
      if (++gap > max_gap) break;
      continue;
    }
    if (std::abs(d - object_disparity) > tolerance) break;
    lowest = y;
    gap = 0;
  }
  return lowest;
}

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// One column of a component: where it meets the road (view pixel and ground point), its depth
// along the view axis (a static object's from its disparity too: StaticDepth), its disparity, its
// height (the rows it fills with its disparity) and its reach, the highest of those rows' height
// above the road as matched (TopOf leaves out the matcher's fattening); bottom: the row of its
// bottom-most pixel in the component, contact_row: the row taken as its contact (StandingHeight);
// row_depth: the depth of its lowest pixel's ground point alone, which max_depth_m limits.
// solid: the column shows the object, not the road beyond, above the contact (SolidAboveContact;
// tested with static_gate on only); a column that is not solid still counts for the component's
// height, but gives no point.
struct Contact {
  int x = 0, y = 0, bottom = 0, contact_row = 0;
  Eigen::Vector2d ground{0, 0};
  double depth = 0.0, disparity = 0.0, height = 0.0, reach = 0.0, row_depth = 0.0;
  bool solid = true;
  bool placed_static = false;  // depth from StaticDepth (the row and the disparity combined)
};

// A rigid object that moves parallel to the views (or stands still) has, in every column,
// disparity = f * (its displacement relative to the camera) / depth: depth times disparity is
// the same for all its columns. A column whose contact point breaks this (its bottom-most pixel
// is not where the object meets the road, e.g. only the top of a face was matched) is dropped.
// Components that hardly move relative to the camera (median |disparity| below
// min_disparity) carry no such information and are kept as they are.
std::vector<Contact> ConsistentContacts(std::vector<Contact> contacts, double min_disparity, double tolerance) {
  if (contacts.size() < 3) return contacts;
  std::vector<double> products, disparities;
  for (const Contact& k : contacts) {
    products.push_back(k.depth * k.disparity);
    disparities.push_back(std::abs(k.disparity));
  }
  if (Median(disparities) < min_disparity) return contacts;
  const double m = Median(products);
  std::vector<Contact> kept;
  for (const Contact& k : contacts) {
    if (std::abs(k.depth * k.disparity - m) <= tolerance * std::abs(m)) kept.push_back(k);
  }
  return kept;
}

// Contacts (in column order) farther than max_jump from both neighbours on the ground are dropped.
std::vector<Contact> ContinuousContacts(const std::vector<Contact>& contacts, double max_jump) {
  if (contacts.size() < 3) return contacts;
  std::vector<Contact> kept;
  for (size_t i = 0; i < contacts.size(); ++i) {
    const bool before = i > 0 && (contacts[i].ground - contacts[i - 1].ground).norm() <= max_jump;
    const bool after = i + 1 < contacts.size() && (contacts[i].ground - contacts[i + 1].ground).norm() <= max_jump;
    if (before || after) kept.push_back(contacts[i]);
  }
  return kept;
}

// Each contact placed by its disparity (StaticDepth) moved along its column (ColumnToGround) to the
// median depth of such contacts within `half_window` columns of it. The matching windows of those
// columns overlap its own, so they measure one stretch of the object with errors that are not
// independent, and each column's row scatters (a row spans D^2 / (f h) of road at depth D): the
// component's nearest point, what the map reports, would be the extreme of that scatter - a thin
// pole or a wall's face at slow speed placed up to a metre short. The median keeps an object's
// corners and ends (a step in depth stays a step). Contacts placed by their rows alone (moving
// objects, objects keeping pace) keep their rows: their trims already move them half a window up,
// and a median over them put a car keeping pace 0.5 m beyond its side
// (docs/experiments/detection-history.md).
// Contacts come in column order; only their ground points change, so the depths read stay the
// measured ones.
std::vector<Contact> MedianContacts(std::vector<Contact> contacts, int half_window, const VirtualView& reference,
                                    double baseline_m) {
  size_t first = 0;
  for (Contact& k : contacts) {
    while (contacts[first].x < k.x - half_window) ++first;
    if (!k.placed_static) continue;
    std::vector<double> near;
    for (size_t j = first; j < contacts.size() && contacts[j].x <= k.x + half_window; ++j) {
      if (contacts[j].placed_static) near.push_back(contacts[j].depth);
    }
    ColumnToGround(reference, k.x, reference.spec().focal_px * baseline_m / Median(near), baseline_m, &k.ground);
  }
  return contacts;
}

// What the contact search of one matched pair reads.
struct ContactSearch {
  const VirtualView& reference;
  const cv::Mat& disparity;
  const cv::Mat& score;
  const cv::Mat& labels;  // FindComponents' labels of the column histogram
  const cv::Mat& ignore;
  const cv::Mat& road;    // the road's disparity
  double baseline_m;      // the camera's displacement between the two views
  const SideDetectorOptions& options;
};

// The depth of a static object at `disparity` (f B / d) combined with its contact's, when the two
// agree within their errors: the contact's row is known to half a matching window (the matcher
// carries an object's disparity that far below its bottom edge; one row spans D^2 / (f h) of road
// at depth D, camera height h), the disparity to disparity_sigma_px. False when they disagree (the
// object moves) or the disparity is below min_motion_disparity_px (keeping pace or coming towards
// us: no static depth, or one too far and too uncertain to place anything).
bool StaticDepth(const ContactSearch& s, int x, int contact_row, double contact_depth, double disparity, double* depth) {
  const SideDetectorOptions& o = s.options;
  if (!(disparity >= o.min_motion_disparity_px)) return false;
  const ViewSpec& spec = s.reference.spec();
  const double static_depth = spec.focal_px * s.baseline_m / disparity;
  const double static_sigma = static_depth * o.disparity_sigma_px / disparity;
  Eigen::Vector3d above;
  const int half = o.stereo.block_height / 2;
  if (!PixelToGround(s.reference, x, contact_row - half, &above)) return false;  // the row says little
  // ... and the road just before the object can be told from it only where their disparities differ
  // by more than contact_tolerance_px: over D^2 contact_tolerance_px / (f B) of road in front of a
  // static object the walk down (ExtendToContact) may carry the contact nearer (slow driving: a
  // small B; a fine verge matched at the object's disparity).
  const double row_sigma = std::abs(ViewDepth(s.reference, above) - contact_depth);
  const double road_sigma = contact_depth * contact_depth * o.contact_tolerance_px / (spec.focal_px * s.baseline_m);
  const double contact_sigma = std::max(1e-6, std::hypot(row_sigma, road_sigma));
  if (std::abs(static_depth - contact_depth) > o.static_gate * std::hypot(static_sigma, contact_sigma)) return false;
  const double ws = 1.0 / (static_sigma * static_sigma), wc = 1.0 / (contact_sigma * contact_sigma);
  *depth = (ws * static_depth + wc * contact_depth) / (ws + wc);
  return true;
}

// Whether the column shows a solid object above its contact: over min_obstacle_height_m up from
// `lowest` (at the contact's depth) no pixel sees static road or background beyond the contact
// (disparity below f B / depth by more than contact_tolerance_px and not the object's own). A
// column past an object's end fails: the matcher carries the end's disparity into it over
// untextured background, and where it meets the road at the end's depth that road has the end's
// disparity, but between the two the road farther away shows.
bool SolidAboveContact(const ContactSearch& s, int x, int lowest, double depth, double disparity) {
  const SideDetectorOptions& o = s.options;
  const ViewSpec& spec = s.reference.spec();
  const double beyond = spec.focal_px * s.baseline_m / depth - o.contact_tolerance_px;
  const int rows = static_cast<int>(std::ceil(o.min_obstacle_height_m * spec.focal_px / depth));
  for (int y = lowest - 1; y >= std::max(0, lowest - rows); --y) {
    const float d = s.disparity.at<float>(y, x);
    if (std::isfinite(d) && d < beyond && std::abs(d - disparity) > o.contact_tolerance_px) return false;
  }
  return true;
}

// A column's top above the road: its reach less the half window by which the matcher carries an
// object's disparity above its top edge.
double TopOf(const Contact& k, int block_height, double focal_px) {
  return std::max(0.0, k.reach - block_height / 2 * k.depth / focal_px);
}

// The value that three quarters of `values` reach at least (reorders them).
double UpperQuartile(std::vector<double>* values) {
  const auto q = values->begin() + values->size() / 4;
  std::nth_element(values->begin(), q, values->end(), std::greater<double>());
  return *q;
}

// Whether a pixel with the component's disparity belongs to the object: where it sees the road,
// only when it stands out from the road's disparity (SideDetectorOptions::member_min_score). Above
// the horizon nothing is road: any pixel that scores counts.
bool Member(float score, float road_disparity, double min_score) {
  return score > 0.0f && (!std::isfinite(road_disparity) || score >= min_score);
}

// Whether pixel (x, y) belongs to component c: matched in one of its histogram bins, and a member
// of the histogram's votes (Member).
bool InComponent(const ContactSearch& s, const HistogramComponent& c, int x, int y) {
  const HistogramOptions& ho = s.options.histogram;
  const float v = s.disparity.at<float>(y, x);
  if (!std::isfinite(v) || !Member(s.score.at<float>(y, x), s.road.at<float>(y, x), s.options.member_min_score)) return false;
  const int bin = static_cast<int>(std::floor((v - ho.min_disparity) / ho.bin_px));
  return bin >= 0 && bin < s.labels.rows && s.labels.at<int>(bin, x) == c.label;
}

// The height above the road that a column of component c stands up to from its contact
// (ConnectedTop; SideDetectorOptions::pacing_above_camera).
double StandingHeight(const ContactSearch& s, const HistogramComponent& c, const Contact& k) {
  const double f = s.reference.spec().focal_px;
  const int top = ConnectedTop(s.disparity, k.x, k.bottom, k.disparity, s.options.contact_tolerance_px,
                               static_cast<int>(s.options.max_gap_below_m * f / k.depth),
                               [&](int y) { return InComponent(s, c, k.x, y); });
  return std::max(0, k.contact_row - top) * k.depth / f;
}

// A component's contacts with the road, one per column where it has one.
std::vector<Contact> ComponentContacts(const ContactSearch& s, const HistogramComponent& c) {
  const SideDetectorOptions& o = s.options;
  const ViewSpec& spec = s.reference.spec();
  std::vector<Contact> contacts;
  for (int x = c.x_begin; x < c.x_end; ++x) {
    // The component's pixels in this column; the bottom-most is the contact with the road.
    int top = -1, bottom = -1, rows = 0;
    for (int y = 0; y < spec.height; ++y) {
      if (InComponent(s, c, x, y)) {
        if (top < 0) top = y;
        bottom = y;
        ++rows;
      }
    }
    const float disparity = c.column_disparity[x - c.x_begin];
    Eigen::Vector3d g;
    if (bottom < 0 || !std::isfinite(disparity) || !PixelToGround(s.reference, x, bottom, &g)) continue;
    const int lowest = ExtendToContact(s.disparity, s.ignore, x, bottom, disparity, o.contact_tolerance_px,
                                       static_cast<int>(o.max_gap_below_m * spec.focal_px / ViewDepth(s.reference, g)));
    if (lowest != bottom && !PixelToGround(s.reference, x, lowest, &g)) continue;
    Contact k;
    k.x = x;
    k.y = lowest;
    // Depth and disparity of the lowest matched pixel (for the motion); the contact with the
    // road, placed on the map, contact_trim_rows higher (vertical fattening; half a window for
    // an object keeping pace with us over road of a different disparity); a static object's
    // contact and depth where its disparity puts it (StaticDepth).
    k.depth = k.row_depth = ViewDepth(s.reference, g);
    int trim = o.contact_trim_rows;
    const float road_here = s.road.at<float>(lowest, x);
    if (std::abs(disparity) < o.min_motion_disparity_px && std::isfinite(road_here) &&
        std::abs(road_here - disparity) > o.pacing_road_contrast_px) {
      trim = std::max(trim, o.stereo.block_height / 2);
    }
    const int contact = std::max(0, lowest - trim);
    if (contact != lowest && !PixelToGround(s.reference, x, contact, &g)) continue;
    k.ground = Eigen::Vector2d(g.x(), g.z());
    double depth = 0.0;
    Eigen::Vector2d ground;
    if (o.static_gate > 0 && StaticDepth(s, x, contact, ViewDepth(s.reference, g), disparity, &depth) &&
        ColumnToGround(s.reference, x, spec.focal_px * s.baseline_m / depth, s.baseline_m, &ground)) {
      k.ground = ground;
      k.depth = depth;
      k.placed_static = true;
    }
    // Part of placing static objects by their disparity: with rows alone the columns it leaves out
    // mostly stayed inside their object's detection, and leaving them out cost precision elsewhere.
    k.solid = o.static_gate <= 0 || SolidAboveContact(s, x, lowest, k.depth, disparity);
    k.disparity = disparity;
    k.height = (rows + lowest - bottom) * k.depth / spec.focal_px;
    k.reach = std::max(0, contact - top) * k.depth / spec.focal_px;
    k.bottom = bottom;
    k.contact_row = contact;
    contacts.push_back(k);
  }
  return contacts;
}

// The object's own displacement along the camera's, B - median(depth x disparity) / f, as a
// ground speed with its sigma: the matching noise, or the columns' own scatter (robust sigma)
// when that is larger (a component mixing the object with its background disagrees with itself).
void MeasureMotion(const std::vector<Contact>& contacts, double baseline_m, double focal_px, double interval_s,
                   double disparity_sigma_px, Detection* det) {
  std::vector<double> products, depths;
  for (const Contact& k : contacts) {
    products.push_back(k.depth * k.disparity);
    depths.push_back(k.depth);
  }
  const double product = Median(products);
  std::vector<double> deviations;
  for (const double p : products) deviations.push_back(std::abs(p - product));
  det->has_motion = true;
  det->motion_mps = (baseline_m - product / focal_px) / interval_s;
  det->motion_sigma_mps =
      std::max(disparity_sigma_px * Median(depths), 1.4826 * Median(deviations)) / focal_px / interval_s;
}

}  // namespace

SideDetectorOptions::SideDetectorOptions() {
  stereo = DetectionStereoOptions();
  stereo.min_disparity = -16;
  // The road beside the car changes its disparity by B / H per row (baseline B, camera height H):
  // the half-resolution level's windows span no more rows than the full level's.
  stereo.coarse_same_rows = true;
  histogram.two_sided = true;
  histogram.min_columns = 10;  // nearby vehicles fill much of a side view; small blobs are road
}

void SideDetectorOptions::Check() const {
  const OptionCheck Require("side detector");
  Require(view_width > 0 && view_width <= 8192, "view_width", view_width, "1..8192 px");
  Require(view_height > 0 && view_height <= 8192, "view_height", view_height, "1..8192 px");
  Require(focal_px > 0 && focal_px <= 100.0 * view_width, "focal_px", focal_px, "> 0 and at most 100 view widths");
  Require(horizon_fraction > 0 && horizon_fraction < 1, "horizon_fraction", horizon_fraction, "0 < h < 1");
  Require(pacing_persistence_m >= 0, "pacing_persistence_m", pacing_persistence_m, ">= 0 (0 = no test)");
  Require(max_vehicle_width_m >= 0, "max_vehicle_width_m", max_vehicle_width_m, ">= 0 (0 = no test)");
  Require(back_half_angle_deg >= 0 && back_half_angle_deg < 80, "back_half_angle_deg", back_half_angle_deg, "0 <= a < 80");
  Require(forward_half_angle_deg >= 0 && forward_half_angle_deg < 80, "forward_half_angle_deg", forward_half_angle_deg,
          "0 <= a < 80");
  Require(max_range_m > 0, "max_range_m", max_range_m, "> 0");
  Require(max_depth_m > 0, "max_depth_m", max_depth_m, "> 0");
  Require(own_car_height_m >= 0, "own_car_height_m", own_car_height_m, ">= 0");
  Require(min_baseline_m > 0, "min_baseline_m", min_baseline_m, "> 0");
  Require(min_obstacle_height_m >= 0, "min_obstacle_height_m", min_obstacle_height_m, ">= 0");
  Require(min_static_distance_m > 0, "min_static_distance_m", min_static_distance_m, "> 0");
  Require(min_view_scale > 0 && min_view_scale <= 1, "min_view_scale", min_view_scale, "0 < s <= 1");
  Require(motion_tolerance > 0, "motion_tolerance", motion_tolerance, "> 0");
  Require(min_motion_disparity_px >= 0, "min_motion_disparity_px", min_motion_disparity_px, ">= 0");
  Require(max_contact_jump_m > 0, "max_contact_jump_m", max_contact_jump_m, "> 0");
  Require(disparity_sigma_px > 0, "disparity_sigma_px", disparity_sigma_px, "> 0");
  Require(static_gate >= 0, "static_gate", static_gate, ">= 0 (0 = placed by the contact alone)");
  Require(member_min_score >= 0 && member_min_score <= 1, "member_min_score", member_min_score, "in [0, 1]");
  Require(max_gap_below_m >= 0, "max_gap_below_m", max_gap_below_m, ">= 0");
  Require(contact_tolerance_px >= 0, "contact_tolerance_px", contact_tolerance_px, ">= 0");
  Require(contact_trim_rows >= 0 && contact_trim_rows < view_height, "contact_trim_rows", contact_trim_rows, "0 <= rows < view_height");
  Require(pacing_road_contrast_px > 0, "pacing_road_contrast_px", pacing_road_contrast_px, "> 0");
  stereo.Check();
}

SideDetector::SideDetector(const Rig& rig, const std::string& camera, Side side,
                           const SideDetectorOptions& options)
    : camera_(rig.Camera(camera)), side_(side), vehicle_(rig.vehicle), options_(options),
      camera_height_m_(-camera_.vehicle_from_camera.t.y()) {
  options.Check();
  options_.histogram.min_disparity = options.stereo.min_disparity;
  options_.histogram.max_disparity = options.stereo.min_disparity + options.stereo.num_disparities;
  options_.histogram.two_sided = true;
  options_.histogram.Check();
  matcher_ = std::make_unique<SadStereoMatcher>(options.stereo);
}

SideDetector::~SideDetector() = default;

namespace {
// A side view's width and the share of its columns behind the principal column, at `scale`.
std::pair<int, double> SideViewColumns(const SideDetectorOptions& o, double scale) {
  const int width = static_cast<int>(std::lround(o.view_width * scale));
  if (o.back_half_angle_deg <= 0.0 && o.forward_half_angle_deg <= 0.0) return {width, 0.5};
  // Each half as view_width gives, or focal_px x tan of its angle.
  auto half = [&](double angle_deg) {
    return angle_deg > 0.0 ? o.focal_px * scale * std::tan(angle_deg * kRadPerDeg) : (width - 1) / 2.0;
  };
  const double front = half(o.forward_half_angle_deg), back = half(o.back_half_angle_deg);
  const int total = static_cast<int>(std::lround(front + back)) + 1;
  return {total, (total - 1 - front) / (total - 1)};
}
}  // namespace

ViewSpec SideDetectorViewSpec(Side side, const SideDetectorOptions& o, double scale, double yaw_rad) {
  const auto [width, back_fraction] = SideViewColumns(o, scale);
  return SideViewSpec(side, width, static_cast<int>(std::lround(o.view_height * scale)), o.focal_px * scale, yaw_rad,
                      o.horizon_fraction, back_fraction);
}

std::pair<int, int> SideMatchedColumns(Side side, int width, const StereoOptions& stereo) {
  const auto [first, last] = MatchedColumns(width, stereo);
  if (side == Side::kLeft) return {width - 1 - last, width - 1 - first};
  return {first, last};
}

bool Persisting(const std::vector<Eigen::Vector2d>& points, const std::vector<std::vector<Eigen::Vector2d>>& earlier,
              double distance) {
  std::vector<double> nearest;
  for (const Eigen::Vector2d& b : points) {
    double d2 = std::numeric_limits<double>::infinity();
    for (const std::vector<Eigen::Vector2d>& component : earlier) {
      for (const Eigen::Vector2d& a : component) d2 = std::min(d2, (a - b).squaredNorm());
    }
    nearest.push_back(d2);
  }
  return !nearest.empty() && Median(nearest) <= distance * distance;
}

int ConnectedTop(const cv::Mat& disparity, int x, int bottom, double disparity_px, double tolerance_px, int max_gap_px,
                 const std::function<bool(int)>& member) {
  CV_Assert(disparity.type() == CV_32F && x >= 0 && x < disparity.cols && bottom >= 0 && bottom < disparity.rows);
  int top = bottom, gap = 0;
  for (int y = bottom - 1; y >= 0; --y) {
    const float v = disparity.at<float>(y, x);
    if (!std::isfinite(v)) {
      if (++gap > max_gap_px) break;
      continue;
    }
    if (!member(y) && !(std::abs(v - disparity_px) <= tolerance_px)) break;
    top = y;
    gap = 0;
  }
  return top;
}

int SideDetector::ScaleSixteenths(double baseline_m) const {
  const double upper = options_.stereo.min_disparity + options_.stereo.num_disparities - 1;
  const double scale = upper * options_.min_static_distance_m / (options_.focal_px * baseline_m);
  const int lowest = static_cast<int>(std::ceil(16 * options_.min_view_scale));
  return std::clamp(static_cast<int>(std::floor(16 * scale)), std::min(lowest, 16), 16);
}

SideViewCache& SideDetector::Views(int sixteenths) {
  std::unique_ptr<SideViewCache>& views = views_[sixteenths];
  if (!views) {
    const double s = sixteenths / 16.0;
    const auto [width, back_fraction] = SideViewColumns(options_, s);
    views = std::make_unique<SideViewCache>(camera_, side_, width, static_cast<int>(std::lround(options_.view_height * s)),
                                            options_.focal_px * s, kSideViewYawStepRad, 16, options_.horizon_fraction,
                                            back_fraction);
  }
  return *views;
}

const SideDetector::ViewGeometry& SideDetector::Geometry(const VirtualView& view, std::pair<int, long> key) {
  const auto it = geometry_.find(key);
  if (it != geometry_.end()) return it->second;
  if (geometry_.size() > 64) geometry_.clear();  // a long turn through many yaws
  ViewGeometry g;
  g.ignore = OwnCarMask(view, vehicle_, options_.own_car_height_m);
  cv::bitwise_or(g.ignore, view.mask() == 0, g.ignore);
  if (!view.own_car().empty()) g.ignore |= view.own_car();  // as estimated from the drive
  // Matched as prepared: mirrored for the left side.
  g.valid = view.mask().clone();
  if (side_ == Side::kLeft) cv::flip(g.valid, g.valid, 1);
  g.inverse_depth = RoadInverseDepth(view);
  return geometry_.emplace(key, std::move(g)).first->second;
}

bool SideDetector::MatchPair(const cv::Mat& previous_omni, const cv::Mat& current_omni,
                             const PlanarPose& current_in_previous, bool continuing, SideResult* r, Matched* m) {
  const bool had_last = last_valid_;
  last_valid_ = false;  // until this call has matched
  // The camera's displacement, in the previous frame's vehicle frame.
  const Pose rel = current_in_previous.ToPose3();
  const Eigen::Vector3d t = camera_.vehicle_from_camera.t;
  const Eigen::Vector3d delta = rel.Apply(t) - t;
  r->baseline_m = std::hypot(delta.x(), delta.z());
  if (r->baseline_m < options_.min_baseline_m) {
    r->skipped = true;
    r->reason = Str("camera moved ", r->baseline_m, " m (< ", options_.min_baseline_m, " m)");
    return false;
  }
  // Both views parallel to the displacement: heading alpha in the previous frame, alpha - dh in
  // the current one. SideViewSpec's yaw turns towards the front on either side.
  const double alpha = std::atan2(delta.x(), delta.z());
  // The displacement's direction in the current vehicle frame (for the velocity measurement).
  m->direction = WorldToBodyDirection(current_in_previous, Eigen::Vector2d(delta.x(), delta.z()).normalized());
  const double sign = side_ == Side::kLeft ? 1.0 : -1.0;
  const int sixteenths = ScaleSixteenths(r->baseline_m);
  // A static object as deep as the views keep (max_depth_m) must shift by min_motion_disparity_px:
  // with less, nothing there is told from something keeping pace with us or from the road (slow
  // driving, high frame rates, coarse images).
  const double shift_px = options_.focal_px * sixteenths / 16.0 * r->baseline_m / options_.max_depth_m;
  if (shift_px < options_.min_motion_disparity_px) {
    r->skipped = true;
    r->reason = Str("camera moved ", r->baseline_m, " m: a static object ", options_.max_depth_m, " m deep shifts ",
                    shift_px, " px (< min_motion_disparity_px ", options_.min_motion_disparity_px, ")");
    return false;
  }
  r->view_scale = sixteenths / 16.0;
  r->motion = {camera_.name, {t.x(), t.z()}, std::atan2(m->direction.x(), m->direction.y()),
               options_.focal_px * r->view_scale * r->baseline_m / options_.disparity_sigma_px};
  SideViewCache& views = Views(sixteenths);
  const VirtualView& previous_view = views.Get(sign * alpha);
  const std::pair<int, long> previous_key{sixteenths, views.Key(sign * alpha)};
  // The last call's current view, when it is this call's previous one.
  const bool reuse = continuing && had_last && last_key_ == previous_key;
  views_reused_ += reuse;
  const cv::Mat previous = reuse ? last_view_ : previous_view.Render(GreyImage(previous_omni));
  const VirtualView& current_view = views.Get(sign * (alpha - current_in_previous.heading_rad));
  const std::pair<int, long> current_key{sixteenths, views.Key(sign * (alpha - current_in_previous.heading_rad))};
  const cv::Mat current = current_view.Render(GreyImage(current_omni));
  // The current frame is the reference, so that moving objects are placed where they are now.
  // The camera moves along -x of a right view: static things move right from the previous to the
  // current image, so current(x) matches previous(x - d) with d = f B / depth > 0, the matcher's
  // convention. A left view moves along +x: mirrored left to right, the images follow the same
  // convention, and the disparity is mirrored back.
  m->reference = &current_view;
  r->reference_view = current;
  r->other_view = previous;
  const ViewSpec& spec = current_view.spec();
  // (The previous view's validity first: looking up a geometry may drop the others.)
  const cv::Mat previous_valid = reuse ? cv::Mat() : Geometry(previous_view, previous_key).valid;
  m->geometry = &Geometry(current_view, current_key);
  // Both views prefiltered as matched (mirrored for the left side); the current one is kept for
  // the next call.
  const auto prepare = [&](const cv::Mat& view, const cv::Mat& valid, SadStereoMatcher::PreparedView* prepared) {
    if (side_ == Side::kLeft) {
      cv::Mat mirrored;
      cv::flip(view, mirrored, 1);
      matcher_->Prepare(mirrored, prepared, valid);
    } else {
      matcher_->Prepare(view, prepared, valid);
    }
  };
  if (!reuse) prepare(previous, previous_valid, &last_prepared_);
  prepare(current, m->geometry->valid, &prepared_);
  r->disparity = matcher_->Compute(prepared_, last_prepared_);
  if (side_ == Side::kLeft) cv::flip(r->disparity, r->disparity, 1);
  const auto [matched_first, matched_last] = SideMatchedColumns(side_, spec.width, options_.stereo);
  r->sector = ViewColumnsSector(camera_.name, {t.x(), t.z()}, spec, matched_first, matched_last, options_.max_depth_m);
  std::swap(last_prepared_, prepared_);
  last_view_ = current;
  last_key_ = current_key;
  last_valid_ = true;
  r->disparity.setTo(kInvalidDisparity, m->geometry->ignore);
  return true;
}

SideResult SideDetector::Detect(const cv::Mat& previous_omni, const cv::Mat& current_omni,
                                const PlanarPose& current_in_previous, double interval_s, bool continuing) {
  SideResult r;
  Matched m;
  if (!MatchPair(previous_omni, current_omni, current_in_previous, continuing, &r, &m)) {
    last_components_.clear();
    return r;
  }
  const ViewSpec& spec = m.reference->spec();
  const cv::Mat road = RoadDisparity(m.geometry->inverse_depth, spec.focal_px, r.baseline_m);
  const HistogramOptions& ho = options_.histogram;
  r.score = ScoreImage(r.disparity, road, ho, RoadRamp(road, options_.stereo.block_height / 2 + 1));
  cv::Mat moments, labels;
  r.histogram = ColumnHistogram(r.disparity, r.score, ho, &moments);
  const std::vector<HistogramComponent> components = FindComponents(r.histogram, ho, &labels, moments);
  r.obstacle = cv::Mat(spec.height, spec.width, CV_8U, cv::Scalar(0));
  const auto [first_valid, last_valid] = ValidColumns(r.disparity);
  const int margin = options_.stereo.block_width;
  const ContactSearch search{*m.reference, r.disparity, r.score, labels, m.geometry->ignore, road, r.baseline_m, options_};
  // The last call's components count for the pacing test only when it matched the previous frame.
  std::vector<std::vector<Eigen::Vector2d>> last_components;
  if (continuing) last_components.swap(last_components_);
  last_components_.clear();
  int id = 0;
  for (const HistogramComponent& c : components) {
    std::vector<Contact> contacts = ComponentContacts(search, c);
    contacts = ConsistentContacts(std::move(contacts), options_.min_motion_disparity_px, options_.motion_tolerance);
    contacts = ContinuousContacts(contacts, options_.max_contact_jump_m);
    if (options_.median_contacts) {
      contacts = MedianContacts(std::move(contacts), options_.stereo.block_width / 2, *m.reference, r.baseline_m);
    }
    std::vector<Eigen::Vector2d> points;
    std::vector<double> heights, tops, disparities;
    std::vector<const Contact*> kept;
    // The height test over all the component's columns: the columns that are not solid are its low
    // ones, and without them low components (road, kerbs) would pass it.
    std::vector<Contact> solid;
    for (const Contact& k : contacts) {
      heights.push_back(k.height);
      tops.push_back(TopOf(k, options_.stereo.block_height, spec.focal_px));
      if (k.solid) solid.push_back(k);
    }
    for (const Contact& k : solid) {
      if (k.ground.norm() > options_.max_range_m || k.row_depth > options_.max_depth_m) continue;
      points.push_back(k.ground);
      disparities.push_back(std::abs(k.disparity));
      kept.push_back(&k);
    }
    if (points.empty() || Median(heights) < options_.min_obstacle_height_m) continue;
    last_components_.push_back(points);
    const bool pacing = Median(disparities) < options_.min_motion_disparity_px;
    if (pacing && options_.pacing_persistence_m > 0 && !Persisting(points, last_components, options_.pacing_persistence_m)) {
      continue;
    }
    if (pacing && options_.max_vehicle_width_m > 0) {
      const auto [nearest, farthest] = std::minmax_element(kept.begin(), kept.end(), [](const Contact* a, const Contact* b) {
        return a->depth < b->depth;
      });
      if ((*farthest)->depth - (*nearest)->depth > options_.max_vehicle_width_m) continue;
    }
    // The object's top above the road: three quarters of its columns reach at least this high. An
    // obstacle's top stands min_obstacle_height_m above the road too (a kerb's or a road band's
    // mismatch does not).
    const double top = UpperQuartile(&tops);
    if (top < options_.min_obstacle_height_m) continue;
    if (pacing && options_.pacing_above_camera) {
      // Only for a component keeping pace: the walk up every column is not needed for the others.
      std::vector<double> standing;
      for (const Contact& k : contacts) standing.push_back(StandingHeight(search, c, k));
      if (UpperQuartile(&standing) <= camera_height_m_) continue;
    }
    for (const Contact* k : kept) r.obstacle.at<std::uint8_t>(k->y, k->x) = 255;
    Detection det = DetectionFromPoints(points, camera_.name);
    det.height_m = top;
    if (c.x_begin <= first_valid + margin) det.clipped_ends.push_back(points.front());
    if (c.x_end - 1 >= last_valid - margin) det.clipped_ends.push_back(points.back());
    det.id = id++;
    if (interval_s > 0 && solid.size() >= 3) {
      MeasureMotion(solid, r.baseline_m, spec.focal_px, interval_s, options_.disparity_sigma_px, &det);
      det.motion_direction = m.direction;
    }
    r.detections.push_back(std::move(det));
  }
  return r;
}

}  // namespace dps
