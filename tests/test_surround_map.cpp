// The surround map picture (surround_map.h): the own car, obstacles, tracks, coverage and the
// occupancy grid land where the vehicle-frame geometry puts them; each frame's background shades
// what that frame measured. Map pixel of vehicle (x, z):
// u = size/2 + x * scale, v = size/2 - z * scale, scale = size / (2 range) px per metre.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "check.h"
#include "dps/camera/rig_io.h"
#include "dps/map/surround_map.h"
#include "dps/util/error.h"

namespace {

const dps::MapOptions kMap;  // 600 px, 30 m: 10 px per metre
const double kScale = kMap.size_px / (2.0 * kMap.range_m);

cv::Point Pixel(double x, double z) {
  return cv::Point(cvRound(kMap.size_px / 2.0 + x * kScale), cvRound(kMap.size_px / 2.0 - z * kScale));
}

// Pixels of a colour class within `radius` px of a point.
int Count(const cv::Mat& map, cv::Point at, int radius, bool (*is)(const cv::Vec3b&)) {
  int n = 0;
  for (int v = std::max(0, at.y - radius); v <= std::min(map.rows - 1, at.y + radius); ++v) {
    for (int u = std::max(0, at.x - radius); u <= std::min(map.cols - 1, at.x + radius); ++u) n += is(map.at<cv::Vec3b>(v, u));
  }
  return n;
}
bool Black(const cv::Vec3b& p) { return p[0] < 30 && p[1] < 30 && p[2] < 30; }
bool Red(const cv::Vec3b& p) { return p[2] > 180 && p[0] < 80 && p[1] < 80; }
bool NearMark(const cv::Vec3b& p) { return p[2] > 90 && p[2] < 160 && p[0] < 40 && p[1] < 40; }
bool Blue(const cv::Vec3b& p) { return p[0] > 150 && p[2] < 60; }
bool White(const cv::Vec3b& p) { return p == cv::Vec3b(255, 255, 255); }
bool Magenta(const cv::Vec3b& p) { return p == cv::Vec3b(220, 90, 220); }
bool HatchGrey(const cv::Vec3b& p) { return p == cv::Vec3b(110, 110, 110); }

dps::Coverage FrontOnly() {
  dps::Coverage c;
  c.sectors.push_back({"front", {0.0, 0.9}, 0.0, 0.8});  // +-46 degrees straight ahead
  return c;
}

void TestBackgroundAndObstacles() {
  dps::Vehicle car;
  car.width_m = 1.8;
  car.length_m = 4.4;
  const cv::Mat background = dps::DrawMapBackground(car, FrontOnly(), kMap);
  CHECK_EQ(background.cols, kMap.size_px);
  // The own car: its whole footprint black, nothing black just beside it.
  const cv::Point centre = Pixel(0, 0);
  CHECK_EQ(Count(background, centre, 8, Black), 17 * 17);
  CHECK_EQ(Count(background, Pixel(3.0, 0.0), 3, Black), 0);
  // The front sector shaded, the ground behind (outside it, between range rings) left white.
  CHECK(!White(background.at<cv::Vec3b>(Pixel(0.0, 12.0))));
  CHECK(White(background.at<cv::Vec3b>(Pixel(0.0, -12.0))));
  // The legend at the bottom right: a swatch of the front sector's shade as the map shows it, and
  // of the grid's free colour (the map behind the car there is otherwise white).
  const cv::Vec3b shade = background.at<cv::Vec3b>(Pixel(0.0, 12.0));
  const cv::Mat corner = background(cv::Rect(kMap.size_px - 250, kMap.size_px - 250, 250, 250));
  int shaded = 0, free_colour = 0;
  for (int v = 0; v < corner.rows; ++v) {
    for (int u = 0; u < corner.cols; ++u) {
      const cv::Vec3b p = corner.at<cv::Vec3b>(v, u);
      shaded += cv::norm(cv::Vec3i(p) - cv::Vec3i(shade), cv::NORM_INF) <= 1;
      free_colour += p == cv::Vec3b(dps::kGridFreeBlueRed, dps::kGridFreeGreen, dps::kGridFreeBlueRed);
    }
  }
  CHECK(shaded >= 100);
  CHECK(free_colour >= 100);
  CHECK(White(background.at<cv::Vec3b>(Pixel(-8.0, -25.0))));  // the bottom left: no legend

  // An obstacle 10 m ahead, 4 m to the right: a 2 m wide row of ground points.
  std::vector<Eigen::Vector2d> points;
  for (double x = 3.0; x <= 5.0 + 1e-9; x += 0.25) points.emplace_back(x, 10.0);
  dps::Detection d = dps::DetectionFromPoints(points, "front");
  d.lane = 0;  // in the ego lane: red
  const cv::Mat map = dps::DrawSurroundMap(background, {d}, kMap, "test");
  const int at_obstacle = Count(map, Pixel(4.0, 10.0), 5, Red);
  const int elsewhere = Count(map, Pixel(-4.0, 10.0), 10, Red) + Count(map, Pixel(4.0, 14.0), 10, Red);
  std::printf("map: %d red pixels at the obstacle, %d elsewhere\n", at_obstacle, elsewhere);
  CHECK(at_obstacle > 40);
  CHECK_EQ(elsewhere, 0);
  // Its ends: red at the far one, the near point's dark red mark at the near one, nothing a
  // metre beyond.
  CHECK(Count(map, Pixel(5.0, 10.0), 2, Red) > 0);
  CHECK(Count(map, Pixel(3.0, 10.0), 1, NearMark) > 0);
  CHECK_EQ(Count(map, Pixel(4.0, 10.0), 1, NearMark), 0);
  CHECK_EQ(Count(map, Pixel(6.5, 10.0), 3, Red), 0);
  // Coloured by lane: orange in a lane to the left, purple to the right, grey-brown unknown; each
  // drawn where the ego lane's would be, and no red.
  const auto Orange = [](const cv::Vec3b& p) { return p == cv::Vec3b(0, 150, 255); };
  const auto Purple = [](const cv::Vec3b& p) { return p == cv::Vec3b(160, 30, 140); };
  const auto Unknown = [](const cv::Vec3b& p) { return p == cv::Vec3b(90, 110, 130); };
  const std::pair<std::optional<int>, bool (*)(const cv::Vec3b&)> lanes[] = {{-1, Orange}, {2, Purple}, {std::nullopt, Unknown}};
  for (const auto& [lane, is] : lanes) {
    d.lane = lane;
    const cv::Mat coloured = dps::DrawSurroundMap(background, {d}, kMap, "test");
    CHECK(Count(coloured, Pixel(4.0, 10.0), 5, is) > 40);
    CHECK_EQ(Count(coloured, Pixel(4.0, 10.0), 5, Red), 0);
  }
}

void TestTracksAndGrid() {
  dps::Vehicle car;
  const cv::Mat background = dps::DrawMapBackground(car, FrontOnly(), kMap);
  // A confirmed track at (-3, 8) predicted at (-3, 14): an arrow between them, its id beside.
  dps::TrackState t;
  t.id = 7;
  t.confirmed = true;
  t.x_m = -3.0;
  t.z_m = 8.0;
  t.predicted = Eigen::Vector2d(-3.0, 14.0);
  t.predicted_cov = Eigen::Matrix2d::Identity() * 0.25;
  cv::Mat map = background.clone();
  dps::DrawTracks(map, {t}, kMap);
  CHECK(Count(map, Pixel(-3.0, 11.0), 2, Blue) > 0);  // the arrow's middle
  CHECK(Count(map, Pixel(-3.0, 14.0), 6, Blue) > 0);  // its head and the ellipse
  CHECK_EQ(Count(map, Pixel(3.0, 11.0), 10, Blue), 0);
  // Lane boundaries: the right one 1.75 m out, solid, along the whole map; a dashed left one.
  cv::Mat laned = background.clone();
  dps::DrawLanes(laned, {{0, 0.0, "right", 1.75, 0.0, 0.0, "solid", 1.0}, {0, 0.0, "left", -1.75, 0.0, 0.0, "dashed", 1.0}},
                 kMap);
  const auto lane = [](const cv::Vec3b& p) { return p[1] > 140 && p[2] > 200 && p[0] < 60; };
  int solid = 0, dashed = 0;
  for (double z = -25.0; z <= 25.0; z += 1.0) {
    solid += lane(laned.at<cv::Vec3b>(Pixel(1.75, z)));
    dashed += lane(laned.at<cv::Vec3b>(Pixel(-1.75, z)));
  }
  std::printf("lanes on the map: the solid line in %d of 51 sampled metres, the dashed one in %d\n", solid, dashed);
  CHECK(solid >= 48);
  CHECK(dashed >= 12 && dashed <= 24);  // 3 m of every 9
  CHECK(!lane(laned.at<cv::Vec3b>(Pixel(0.0, 10.0))));
  // The label with class and lane ("vehicle L-1") reaches further right than the id alone.
  const auto label_pixels = [&](const dps::TrackState& s) {
    cv::Mat m = background.clone();
    dps::DrawTracks(m, {s}, kMap);
    const cv::Point at = Pixel(s.x_m, s.z_m);
    int n = 0;
    for (int y = at.y - 20; y < at.y; ++y) {
      for (int x = at.x + 30; x < std::min(m.cols, at.x + 120); ++x) n += Blue(m.at<cv::Vec3b>(y, x));
    }
    return n;
  };
  dps::TrackState labelled = t;
  labelled.object_class = "vehicle";
  labelled.lane = -1;
  CHECK(label_pixels(labelled) > label_pixels(t) + 20);
  // The ego's lane position under the caption, in the lane colour.
  cv::Mat ego = background.clone();
  dps::EgoLaneRow row;
  row.lp_m = 0.12;
  row.lane_width_m = 3.5;
  dps::DrawEgoLane(ego, row);
  int ego_text = 0;
  for (int y = 28; y < 44; ++y) {
    for (int x = 10; x < 300; ++x) ego_text += lane(ego.at<cv::Vec3b>(y, x));
  }
  CHECK(ego_text > 50);
  t.confirmed = false;  // tentative tracks are not drawn
  cv::Mat none = background.clone();
  dps::DrawTracks(none, {t}, kMap);
  CHECK_EQ(cv::norm(none, background, cv::NORM_INF), 0.0);

  // The occupancy grid under it: a wall 12 m ahead seen for a few frames shows grey there, the
  // ground before it light green, and the own car stays black on top.
  dps::OccupancyGrid grid;
  std::vector<Eigen::Vector2d> wall;
  for (double x = -2.0; x <= 2.0 + 1e-9; x += 0.1) wall.emplace_back(x, 12.0);
  for (int f = 0; f < 5; ++f) grid.Update(f / 15.0, dps::PlanarPose{}, FrontOnly(), {dps::DetectionFromPoints(wall, "front")});
  const cv::Mat framed = dps::DrawFrameMap(background, grid, car, {}, {}, kMap, "grid");
  const cv::Vec3b at_wall = framed.at<cv::Vec3b>(Pixel(0.0, 12.1)), before = framed.at<cv::Vec3b>(Pixel(0.0, 6.0));
  std::printf("grid on the map: wall (%d, %d, %d), ground before it (%d, %d, %d)\n", at_wall[0], at_wall[1], at_wall[2],
              before[0], before[1], before[2]);
  CHECK(std::max({at_wall[0], at_wall[1], at_wall[2]}) < 180);  // darkened towards grey
  CHECK(std::abs(at_wall[0] - at_wall[1]) <= 10 && std::abs(at_wall[1] - at_wall[2]) <= 10);
  CHECK(before[1] > before[0] && before[1] > before[2]);
  CHECK_EQ(Count(framed, Pixel(0, 0), 8, Black), 17 * 17);

  // Drawn into a picture of the right size, the same map in the same buffer (whatever it held).
  cv::Mat reused(background.size(), background.type(), cv::Scalar(1, 2, 3));
  const std::uint8_t* buffer = reused.data;
  dps::DrawFrameMap(background, grid, car, {}, {}, kMap, "grid", reused);
  CHECK(reused.data == buffer);
  CHECK_EQ(cv::norm(reused, framed, cv::NORM_INF), 0.0);
}

}  // namespace

// The background is what the frame measured (MapBackgrounds): with both side views matched their
// sectors are shaded as deep as their depth limit, in their own colours; a frame whose left view was
// not matched (the car standing) leaves the left side white while the right keeps its colour; the
// same coverage again gives the picture already drawn.
void TestFrameBackgrounds() {
  dps::Vehicle car;
  car.width_m = 1.8;
  car.length_m = 4.4;
  dps::Coverage all = FrontOnly();
  dps::Sector left{"left", {-1.0, 0.5}, -90.0 * M_PI / 180, 40.0 * M_PI / 180};
  left.max_depth_m = 6.0;
  left.depth_direction_rad = -90.0 * M_PI / 180;
  dps::Sector right = left;
  right.name = "right";
  right.apex = {1.0, 0.5};
  right.direction_rad = right.depth_direction_rad = 90.0 * M_PI / 180;
  all.sectors.push_back(left);
  all.sectors.push_back(right);
  dps::Coverage no_left = FrontOnly();
  no_left.sectors.push_back(right);
  dps::MapBackgrounds backgrounds(car, kMap);
  const cv::Mat both = backgrounds.For(all).clone();
  const cv::Mat standing = backgrounds.For(no_left).clone();
  // Abeam 4 m out: inside either view's depth; 9 m out: beyond it.
  CHECK(!White(both.at<cv::Vec3b>(Pixel(-4.0, 0.5))));
  CHECK(!White(both.at<cv::Vec3b>(Pixel(4.0, 0.5))));
  CHECK(White(both.at<cv::Vec3b>(Pixel(-9.0, 0.5))));
  CHECK(White(both.at<cv::Vec3b>(Pixel(9.0, 0.5))));
  CHECK(both.at<cv::Vec3b>(Pixel(-4.0, 0.5)) != both.at<cv::Vec3b>(Pixel(4.0, 0.5)));  // each its colour
  CHECK(White(standing.at<cv::Vec3b>(Pixel(-4.0, 0.5))));
  CHECK(standing.at<cv::Vec3b>(Pixel(4.0, 0.5)) == both.at<cv::Vec3b>(Pixel(4.0, 0.5)));
  // Drawn once per coverage.
  const cv::Mat& again = backgrounds.For(all);
  CHECK(again.data == backgrounds.For(all).data);
  CHECK_EQ(cv::norm(again, both, cv::NORM_INF), 0.0);
}

// Where motion stereo tells depth (MotionSight): a viewpoint displaced by b between two frames
// sees a static point's direction turn; depth is told where the turn is at least the matching
// noise over the focal length. Checked against the turn computed from the two viewpoints directly,
// over points 4-40 m from the viewpoint in every direction (those within 10 % of the limit left
// out: the disc is the small-displacement form, off by up to b / r = 7.5 %).
void TestMotionSight() {
  const double f = 170.0, sigma = 1.0, b = 0.3;
  for (const double heading_deg : {0.0, 20.0, -135.0}) {
    const double h = heading_deg * M_PI / 180;
    const dps::MotionSight m{"left", {-1.0, 0.9}, h, f * b / sigma};
    const Eigen::Vector2d step(b * std::sin(h), b * std::cos(h));
    int agree = 0, checked = 0;
    for (int i = 0; i < 4000; ++i) {
      // A deterministic spread: distances 4-40 m, every bearing.
      const double r = 4.0 + 36.0 * ((i * 7919) % 4000) / 4000.0, a = 2 * M_PI * i / 4000.0;
      const Eigen::Vector2d p = m.viewpoint + r * Eigen::Vector2d(std::sin(a), std::cos(a));
      const Eigen::Vector2d now = p - m.viewpoint, before = p - (m.viewpoint - step);
      const double turn = std::acos(std::clamp(now.normalized().dot(before.normalized()), -1.0, 1.0));
      const double ratio = turn * f / sigma;
      if (std::abs(ratio - 1.0) < 0.1) continue;
      ++checked;
      agree += m.TellsDepth(p) == (ratio > 1.0);
    }
    std::printf("motion sight, heading %.0f deg: %d of %d points agree with the direct turn\n", heading_deg, agree,
                checked);
    CHECK(checked > 3000);
    CHECK_EQ(agree, checked);
  }
}

// The map hatches where the frame's motion stereo tells no depth, outside the measured sectors: at
// speed (D = 40 m) straight behind the car, not beside it nor in the front sector; a frame without
// motion stereo hatches nothing.
void TestMotionBlindWedges() {
  dps::Vehicle car;
  dps::Coverage moving = FrontOnly();
  moving.motion.push_back({"left", {-1.0, 0.9}, 0.0, 40.0});
  moving.motion.push_back({"right", {1.0, 0.9}, 0.0, 40.0});
  CHECK(moving.MotionBlind({0.0, -20.0}));
  CHECK(!moving.MotionBlind({-8.0, 0.0}));
  CHECK(!FrontOnly().MotionBlind({0.0, -20.0}));
  const cv::Mat map = dps::DrawMapBackground(car, moving, kMap);
  CHECK(Count(map, Pixel(0.0, -20.0), 4, Magenta) > 0);
  CHECK_EQ(Count(map, Pixel(-8.0, 0.0), 4, Magenta), 0);
  CHECK_EQ(Count(map, Pixel(0.0, 12.0), 4, Magenta), 0);  // the front pair measures there
  const cv::Mat still = dps::DrawMapBackground(car, FrontOnly(), kMap);
  CHECK_EQ(Count(still, Pixel(0.0, -20.0), 4, Magenta), 0);
}

// The road no camera sees, for two omni cameras in the mirrors (1 m up, 1 m out, 0.9 m ahead of
// the centre of a 4.8 x 1.8 m car) with the car's box 1 m high: 0.2 m ahead of the bumper the
// segment from either camera enters the box's side 0.1 m inboard at 0.9 m up, so the bonnet hides
// it; 2.5 m beside the right camera the right camera sees the road (68 degrees off its axis),
// the left camera's segment crosses the car 0.98 m up; the footprint's centre is under the car.
void TestRoadNoCameraSees() {
  dps::Rig rig = dps::ReadRig(std::string(DPS_SOURCE_DIR) + "/data/rigs/omni_pair.yaml");
  const auto unseen_at = [&](const cv::Mat& unseen, double x, double z) { return unseen.at<uchar>(Pixel(x, z)) == 255; };
  const cv::Mat unseen = dps::RoadNoCameraSees(rig, 1.0, kMap);
  CHECK_EQ(unseen.size(), cv::Size(kMap.size_px, kMap.size_px));
  CHECK(unseen_at(unseen, 0.0, 2.6));
  CHECK(unseen_at(unseen, 0.0, 0.0));
  CHECK(!unseen_at(unseen, 3.5, 0.9));
  CHECK(!unseen_at(unseen, -3.5, 0.9));
  // Without the car's box the bumper's road is seen.
  CHECK(!unseen_at(dps::RoadNoCameraSees(rig, 0.0, kMap), 0.0, 2.6));
  // The right camera's own car covering its whole image: the road beside it is seen by no camera.
  dps::Rig own = rig;
  own.cameras[1].own_car = cv::Mat(480, 640, CV_8U, cv::Scalar(255));
  CHECK(unseen_at(dps::RoadNoCameraSees(own, 1.0, kMap), 3.5, 0.9));
  CHECK(!unseen_at(dps::RoadNoCameraSees(own, 1.0, kMap), -3.5, 0.9));
  // ... and so with its valid pixels none (the mask).
  dps::Rig blind = rig;
  blind.cameras[1].mask = cv::Mat(480, 640, CV_8U, cv::Scalar(0));
  CHECK(unseen_at(dps::RoadNoCameraSees(blind, 1.0, kMap), 3.5, 0.9));
  // Drawn cross-hatched in grey, with the motion's hatching kept off it.
  dps::Coverage moving = FrontOnly();
  moving.motion.push_back({"right", {1.0, 0.9}, 0.0, 40.0});
  const cv::Mat map = dps::DrawMapBackground(rig.vehicle, moving, kMap, unseen);
  CHECK(Count(map, Pixel(0.0, 2.8), 4, HatchGrey) > 0);
  CHECK_EQ(Count(map, Pixel(3.5, 0.9), 4, HatchGrey), 0);
  bool threw = false;
  try {
    dps::DrawMapBackground(rig.vehicle, moving, kMap, cv::Mat(10, 10, CV_8U, cv::Scalar(0)));
  } catch (const dps::Error&) {
    threw = true;
  }
  CHECK(threw);
}

int main() {
  TestBackgroundAndObstacles();
  TestTracksAndGrid();
  TestFrameBackgrounds();
  TestMotionSight();
  TestMotionBlindWedges();
  TestRoadNoCameraSees();
  return dps_test::Report();
}
