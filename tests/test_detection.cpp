// Tests of obstacle detection and scoring: the column histogram of a known disparity image,
// the front projection against hand-computed points, fusion of parts, the scoring rules of
// DESIGN.md §5 on hand-made cases (tracks' velocity errors too), and front detection on rendered
// drives with known truth (a lead car, the empty road, a pole beyond a parked car, two cars parked
// in a row).
#include <algorithm>
#include <cmath>
#include <map>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "check.h"
#include "fixtures.h"
#include "dps/camera/rig_io.h"
#include "dps/detect/disparity_histogram.h"
#include "dps/detect/front_detection.h"
#include "dps/eval/evaluation.h"
#include "dps/eval/visibility.h"
#include "dps/map/tracker.h"
#include "dps/pipeline/surround_pipeline.h"
#include "dps/pipeline/drive_processing.h"
#include "dps/stereo/sad_stereo.h"
#include "dps/synth/scene_io.h"
#include "dps/synth/scene_renderer.h"
#include "dps/synth/synth.h"
#include "dps/synth/truth.h"
#include "dps/util/error.h"

namespace {

using dps_test::kSource;
constexpr double kRangeTolFraction = 0.03;  // front range error on the rendered lead car
constexpr double kExtentTolM = 0.75;         // sides of its extent vs its back (the scoring tolerance)

void TestHistogram() {
  // Road disparity 0.5 (y - 20) below row 20; an obstacle at d = 12.3 in columns 30..50, rows
  // 10..40; the rest of the image is road.
  const int w = 80, h = 60;
  cv::Mat road(h, w, CV_32F, cv::Scalar(dps::kInvalidDisparity)), disp(h, w, CV_32F);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (y > 20) road.at<float>(y, x) = 0.5f * (y - 20);
      disp.at<float>(y, x) = y > 20 ? 0.5f * (y - 20) : dps::kInvalidDisparity;
      if (x >= 30 && x <= 50 && y >= 10 && y <= 40) disp.at<float>(y, x) = 12.3f;
    }
  }
  dps::HistogramOptions o;
  o.max_disparity = 32;
  o.score_ramp_px = 2.0;
  const cv::Mat score = dps::ScoreImage(disp, road, o);
  CHECK_NEAR(score.at<float>(15, 40), 1.0, 0);       // above the horizon: road disparity 0
  CHECK_NEAR(score.at<float>(40, 10), 0.0, 0);       // the road itself
  CHECK_NEAR(score.at<float>(44, 40), 0.0, 0);       // below the obstacle (row 44: road 12)
  CHECK_NEAR(score.at<float>(40, 40), 1.0, 0);       // the obstacle's bottom row: 12.3 vs road 10
  CHECK_NEAR(score.at<float>(42, 40), 0.0, 0);       // road again below it
  cv::Mat moments;
  const cv::Mat hist = dps::ColumnHistogram(disp, score, o, &moments);
  CHECK_EQ(hist.rows, 32);
  // Column 40: rows 10..40 vote for bin 12; rows 10..20 and rows up to where the road is 2 px
  // below 12.3 count fully, the last ones partly.
  double expected = 0;
  for (int y = 10; y <= 40; ++y) {
    const double base = y > 20 ? 0.5 * (y - 20) : 0.0;
    expected += std::clamp((12.3 - base) / 2.0, 0.0, 1.0);
  }
  CHECK_NEAR(hist.at<float>(12, 40), expected, 1e-4);
  CHECK_NEAR(hist.at<float>(12, 10), 0.0, 0);
  cv::Mat labels;
  const std::vector<dps::HistogramComponent> c = dps::FindComponents(hist, o, &labels, moments);
  CHECK_EQ(c.size(), size_t{1});
  if (c.size() == 1) {
    CHECK(c[0].x_begin <= 31 && c[0].x_end >= 50);
    CHECK_NEAR(c[0].column_disparity[40 - c[0].x_begin], 12.3, 1e-4);  // exact centroid
  }
  // Far bins need fewer votes: a strong component (bin 16, 20 votes per column, columns 10..20: 8
  // after smoothing, its edge columns 2.4) and a weak far one (bin 6, 6 votes: 2.4 after
  // smoothing, under the threshold of 4 but over 4 x max(0.4, 6.5 / 32) = 1.6).
  {
    cv::Mat far_hist(64, 80, CV_32F, cv::Scalar(0));
    far_hist(cv::Range(16, 17), cv::Range(10, 21)).setTo(20.0f);
    far_hist(cv::Range(6, 7), cv::Range(50, 61)).setTo(6.0f);
    dps::HistogramOptions fo;
    fo.max_disparity = 64;
    const auto by_column = [&](const dps::HistogramOptions& options) {
      std::vector<dps::HistogramComponent> found = dps::FindComponents(far_hist, options);
      std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.x_begin < b.x_begin; });
      return found;
    };
    const std::vector<dps::HistogramComponent> one = by_column(fo);
    fo.far_reference_px = 32;
    const std::vector<dps::HistogramComponent> two = by_column(fo);
    CHECK_EQ(one.size(), size_t{1});
    CHECK_EQ(two.size(), size_t{2});
    if (one.size() == 1 && two.size() == 2) {
      // The strong one as before (its edges, over the lower threshold of its bin, 4 x 16.5 / 32 =
      // 2.06, not taken); the weak one where it is, at its disparity (bin centre 6.5).
      CHECK_EQ(two[0].x_begin, one[0].x_begin);
      CHECK_EQ(two[0].x_end, one[0].x_end);
      CHECK(two[1].x_begin >= 48 && two[1].x_begin <= 50 && two[1].x_end >= 61 && two[1].x_end <= 63);
      CHECK_NEAR(two[1].column_disparity[55 - two[1].x_begin], 6.5, 1e-4);
    }
    fo.far_clearance_columns = 1;  // no clearance: the strong one's edges pass the lower threshold
    const std::vector<dps::HistogramComponent> fat = by_column(fo);
    CHECK(!fat.empty() && !one.empty() && fat[0].x_end - fat[0].x_begin > one[0].x_end - one[0].x_begin);
  }
  // Too few votes: nothing.
  o.min_votes = 1e6;
  CHECK(dps::FindComponents(hist, o).empty());
  o.bin_px = 0;
  CHECK_THROWS_WITH(o.Check(), dps::Error, "bin_px");
  // The columns with any valid disparity: the matcher's border (0..3) and a masked edge (18, 19)
  // hold none; a column with a single valid pixel counts.
  cv::Mat border(10, 20, CV_32F, cv::Scalar(dps::kInvalidDisparity));
  border.colRange(4, 18).setTo(5.0f);
  border.col(4).setTo(dps::kInvalidDisparity);
  border.at<float>(7, 4) = 3.0f;
  const auto [first, last] = dps::ValidColumns(border);
  CHECK_EQ(first, 4);
  CHECK_EQ(last, 17);
  const auto [none_first, none_last] = dps::ValidColumns(cv::Mat(4, 6, CV_32F, cv::Scalar(dps::kInvalidDisparity)));
  CHECK(none_first > none_last);
}

// A slanted surface (disparity 20 falling to 11 across columns 10..100) over a road, with a
// stretch of columns 50..64 where the surface has no texture: linked into one. The same stretch
// showing the road beyond the surface (a real gap between two objects): not linked.
void TestLinking() {
  const int w = 120, h = 80;
  cv::Mat road(h, w, CV_32F, cv::Scalar(dps::kInvalidDisparity));
  for (int y = 21; y < h; ++y) road.row(y).setTo(0.5f * (y - 20));
  for (const bool see_through : {false, true}) {
    cv::Mat disp = road.clone();
    for (int x = 10; x <= 100; ++x) {
      const float d = 20.0f - 0.1f * (x - 10);
      const bool gap = x >= 50 && x <= 64;
      for (int y = 5; y < 20 + 2 * d; ++y) {  // down to where it meets the road
        disp.at<float>(y, x) = gap ? (see_through ? road.at<float>(y, x) : dps::kInvalidDisparity) : d;
      }
    }
    dps::HistogramOptions o;
    o.max_disparity = 40;
    o.link_max_gap = 20;
    const cv::Mat score = dps::ScoreImage(disp, road, o);
    cv::Mat moments, labels;
    const cv::Mat hist = dps::ColumnHistogram(disp, score, o, &moments);
    const std::vector<dps::HistogramComponent> parts = dps::FindComponents(hist, o, &labels, moments);
    CHECK_EQ(parts.size(), size_t{2});
    const std::vector<dps::HistogramComponent> linked = dps::LinkComponents(parts, disp, road, o, &labels);
    CHECK_EQ(linked.size(), see_through ? size_t{2} : size_t{1});
    if (linked.size() != 1) continue;
    CHECK(linked[0].x_begin <= 12 && linked[0].x_end >= 99);
    CHECK_NEAR(linked[0].column_disparity[80 - linked[0].x_begin], 13.0, 0.5);
    CHECK(!std::isfinite(linked[0].column_disparity[57 - linked[0].x_begin]));  // the gap itself
    const int gone = parts[0].label == linked[0].label ? parts[1].label : parts[0].label;
    CHECK_EQ(cv::countNonZero(labels == gone), 0);  // relabelled
    // A veto from the caller keeps them apart.
    const dps::LinkVeto never = [](const dps::HistogramComponent&, int, float, const dps::HistogramComponent&, int,
                                   float) { return false; };
    CHECK_EQ(dps::LinkComponents(parts, disp, road, o, nullptr, never).size(), size_t{2});
  }
  // A pole (disparity 15, columns 36..41) beyond the end of a slanted surface (columns 46..100,
  // disparity 20 falling to 14.6), columns 42..45 between them without texture: near in depth
  // (ratio 1.33), nothing seen through the gap, but off the surface's plane (the surface's line
  // gives 20.4 to 21 over the pole): not linked. The same pole at the disparity the line gives:
  // linked.
  for (const bool on_line : {false, true}) {
    cv::Mat disp = road.clone();
    for (int x = 36; x <= 100; ++x) {
      const bool gap = x >= 42 && x <= 45;
      const float d = x < 46 ? (on_line ? 20.0f + 0.1f * (46 - x) : 15.0f) : 20.0f - 0.1f * (x - 46);
      for (int y = 5; y < 20 + 2 * d; ++y) disp.at<float>(y, x) = gap ? dps::kInvalidDisparity : d;
    }
    dps::HistogramOptions o;
    o.max_disparity = 40;
    o.link_max_gap = 20;
    o.close_width = 1;  // keep the two apart in the histogram
    const cv::Mat score = dps::ScoreImage(disp, road, o);
    cv::Mat moments, labels;
    const cv::Mat hist = dps::ColumnHistogram(disp, score, o, &moments);
    const std::vector<dps::HistogramComponent> parts = dps::FindComponents(hist, o, &labels, moments);
    CHECK_EQ(parts.size(), size_t{2});
    CHECK_EQ(dps::LinkComponents(parts, disp, road, o, &labels).size(), on_line ? size_t{1} : size_t{2});
    o.link_fit_columns = 0;  // without the plane test, linked either way
    CHECK_EQ(dps::LinkComponents(parts, disp, road, o).size(), size_t{1});
  }
}

void TestFrontProjection() {
  const dps::Rig rig = dps::ReadRig(kSource + "/data/rigs/omni_pair.yaml");
  dps::FrontDetectorOptions o;  // 400x200, f = 170
  const dps::FrontDetector front(rig, o);
  Eigen::Vector2d g;
  // Eq. 16 by hand: B = 2 m, d = 34 px -> depth 10 m ahead of the cameras (z = 0.9), lateral from
  // the left camera (x = -1) = (x - cx) depth / f.
  CHECK(front.ColumnToGround(199.5, 34.0, &g));
  CHECK_NEAR(g.x(), -1.0, 1e-9);
  CHECK_NEAR(g.y(), 10.9, 1e-9);
  CHECK(front.ColumnToGround(199.5 + 17.0, 34.0, &g));
  CHECK_NEAR(g.x(), 0.0, 1e-9);
  CHECK(!front.ColumnToGround(100, 0.0, &g));
  // The road disparity at a row below the horizon: ground 1 m below, d = f B / depth with
  // depth = f H / (y - cy).
  CHECK_NEAR(front.road_disparity().at<float>(150, 100), (150 - 99.5) * 2.0 / 1.0, 1e-3);
  CHECK(!std::isfinite(front.road_disparity().at<float>(50, 100)));
}

void TestFusion() {
  auto det = [](double x, double z, const char* source) {
    dps::Detection d = dps::DetectionFromPoints({{x, z}, {x + 0.4, z}}, source);
    d.frame = 3;
    return d;
  };
  const std::vector<dps::Detection> fused =
      dps::FuseDetections({det(1, 10, "front"), det(1.2, 10.5, "left"), det(6, 10, "front")}, 1.0);
  CHECK_EQ(fused.size(), size_t{2});
  int merged = 0;
  for (const dps::Detection& d : fused) {
    if (d.n_points == 4) {
      ++merged;
      CHECK_EQ(d.source, std::string("front"));  // holds the nearest point (1, 10)
      CHECK_NEAR(d.z_min_m, 10.0, 0);
      CHECK_NEAR(d.z_max_m, 10.5, 0);
    }
    CHECK_EQ(d.frame, 3);
  }
  CHECK_EQ(merged, 1);
  // Vehicle parts: a car's side seen by the right camera (x = 2.5, z -0.5..2) and its back seen by
  // the front pair (z = 3.5, x 2.5..4.3) fit a 5 m x 2.2 m footprint together: one object. The
  // side of the next car in the row (z 5..9.5) does not fit with either: kept apart.
  auto line = [](double x0, double z0, double x1, double z1, const char* source) {
    std::vector<Eigen::Vector2d> p;
    for (int i = 0; i <= 10; ++i) p.emplace_back(x0 + (x1 - x0) * i / 10.0, z0 + (z1 - z0) * i / 10.0);
    dps::Detection d = dps::DetectionFromPoints(p, source);
    d.frame = 7;
    return d;
  };
  const std::vector<dps::Detection> parts = {line(2.5, -0.5, 2.5, 2.0, "right"), line(2.5, 3.5, 4.3, 3.5, "front"),
                                             line(2.5, 5.0, 2.5, 9.5, "front")};
  const std::vector<dps::Detection> vehicles = dps::MergeVehicleParts(parts, 5.0, 2.2, false);
  CHECK_EQ(vehicles.size(), size_t{2});
  for (const dps::Detection& d : vehicles) {
    if (d.n_points != 22) continue;
    CHECK_EQ(d.source, std::string("right"));  // its nearest point (2.5, 0) is the side's
    CHECK_NEAR(d.x_m, 2.5, 1e-12);
    CHECK_NEAR(d.z_m, 0.0, 1e-12);
    CHECK_NEAR(d.z_max_m, 3.5, 1e-12);
  }
  // Only across sources: the two front parts would not be tried together anyway; a shorter
  // vehicle keeps the side and the back apart.
  CHECK_EQ(dps::MergeVehicleParts(parts, 5.0, 2.2, true).size(), size_t{2});
  CHECK_EQ(dps::MergeVehicleParts(parts, 3.5, 2.2, false).size(), size_t{3});
  // Two front parts of one car's side (x = 2.5, z 4..6 and 7.5..9; the stretch between without
  // texture) fit one 5 m footprint and are merged. Seen from the front pair at (0, 0.9), the
  // stretch is a gap between two objects when the pair saw something behind it on the same
  // bearings (a wall at x = 5): then kept apart — unless no viewpoints are given.
  const dps::Detection near_part = line(2.5, 4.0, 2.5, 6.0, "front"), far_part = line(2.5, 7.5, 2.5, 9.0, "front");
  const std::map<std::string, Eigen::Vector2d> viewpoints = {{"front", Eigen::Vector2d(0, 0.9)}};
  CHECK_EQ(dps::MergeVehicleParts({near_part, far_part}, 5.0, 2.2, false, viewpoints).size(), size_t{1});
  std::vector<Eigen::Vector2d> wall;
  for (double z = 8.0; z <= 16.0; z += 0.02) wall.emplace_back(5.0, z);
  dps::Detection behind = dps::DetectionFromPoints(wall, "front");
  behind.frame = 7;
  CHECK_EQ(dps::MergeVehicleParts({near_part, far_part, behind}, 5.0, 2.2, false, viewpoints).size(), size_t{3});
  CHECK_EQ(dps::MergeVehicleParts({near_part, far_part, behind}, 5.0, 2.2, false).size(), size_t{2});
  // The front pair's depth error (half a pixel of disparity at f = 170 px, B = 2.2 m: k r^2 with
  // k = 0.5 / 374 per metre) at each part's far end: two parts of one car's side spanning 5.8 m at
  // 9-15 m (0.27 m and 0.15 m of error there) fit a 5.5 m footprint; the same 5.8 m at 1.5-7.5 m
  // (0.06 m and 0.02 m) do not; without the error neither does.
  const std::map<std::string, double> depth_error = {{"front", 0.5 / (170.0 * 2.2)}};
  const dps::Detection side_a = line(2.5, 9.0, 2.5, 11.0, "front"), side_b = line(2.5, 13.2, 2.5, 14.8, "front");
  CHECK_EQ(dps::MergeVehicleParts({side_a, side_b}, 5.5, 2.2, false, viewpoints, depth_error).size(), size_t{1});
  CHECK_EQ(dps::MergeVehicleParts({side_a, side_b}, 5.5, 2.2, false, viewpoints).size(), size_t{2});
  const dps::Detection close_a = line(2.5, 1.5, 2.5, 3.5, "front"), close_b = line(2.5, 5.7, 2.5, 7.3, "front");
  CHECK_EQ(dps::MergeVehicleParts({close_a, close_b}, 5.5, 2.2, false, viewpoints, depth_error).size(), size_t{2});
}

// A rig with one pinhole camera (unified, xi = 0; 640x480, f = 300 px) 1.2 m above the road at
// the front of a 4.5 m x 1.8 m car, looking straight ahead.
dps::Rig ForwardCameraRig() {
  dps::Rig rig;
  rig.vehicle.length_m = 4.5;
  rig.vehicle.width_m = 1.8;
  Eigen::Matrix3d K;
  K << 300, 0, 319.5, 0, 300, 239.5, 0, 0, 1;
  dps::Pose pose;
  pose.t = Eigen::Vector3d(0, -1.2, 2.5);
  rig.cameras.push_back({"front", dps::CameraModel::Unified(640, 480, K, 0.0), pose, cv::Mat(), "", cv::Mat()});
  return rig;
}

// Which objects the cameras see (DESIGN.md §5): faces turned to the camera, the field, the mask,
// the own car and other objects hiding them.
void TestVisibility() {
  dps::Rig rig = ForwardCameraRig();
  const dps::TruthRow car{0, 0.0, 1, "car", 0.0, 10.0, 0.0, 4.5, 1.8, 1.5, 0, 0};
  const dps::Visibility vis(rig);
  // The camera (x = 0, 1.2 m high, below the car's 1.5 m roof) sees only the car's back face: its
  // share of the box's surface is w h / 2 (w h + l h + l w).
  const double back = 1.8 * 1.5 / (2 * (1.8 * 1.5 + 4.5 * 1.5 + 4.5 * 1.8));
  CHECK_NEAR(vis.SeenFraction(car, {&car}, 0), back, 1e-9);
  CHECK(vis.Sees(car, {&car}));
  // Moved 1 m to the right, its left side shows too: more than the back alone.
  dps::TruthRow right = car;
  right.x_m = 1.5;
  CHECK(vis.SeenFraction(right, {&right}, 0) > back + 0.01);
  // Behind the car: outside the field.
  dps::TruthRow behind = car;
  behind.z_m = -10.0;
  CHECK_NEAR(vis.SeenFraction(behind, {&behind}, 0), 0.0, 0);
  CHECK(!vis.Sees(behind, {&behind}));
  // Hidden behind a truck (3.5 m high, 2.5 m wide, 8 m long, z 8..16) a car at 20 m is not seen;
  // without the truck it is.
  dps::TruthRow hidden = car;
  hidden.id = 2;
  hidden.z_m = 20.0;
  const dps::TruthRow truck{0, 0.0, 3, "truck", 0.0, 12.0, 0.0, 8.0, 2.5, 3.5, 0, 0};
  CHECK_NEAR(vis.SeenFraction(hidden, {&hidden, &truck}, 0), 0.0, 0);
  CHECK_NEAR(vis.SeenFraction(hidden, {&hidden}, 0), back, 1e-9);
  // A low object (0.5 m) right beside the car is hidden by the own car (1.5 m high) from a camera
  // in the left mirror looking right across it, and seen with an own car 0.3 m high.
  dps::Rig mirror = rig;
  mirror.cameras[0].vehicle_from_camera.t = Eigen::Vector3d(-1.0, -1.2, 0.5);
  mirror.cameras[0].vehicle_from_camera.R = dps::AxisAngle(Eigen::Vector3d::UnitY(), M_PI / 2);  // z -> +X
  const dps::TruthRow low{0, 0.0, 4, "box", 3.0, 0.5, 0.0, 1.0, 1.0, 0.5, 0, 0};
  CHECK_NEAR(dps::Visibility(mirror).SeenFraction(low, {&low}, 0), 0.0, 0);
  dps::VisibilityOptions flat;
  flat.own_car_height_m = 0.3;
  CHECK(dps::Visibility(mirror, flat).SeenFraction(low, {&low}, 0) > 0.05);
  // A mask that sees nothing.
  rig.cameras[0].mask = cv::Mat::zeros(480, 640, CV_8U);
  CHECK(!dps::Visibility(rig).Sees(car, {&car}));
  dps::VisibilityOptions bad;
  bad.min_seen_fraction = 0.0;
  CHECK_THROWS_WITH(dps::Visibility(ForwardCameraRig(), bad), dps::Error, "min_seen_fraction");
}

void TestEvaluation() {
  dps::TruthRow car{0, 0.0, 1, "car", 0.0, 10.0, 0.0, 4.5, 1.8, 1.5, 0, 0};
  dps::TruthRow far{0, 0.0, 2, "car", 0.0, 30.0, 0.0, 4.5, 1.8, 1.5, 0, 0};   // beyond 20 m
  dps::TruthRow side{0, 0.0, 3, "car", -4.0, 0.0, 0.0, 4.5, 1.8, 1.5, 0, 0};  // beside, left
  CHECK_NEAR(dps::NearPoint(car).y(), 7.75, 1e-12);
  CHECK_NEAR(dps::NearPoint(side).x(), -3.1, 1e-12);
  CHECK_NEAR(dps::DistanceToFootprint(car, {0.5, 9.0}), 0.0, 1e-12);  // inside
  CHECK_NEAR(dps::DistanceToFootprint(car, {3.0, 10.0}), 2.1, 1e-12);
  auto det = [](double x, double z, const char* source) {
    dps::Detection d = dps::DetectionFromPoints({{x, z}}, source);
    d.frame = 0;
    return d;
  };
  // One hit on the car (0.15 m short, within max(0.75, 0.775)), one false detection, one
  // detection within tolerance of the side car but from a second part (only one may match).
  const std::vector<dps::Detection> dets = {det(0.3, 7.6, "front"), det(6, 5, "front"), det(-3.0, 0.2, "left"),
                                            det(-3.2, 0.6, "left")};
  dps::EvaluationOptions o;
  dps::EvaluationResult r = dps::Evaluate(dets, {car, far, side}, o);
  CHECK_EQ(r.overall.objects, 2);
  CHECK_EQ(r.overall.matched_objects, 2);
  CHECK_EQ(r.overall.detections, 4);
  CHECK_EQ(r.overall.matched_detections, 2);
  CHECK_NEAR(r.overall.Recall(), 1.0, 0);
  CHECK_NEAR(r.overall.Precision(), 0.5, 0);
  CHECK_EQ(r.bands[0].objects, 2);  // both near points within 10 m
  // The false ones: (6, 5) near nothing (a phantom); the side car's second part a duplicate of
  // the side car (id 3), 0.1 m from its footprint.
  CHECK_EQ(r.false_causes[static_cast<int>(dps::FalseCause::kPhantom)], 1);
  CHECK_EQ(r.false_causes[static_cast<int>(dps::FalseCause::kDuplicate)], 1);
  CHECK_EQ(r.false_causes[static_cast<int>(dps::FalseCause::kMisplaced)], 0);
  CHECK_EQ(r.sources[1].source, std::string("left"));
  CHECK_EQ(r.sources[1].false_causes[static_cast<int>(dps::FalseCause::kDuplicate)], 1);
  for (const dps::ScoringError& e : r.errors) {
    if (e.missed) continue;
    CHECK_EQ(e.near_object_id, e.cause == dps::FalseCause::kDuplicate ? 3 : -1);
    if (e.cause == dps::FalseCause::kDuplicate) CHECK_NEAR(e.near_object_m, 0.1, 1e-9);
  }
  CHECK(dps::EvaluationJson(r).find("\"false_causes\": {\"duplicate\": 1, \"misplaced\": 0, \"phantom\": 1}") !=
        std::string::npos);
  // Range errors: the side car takes the detection inside its footprint (distance 0 beats 0.1):
  // |range(-3.2, 0.6) - 3.1|; the car |range(0.3, 7.6) - 7.75|.
  std::vector<double> errors = r.overall.range_errors_m;
  std::sort(errors.begin(), errors.end());
  CHECK_NEAR(errors[0], std::abs(std::hypot(0.3, 7.6) - 7.75), 1e-9);
  CHECK_NEAR(errors[1], std::abs(std::hypot(-3.2, 0.6) - 3.1), 1e-9);
  // Zones by the near point: the car ahead (front), the side car (side), a car 10 m behind (rear);
  // the false detection (6, 5) by its own point (front of the 4.8 m default length).
  const dps::TruthRow behind{0, 0.0, 6, "car", 0.0, -12.25, 0.0, 4.5, 1.8, 1.5, 0, 0};
  r = dps::Evaluate(dets, {car, far, side, behind}, o);
  CHECK_EQ(r.zones.size(), size_t{3});
  CHECK(r.zones[0].name == "front" && r.zones[1].name == "side" && r.zones[2].name == "rear");
  CHECK_EQ(r.zones[0].objects, 1);
  CHECK_EQ(r.zones[1].objects, 1);
  CHECK_EQ(r.zones[2].objects, 1);
  CHECK_EQ(r.zones[2].matched_objects, 0);
  CHECK_EQ(r.zones[0].detections, 2);
  CHECK_EQ(r.zones[0].matched_detections, 1);
  CHECK_EQ(r.zones[1].detections, 2);
  CHECK_EQ(r.overall.objects, 3);
  // By kind: a pole beside the side car, missed, is the only pole.
  const dps::TruthRow pole{0, 0.0, 7, "pole", 4.0, 2.0, 0.0, 0.2, 0.2, 3.0, 0, 0};
  r = dps::Evaluate(dets, {car, far, side, behind, pole}, o);
  CHECK_EQ(r.kinds.size(), size_t{2});
  CHECK(r.kinds[0].name == "car" && r.kinds[1].name == "pole");
  CHECK_EQ(r.kinds[0].objects, 3);
  CHECK_EQ(r.kinds[0].matched_objects, 2);
  CHECK_EQ(r.kinds[1].objects, 1);
  CHECK_EQ(r.kinds[1].matched_objects, 0);
  CHECK(dps::EvaluationJson(r).find("\"kinds\": [{\"band\": \"car\", \"objects\": 3, \"matched_objects\": 2") !=
        std::string::npos);
  // With a rig whose one camera looks ahead (below), the car behind is seen by no camera and does
  // not count; a detection matching it is still a true one.
  o.visibility = std::make_shared<const dps::Visibility>(ForwardCameraRig());
  r = dps::Evaluate({det(0.3, 7.6, "front"), det(0.0, -10.0, "left")}, {car, behind}, o);
  CHECK_EQ(r.overall.objects, 1);
  CHECK_EQ(r.overall.matched_objects, 1);
  CHECK_EQ(r.overall.detections, 2);
  CHECK_EQ(r.overall.matched_detections, 2);
  CHECK_EQ(r.zones[2].objects, 0);
  CHECK_EQ(r.zones[2].detections, 1);
  o.visibility = nullptr;
  // A further restriction to a front-only field of view (+-50 degrees from (0, 0.9)) leaves out
  // the side and rear cars, the left detections and (6, 5), 55.6 degrees off the axis.
  o.coverage.sectors.push_back({"front", {0, 0.9}, 0.0, 50.0 * M_PI / 180.0});
  r = dps::Evaluate(dets, {car, far, side, behind}, o);
  CHECK_EQ(r.overall.objects, 1);
  CHECK_EQ(r.overall.detections, 1);
  o.coverage = dps::Coverage();
  // A car whose near point is 19.5 m away (z 19.5..24) is counted; a detection inside its
  // footprint at 20.3 m, outside the zone, still matches it (recall 1) but is not counted for
  // precision. A detection in the zone on the same car is taken first, and then the one outside
  // is left over, neither matched nor false.
  const dps::TruthRow edge{0, 0.0, 5, "car", 0.0, 21.75, 0.0, 4.5, 1.8, 1.5, 0, 0};
  r = dps::Evaluate({det(0.2, 20.3, "front")}, {edge}, dps::EvaluationOptions{});
  CHECK_EQ(r.overall.objects, 1);
  CHECK_EQ(r.overall.matched_objects, 1);
  CHECK_EQ(r.overall.detections, 0);
  CHECK(dps::ScoringErrorsCsv(r) == "frame,error,id,kind,x,z,range,cause,near_id,near_m\n");
  r = dps::Evaluate({det(0.2, 20.3, "front"), det(0.1, 18.9, "front")}, {edge}, dps::EvaluationOptions{});
  CHECK_EQ(r.overall.matched_objects, 1);
  CHECK_EQ(r.overall.detections, 1);
  CHECK_EQ(r.overall.matched_detections, 1);
  CHECK_NEAR(r.overall.range_errors_m.at(0), std::abs(std::hypot(0.1, 18.9) - 19.5), 1e-9);
  // Detections more than the tolerance away do not match; the error list names the missed car
  // (id 1, near point (0, 7.75)) and the false detection (front, (2, 7)): the car misplaced, 1.1 m
  // beside and 0.75 m before its footprint (1.331 m, within twice its 0.775 m tolerance). 2 m
  // farther out, nothing is near it.
  r = dps::Evaluate({det(2.0, 7.0, "front")}, {car}, dps::EvaluationOptions{});
  CHECK_EQ(r.overall.matched_objects, 0);
  CHECK(dps::EvaluationJson(r).find("\"recall\": 0.0000") != std::string::npos);
  CHECK_EQ(dps::ScoringErrorsCsv(r), std::string("frame,error,id,kind,x,z,range,cause,near_id,near_m\n"
                                                 "0,missed,1,car,0.000,7.750,7.750,,,\n"
                                                 "0,false,-1,front,2.000,7.000,7.280,misplaced,1,1.331\n"));
  r = dps::Evaluate({det(4.0, 7.0, "front")}, {car}, dps::EvaluationOptions{});
  CHECK_EQ(r.false_causes[static_cast<int>(dps::FalseCause::kPhantom)], 1);
  CHECK(dps::EvaluationTable(r).find("0 duplicate (a second detection of a found object), 0 misplaced") !=
        std::string::npos);
  // An empty road of 10 frames with a false detection in frame 3 (and one 30 m out in frame 5):
  // without the drive's frame count only the frames with detections are known; with it, 1 of 10
  // frames has a detection in the zone.
  dps::Detection late = det(0.0, 3.0, "front"), far_out = det(0.0, 30.0, "front");
  late.frame = 3;
  far_out.frame = 5;
  r = dps::Evaluate({late, far_out}, {}, dps::EvaluationOptions{});
  CHECK_EQ(r.frames, 2);
  dps::EvaluationOptions drive;
  drive.frame_count = 10;
  r = dps::Evaluate({late, far_out}, {}, drive);
  CHECK_EQ(r.frames, 10);
  CHECK_EQ(r.frames_with_detections, 1);
  CHECK_EQ(r.overall.detections, 1);
  drive.frame_count = -1;
  CHECK_THROWS_WITH(dps::Evaluate({}, {}, drive), dps::Error, "evaluation option frame_count = -1");
}

// Tracks' velocity errors: a pole standing at (3, 5) tracked at 0.2 m/s and a car driving at
// 10 m/s tracked at 9, 8 and 13 m/s over three frames. All six matches: median 1 m/s (nearest
// rank of 0.2, 0.2, 0.2, 1, 2, 3); the car's alone (moving at 0.5 m/s or more): median 2, 90th
// percentile 3 m/s; with a moving speed above every object's, none.
void TestTrackVelocities() {
  std::vector<dps::TruthRow> truth;
  std::vector<dps::TrackState> tracks;
  const double car_vz[] = {9.0, 8.0, 13.0};
  for (int f = 0; f < 3; ++f) {
    truth.push_back({f, f / 15.0, 1, "pole", 3.0, 5.0, 0.0, 0.2, 0.2, 3.0, 0.0, 0.0});
    truth.push_back({f, f / 15.0, 2, "car", 0.0, 12.0, 0.0, 4.5, 1.8, 1.5, 0.0, 10.0});
    for (const int id : {1, 2}) {
      dps::TrackState t;
      t.frame = f;
      t.t_s = f / 15.0;
      t.id = id;
      t.confirmed = true;
      t.x_m = id == 1 ? 3.0 : 0.0;
      t.z_m = id == 1 ? 5.0 : 10.0;
      t.vx_mps = id == 1 ? 0.2 : 0.0;
      t.vz_mps = id == 1 ? 0.0 : car_vz[f];
      tracks.push_back(t);
    }
  }
  dps::EvaluationOptions o;
  const dps::BandScore all = dps::EvaluateTracks(tracks, truth, o).positions.overall;
  std::printf("track velocities: median %.3f m/s over %zu matches, moving objects median %.3f / p90 %.3f m/s over %zu\n",
              all.MedianVelocityError(), all.velocity_errors_mps.size(), all.MedianMovingVelocityError(),
              all.MovingVelocityErrorP90(), all.moving_velocity_errors_mps.size());
  CHECK_EQ(all.velocity_errors_mps.size(), size_t{6});
  CHECK_NEAR(all.MedianVelocityError(), 1.0, 1e-9);
  CHECK_EQ(all.moving_velocity_errors_mps.size(), size_t{3});
  CHECK_NEAR(all.MedianMovingVelocityError(), 2.0, 1e-9);
  CHECK_NEAR(all.MovingVelocityErrorP90(), 3.0, 1e-9);
  o.moving_speed_mps = 10.5;
  const dps::BandScore none = dps::EvaluateTracks(tracks, truth, o).positions.overall;
  CHECK(none.moving_velocity_errors_mps.empty() && std::isnan(none.MedianMovingVelocityError()));
  o.moving_speed_mps = -1.0;
  CHECK_THROWS_WITH(dps::EvaluateTracks(tracks, truth, o), dps::Error, "evaluation option moving_speed_mps = -1");
}

// Front detection on rendered drives: the lead car found at its true range in every frame where
// its back is within 20 m, and nothing within 20 m on the empty road.
void TestRenderedFront() {
  for (const char* name : {"lead_car", "empty_road"}) {
    dps::Scene scene = dps_test::SmallScene(name);
    const dps::SceneRenderer renderer(scene);
    // Every frame, as dps-process runs it (the temporal filter removes single-frame mismatches:
    // without it, a few frames show a 5-column blob on the empty road); every sixth scored.
    dps::FrontDetector front(scene.rig, dps::DefaultPipelineOptions(scene.rig).front);
    int frames = 0, expected = 0, found = 0, false_alarms = 0;
    double worst = 0, worst_side = 0;
    for (int f = 0; f < scene.FrameCount(); ++f) {
      const dps::FrameState st = renderer.StateAt(scene.FrameTime(f));
      const dps::FrontResult r = front.Detect(renderer.Render(st, 0, f).image, renderer.Render(st, 1, f).image);
      if (f % 6 != 0) continue;
      const std::vector<dps::TruthRow> truth = dps::TruthAt(st, f);
      ++frames;
      for (const dps::TruthRow& t : truth) expected += dps::NearPoint(t).norm() <= 20;
      for (const dps::Detection& d : r.detections) {
        if (d.range_m > 20) continue;
        bool matched = false;
        for (const dps::TruthRow& t : truth) {
          const double range = dps::NearPoint(t).norm();
          if (dps::DistanceToFootprint(t, {d.x_m, d.z_m}) <= std::max(0.75, 0.1 * range)) {
            matched = true;
            worst = std::max(worst, std::abs(d.range_m - range) / range);
            // Lateral extent against the car's back (heading 0: x +- width / 2), after the
            // half-window trim of foreground fattening.
            worst_side = std::max({worst_side, std::abs(d.x_min_m - (t.x_m - t.width_m / 2)),
                                   std::abs(d.x_max_m - (t.x_m + t.width_m / 2))});
          }
        }
        found += matched;
        false_alarms += !matched;
      }
    }
    std::printf("rendered front %-10s: %d frames, %d of %d objects within 20 m matched, %d false, worst range "
                "error %.1f %%, worst side of the extent %.2f m off\n", name, frames, found, expected, false_alarms,
                100 * worst, worst_side);
    CHECK_EQ(false_alarms, 0);
    if (std::string(name) == "lead_car") {
      CHECK(expected >= 10);
      CHECK_EQ(found, expected);
      CHECK(worst <= kRangeTolFraction);
      CHECK(worst_side <= kExtentTolM);
    }
  }
}

// A car keeping pace 1.6 m ahead of the bumper, nearer than the front pair's range reaches (f B /
// its largest disparity: 3.6 m from the cameras of the shipped rig): with the near pair
// (PipelineOptions::front_near) a detection gives its back's range within 10 % in four of five
// frames after the first two (the temporal filter's; 11 of 13, the others find only parts farther
// back), and nothing else lies within 20 m; the front pair alone sees only parts of the car farther
// back in every frame.
void TestNearFront() {
  dps::Scene scene = dps_test::SmallScene("lead_car");
  scene.duration_s = 1.0;
  const double speed = 10.0;
  scene.ego = dps::MotionProfile({{0.0, speed, 0.0}});
  dps::SceneObject& car = scene.objects.at(0);
  car.start = dps::PlanarPose{0.0, scene.rig.vehicle.length_m / 2 + 1.6 + car.length_m / 2, 0.0};
  car.motion = dps::MotionProfile({{0.0, speed, 0.0}});
  const dps::SceneRenderer renderer(scene);
  std::map<bool, int> ranged, false_alarms;
  std::map<bool, double> nearest_error;  // the best frame's range error of the nearest match
  int frames = 0;
  for (const bool near : {true, false}) {
    dps::PipelineOptions o = dps::DefaultPipelineOptions(scene.rig);
    o.front_near = near;
    o.sides = o.lanes = false;
    dps::SurroundPipeline pipeline(scene.rig, o);
    frames = 0;
    nearest_error[near] = 1e9;
    for (int f = 0; f < scene.FrameCount(); ++f) {
      const dps::FrameState st = renderer.StateAt(scene.FrameTime(f));
      const dps::FrameOutput out = pipeline.Process(dps_test::RenderedInput(scene, renderer, st, f));
      if (f < 2) continue;
      ++frames;
      const dps::TruthRow truth = dps::TruthAt(st, f).at(0);
      const double range = dps::NearPoint(truth).norm();
      double error = 1e9;
      for (const dps::Detection& d : out.detections) {
        if (d.range_m > 20) continue;
        if (dps::DistanceToFootprint(truth, {d.x_m, d.z_m}) <= std::max(0.75, 0.1 * range)) {
          error = std::min(error, std::abs(d.range_m - range) / range);
        } else {
          ++false_alarms[near];
        }
      }
      ranged[near] += error <= 0.1;
      nearest_error[near] = std::min(nearest_error[near], error);
    }
  }
  std::printf("car 1.6 m ahead of the bumper: its range within 10 %% in %d of %d frames with the near pair (%d false), "
              "%d without (the nearest match at best %.0f %% off)\n", ranged[true], frames, false_alarms[true],
              ranged[false], 100 * nearest_error[false]);
  CHECK(frames >= 10);
  CHECK(ranged[true] * 5 >= frames * 4);
  CHECK_EQ(false_alarms[true], 0);
  CHECK_EQ(ranged[false], 0);
}

// Drift correction inside the detector: rectified with a right camera believed 0.4 degrees
// pitched, the first frame measures the rows' shift and rebuilds the right view.
void TestDriftCorrection() {
  dps::Scene scene = dps_test::SmallScene("parked_cars");
  const dps::SceneRenderer renderer(scene);
  dps::Rig drifted = scene.rig;
  dps::RigCamera& rc = drifted.cameras[1];
  rc.vehicle_from_camera.R = dps::AxisAngle({1, 0, 0}, 0.4 * M_PI / 180.0) * rc.vehicle_from_camera.R;
  dps::FrontDetector front(drifted, dps::DefaultPipelineOptions(drifted).front);
  const dps::FrameState st = renderer.StateAt(0.0);
  const dps::FrontResult r = front.Detect(renderer.Render(st, 0, 0).image, renderer.Render(st, 1, 0).image);
  std::printf("drift correction: measured %.3f px on the first frame\n", r.vertical_offset_px);
  CHECK(r.drift_measured);
  // What geometry predicts: the rows the drifted right view moves a point 20 m ahead by.
  const dps::FrontDetectorOptions fo = dps::DefaultPipelineOptions(drifted).front;
  const dps::ViewSpec spec = dps::FrontViewSpec(drifted, "left", "right", fo.view_width, fo.view_height, fo.focal_px);
  const double expected = dps_test::DriftedRowShift(scene.rig.Camera("right"), rc, spec, {0, -0.5, 20});
  std::printf("drift correction: geometry predicts %.3f px\n", expected);
  CHECK_NEAR(r.vertical_offset_px, expected, 0.3);
  const dps::VerticalOffset after = dps::EstimateVerticalOffset(r.left_view, r.right_view, 0, 64);
  CHECK_NEAR(after.offset_px, 0.0, 0.3);
}

}  // namespace

// The front pair's field of view is where both cameras' views overlap: a point counts exactly
// when it lies within the half-angle of the view axis seen from each camera — also with the right
// camera 0.4 m further back (the front view's axis then turns with the baseline).
void TestFrontCoverage() {
  for (const double right_dz : {0.0, -0.4}) {
    dps::Rig rig = dps::ReadRig(kSource + "/data/rigs/omni_pair.yaml");
    for (dps::RigCamera& c : rig.cameras) {
      if (c.name == "right") c.vehicle_from_camera.t.z() += right_dz;
    }
    dps::PipelineOptions o = dps::DefaultPipelineOptions(rig);
    o.sides = false;
    const dps::Coverage coverage = dps::PipelineCoverage(rig, o);
    CHECK_EQ(coverage.sectors.size(), size_t(1));
    const dps::Sector& front = coverage.sectors[0];
    CHECK_NEAR(front.half_angle_rad, std::atan(200.0 / 170.0), 1e-12);
    if (right_dz == 0.0) {  // from the midpoint, overlapping (B / 2) / tan(half) ahead of it
      CHECK_NEAR(front.apex.x(), 0.0, 1e-9);
      CHECK_NEAR(front.apex.y(), 0.9, 1e-9);
      CHECK_NEAR(front.start_m, 1.0 * 170.0 / 200.0, 1e-9);
    }
    int inside = 0, mismatches = 0;
    for (double x = -8; x <= 8; x += 0.25) {
      for (double z = -2; z <= 12; z += 0.25) {
        bool both = true;
        for (const dps::RigCamera& c : rig.cameras) {
          const double a = std::atan2(x - c.vehicle_from_camera.t.x(), z - c.vehicle_from_camera.t.z());
          both = both && std::abs(std::remainder(a - front.direction_rad, 2 * M_PI)) <= front.half_angle_rad;
        }
        inside += both;
        mismatches += both != coverage.Contains({x, z});
      }
    }
    CHECK(inside > 1000);
    CHECK(mismatches <= 2);  // points on an edge, to rounding
  }
}

// Each side's sector is the columns motion stereo matches: those whose every searched disparity
// keeps the window inside both views (worked out here from the stereo options), seen from the
// camera; the strips beyond them at either edge of the view are not in it. The matcher leaves
// exactly those strips invalid.
void TestSideCoverage() {
  const dps::Rig rig = dps::ReadRig(kSource + "/data/rigs/omni_pair.yaml");
  const dps::PipelineOptions o = dps::DefaultPipelineOptions(rig);
  const dps::Coverage coverage = dps::PipelineCoverage(rig, o);
  CHECK_EQ(coverage.sectors.size(), size_t(3));
  const dps::StereoOptions& st = o.side.stereo;
  const int w = o.side.view_width, rw = st.block_width / 2, d_max = st.min_disparity + st.num_disparities - 1;
  const int lo = rw + std::max(0, d_max), hi = w - 1 - rw + std::min(0, st.min_disparity);  // of the matched image
  for (const dps::Side side : {dps::Side::kLeft, dps::Side::kRight}) {
    const bool left = side == dps::Side::kLeft;
    const dps::Sector& sector = coverage.sectors[left ? 1 : 2];
    CHECK_EQ(sector.name, std::string(left ? "left" : "right"));
    const dps::ViewSpec view = dps::SideViewSpec(side, w, o.side.view_height, o.side.focal_px, 0.0, o.side.horizon_fraction);
    const Eigen::Vector3d camera = rig.Camera(left ? "left" : "right").vehicle_from_camera.t;
    // The left view is matched mirrored: its matched columns, unmirrored.
    const int first = left ? w - 1 - hi : lo, last = left ? w - 1 - lo : hi;
    const auto ground = [&](double x) -> Eigen::Vector2d {  // 5 m from the camera along column x
      const Eigen::Vector3d ray = view.vehicle_from_view * Eigen::Vector3d((x - view.cx) / view.focal_px, 0, 1);
      return Eigen::Vector2d(camera.x(), camera.z()) + 5.0 * Eigen::Vector2d(ray.x(), ray.z()).normalized();
    };
    for (const int x : {first + 1, (first + last) / 2, last - 1}) CHECK(sector.Contains(ground(x)));
    for (const int x : {first - 2, 10, last + 2, w - 10}) CHECK(!sector.Contains(ground(x)));
    std::printf("%s side: columns %d-%d of %d matched, sector %.1f to %.1f degrees\n", sector.name.c_str(), first, last,
                w, (sector.direction_rad - sector.half_angle_rad) * 180 / M_PI,
                (sector.direction_rad + sector.half_angle_rad) * 180 / M_PI);
  }
  // The matcher's valid columns on a textured pair shifted by a disparity in the range.
  cv::Mat a(60, w, CV_8U), b;
  cv::RNG(7).fill(a, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(a, a, cv::Size(), 1.2);
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, -5, 0, 1, 0);
  cv::warpAffine(a, b, shift, a.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  dps::SadStereoMatcher matcher(st);
  const cv::Mat d = matcher.Compute(a, b);
  cv::Mat valid_columns;
  cv::reduce(d < dps::kInvalidDisparity, valid_columns, 0, cv::REDUCE_MAX);
  CHECK_EQ(cv::countNonZero(valid_columns.colRange(0, lo)), 0);
  CHECK_EQ(cv::countNonZero(valid_columns.colRange(hi + 1, w)), 0);
  CHECK(valid_columns.at<std::uint8_t>(0, lo) && valid_columns.at<std::uint8_t>(0, hi));
  CHECK(dps::MatchedColumns(w, st) == std::make_pair(lo, hi));
  // A view reaching 60 degrees behind its axis: its backward edge looks 150 degrees from straight
  // ahead, its forward edge as far forward as the symmetric view's; without it, the symmetric view.
  dps::SideDetectorOptions back = o.side;
  back.back_half_angle_deg = 60.0;
  for (const dps::Side side : {dps::Side::kLeft, dps::Side::kRight}) {
    const dps::ViewSpec symmetric = dps::SideDetectorViewSpec(side, o.side);
    const dps::ViewSpec plain = dps::SideViewSpec(side, w, o.side.view_height, o.side.focal_px, 0.0, o.side.horizon_fraction);
    CHECK(symmetric.width == plain.width && symmetric.cx == plain.cx);
    const dps::ViewSpec view = dps::SideDetectorViewSpec(side, back);
    const auto bearing = [&](const dps::ViewSpec& v, double x) {  // degrees from +Z, either side
      const Eigen::Vector3d ray = v.vehicle_from_view * Eigen::Vector3d((x - v.cx) / v.focal_px, 0, 1);
      return std::atan2(std::abs(ray.x()), ray.z()) * 180 / M_PI;
    };
    const bool left = side == dps::Side::kLeft;  // image x runs forwards in a left view
    const double back_edge = bearing(view, left ? -0.5 : view.width - 0.5);
    const double front_edge = bearing(view, left ? view.width - 0.5 : -0.5);
    CHECK_NEAR(back_edge, 150.0, 0.2);
    CHECK_NEAR(front_edge, bearing(plain, left ? plain.width - 0.5 : -0.5), 0.2);
  }
}

// Front detections of the parked row's frame `last` (straight at 8 m/s; `objects` placed at
// t = 0; frames 0..last detected in turn, as dps-process does); prints them and returns them and
// the frame's truth.
std::vector<dps::Detection> FrontOfParkedRow(const std::vector<dps::SceneObject>& objects,
                                             const dps::FrontDetectorOptions& options, int last,
                                             std::vector<dps::TruthRow>* truth) {
  dps::Scene scene = dps_test::SmallScene("parked_cars");
  scene.objects = objects;
  const dps::SceneRenderer renderer(scene);
  dps::FrontDetector front(scene.rig, options);
  dps::FrontResult r;
  for (int f = 0; f <= last; ++f) {
    const dps::FrameState state = renderer.StateAt(scene.FrameTime(f));
    *truth = dps::TruthAt(state, f);
    r = front.Detect(renderer.Render(state, 0, f).image, renderer.Render(state, 1, f).image);
  }
  for (const dps::Detection& d : r.detections) {
    std::printf("  front detection (%.2f, %.2f), z %.2f..%.2f\n", d.x_m, d.z_m, d.z_min_m, d.z_max_m);
  }
  return r.detections;
}

// A standing object of the parked row's scene at (x, z) at t = 0: a car (4.5 x 1.8 x 1.5 m) or
// a pole (0.2 x 0.2 x 3 m).
dps::SceneObject Parked(int id, const char* kind, double x, double z, int colour) {
  dps::SceneObject o;
  o.id = id;
  o.kind = kind;
  if (o.kind == "pole") {
    o.length_m = o.width_m = 0.2;
    o.height_m = 3.0;
  }
  o.start.x_m = x;
  o.start.z_m = z;
  o.colour = colour;
  return o;
}

// The front detector's default options for the parked row's rig.
dps::FrontDetectorOptions ParkedRowFrontOptions() {
  return dps::DefaultPipelineOptions(dps::ReadScene(kSource + "/data/scenes/parked_cars.yaml").rig).front;
}

// Detections within the scoring tolerance of a truth object's footprint.
int Found(const std::vector<dps::Detection>& detections, const dps::TruthRow& truth) {
  const double tolerance = std::max(0.75, 0.1 * dps::NearPoint(truth).norm());
  int found = 0;
  for (const dps::Detection& d : detections) found += dps::DistanceToFootprint(truth, {d.x_m, d.z_m}) <= tolerance;
  return found;
}

// Two cars parked in a row on the right, 1.5 m apart (the parked row's first two; at frame 5
// z 1.08..5.58 and 7.08..11.58): their sides lie on one plane and the gap between them shows
// only the second car's untextured front, so the two sides qualify for linking — but together
// they are 10.5 m long. Returns the detections on the second car at `frame`, the cars on the
// right (side 1) or mirrored to the left (side -1).
int SecondCarFound(const dps::FrontDetectorOptions& options, double side, int frame) {
  std::vector<dps::TruthRow> truth;
  const std::vector<dps::Detection> detections = FrontOfParkedRow(
      {Parked(1, "car", side * 3.4, 6.0, 2), Parked(2, "car", side * 3.4, 12.0, 3)}, options, frame, &truth);
  return Found(detections, truth.at(1));
}

void TestCarsInRow() {
  dps::FrontDetectorOptions without_rule = ParkedRowFrontOptions();
  without_rule.link_vehicle_length_m = 0.0;
  const int with_rule = SecondCarFound(ParkedRowFrontOptions(), 1.0, 5);
  const int without = SecondCarFound(without_rule, 1.0, 5);
  std::printf("second of two parked cars: %d detection(s) on it with the vehicle-length rule, %d without\n",
              with_rule, without);
  CHECK_EQ(with_rule, 1);
}

// The same two cars parked on the left (x -4.3..-2.5), at frame 8 (z -0.52..3.98 and 5.48..9.98):
// objects beyond the left camera are matched with the right view as the reference, so the second
// car is found as on the right. With the left view as the only reference the first car hid the
// second one's side from it and no detection lay on the second car in this frame (nor in frame
// 14; the mirrored parked row's recall was 0.81 against 0.935 on the right).
void TestRowOnTheLeft() {
  for (const double side : {1.0, -1.0}) {
    const int found = SecondCarFound(ParkedRowFrontOptions(), side, 8);
    std::printf("second of two parked cars on the %s: %d detection(s) on it\n", side > 0 ? "right" : "left", found);
    CHECK_EQ(found, 1);
  }
}

// A parked car on the right (x 2.5..4.3, z 3.35..7.85) and a 3 m pole 3.7 m beyond its far end
// (x 2.9, z 11.6; the parked row's frame 12): in the left view the pole's disparity spreads
// over the sky up to the car's side and the gap between them shows nothing farther, so the two
// parts qualify for linking — but the pole's top is twice as high. Returns the number of
// detections within the scoring tolerance of the pole's footprint.
int PoleBeyondCarFound(double link_max_top_difference_m) {
  dps::FrontDetectorOptions options = ParkedRowFrontOptions();
  options.temporal_max_variance_px2 = 0;  // one frame
  options.link_max_top_difference_m = link_max_top_difference_m;
  std::vector<dps::TruthRow> truth;
  const std::vector<dps::Detection> detections =
      FrontOfParkedRow({Parked(1, "car", 3.4, 5.6, 3), Parked(2, "pole", 2.9, 11.6, 0)}, options, 0, &truth);
  return Found(detections, truth.at(1));
}

void TestPoleBeyondCar() {
  const int with_rule = PoleBeyondCarFound(dps::FrontDetectorOptions().link_max_top_difference_m);
  const int without = PoleBeyondCarFound(0.0);
  std::printf("pole beyond a parked car: %d detection(s) on the pole with the top-height rule, %d without\n",
              with_rule, without);
  CHECK_EQ(with_rule, 1);
}

// The height a front detection reports is the object's top above the road (object_attributes.h
// classes by it): a parked car (1.5 m) and a pole (3 m) ahead, one frame. Counting the rows an
// object fills with its disparity instead gave 0.77 m for one of the car's two detections (its
// body's untextured bands leave rows out; on the battery's tuning drives trucks and poles ahead
// measured about half their height that way).
void TestObjectHeights() {
  dps::FrontDetectorOptions options = ParkedRowFrontOptions();
  options.temporal_max_variance_px2 = 0;  // one frame
  std::vector<dps::TruthRow> truth;
  const std::vector<dps::Detection> detections =
      FrontOfParkedRow({Parked(1, "car", 3.4, 8.0, 3), Parked(2, "pole", -2.9, 11.6, 0)}, options, 0, &truth);
  for (const dps::TruthRow& t : truth) {
    const double tolerance = std::max(0.75, 0.1 * dps::NearPoint(t).norm());
    int measured = 0;
    for (const dps::Detection& d : detections) {
      if (dps::DistanceToFootprint(t, {d.x_m, d.z_m}) > tolerance) continue;
      std::printf("  %s %.1f m high: detection's height %.2f m\n", t.kind.c_str(), t.height_m, d.height_m);
      // Two rows of the view at 12 m are 0.14 m.
      CHECK_NEAR(d.height_m, t.height_m, 0.25);
      ++measured;
    }
    CHECK(measured >= 1);
  }
}

// Every detector and pipeline setting is checked: a value out of range is an error naming it.
void TestOptionChecks() {
  const dps::Rig rig = dps::ReadRig(std::string(DPS_SOURCE_DIR) + "/data/rigs/omni_pair.yaml");
  dps::PipelineOptions o = dps::DefaultPipelineOptions(rig);
  o.Check();  // the defaults are valid
  dps::PipelineOptions bad = o;
  bad.front.temporal_forgetting = 0.0;
  CHECK_THROWS_WITH(bad.Check(), dps::Error, "front detector option temporal_forgetting = 0");
  bad = o;
  bad.front.range_edge_px = -1.0;
  CHECK_THROWS_WITH(bad.Check(), dps::Error, "front detector option range_edge_px = -1");
  dps::NearFrontOptions(o.front).Check();  // the near pair's, derived from valid ones, are valid
  bad = o;
  bad.side.horizon_fraction = 1.5;
  CHECK_THROWS_WITH(bad.Check(), dps::Error, "side detector option horizon_fraction = 1.5");
  bad = o;
  bad.side.max_vehicle_width_m = -1.0;
  CHECK_THROWS_WITH(bad.Check(), dps::Error, "side detector option max_vehicle_width_m = -1");
  bad = o;
  bad.side.static_gate = -0.5;
  CHECK_THROWS_WITH(bad.Check(), dps::Error, "side detector option static_gate = -0.5");
  bad = o;
  bad.vehicle_width_m = -1.0;
  CHECK_THROWS_WITH(dps::SurroundPipeline(rig, bad), dps::Error, "pipeline option vehicle_width_m = -1");
  bad = o;
  bad.side.stereo.num_disparities = 0;
  CHECK_THROWS_WITH(dps::SideDetector(rig, "left", dps::Side::kLeft, bad.side), dps::Error, "num_disparities");
  // The drive's, the map's and the evaluation's options too.
  dps::DriveOptions drive;
  drive.Check();
  drive.image_fps = 0.0;
  CHECK_THROWS_WITH(drive.Check(), dps::Error, "drive option image_fps = 0");
  drive = dps::DriveOptions();
  drive.map.size_px = 3;
  CHECK_THROWS_WITH(drive.Check(), dps::Error, "map option size_px = 3");
  drive = dps::DriveOptions();
  drive.default_pipeline = false;
  drive.pipeline = bad;
  CHECK_THROWS_WITH(dps::ProcessDrive("nowhere", "nowhere_out", drive), dps::Error, "num_disparities");
  dps::EvaluationOptions evaluation;
  evaluation.max_range_m = 0.0;
  CHECK_THROWS_WITH(dps::Evaluate({}, {}, evaluation), dps::Error, "evaluation option max_range_m = 0");
}

// The front pair's detections behind a nearer one of its own, seen from the cameras' midpoint
// (0, 0), 1 m high: a truck's back 4.6 m ahead (x -1.4..1.4, 2.0 m high) hides a narrow part at
// 12.8 m (x 0..0.2) 2.5 m high - below the sight line over the truck's top there (3.7 m) - and
// one at 7.7 m; a pole at 12.8 m reaching 5 m rises above that line, a part at 9 m off the truck's
// bearings is beside it, a part 0.2 m behind the back is within the depth error (one object's
// face), a side camera's detection is another viewpoint's, and one without a height is unknown:
// all kept.
void TestHidden() {
  auto part = [](double x0, double x1, double z, double height, const char* source) {
    std::vector<Eigen::Vector2d> p;
    for (int i = 0; i <= 10; ++i) p.emplace_back(x0 + (x1 - x0) * i / 10.0, z);
    dps::Detection d = dps::DetectionFromPoints(p, source);
    d.height_m = height;
    return d;
  };
  const double k = 0.5 / (170 * 2.0);
  const std::vector<dps::Detection> in = {
      part(-1.4, 1.4, 4.6, 2.0, "front"),  part(0.0, 0.2, 12.8, 2.5, "front"), part(-0.2, -0.1, 7.7, 1.6, "front"),
      part(0.3, 0.5, 12.8, 5.0, "front"),  part(2.5, 3.0, 9.0, 1.5, "front"),  part(-0.5, 0.5, 4.8, 1.2, "front"),
      part(0.0, 0.2, 12.8, 2.5, "left"),   part(0.6, 0.8, 12.8, std::nan(""), "front")};
  const std::vector<dps::Detection> out = dps::DropHidden(in, "front", Eigen::Vector2d(0, 0), 1.0, k);
  CHECK_EQ(out.size(), size_t{6});
  for (const dps::Detection& d : out) {
    CHECK(!(d.source == "front" && std::abs(d.z_m - 12.8) < 1e-9 && d.x_m < 0.25));
    CHECK(!(std::abs(d.z_m - 7.7) < 1e-9));
  }
  // The truck's back gone (not found this frame): nothing hides them.
  CHECK_EQ(dps::DropHidden({in.begin() + 1, in.end()}, "front", Eigen::Vector2d(0, 0), 1.0, k).size(), size_t{7});
}

int main() {
  TestOptionChecks();
  TestHistogram();
  TestLinking();
  TestFrontProjection();
  TestFusion();
  TestHidden();
  TestVisibility();
  TestEvaluation();
  TestTrackVelocities();
  TestFrontCoverage();
  TestSideCoverage();
  TestRenderedFront();
  TestNearFront();
  TestPoleBeyondCar();
  TestObjectHeights();
  TestCarsInRow();
  TestRowOnTheLeft();
  TestDriftCorrection();
  return dps_test::Report();
}
